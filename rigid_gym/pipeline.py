"""The step, phase by phase (Guendelman, Bridson & Fedkiw 2003, as in DESIGN.md §4).

:func:`step` runs each phase as one kernel call over every world at once; ``SolverConfig``
switches phases off and ``Profile`` times them. Reading it top to bottom is reading the
algorithm. :func:`advance` runs the same phases in the same order inside one kernel call for
many steps (``kernels/step.py``): the fast path ``World.step`` takes unless it is profiling;
the two give bit-identical states.
"""

from __future__ import annotations

import time
from collections import defaultdict

import numpy as np

from rigid_gym.config import SolverConfig
from rigid_gym.kernels import integrate, solver
from rigid_gym.kernels.jit import for_worlds
from rigid_gym.kernels.step import Settings, step_world, step_worlds

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
    pair capacity."""

    def __init__(self, num_worlds: int, num_bodies: int, pair_contacts: int):
        self.num_worlds, self.num_bodies = num_worlds, num_bodies
        self.scratch = _allocate(solver.Scratch, solver.SCRATCH_SHAPES, num_worlds,
                                 n=num_bodies, c=pair_contacts)
        self.wide = _allocate(solver.Scratch, solver.SCRATCH_SHAPES, num_worlds, n=num_bodies,
                              c=SUPPORT_CONTACTS * pair_contacts)
        self.graph = None
        self.pair_capacity = -1

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
                    magnitude, up)


def advance(world, steps: int) -> None:
    """Advance every world of ``world`` by ``steps`` steps in one kernel call (more only when
    the pair buffers must grow first). A single world runs on the calling thread."""
    s, m, geo, pairs, work = world.state, world.model, world.geometry, world.collider, world.workspace
    done = np.zeros(world.num_worlds, dtype=np.int64)
    while True:
        work.fit_pairs(pairs.pair_a.shape[1])
        args = (world.dt, s, m, geo, pairs.pairs, work.scratch, work.wide, work.graph,
                world.settings, world.attached)
        if world.num_worlds == 1:
            done[0] += step_world(0, steps - done[0], *args)
        else:
            step_worlds(steps, done, *args)
        if np.all(done == steps):
            return
        pairs.grow_pairs()


def place_attached(world, index: int | None = None) -> None:
    """Put every attached body (``World.attach``) at its offset from its parent, in every
    world or in world ``index`` only."""
    s, a = world.state, world.attached
    args = (s.position, s.orientation, s.velocity, s.angular_momentum, s.angular_velocity,
            s.rotation, a.parent, a.offset_position, a.offset_orientation)
    if index is not None:
        integrate.place_attached(index, *args)
    else:
        for_worlds(integrate.place_attached_bodies, world.num_worlds)(*args)


def step(world, config: SolverConfig, dt: float, profile: Profile) -> None:
    """Advance every world of ``world`` (a :class:`rigid_gym.World`) by ``dt`` seconds, one
    kernel call per phase, timing each phase into ``profile``."""
    s, m, geo, pairs, work = world.state, world.model, world.geometry, world.collider, world.workspace
    # light kernels run serially for a single world (waking the thread pool costs more than
    # their work); the solver phases run their parallel code on the calling thread alone
    k = lambda compiled: for_worlds(compiled, world.num_worlds)  # noqa: E731
    place_attached(world)  # held bodies start the step at their place
    gravity = float(np.linalg.norm(m.gravity))
    on = config.phases(gravity > 0.0)
    # 0. broad phase: every pair whose boxes may meet within this step (velocities included);
    #    when no world has one, the impulse phases have nothing to do
    if on["broad_phase"]:
        profile.run("broad_phase", pairs.find_pairs, s, 0.0, dt, gravity)
        pairs.pair_impulse.fill(0.0)  # Coulomb's limit applies to each pair's step total
        if not pairs.pair_count.any():
            on = {**on, "collision": False, "contact": False, "shock_propagation": False}
    work.fit_pairs(pairs.pair_a.shape[1])
    # 1. collision: at poses predicted with the old velocities, real restitution
    if on["collision"]:
        profile.run("collision", solver.resolve_contacts, s, m, geo, pairs.pair_a, pairs.pair_b,
                    pairs.pair_count, pairs.pair_impulse, dt, solver.COLLISION,
                    config.collision_passes, work.scratch)
    # 2. velocity update: V += dt (g + F/M), L += dt tau
    profile.run("update_velocities", k(integrate.update_velocities),
                s.velocity, s.angular_momentum, s.angular_velocity, s.rotation, s.force, s.torque,
                m.inverse_mass, m.inverse_moments, m.motion, m.gravity, dt)
    # 3. contact: predicted with the new velocities, restitution ramping from -0.9 to 0
    if on["contact"]:
        profile.run("contact", solver.resolve_contacts, s, m, geo, pairs.pair_a, pairs.pair_b,
                    pairs.pair_count, pairs.pair_impulse, dt, solver.CONTACT,
                    config.contact_passes, work.scratch)
    # 4. shock propagation: level by level from the ground up, lower levels frozen
    if on["shock_propagation"]:
        profile.run("shock_propagation", solver.propagate_shock, s, m, geo, pairs.pair_a,
                    pairs.pair_b, pairs.pair_count, pairs.pair_impulse, dt, world.settings.up,
                    config.shock_sweeps, work.scratch, work.wide, work.graph)
    # 5. position update with the final velocities: X += dt V, q by the exact rotation
    profile.run("update_positions", k(integrate.update_positions),
                s.position, s.orientation, s.velocity, s.angular_momentum, s.angular_velocity,
                s.rotation, s.torque, m.inverse_moments, m.motion, dt, config.rotation_order)
    s.force.fill(0.0)
    s.torque.fill(0.0)
