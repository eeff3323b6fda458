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
from rigid_gym.kernels.step import Pairs

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
        self.order = np.tile(np.arange(n, dtype=np.int64), (num_worlds, 1))
        self.reach = np.zeros((num_worlds, n))
        self.start = np.zeros((num_worlds, 3, n, 3))
        self.pair_count = np.zeros(num_worlds, dtype=np.int32)
        self.contact_count = np.zeros(num_worlds, dtype=np.int32)
        self._allocate_pairs(max(8, 2 * n))
        self._allocate_contacts(64)

    @property
    def pairs(self) -> Pairs:
        """The broad phase's buffers as the step kernels take them."""
        return Pairs(self.bounds, self.order, self.pair_a, self.pair_b, self.pair_count,
                     self.pair_impulse, self.keys, self.tmp, self.reach, self.start)

    def grow_pairs(self) -> None:
        """Make room for at least the pairs the last broad phase found (pair_count)."""
        needed = int(self.pair_count.max(initial=0))
        if needed > self.pair_a.shape[1]:
            self._allocate_pairs(2 * needed)

    def _allocate_pairs(self, capacity: int) -> None:
        b = len(self.pair_count)
        self.pair_a = np.zeros((b, capacity), dtype=np.int32)
        self.pair_b = np.zeros((b, capacity), dtype=np.int32)
        self.pair_impulse = np.zeros((b, capacity, 3))  # the solver's per-step totals, N s
        self.keys = np.zeros((b, capacity), dtype=np.int64)
        self.tmp = np.zeros((b, capacity), dtype=np.int64)

    def _allocate_contacts(self, capacity: int) -> None:
        b = len(self.contact_count)
        self.body_a = np.zeros((b, capacity), dtype=np.int32)
        self.body_b = np.zeros((b, capacity), dtype=np.int32)
        self.point = np.zeros((b, capacity, 3))
        self.normal = np.zeros((b, capacity, 3))
        self.depth = np.zeros((b, capacity))

    def find_pairs(self, state, margin: float, dt: float = 0.0, acceleration: float = 0.0,
                   worlds=slice(None)) -> None:
        """Fill pair_a/pair_b/pair_count with the pairs that may touch within dt (s) of the
        state's poses (a ``world.State``), boxes grown by margin (m) and by how far the bodies
        can move in dt under an acceleration bound (m/s^2); for ``worlds`` (a slice)."""
        part = type(state)(*(a[worlds] for a in state))
        while True:
            find_pairs(part.position, part.rotation, part.velocity, part.angular_velocity,
                       self.motion, self.geometry, margin, dt, acceleration, self.sweep,
                       self.bounds[worlds], self.order[worlds], self.pair_a[worlds],
                       self.pair_b[worlds], self.pair_count[worlds], self.keys[worlds],
                       self.tmp[worlds], self.reach[worlds])
            if int(self.pair_count[worlds].max(initial=0)) <= self.pair_a.shape[1]:
                return
            self.grow_pairs()

    def detect(self, state, margin: float = 0.0, worlds=slice(None)) -> None:
        """Fill the contact buffers for the state's current poses (contacts deeper than -margin,
        m), of ``worlds`` (a slice, or one world's index)."""
        if not isinstance(worlds, slice):
            worlds = slice(worlds, worlds + 1)
        self.find_pairs(state, margin, worlds=worlds)
        part = type(state)(*(a[worlds] for a in state))
        while True:
            detect_contacts(part.position, part.rotation, self.geometry, self.pair_a[worlds],
                            self.pair_b[worlds], self.pair_count[worlds], margin,
                            self.body_a[worlds], self.body_b[worlds], self.point[worlds],
                            self.normal[worlds], self.depth[worlds], self.contact_count[worlds])
            needed = int(self.contact_count[worlds].max(initial=0))
            if needed <= self.depth.shape[1]:
                return
            self._allocate_contacts(2 * needed)

    def contacts(self, worlds=slice(None), first: int = 0) -> Contacts:
        """The last ``detect`` result of ``worlds`` as flat arrays (copies); world indices
        count from ``first``."""
        if not isinstance(worlds, slice):
            worlds = slice(worlds, worlds + 1)
        counts = self.contact_count[worlds]
        rows = [np.arange(c) for c in counts]
        world = np.concatenate([np.full(c, first + w, dtype=np.int32)
                                for w, c in enumerate(counts)])
        pick = lambda arr: np.concatenate([arr[worlds][w, r] for w, r in enumerate(rows)])  # noqa: E731
        return Contacts(world, pick(self.body_a), pick(self.body_b), pick(self.point),
                        pick(self.normal), pick(self.depth))
