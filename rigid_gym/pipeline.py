"""The step, phase by phase (Guendelman, Bridson & Fedkiw 2003, as in DESIGN.md §4).

Each phase is one kernel call over every world at once; ``SolverConfig`` switches phases off
and ``Profile`` (optional) times them. Reading this function top to bottom is reading the
algorithm.
"""

from __future__ import annotations

import time
from collections import defaultdict

from rigid_gym.config import SolverConfig
from rigid_gym.kernels import integrate


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


def _call(profile: Profile | None, name: str, fn, *args) -> None:
    if profile is None:
        fn(*args)
    else:
        profile.run(name, fn, *args)


def step(state, model, config: SolverConfig, dt: float, profile: Profile | None = None) -> None:
    """Advance every world in ``state`` by ``dt`` seconds, in place.

    state: :class:`rigid_gym.world.State`; model: :class:`rigid_gym.world.Model`.
    """
    s, m = state, model
    # velocity update: V += dt (g + F/M), L += dt tau
    _call(profile, "update_velocities", integrate.update_velocities,
          s.velocity, s.angular_momentum, s.angular_velocity, s.rotation, s.force, s.torque,
          m.inverse_mass, m.inverse_moments, m.motion, m.gravity, dt)
    # position update with the final velocities: X += dt V, q advanced by the exact rotation
    _call(profile, "update_positions", integrate.update_positions,
          s.position, s.orientation, s.velocity, s.angular_momentum, s.angular_velocity,
          s.rotation, s.torque, m.inverse_moments, m.motion, dt,
          config.rotation_order)
