"""Solver speed: steps per second for standard scenes, with phases switched on and off.

Scenes (dt = 1/240, one world; from ``rigid_gym.report.scenes``): the resting 10-cube stack,
the 55-box pyramid, and piles of 10, 100 and 1000 mixed bodies (boxes, spheres, capsules)
dropped in a walled pit. Each is first run for ``SETTLE`` steps (so stacks are at rest and
piles are in contact), then timed over ``STEPS`` steps; the figure is the median of
``REPEATS`` timings. Configurations: the default
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
from rigid_gym.report.scenes import cube_stack, pile, pyramid

DT = 1 / 240


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
    scenes = [("10-cube stack", cube_stack(10), 240, 240), ("pile of 10", pile(10), 240, 240)]
    if not args.quick:
        scenes += [("55-box pyramid", pyramid(10), 240, 120), ("pile of 100", pile(100), 240, 48),
                   ("pile of 1000", pile(1000), 120, 4)]
    variants = [("default", {}), ("no contact phase", {"contact_passes": 0}),
                ("no shock propagation", {"shock_sweeps": 0}),
                ("neither", {"contact_passes": 0, "shock_sweeps": 0})]
    steps_per_second(cube_stack(2), None, 2, 2, 1)  # warm-up outside the timings
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
