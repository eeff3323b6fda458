"""The step, phase by phase (Guendelman, Bridson & Fedkiw 2003, as in DESIGN.md §4).

:func:`step` runs each phase as one kernel call over every world at once; ``SolverConfig``
switches phases off and ``Profile`` times them. Reading it top to bottom is reading the
algorithm. :func:`advance` runs the same phases in the same order inside one kernel call for
many steps: the fast path ``World.step`` takes unless it is profiling. Both call the same
kernel (``kernels.step.step_worlds``, phases selected by bits), so they give bit-identical
states. A batch of worlds is shared out over threads in ranges of worlds (the kernel releases
the GIL); a single world runs on the calling thread.
"""

from __future__ import annotations

import os
import time
from collections import defaultdict
from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np

from rigid_gym.config import SolverConfig
from rigid_gym.kernels import integrate, rest, solver
from rigid_gym.kernels.jit import compiled_entry
from rigid_gym.kernels.step import (
    BROAD_PHASE,
    COLLISION_PHASE,
    CONTACT_PHASE,
    EVERY_PHASE,
    POSITION_PHASE,
    SHOCK_PHASE,
    VELOCITY_PHASE,
    Settings,
    step_worlds,
)

SUPPORT_CONTACTS = 4
"""Room for one body's contacts with its frozen supports in shock propagation, in pair
capacities (a box on up to 4 boxes combines them all; beyond that supports are resolved
one by one)."""


class Profile:
    """Accumulated wall time (s) and call count per phase."""

    def __init__(self):
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)

    def run(self, name: str, fn, *args) -> None:
        start = time.perf_counter()
        fn(*args)
        self.seconds[name] += time.perf_counter() - start
        self.calls[name] += 1


class Workspace:
    """The impulse phases' work arrays for B worlds of n bodies (``solver.Scratch`` for one
    pair's contacts and for one body's contacts with all its supports, ``solver.Graph`` for
    shock propagation), allocated once and reused by every step; the graph grows with the
    pair capacity. ``rest``: sleeping's bookkeeping (``kernels/rest.Rest``), kept from step
    to step. ``step_call``: ``step_worlds``' compiled entry for this world's argument
    types (``jit.compiled_entry``), bound at the first step."""

    def __init__(self, num_worlds: int, num_bodies: int, pair_contacts: int):
        self.num_worlds, self.num_bodies = num_worlds, num_bodies
        self.step_call = None
        self.scratch = _allocate(solver.Scratch, solver.SCRATCH_SHAPES, num_worlds,
                                 n=num_bodies, c=pair_contacts)
        self.wide = _allocate(solver.Scratch, solver.SCRATCH_SHAPES, num_worlds, n=num_bodies,
                              c=SUPPORT_CONTACTS * pair_contacts)
        self.graph = None
        self.pair_capacity = -1
        self.rest = _allocate(rest.Rest, rest.REST_SHAPES, num_worlds, n=num_bodies)
        self.forget(slice(None))

    def forget(self, worlds) -> None:
        """No body of ``worlds`` (an index or a slice) sleeps in their next step: what
        changed cannot be seen in their state (masses, materials, attachments)."""
        self.rest.previous_partner[worlds] = rest.SEVERAL

    def fit_pairs(self, pair_capacity: int) -> None:
        """Size the graph for ``pair_capacity`` pairs per world."""
        if pair_capacity != self.pair_capacity:
            self.graph = _allocate(solver.Graph, solver.GRAPH_SHAPES, self.num_worlds,
                                   n=self.num_bodies, p=pair_capacity)
            self.pair_capacity = pair_capacity


def _allocate(kind, shapes, num_worlds: int, **sizes):
    """A namedtuple ``kind`` of zeroed arrays (num_worlds, *shape); shapes name sizes as
    "n", "c", "p", "2p" or "n+1", "n+2"."""
    def size(dim):
        if isinstance(dim, int):
            return dim
        if dim.startswith("2"):
            return 2 * sizes[dim[1:]]
        if "+" in dim:
            name, extra = dim.split("+")
            return sizes[name] + int(extra)
        return sizes[dim]

    return kind(*(np.zeros((num_worlds,) + tuple(size(d) for d in shape), dtype=dtype)
                  for _, shape, dtype in shapes))


def settings(config: SolverConfig, gravity: np.ndarray, sweep: bool) -> Settings:
    """The kernels' view of ``config`` for a scene with ``gravity`` (3,) m/s^2, the broad
    phase by sort and sweep or not (``Collider.sweep``)."""
    magnitude = float(np.linalg.norm(gravity))
    up = -gravity / magnitude if magnitude > 0.0 else np.array([0.0, 0.0, 1.0])
    return Settings(config.collision_passes, config.contact_passes, config.shock_sweeps,
                    config.rotation_order, bool(sweep), config.phases()["broad_phase"],
                    config.sleep, magnitude, up)


