"""The step, phase by phase (Guendelman, Bridson & Fedkiw 2003,
"Nonconvex rigid bodies with stacking"; docs/architecture.md).

:func:`step` runs each phase as one call of the compiled core over every world at once;
``SolverConfig`` switches phases off and ``Profile`` times them. Reading it top to bottom is
reading the algorithm. :func:`advance` runs whole steps in one call: the fast path
``World.step`` takes unless it is profiling. Both reach the same function of the core
(``step_world`` in ``src/step.cpp``, phases selected by bits), so they give bit-identical
states. The core shares a batch's worlds out over its thread pool with the GIL released; a
single world runs on the calling thread.
"""

from __future__ import annotations

import time
from collections import defaultdict

import numpy as np

from rigid_gym._core import (
    BROAD_PHASE,
    COLLISION_PHASE,
    CONTACT_PHASE,
    EVERY_PHASE,
    POSITION_PHASE,
    SHOCK_PHASE,
    VELOCITY_PHASE,
)
from rigid_gym.config import SolverConfig


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


def settings(config: SolverConfig, gravity: np.ndarray, sweep: bool) -> dict:
    """The core's view of ``config`` (``Settings`` in ``src/world.h``) for a scene with
    ``gravity`` (3,) m/s^2, the broad phase by sort and sweep or not."""
    magnitude = float(np.linalg.norm(gravity))
    up = -gravity / magnitude if magnitude > 0.0 else np.array([0.0, 0.0, 1.0])
    return dict(collision_passes=config.collision_passes, contact_passes=config.contact_passes,
                shock_sweeps=config.shock_sweeps, rotation_order=config.rotation_order,
                sweep=bool(sweep), broad_phase=config.phases()["broad_phase"],
                sleep=config.sleep, detect_every_pass=config.detect_every_pass,
                keep_energy=config.keep_energy, overlap_correction=config.overlap_correction,
                gravity=magnitude, up=tuple(float(u) for u in up))


def advance(world, steps: int, phases: int = EVERY_PHASE) -> None:
    """Advance every world of ``world`` by ``steps`` steps, running the ``phases`` bits of
    each (``src/step.h``), in one call of the core."""
    world.core.step(steps, phases, world.dt)


def step(world, config: SolverConfig, profile: Profile) -> None:
    """Advance every world of ``world`` (a :class:`rigid_gym.World`) by one step, one call of
    the core per phase, timing each phase into ``profile``."""
    gravity = float(np.linalg.norm(world.model.gravity))
    on = config.phases(gravity > 0.0)
    # 0. broad phase: every pair whose boxes may meet within this step (velocities included);
    #    held bodies are put at their place first. When no world has a pair, the impulse
    #    phases have nothing to do
    run = lambda name, bit: profile.run(name, advance, world, 1, bit)
    if on["broad_phase"]:
        run("broad_phase", BROAD_PHASE)
    else:
        advance(world, 1, BROAD_PHASE)  # places held bodies, finds no pair
    if not world.core.pair_counts.any():
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
    #    the pairs that adds, phases 1-4 run again (timed here): src/step.cpp, step_world
    run("update_positions", POSITION_PHASE)
