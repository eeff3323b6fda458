"""Accuracy and cost of the sampled mass properties against the exact ones.

For each shape and each estimator (grid: resolution^3 cell centres; Monte Carlo: uniform
random points in the bounding box) prints a markdown table of
  points         sample points tried (resolution^3 for the grid)
  mass error     |M - M_exact| / M_exact
  inertia error  |I - I_exact|_F / |I_exact|_F (Frobenius norm, tensors about each one's centre)
                 (Monte Carlo: root mean square over seeds 0-4, so the trend is not one draw's)
  ms             wall time of one estimate, median of 3 runs after a warm-up call (so
                 one-time costs are not counted)
and then the observed convergence order: the least-squares slope of log(error) against
log(points), leaving out errors at round-off level (1e-13, ``rigid_gym.report.accuracy``; "exact": the grid and Monte Carlo masses of
a box, whose bounding box is the box itself). What to expect: -1/2 for Monte Carlo. For the
grid, -2/3 where only the midpoint rule's h^2 per cell is missed (the box's tensor); -1/3 (first
order in h) with a sawtooth where a flat face cuts the cells at a fixed fraction (the L: faces at
x = 0.3 m); in between where a curved surface cuts the cells at varying fractions and the
errors partly cancel (sphere, capsule).

    python benchmarks/mass_properties.py
"""

import functools

from rigid_gym.inertia import mass_properties, mass_properties_grid, mass_properties_monte_carlo
from rigid_gym.meshes import box_mesh, l_shape_mesh
from rigid_gym.report.accuracy import inertia_errors as errors
from rigid_gym.report.accuracy import median_seconds, observed_order
from rigid_gym.shapes import Box, Capsule, Sphere

DENSITY = 1000.0  # kg/m^3
HALF_EXTENTS = (0.1, 0.2, 0.3)  # m
SHAPES = {
    "Box": Box(HALF_EXTENTS),
    "Sphere": Sphere(0.5),
    "Capsule": Capsule(0.2, 0.3),
    "mesh cube": box_mesh(HALF_EXTENTS),
    "L mesh": l_shape_mesh((1.0, 0.8), 0.3, 0.2),
}
GRID_RESOLUTIONS = (8, 16, 32, 64, 128)
MONTE_CARLO_SAMPLES = (1_000, 10_000, 100_000, 1_000_000)
REPEATS = 3


SEEDS = range(5)


def estimators():
    """(method, points tried, seeds, estimate(shape, seed) -> MassProperties) for every row."""
    for n in GRID_RESOLUTIONS:
        yield "grid", n**3, [0], lambda shape, seed, n=n: mass_properties_grid(shape, DENSITY, n)
    for n in MONTE_CARLO_SAMPLES:
        yield "Monte Carlo", n, SEEDS, lambda shape, seed, n=n: mass_properties_monte_carlo(
            shape, DENSITY, n, seed)


def order(points: list[int], errs: list[float]) -> str:
    """Slope of log(error) against log(points) over errors above round-off, or "exact"."""
    slope = observed_order(points, errs)
    return "exact" if slope is None else f"{slope:+.2f}"


def main():
    rows, orders = [], []
    for name, shape in SHAPES.items():
        exact = mass_properties(shape, DENSITY)
        mass_properties_grid(shape, DENSITY, 4)  # warm-up: starts the core's worker threads
        by_method = {}
        for method, points, seeds, estimate in estimators():
            mass_err, inertia_err = errors([estimate(shape, seed) for seed in seeds], exact)
            seconds = median_seconds(functools.partial(estimate, shape, 0), REPEATS)
            rows.append(f"| {name} | {method} | {points:,} | {mass_err:.2e} | {inertia_err:.2e} "
                        f"| {1e3 * seconds:.1f} |")
            by_method.setdefault(method, []).append((points, mass_err, inertia_err))
        for method, results in by_method.items():
            points, mass_errs, inertia_errs = (list(column) for column in zip(*results))
            orders.append(f"| {name} | {method} | {order(points, mass_errs)} "
                          f"| {order(points, inertia_errs)} |")

    print("| shape | method | points | mass error | inertia error | ms |")
    print("|---|---|---:|---:|---:|---:|")
    print("\n".join(rows))
    print()
    print("Observed order: slope of log(error) vs log(points)")
    print()
    print("| shape | method | mass | inertia |")
    print("|---|---|---:|---:|")
    print("\n".join(orders))


if __name__ == "__main__":
    main()
