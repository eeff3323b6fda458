"""Contact generation time per step for piles of boxes, with and without the broad phase.

Scenes: N boxes (half extents 0.095-0.105 m, turned a little about random axes) on a jittered
lattice 0.2 m apart, in a few layers (1 for N = 10, 2 for 100, 4 for 1000) resting 1-2 mm
into the ground and into each other, so every box touches its neighbours, as in a settled
pile. For each N it times ``World.contacts`` (broad phase + narrow phase, the rows copied out)
and ``World.candidate_pairs`` (broad phase alone), with sort-and-sweep
(``SolverConfig(sweep=True)``) and brute force (``sweep=False``); times are medians of several
runs, each the mean of a batch of calls, after a warm-up call. Then:

  growth exponent   the least-squares slope of log(time) against log(N) over N = 10..1000;
  crossover         the smallest N from which sort-and-sweep's broad phase is faster than
                    brute force's at every larger N measured (the narrow phase is the same
                    work for both): the honest value for ``collision.SWEEP_MIN_BODIES``.

Threads: a query runs on the calling thread (one world, one core).

    python benchmarks/collision.py
"""

import time

import numpy as np

import rigid_gym as rg
from rigid_gym import collision

SIZES = (10, 100, 1000)
CROSSOVER_SIZES = (2, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256)


def layers_for(n: int) -> int:
    return 1 if n <= 32 else 2 if n <= 300 else 4


def pile(n: int, seed: int = 0) -> rg.Scene:
    """n boxes touching their neighbours in ``layers_for(n)`` layers on the ground."""
    rng = np.random.default_rng(seed)
    layers = layers_for(n)
    side = int(np.ceil(np.sqrt(n / layers)))
    scene = rg.Scene()
    scene.add_ground()
    for k in range(n):
        layer, cell = divmod(k, side * side)
        i, j = divmod(cell, side)
        axis = rng.normal(size=3)
        axis[2] *= 5.0  # mostly a turn about z, a slight tilt
        angle = rng.uniform(0.0, 0.15)
        q = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis / np.linalg.norm(axis)])
        position = (0.2 * i + rng.uniform(-0.01, 0.01), 0.2 * j + rng.uniform(-0.01, 0.01),
                    0.1 + 0.2 * layer - 0.002 * (layer + 1))
        scene.add_body(rg.Box(rng.uniform(0.095, 0.105, 3)), mass=1.0, position=position,
                       orientation=q)
    return scene


def seconds_per_call(fn, budget: float = 0.3, runs: int = 7) -> float:
    """Median over ``runs`` of the mean time of a batch of calls lasting about ``budget`` s."""
    fn()
    start = time.perf_counter()
    fn()
    once = max(time.perf_counter() - start, 1e-7)
    batch = max(1, int(budget / runs / once))
    samples = []
    for _ in range(runs):
        start = time.perf_counter()
        for _ in range(batch):
            fn()
        samples.append((time.perf_counter() - start) / batch)
    return float(np.median(samples))


def measure(n: int, sweep: bool, what: str) -> tuple[float, int, int]:
    """(seconds per call, candidate pairs, contacts) of contacts or candidate_pairs (``what``:
    "detect" or "pairs") for an n-box pile."""
    world = rg.World(pile(n), config=rg.SolverConfig(sweep=sweep))
    query = world.contacts if what == "detect" else world.candidate_pairs
    t = seconds_per_call(query)
    return t, len(world.candidate_pairs()), len(world.contacts().depth)


def slope(sizes, times) -> float:
    return float(np.polyfit(np.log(sizes), np.log(times), 1)[0])


def main() -> None:

    print("## Contact generation per step (one world, one core)\n")
    print("| boxes | layers | pairs | contacts | detect, sweep (ms) | detect, brute (ms) "
          "| broad phase, sweep (ms) | broad phase, brute (ms) |")
    print("|---|---|---|---|---|---|---|---|")
    rows = {}
    for n in SIZES:
        ds, pairs, found = measure(n, True, "detect")
        db, pairs_b, found_b = measure(n, False, "detect")
        bs = measure(n, True, "pairs")[0]
        bb = measure(n, False, "pairs")[0]
        assert (pairs, found) == (pairs_b, found_b), "sweep and brute force disagree"
        rows[n] = (ds, db, bs, bb)
        print(f"| {n} | {layers_for(n)} | {pairs} | {found} | {1e3 * ds:.3f} | {1e3 * db:.3f} "
              f"| {1e3 * bs:.3f} | {1e3 * bb:.3f} |")
    sizes = list(SIZES)
    print("\n| growth exponent (slope of log t vs log N, N = 10..1000) | sweep | brute force |")
    print("|---|---|---|")
    for k, name in ((0, "detect"), (2, "broad phase")):
        print(f"| {name} | {slope(sizes, [rows[n][k] for n in sizes]):.2f} "
              f"| {slope(sizes, [rows[n][k + 1] for n in sizes]):.2f} |")

    print("\n## Crossover: broad phase alone, sweep vs brute force\n")
    print("| boxes | sweep (us) | brute (us) | brute / sweep | detect, sweep (us) "
          "| detect, brute (us) |")
    print("|---|---|---|---|---|---|")
    faster = {}
    for n in CROSSOVER_SIZES:
        bs, bb = measure(n, True, "pairs")[0], measure(n, False, "pairs")[0]
        ds, db = measure(n, True, "detect")[0], measure(n, False, "detect")[0]
        faster[n] = bs < bb
        print(f"| {n} | {1e6 * bs:.2f} | {1e6 * bb:.2f} | {bb / bs:.2f} | {1e6 * ds:.2f} "
              f"| {1e6 * db:.2f} |")
    crossover = next((n for n in CROSSOVER_SIZES
                      if all(faster[m] for m in CROSSOVER_SIZES if m >= n)), None)
    print(f"\nMeasured crossover: sort-and-sweep wins from {crossover} bodies on "
          f"(collision.SWEEP_MIN_BODIES = {collision.SWEEP_MIN_BODIES}).")


if __name__ == "__main__":
    main()