THREADS = min(numba.config.NUMBA_NUM_THREADS,
              len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count())
"""Threads a batch of worlds is shared out over: the cores this process may use, at most
``NUMBA_NUM_THREADS`` (the environment variable limits it as it limits numba's own pool)."""
_pool: ThreadPoolExecutor | None = None


def advance(world, steps: int, phases: int = EVERY_PHASE) -> None:
    """Advance every world of ``world`` by ``steps`` steps, running the ``phases`` bits of
    each (``kernels.step``), in one kernel call per range of worlds (more only when the pair
    buffers must grow first: then a position phase alone, which found more pairs than fit,
    runs again as a whole step)."""
    s, m, geo, pairs, work = world.state, world.model, world.geometry, world.collider, world.workspace
    done = np.zeros(world.num_worlds, dtype=np.int64)
    while True:
        work.fit_pairs(pairs.pair_a.shape[1])
        args = (steps, phases, done, world.dt, s, m, geo, pairs.pairs, work.scratch, work.wide,
                work.graph, world.settings, world.attached, work.rest)
        *others, mine = _world_ranges(world.num_worlds)
        if work.step_call is None:  # the buffers grow with the same types: bound once
            work.step_call = compiled_entry(step_worlds, *mine, *args)
        futures = [_threads().submit(work.step_call, *r, *args) for r in others]
        work.step_call(*mine, *args)  # the calling thread takes a range too
        for future in futures:
            future.result()
        if np.all(done == steps):
            return
        pairs.grow_pairs()
        if not phases & BROAD_PHASE:  # a position phase whose relist outgrew the buffers
            phases = EVERY_PHASE  # put the step back to its start: it runs again whole


def _world_ranges(num_worlds: int) -> list[tuple[int, int]]:
    """(first, last) ranges covering the worlds, one per thread (as many as worlds, at most).
    One each is fastest: every call costs ~3 us of argument unboxing, under the GIL."""
    count = min(num_worlds, THREADS)
    if count == 1:
        return [(0, num_worlds)]  # without numpy: a Push env's 10 solver steps take ~40 us
    bounds = np.linspace(0, num_worlds, count + 1).round().astype(int)
    return list(zip(bounds[:-1].tolist(), bounds[1:].tolist()))


def _threads() -> ThreadPoolExecutor:
    """The process's pool of THREADS - 1 threads (the calling thread is the last one),
    started at the first batched step."""
    global _pool
    if _pool is None:
        _pool = ThreadPoolExecutor(max(THREADS - 1, 1), thread_name_prefix="rigid_gym-step")
    return _pool


def place_attached(world, index: int) -> None:
    """Put every attached body (``World.attach``) of world ``index`` at its offset from its
    parent."""
    s, a = world.state, world.attached
    integrate.place_attached(index, s.position, s.orientation, s.velocity, s.angular_momentum,
                             s.angular_velocity, s.rotation, a.parent, a.offset_position,
                             a.offset_orientation)


def step(world, config: SolverConfig, profile: Profile) -> None:
    """Advance every world of ``world`` (a :class:`rigid_gym.World`) by one step, one kernel
    call per phase, timing each phase into ``profile``."""
    gravity = float(np.linalg.norm(world.model.gravity))
    on = config.phases(gravity > 0.0)
    # 0. broad phase: every pair whose boxes may meet within this step (velocities included);
    #    held bodies are put at their place first. When no world has a pair, the impulse
    #    phases have nothing to do
    run = lambda name, bit: profile.run(name, advance, world, 1, bit)  # noqa: E731
    if on["broad_phase"]:
        run("broad_phase", BROAD_PHASE)
    else:
        advance(world, 1, BROAD_PHASE)  # places held bodies, finds no pair
    if not world.collider.pair_count.any():
        on = {**on, "collision": False, "contact": False, "shock_propagation": False}
    # 1. collision: at poses predicted with the old velocities, real restitution
    if on["collision"]:
        run("collision", COLLISION_PHASE)
    # 2. velocity update: V += dt (g + F/M), L += dt tau
    run("update_velocities", VELOCITY_PHASE)
    # 3. contact: predicted with the new velocities, restitution ramping from -0.9 to 0
    if on["contact"]:
        run("contact", CONTACT_PHASE)
    # 4. shock propagation: level by level from the ground up, lower levels frozen
    if on["shock_propagation"]:
        run("shock_propagation", SHOCK_PHASE)
    # 5. position update with the final velocities: X += dt V, q by the exact rotation; held
    #    bodies put at their place again. A body sped past its box first grows it, and with
    #    the pairs that adds, phases 1-4 run again (timed here): kernels/step.py, step_world
    run("update_positions", POSITION_PHASE)
