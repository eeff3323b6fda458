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
    python benchmarks/solver.py --timers   # what timing the stages costs (World(profile=True))

``--timers`` steps one world of each of a free ball (the cheapest step there is), the 10-cube
stack and a pile of 100 with its stage timers off and on in alternate rounds, and prints the
median steps/s of each and the difference per step.
"""

import argparse
import dataclasses
import statistics
import time

import numpy as np

import rigid_gym as rg
from rigid_gym.report.scenes import cube_stack, free_ball, pile, pyramid

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


def timer_cost(rounds: int = 21) -> None:
    """Steps/s with ``World.profiling`` off and on, alternating rounds on one world."""
    print("| scene | steps/s, timers off | timers on | on / off | cost per step |")
    print("|---|---:|---:|---:|---:|")
    cases = (("free ball", free_ball(), 20000), ("10-cube stack", cube_stack(10), 240),
             ("pile of 100", pile(100), 48))
    for name, scene, steps in cases:
        world = rg.World(scene, dt=DT)
        world.step(240)
        rates: dict[bool, list[float]] = {False: [], True: []}
        for k in range(2 * rounds):
            world.profiling = bool(k % 2)
            start = time.perf_counter()
            world.step(steps)
            rates[world.profiling].append(steps / (time.perf_counter() - start))
        off, on = statistics.median(rates[False]), statistics.median(rates[True])
        print(f"| {name} | {off:,.0f} | {on:,.0f} | {on / off:.3f} | "
              f"{(1.0 / on - 1.0 / off) * 1e9:,.0f} ns |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="10-stack and small piles only")
    parser.add_argument("--timers", action="store_true",
                        help="what timing the stages costs (World(profile=True))")
    args = parser.parse_args()
    if args.timers:
        timer_cost()
        return
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
