"""Work-precision sweeps: error against the exact answer and run time, per solver setting.

For every case of ``rigid_gym.report.cases``, every setting and every dt, :func:`sweep_case`
runs the case once to measure its errors, then times the same number of steps from the
initial state (``World.reset``) ``repeats`` times without queries; the cost is the median wall
time per simulated second (s/s). :func:`observed_order` fits the slope of log(error) against
log(dt) (or log(samples)). :func:`sweep_mass_properties` does the same for the grid and Monte
Carlo mass-property estimators against the exact integrals.
"""

from __future__ import annotations

import functools
import statistics
import time
from dataclasses import dataclass

import numpy as np

import rigid_gym as rg
from rigid_gym.checks import integer
from rigid_gym.inertia import mass_properties, mass_properties_grid, mass_properties_monte_carlo
from rigid_gym.meshes import l_shape_mesh
from rigid_gym.report.cases import Case

ROUND_OFF = 1e-11
"""Errors at or below this (relative, or m on the ~1 m scale of the scenes) are round-off:
float64 steps add ~1e-16 each, over up to 2e4 steps, with a 5x margin. They are plotted at
this floor and left out of slopes."""


def observed_order(x, errors) -> float | None:
    """Least-squares slope of log(error) against log(x): the observed order of convergence
    (x = dt gives p for error ~ dt^p; x = sample count gives -1/2 for Monte Carlo).

    x, errors: equal-length 1-D sequences, x > 0. Errors that are NaN or at round-off
    (<= ROUND_OFF) are left out; None when fewer than two remain (the method is exact there).
    """
    x, errors = np.asarray(x, dtype=np.float64), np.asarray(errors, dtype=np.float64)
    if x.ndim != 1 or x.shape != errors.shape:
        raise ValueError(f"observed_order: x and errors must be 1-D of equal length, got shapes "
                         f"{x.shape} and {errors.shape}")
    if not np.all(np.isfinite(x)) or np.any(x <= 0.0):
        raise ValueError(f"observed_order: x must be finite and > 0, got {x.tolist()}")
    kept = np.isfinite(errors) & (errors > ROUND_OFF)
    if kept.sum() < 2 or np.unique(x[kept]).size < 2:
        return None
    return float(np.polyfit(np.log(x[kept]), np.log(errors[kept]), 1)[0])


@dataclass
class Curve:
    """One setting of one case over the dt sweep.

    dts (k,) s; errors (k, metrics); cost (k,) wall seconds per simulated second.
    """

    case: str
    setting: str
    dts: np.ndarray
    errors: np.ndarray
    cost: np.ndarray

    def order(self, metric: int = 0) -> float | None:
        return observed_order(self.dts, self.errors[:, metric])


def median_seconds(call, repeats: int) -> float:
    """Median wall time (s, time.perf_counter) of ``repeats`` calls of ``call()``."""
    integer(repeats, "median_seconds: repeats", 1)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def world_for(case: Case, dt: float, overrides: dict | None = None,
              config: rg.SolverConfig | None = None) -> rg.World:
    """A fresh world of ``case`` at ``dt``: ``config`` if given, else ``SolverConfig.for_scene``
    with ``overrides``."""
    scene = case.build()
    if config is None:
        config = rg.SolverConfig.for_scene(scene, **(overrides or {}))
    return rg.World(scene, dt=dt, config=config)


def measure(case: Case, world, repeats: int) -> tuple[tuple[float, ...], float]:
    """(errors, cost in wall s per simulated s) of ``case`` run on a fresh ``world`` (a
    rigid_gym.World or a peer adapter with the same step/reset/state interface); the cost is
    timed over the same number of steps from the initial state, without queries."""
    errors = case.measure(world)
    steps = world.steps

    def run():
        world.reset()
        world.step(steps)

    return errors, median_seconds(run, repeats) / (steps * world.dt)


def sweep(case: Case, label: str, make_world, dts, repeats: int) -> Curve:
    """The Curve of ``case`` over ``dts`` (s), each world made by ``make_world(dt)`` (and
    closed after, if it has a ``close``: peer engines hold a connection)."""
    errors, costs = [], []
    for dt in dts:
        world = make_world(dt)
        err, cost = measure(case, world, repeats)
        errors.append(err)
        costs.append(cost)
        if hasattr(world, "close"):
            world.close()
    return Curve(case.key, label, np.array(dts, dtype=np.float64),
                 np.array(errors, dtype=np.float64), np.array(costs))


