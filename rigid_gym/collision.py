"""Collision detection for a World: broad phase, narrow phase, and buffers that grow.

Buffers have a fixed capacity per world and are reused from call to call; when a kernel reports
more pairs or contacts than fit, the capacity is doubled past what was needed and the call is
repeated, so nothing is ever silently dropped.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rigid_gym.geometry import Geometry
from rigid_gym.kernels.broadphase import find_pairs
from rigid_gym.kernels.contacts import detect_contacts
from rigid_gym.kernels.jit import for_worlds

SWEEP_MIN_BODIES = 64
"""Bounded bodies from which sort-and-sweep beats brute force (benchmarks/collision.py)."""


class Contacts(NamedTuple):
    """Contacts as flat arrays over all worlds, k rows.

    world (k,) int32; body_a, body_b (k,) int32; point (k, 3) m (the deepest point of one body
    inside the other); normal (k, 3) unit, from body_b towards body_a; depth (k,) m,
    > 0 when overlapping. Within a pair the deepest contact comes first.
    """

    world: np.ndarray
    body_a: np.ndarray
    body_b: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    depth: np.ndarray


class Collider:
    """Finds the contacts of B worlds of one scene.

    geometry: compiled shapes; motion (n,) int32; sweep: None picks sort-and-sweep from
    ``SWEEP_MIN_BODIES`` bounded bodies, True/False forces it on/off.
    """

    def __init__(self, geometry: Geometry, motion: np.ndarray, num_worlds: int,
                 sweep: bool | None = None):
        self.geometry = geometry
        self.motion = motion
        n = len(motion)
        bounded = int(np.count_nonzero(geometry.body_unbounded == 0))
        self.sweep = bounded >= SWEEP_MIN_BODIES if sweep is None else bool(sweep)
        self.bounds = np.zeros((num_worlds, n, 6))
        self.pair_count = np.zeros(num_worlds, dtype=np.int32)
        self.contact_count = np.zeros(num_worlds, dtype=np.int32)
        self._allocate_pairs(max(8, 2 * n))
        self._allocate_contacts(64)

    def _allocate_pairs(self, capacity: int) -> None:
        b = len(self.pair_count)
        self.pair_a = np.zeros((b, capacity), dtype=np.int32)
        self.pair_b = np.zeros((b, capacity), dtype=np.int32)
        self.pair_impulse = np.zeros((b, capacity, 3))  # the solver's per-step totals, N s

    def _allocate_contacts(self, capacity: int) -> None:
        b = len(self.contact_count)
        self.body_a = np.zeros((b, capacity), dtype=np.int32)
        self.body_b = np.zeros((b, capacity), dtype=np.int32)
        self.point = np.zeros((b, capacity, 3))
        self.normal = np.zeros((b, capacity, 3))
        self.depth = np.zeros((b, capacity))

    def find_pairs(self, state, margin: float, dt: float = 0.0, acceleration: float = 0.0) -> None:
        """Fill pair_a/pair_b/pair_count with the pairs that may touch within dt (s) of the
        state's poses (a ``world.State``), boxes grown by margin (m) and by how far the bodies
        can move in dt under an acceleration bound (m/s^2)."""
        pairs = for_worlds(find_pairs, len(self.pair_count))
        while True:
            pairs(state.position, state.rotation, state.velocity, state.angular_velocity,
                  self.motion, self.geometry, margin, dt, acceleration, self.sweep, self.bounds,
                  self.pair_a, self.pair_b, self.pair_count)
            needed = int(self.pair_count.max(initial=0))
            if needed <= self.pair_a.shape[1]:
                return
            self._allocate_pairs(2 * needed)

    def detect(self, state, margin: float = 0.0) -> None:
        """Fill the contact buffers for the state's current poses (contacts deeper than -margin,
        m)."""
        self.find_pairs(state, margin)
        detect = for_worlds(detect_contacts, len(self.pair_count))
        while True:
            detect(state.position, state.rotation, self.geometry, self.pair_a, self.pair_b,
                   self.pair_count, margin, self.body_a, self.body_b, self.point, self.normal,
                   self.depth, self.contact_count)
            needed = int(self.contact_count.max(initial=0))
            if needed <= self.depth.shape[1]:
                return
            self._allocate_contacts(2 * needed)

    def contacts(self) -> Contacts:
        """The last ``detect`` result as flat arrays (copies)."""
        rows = [np.arange(c) for c in self.contact_count]
        world = np.concatenate([np.full(c, w, dtype=np.int32) for w, c in enumerate(self.contact_count)])
        pick = lambda arr: np.concatenate([arr[w, r] for w, r in enumerate(rows)])  # noqa: E731
        return Contacts(world, pick(self.body_a), pick(self.body_b), pick(self.point),
                        pick(self.normal), pick(self.depth))
