"""Solver speed: steps per second for standard scenes, with phases switched on and off.

Scenes (dt = 1/240, one world): the resting 10-cube stack, the 55-box pyramid, and piles of
10, 100 and 1000 mixed bodies (boxes, spheres, capsules) dropped in a walled pit. Each is first
run for ``SETTLE`` steps (so stacks are at rest and piles are in contact), then timed over
``STEPS`` steps; the figure is the median of ``REPEATS`` timings. Configurations: the default
(``SolverConfig.for_scene``), the contact phase off, shock propagation off, and both off (free
fall plus the broad phase only, the floor of the step's cost). Rows with a phase off show the
cost of a phase, not a usable setting: a stack without shock propagation is not at rest.

    python benchmarks/solver.py            # the full table (about 10 minutes on 2 cores)
    python benchmarks/solver.py --quick    # 10-stack and small piles only
"""

import argparse
import dataclasses
import statistics
import time

import numpy as np

import rigid_gym as rg

DT = 1 / 240
H = 0.05


def stack(n=10):
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    for k in range(n):
        scene.add_body(rg.Box((H, H, H)), mass=1.0, friction=0.5, position=(0, 0, H + 2 * H * k))
    return scene


def pyramid(rows=10):
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    for r in range(rows):
        for k in range(rows - r):
            scene.add_body(rg.Box((H, H, H)), mass=1.0, friction=0.5,
                           position=((k - (rows - r - 1) / 2) * 2 * H, 0, H + 2 * H * r))
    return scene


def pile(count, seed=0):
    """count bodies on a grid of columns over a square pit sized for them (~8 per column)."""
    rng = np.random.default_rng(seed)
    columns = max(1, int(np.ceil(np.sqrt(count / 8))))
    half = 0.06 * columns
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    for x, y, hx, hy in ((half + 0.05, 0, 0.05, half + 0.1), (-half - 0.05, 0, 0.05, half + 0.1),
                         (0, half + 0.05, half + 0.1, 0.05), (0, -half - 0.05, half + 0.1, 0.05)):
        scene.add_body(rg.Box((hx, hy, 0.5)), position=(x, y, 0.5), static=True)
    shapes = [rg.Box((0.025, 0.025, 0.025)), rg.Sphere(0.025), rg.Capsule(0.02, 0.02)]
    for k in range(count):
        column, layer = k % (columns * columns), k // (columns * columns)
        x = -half + 0.06 + 0.12 * (column % columns)
        y = -half + 0.06 + 0.12 * (column // columns)
        q = rng.normal(size=4)
        scene.add_body(shapes[k % 3], density=500.0, friction=0.5,
                       position=(x + rng.uniform(-0.01, 0.01), y + rng.uniform(-0.01, 0.01),
                                 0.05 + 0.07 * layer), orientation=q / np.linalg.norm(q))
    return scene


def steps_per_second(scene, config, settle, steps, repeats):
    world = rg.World(scene, dt=DT, config=config)
    world.step(settle)
    timings = []
    for _ in range(repeats):
        start = time.perf_counter()
        world.step(steps)
        timings.append((time.perf_counter() - start) / steps)
    return 1.0 / statistics.median(timings)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="10-stack and small piles only")
    args = parser.parse_args()
    scenes = [("10-cube stack", stack(), 240, 240), ("pile of 10", pile(10), 240, 240)]
    if not args.quick:
        scenes += [("55-box pyramid", pyramid(), 240, 120), ("pile of 100", pile(100), 240, 48),
                   ("pile of 1000", pile(1000), 120, 4)]
    variants = [("default", {}), ("no contact phase", {"contact_passes": 0}),
                ("no shock propagation", {"shock_sweeps": 0}),
                ("neither", {"contact_passes": 0, "shock_sweeps": 0})]
    steps_per_second(stack(2), None, 2, 2, 1)  # compile outside the timings
    print("| scene | bodies | " + " | ".join(name for name, _ in variants) + " |")
    print("|---|---|" + "---|" * len(variants))
    growth = []
    for name, scene, settle, steps in scenes:
        base = rg.SolverConfig.for_scene(scene)
        rates = [steps_per_second(scene, dataclasses.replace(base, **change), settle, steps, 3)
                 for _, change in variants]
        bodies = len(scene.bodies)
        if name.startswith("pile"):
            growth.append((bodies, rates[0]))
        print(f"| {name} | {bodies} | " + " | ".join(f"{r:,.0f}" for r in rates) + " |")
    if len(growth) > 1:
        n, rate = np.array(growth, dtype=float).T
        slope = np.polyfit(np.log(n), np.log(1.0 / rate), 1)[0]
        print(f"\ncost per step grows as N^{slope:.2f} over the piles (default configuration)")


if __name__ == "__main__":
    main()
