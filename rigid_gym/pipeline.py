"""The step, phase by phase (Guendelman, Bridson & Fedkiw 2003, as in DESIGN.md §4).

Each phase is one kernel call over every world at once; ``SolverConfig`` switches phases off
and ``Profile`` times them. Reading :func:`step` top to bottom is reading the algorithm.
"""

from __future__ import annotations

import time
from collections import defaultdict

import numpy as np

from rigid_gym.config import SolverConfig
from rigid_gym.kernels import integrate, solver
from rigid_gym.kernels.jit import for_worlds

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


def step(world, config: SolverConfig, dt: float, profile: Profile) -> None:
    """Advance every world of ``world`` (a :class:`rigid_gym.World`) by ``dt`` seconds."""
    s, m, geo, pairs = world.state, world.model, world.geometry, world.collider
    # light kernels run serially for a single world (waking the thread pool costs more than
    # their work); the solver phases keep their parallel code (their serial twins measured
    # 2.5-3.5x slower, a numba code-generation difference not yet understood), which World.step
    # runs on the calling thread alone for a single world (docs/architecture.md)
    k = lambda compiled: for_worlds(compiled, world.num_worlds)  # noqa: E731
    gravity = float(np.linalg.norm(m.gravity))
    on = config.phases(gravity > 0.0)
    capacity = world.pair_contact_capacity
    # 0. broad phase: every pair whose boxes may meet within this step (velocities included);
    #    when no world has one, the impulse phases have nothing to do
    if on["broad_phase"]:
        profile.run("broad_phase", pairs.find_pairs, s, 0.0, dt, gravity)
        pairs.pair_impulse.fill(0.0)  # Coulomb's limit applies to each pair's step total
        if not pairs.pair_count.any():
            on = {**on, "collision": False, "contact": False, "shock_propagation": False}
    # 1. collision: at poses predicted with the old velocities, real restitution
    if on["collision"]:
        profile.run("collision", solver.resolve_contacts, s, m, geo, pairs.pair_a, pairs.pair_b,
                    pairs.pair_count, pairs.pair_impulse, dt, solver.COLLISION,
                    config.collision_passes, capacity)
    # 2. velocity update: V += dt (g + F/M), L += dt tau
    profile.run("update_velocities", k(integrate.update_velocities),
                s.velocity, s.angular_momentum, s.angular_velocity, s.rotation, s.force, s.torque,
                m.inverse_mass, m.inverse_moments, m.motion, m.gravity, dt)
    # 3. contact: predicted with the new velocities, restitution ramping from -0.9 to 0
    if on["contact"]:
        profile.run("contact", solver.resolve_contacts, s, m, geo, pairs.pair_a, pairs.pair_b,
                    pairs.pair_count, pairs.pair_impulse, dt, solver.CONTACT,
                    config.contact_passes, capacity)
    # 4. shock propagation: level by level from the ground up, lower levels frozen
    if on["shock_propagation"]:
        up = -m.gravity / gravity
        profile.run("shock_propagation", solver.propagate_shock, s, m, geo, pairs.pair_a,
                    pairs.pair_b, pairs.pair_count, pairs.pair_impulse, dt, up,
                    config.shock_sweeps, capacity, SUPPORT_CONTACTS * capacity)
    # 5. position update with the final velocities: X += dt V, q by the exact rotation
    profile.run("update_positions", k(integrate.update_positions),
                s.position, s.orientation, s.velocity, s.angular_momentum, s.angular_velocity,
                s.rotation, s.torque, m.inverse_moments, m.motion, dt, config.rotation_order)
