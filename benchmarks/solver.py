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
    python benchmarks/solver.py --passes   # the falling piles with fewer contact passes
    python benchmarks/solver.py --resolves # ns per pair resolve in the impulse stages

``--timers`` steps one world of each of a free ball (the cheapest step there is), the 10-cube
stack and a pile of 100 with its stage timers off and on in alternate rounds, and prints the
median steps/s of each and the difference per step.

``--passes`` times the piles of 10 and 100 over the first second after their drop (reset
before each timing, as ``benchmarks/speed.py`` times its falling scenes) at the default 10
contact passes and at fewer, every count in turn in each round, and prints each count's
steps/s and its median speed-up over the default. Fewer passes change every trajectory in
contact; the report (``rigid-gym report``) tells what they do to its errors. No pass at all
is the floor that the rest of the step (detection, shock propagation, the updates) sets.

``--resolves`` steps the pyramid and the piles of 10 and 100, settled and over the first
second after their drop, with their stage timers on (``World.profile()``), and prints for the
contact and shock stages the contact sets resolved per step (a pair's contacts, or in shock
propagation a body's with all its frozen supports) and the stage's time per resolve: the cost
of a pair resolve, the detection's share of its pair included.
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


PASS_COUNTS = (10, 5, 3, 2, 1, 0)
"""Contact passes timed by ``--passes``; the first is the default (SolverConfig). 0 (no
contact stage: what the rest of the step costs) is a floor, not a usable setting."""


def pass_speed(rounds: int = 7) -> None:
    """Steps/s of the falling piles at each of PASS_COUNTS contact passes, in alternate rounds."""
    print("| scene | " + " | ".join(f"{n} pass{'es' if n != 1 else ''}" for n in PASS_COUNTS)
          + " |")
    print("|---|" + "---:|" * len(PASS_COUNTS))
    scenes = (("pile of 10, falling", pile(10), 10), ("pile of 100, falling", pile(100), 1))
    for name, scene, runs in scenes:  # runs: drops timed per round
        worlds = {n: rg.World(scene, dt=DT,
                              config=rg.SolverConfig.for_scene(scene, contact_passes=n))
                  for n in PASS_COUNTS}
        rates: dict[int, list[float]] = {n: [] for n in PASS_COUNTS}
        for _ in range(rounds):
            for n, world in worlds.items():
                elapsed = 0.0
                for _ in range(runs):
                    world.reset()
                    start = time.perf_counter()
                    world.step(240)
                    elapsed += time.perf_counter() - start
                rates[n].append(240 * runs / elapsed)
        default = rates[PASS_COUNTS[0]]
        cells = [f"{statistics.median(rates[n]):,.0f} "
                 f"({statistics.median(r / d for r, d in zip(rates[n], default)):.2f}x)"
                 for n in PASS_COUNTS]
        print(f"| {name} | " + " | ".join(cells) + " |")


RESOLVE_STAGES = ("contact", "shock_propagation")
"""The impulse stages whose resolves ``--resolves`` reports."""


def resolve_cost(rounds: int = 5) -> None:
    """Per scene and impulse stage: contact sets resolved per step and ns per resolve (the
    median over ``rounds`` timings of 240 steps, stage timers on)."""
    print("| scene | " + " | ".join(f"{stage}: resolves/step | ns/resolve"
                                     for stage in RESOLVE_STAGES) + " |")
    print("|---|" + "---:|---:|" * len(RESOLVE_STAGES))
    scenes = (("55-box pyramid", pyramid(10), False), ("pile of 10", pile(10), False),
              ("pile of 100", pile(100), False), ("pile of 10, falling", pile(10), True),
              ("pile of 100, falling", pile(100), True))
    for name, scene, falling in scenes:
        world = rg.World(scene, dt=DT, profile=True)
        if not falling:
            world.step(480)
        counts: dict[str, list[float]] = {stage: [] for stage in RESOLVE_STAGES}
        costs: dict[str, list[float]] = {stage: [] for stage in RESOLVE_STAGES}
        for _ in range(rounds):
            if falling:
                world.reset()
            before = world.profile()
            world.step(240)
            after = world.profile()
            for stage in RESOLVE_STAGES:
                resolves = after[stage]["resolves"] - before[stage]["resolves"]
                seconds = after[stage]["seconds"] - before[stage]["seconds"]
                counts[stage].append(resolves / 240)
                costs[stage].append(seconds / resolves * 1e9 if resolves else float("nan"))
        cells = [f"{statistics.median(counts[s]):,.0f} | {statistics.median(costs[s]):,.0f}"
                 for s in RESOLVE_STAGES]
        print(f"| {name} | " + " | ".join(cells) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="10-stack and small piles only")
    parser.add_argument("--timers", action="store_true",
                        help="what timing the stages costs (World(profile=True))")
    parser.add_argument("--passes", action="store_true",
                        help="the falling piles with fewer contact passes")
    parser.add_argument("--resolves", action="store_true",
                        help="ns per pair resolve in the contact and shock stages")
    args = parser.parse_args()
    if args.resolves:
        resolve_cost()
        return
    if args.timers:
        timer_cost()
        return
    if args.passes:
        pass_speed()
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
