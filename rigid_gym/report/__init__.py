"""The accuracy and stability report (``rigid-gym report``, ``python benchmarks/report.py``).

    from rigid_gym.report import generate
    generate("docs")               # docs/report.md and docs/images/report/*.png, minutes
    generate("/tmp/r", quick=True)  # a tiny sweep, seconds

Modules: ``scenes`` (the standard scenes, shared with tests and benchmarks), ``cases``
(closed-form cases and their exact answers), ``accuracy`` (work-precision sweeps, observed
orders, mass properties), ``stability`` (stiff and extreme cases with pass criteria), ``peers``
(the same scenes in PyBullet and MuJoCo), ``document`` (markdown and figures).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TypedDict

from rigid_gym.report import accuracy, cases, document, peers, stability


class Sizes(TypedDict):
    dts: tuple[float, ...]
    repeats: int
    grid: tuple[int, ...]
    samples: tuple[int, ...]
    scale: float


FULL: Sizes = {"dts": (1 / 30, 1 / 60, 1 / 120, 1 / 240, 1 / 480, 1 / 960, 1 / 1920),
               "repeats": 5, "grid": (8, 16, 32, 64, 128),
               "samples": (1_000, 10_000, 100_000, 1_000_000), "scale": 1.0}
QUICK: Sizes = {"dts": (1 / 60, 1 / 240), "repeats": 1, "grid": (8, 16),
                "samples": (1_000, 10_000), "scale": 0.02}
"""Sweep sizes: dt values (s), timing repeats, grid resolutions, Monte Carlo sample counts and
the stiff cases' duration scale."""


def generate(out="docs", quick: bool = False, compare: bool = True, log=print) -> Path:
    """Run every measurement and write ``out/report.md`` plus figures; returns its path.
    compare: also measure the peer engines that are installed (PyBullet, MuJoCo)."""
    sizes = QUICK if quick else FULL
    start = time.perf_counter()

    def progress(what: str) -> None:
        log(f"[{time.perf_counter() - start:6.0f} s] {what}")

    found = peers.available() if compare else {"pybullet": False, "mujoco": False}
    curves, savings = [], {}
    for case in cases.CASES:
        progress(f"accuracy: {case.title}")
        curves += accuracy.sweep_case(case, sizes["dts"], sizes["repeats"])
        for label, (engine, make) in peers.PEERS.items():
            if found[engine] and case.key in peers.PEER_CASES:
                curves.append(accuracy.sweep(case, label,
                                             lambda dt, c=case, m=make: m(c.build(), dt),
                                             sizes["dts"], sizes["repeats"]))
        savings[case.key] = accuracy.phase_saving(case, 1 / 240, sizes["repeats"])
    progress("accuracy: mass properties")
    mass = accuracy.sweep_mass_properties(sizes["grid"], sizes["samples"], sizes["repeats"])
    stiff = []
    for run_case in stability.CASES:
        progress(f"stability: {run_case.__name__}")
        stiff += run_case(sizes["scale"])
    results = document.Results(
        curves, savings, mass, stiff, found, quick, time.perf_counter() - start, sizes["dts"],
        f"Timing: median of {sizes['repeats']} run(s). Settings are SolverConfig overrides of "
        "`SolverConfig.for_scene`: *default* (5 collision passes where any e > 0, 10 contact "
        "passes, 2 shock sweeps, rotation order 2), fewer passes, or another rotation order.")
    path = document.write(results, Path(out))
    log(f"wrote {path} in {results.seconds:.0f} s")
    return path