def sweep_case(case: Case, dts, repeats: int) -> list[Curve]:
    """A Curve per setting of ``case`` over ``dts`` (s)."""
    return [sweep(case, label, lambda dt, o=overrides: world_for(case, dt, o), dts, repeats)
            for label, overrides in case.settings.items()]


def phase_saving(case: Case, dt: float, repeats: int) -> dict:
    """What ``SolverConfig.for_scene`` left out of ``case`` and what that saved at ``dt``:
    {'left_out': [phase names], 'cost': s/s with for_scene, 'cost_all_on': s/s with every
    phase on (``SolverConfig()``), 'error', 'error_all_on': the first metric of each,
    'profile': ``World.profile()`` of the for_scene world, run again with its stages timed}."""
    results = {}
    for name, config in (("for_scene", None), ("all_on", rg.SolverConfig())):
        world = world_for(case, dt, config=config)
        errors, cost = measure(case, world, repeats)
        results[name] = (world, errors[0], cost)
    world = results["for_scene"][0]
    profiled = rg.World(world.scene, dt=dt, config=world.config, profile=True)
    profiled.step(world.steps)
    gravity, joints = bool(np.any(world.model.gravity)), bool(world.scene.joints)
    on = world.config.phases(gravity, joints)
    all_on = rg.SolverConfig().phases(gravity, joints)
    return {"left_out": [p for p in on if all_on[p] and not on[p]],
            "cost": results["for_scene"][2], "cost_all_on": results["all_on"][2],
            "error": results["for_scene"][1], "error_all_on": results["all_on"][1],
            "profile": profiled.profile()}


# -- mass properties ---------------------------------------------------------------------------

DENSITY = 1000.0  # kg/m^3
MASS_SHAPES = {
    "Box": rg.Box((0.1, 0.2, 0.3)),
    "Sphere": rg.Sphere(0.5),
    "L mesh": l_shape_mesh((1.0, 0.8), 0.3, 0.2),
}
MONTE_CARLO_SEEDS = range(3)


def inertia_errors(estimates, exact) -> tuple[float, float]:
    """Relative (mass, inertia) errors of ``estimates`` (MassProperties) against ``exact``,
    root mean square over the estimates: |M - M_exact| / M_exact and
    |I - I_exact|_F / |I_exact|_F (tensors about each one's own centre)."""
    mass = [(e.mass - exact.mass) / exact.mass for e in estimates]
    inertia = [np.linalg.norm(e.inertia - exact.inertia) / np.linalg.norm(exact.inertia)
               for e in estimates]
    return float(np.sqrt(np.mean(np.square(mass)))), float(np.sqrt(np.mean(np.square(inertia))))


@dataclass
class SampledCurve:
    """One estimator on one shape: points (k,) samples tried, inertia error (k,) relative,
    seconds (k,) wall time of one estimate."""

    shape: str
    method: str
    points: np.ndarray
    errors: np.ndarray
    seconds: np.ndarray

    def order(self) -> float | None:
        return observed_order(self.points, self.errors)


def sweep_mass_properties(resolutions, samples, repeats: int) -> list[SampledCurve]:
    """Grid (resolution^3 cell centres) and Monte Carlo (uniform points in the bounding box,
    RMS over 3 seeds) inertia errors and times for every shape of ``MASS_SHAPES``."""
    curves = []
    for name, shape in MASS_SHAPES.items():
        exact = mass_properties(shape, DENSITY)
        mass_properties_grid(shape, DENSITY, 4)  # warm-up outside the timings
        for method, counts, estimate, seeds in (
                ("grid", resolutions,
                 lambda n, s, shape=shape: mass_properties_grid(shape, DENSITY, n), [0]),
                ("Monte Carlo", samples,
                 functools.partial(mass_properties_monte_carlo, shape, DENSITY),
                 MONTE_CARLO_SEEDS)):
            points, errors, seconds = [], [], []
            for n in counts:
                errors.append(inertia_errors([estimate(n, s) for s in seeds], exact)[1])
                seconds.append(median_seconds(functools.partial(estimate, n, 0), repeats))
                points.append(n ** 3 if method == "grid" else n)
            curves.append(SampledCurve(name, method, np.array(points, dtype=np.float64),
                                       np.array(errors), np.array(seconds)))
    return curves
