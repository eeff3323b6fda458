"""Writing the report: ``report.md`` and its PNG plots (matplotlib, Agg backend).

:func:`write` takes the measured results (``Results``) and writes ``OUT/report.md`` and the
figures under ``OUT/images/report/``; every plot is log-log with units on both axes, one curve
per setting, and the observed order p (slope of log error against log dt or log samples) in
the legend.
"""

from __future__ import annotations

import platform
import textwrap
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from rigid_gym.report.accuracy import ROUND_OFF, Curve, SampledCurve, observed_order
from rigid_gym.report.cases import CASES, Case
from rigid_gym.report.stability import StiffResult

IMAGES = Path("images") / "report"
"""Folder of the figures, relative to the report's folder."""


@dataclass
class Results:
    """Everything the report shows. curves: rigid_gym and peer Curves of every case;
    savings: case key -> ``accuracy.phase_saving`` dict; mass: SampledCurves; stiff:
    StiffResults; peers: engine name -> available; quick: the tiny sweep; seconds: wall time
    of the whole run; dts: the dt sweep (s); settings: a line describing sizes and repeats."""

    curves: list[Curve]
    savings: dict[str, dict]
    mass: list[SampledCurve]
    stiff: list[StiffResult]
    peers: dict[str, bool]
    quick: bool
    seconds: float
    dts: tuple[float, ...]
    settings: str


def fmt_order(p: float | None) -> str:
    return "exact" if p is None else f"{p:.2f}"


def fmt(x: float, unit: str = "") -> str:
    if x is None or not np.isfinite(x):
        return "n/a"
    return f"{x:.3g}{(' ' + unit) if unit else ''}"


def dt_label(dt: float) -> str:
    return f"1/{round(1 / dt)}"


# -- figures -------------------------------------------------------------------------------

PEER_STYLES = {"PyBullet": ("s--", None), "MuJoCo": ("^--", "tab:purple"),
               "MuJoCo RK4": ("v--", "tab:brown")}
"""Peer curves (``peers.PEERS`` labels): matplotlib format and colour (None: next in the
cycle); rigid_gym's settings are drawn "o-"."""


def _plot_curve(ax, x, y, label, style, color=None):
    """Log-log line through (x, y). Errors at round-off are drawn hollow at the ROUND_OFF
    floor; NaN errors (the run produced no result, e.g. a bounce never seen) are left out
    and named in the label."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    missing = ~np.isfinite(y)
    if missing.any():
        label += f", no result at {missing.sum()} point(s)"
    x, y = x[~missing], y[~missing]
    floored = y <= ROUND_OFF
    shown = np.where(floored, ROUND_OFF, y)
    line, = ax.loglog(x, shown, style, label=label, markersize=5, color=color)
    if floored.any():
        ax.loglog(x[floored], shown[floored], "o", markersize=9, markerfacecolor="none",
                  color=line.get_color())
    return line


def _log_axes(ax, size: int) -> None:
    """Decade tick labels only (minor labels overlap on short ranges), light grid."""
    from matplotlib.ticker import LogLocator, NullFormatter

    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(LogLocator(base=10.0, numticks=12))
        axis.set_minor_formatter(NullFormatter())
    ax.tick_params(labelsize=size)
    ax.grid(True, which="both", alpha=0.3)


def work_precision_panel(ax, case: Case, curves: list[Curve], metric: int) -> None:
    """Error (metric) against wall time per simulated second for every curve of ``case``."""
    for curve in curves:
        style, color = PEER_STYLES.get(curve.setting, ("o-", None))
        _plot_curve(ax, curve.cost, curve.errors[:, metric],
                    f"{curve.setting} (p = {fmt_order(curve.order(metric))})", style, color)
    first = curves[0]
    for x, y, dt in zip(first.cost, first.errors[:, metric], first.dts):
        if np.isfinite(y):
            ax.annotate(dt_label(dt), (x, max(y, ROUND_OFF)), fontsize=6,
                        textcoords="offset points", xytext=(3, 3))
    ax.set_title("\n".join(textwrap.wrap(case.title, 70)), fontsize=8)
    ax.set_xlabel("wall time per simulated second (s/s)", fontsize=7)
    ax.set_ylabel(case.metrics[metric], fontsize=7)
    _log_axes(ax, 6)
    ax.legend(fontsize=6, loc="best")


def figure_work_precision(results: Results, path: Path) -> None:
    """A grid of 3 columns: the first metric of every case."""
    import matplotlib.pyplot as plt

    rows = -(-len(CASES) // 3)
    fig, axes = plt.subplots(rows, 3, figsize=(15, 4.35 * rows))
    for ax, case in zip(axes.flat, CASES):
        work_precision_panel(ax, case, [c for c in results.curves if c.case == case.key], 0)
    for ax in axes.flat[len(CASES):]:
        ax.set_visible(False)
    fig.suptitle("Error against run time (log-log), one curve per solver setting; labels at "
                 "points: dt (s); p = observed order (slope of log error vs log dt); hollow "
                 f"circles: error <= {ROUND_OFF:g} (round-off), drawn at that floor", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.savefig(path, dpi=90)
    plt.close(fig)


def figure_case_metrics(results: Results, case: Case, path: Path) -> None:
    """One panel per metric of ``case`` (the torque-free body has three)."""
    import matplotlib.pyplot as plt

    curves = [c for c in results.curves if c.case == case.key]
    fig, axes = plt.subplots(1, len(case.metrics), figsize=(5 * len(case.metrics), 4.5))
    for metric, ax in enumerate(np.atleast_1d(axes)):
        work_precision_panel(ax, case, curves, metric)
        ax.set_title(case.metrics[metric], fontsize=9)
    fig.suptitle(f"{case.title}: exact answer {case.exact}; p = observed order vs dt",
                 fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.94))
    fig.savefig(path, dpi=90)
    plt.close(fig)


def figure_mass_properties(results: Results, path: Path) -> None:
    """Inertia error against samples and against wall time, grid and Monte Carlo."""
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8))
    for curve in results.mass:
        style = "o-" if curve.method == "grid" else "s--"
        label = f"{curve.shape}, {curve.method} (p = {fmt_order(curve.order())})"
        line = _plot_curve(left, curve.points, curve.errors, label, style)
        _plot_curve(right, curve.seconds, curve.errors, label, style).set_color(line.get_color())
    left.set_xlabel("sample points (grid: resolution^3)")
    right.set_xlabel("wall time of one estimate (s)")
    for ax in (left, right):
        ax.set_ylabel("inertia tensor, relative error (Frobenius)")
        _log_axes(ax, 8)
        ax.legend(fontsize=7)
    fig.suptitle("Mass properties: grid and Monte Carlo (RMS over 3 seeds) against the exact "
                 "integrals; p = slope of log error vs log samples (Monte Carlo: -1/2 expected)",
                 fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.94))
    fig.savefig(path, dpi=90)
    plt.close(fig)


# -- markdown ------------------------------------------------------------------------------

def accuracy_section(results: Results) -> list[str]:
    lines = ["## 1. Error against run time", "",
             f"Sweep: dt = {', '.join(dt_label(d) for d in results.dts)} s. {results.settings}",
             ("Error: against the exact answer (column *exact*). Cost: median wall time of "
              "`World.step` (no queries) per simulated second, s/s. p: observed order, the "
              "least-squares slope of log(error) against log(dt) over errors above round-off "
              f"({ROUND_OFF:g}); *exact* where every error is at round-off. Slope vs cost: the "
              "same against log(cost), the work-precision slope."), "",
             f"![work-precision]({IMAGES / 'work_precision.png'})", "",
             f"![torque-free body]({IMAGES / 'torque_free.png'})", "",
             ("| case | exact | setting | p (vs dt) | slope vs cost | error at dt = 1/240 | "
              "cost at 1/240 (s/s) |"), "|---|---|---|---:|---:|---:|---:|"]
    for case in CASES:
        for curve in (c for c in results.curves if c.case == case.key):
            for metric, name in enumerate(case.metrics):
                at = np.argmin(np.abs(curve.dts - 1 / 240))
                slope = _cost_slope(curve, metric)
                lines.append(f"| {case.title} | {case.exact} | {curve.setting} | "
                             f"{fmt_order(curve.order(metric))} | {fmt_order(slope)} | "
                             f"{fmt(curve.errors[at, metric])} ({name}) | "
                             f"{fmt(curve.cost[at])} |")
    notes = [f"- *{case.title}*: {case.note}" for case in CASES if case.note]
    if notes:
        lines += ["", "Notes:", *notes]
    lines += ["", "**Peers.** " + peers_paragraph(results.peers), ""]
    return lines


def peers_paragraph(found: dict[str, bool]) -> str:
    """What the peer curves are and how they were set up; says which engines are absent."""
    from rigid_gym.report.peers import MUJOCO_TIMECONST

    absent = ("not installed here (or `--no-compare` was given), so it was not measured "
              "(`pip install -e '.[compare]'`). ")
    pybullet = ("PyBullet is measured in the same run on the same scenes (dashed curves, "
                "squares; `rigid_gym.report.peers`: friction and restitution set so the pair "
                "values match, damping off, restitution at any speed). It was not tuned "
                "further: where its relative error nears 1 the run lost the effect entirely "
                "(its ball stops bouncing at small dt with these settings; not investigated). "
                if found.get("pybullet") else "PyBullet is " + absent)
    mujoco = ("MuJoCo is measured the same way (dashed curves, triangles; `peers.MuJoCoWorld`: "
              "the scene written as MJCF by `peers.mjcf`, `mujoco.mj_step` in a Python loop, "
              "its default semi-implicit Euler integrator and RK4 as a second curve, default "
              "pyramidal friction cone with the pair's mu, frictionless contacts with condim 1, "
              "no damping). MuJoCo has no coefficient of restitution: its contacts are soft "
              "spring-dampers, so e is mapped to the damping ratio zeta = -ln e / sqrt(pi^2 + "
              "ln^2 e) of a linear spring-damper that rebounds at e times its approach speed "
              "(zeta = 1 at e = 0, 0 at e = 1), as solref = (-w^2, -2 zeta w) with "
              f"w = 1 / max({MUJOCO_TIMECONST:g} s, 2 dt) (MuJoCo's default time constant and "
              "its 2 dt floor). The mapping is approximate (the impedance solimp and the "
              "integrator change the effective spring), so the bounce errors measure it as "
              "much as the integration. Soft contacts also sink and creep: the stacked cubes "
              "settle into their contacts and the block on the 20 deg incline slips slowly "
              "under static friction, at about the same rate at every dt, so those two errors "
              "do not fall with dt (a modelling difference, not a step-size error). The cube "
              "on the 30 deg incline rocks about its pitch axis and hops (its contacts come "
              "and go) instead of sliding flat, so its acceleration scatters over dt (with "
              "the elliptic cone too; not investigated). "
              if found.get("mujoco") else "MuJoCo is " + absent)
    return pybullet + mujoco


def _cost_slope(curve: Curve, metric: int) -> float | None:
    return observed_order(curve.cost, curve.errors[:, metric])


def mass_section(results: Results) -> list[str]:
    lines = ["## 2. Mass properties: grid and Monte Carlo against the exact integrals", "",
             f"![mass properties]({IMAGES / 'mass_properties.png'})", "",
             "| shape | method | points | inertia error | ms per estimate |", "|---|---|---:|---:|---:|"]
    for curve in results.mass:
        for n, err, sec in zip(curve.points, curve.errors, curve.seconds):
            lines.append(f"| {curve.shape} | {curve.method} | {int(n):,} | {fmt(err)} | "
                         f"{fmt(1e3 * sec)} |")
    lines += ["", "Observed order (slope vs samples): " + "; ".join(
        f"{c.shape} {c.method} {fmt_order(c.order())}" for c in results.mass) + ". Grid "
        "errors of curved or oblique surfaces fluctuate with the resolution (which cell "
        "centres fall inside a sphere is a lattice-point count: its inertia error is 1.4e-3 "
        "at 64^3, 1.6e-3 at 128^3 and 4e-5 at 200^3), so their slopes are rough; a box "
        "aligned with the grid shows the midpoint rule's clean -2/3.", ""]
    return lines


def stiff_section(results: Results) -> list[str]:
    from rigid_gym.report import stability

    failed = [r for r in results.stiff if not r.passed]
    lines = ["## 3. Stiff and extreme cases", "",
             (f"{len(results.stiff) - len(failed)} of {len(results.stiff)} cases pass. Bounds "
              "(stated before measuring, the same for every case unless the row says otherwise):"),
             "",
             (f"- energy growth: E(t) - E(0) <= {stability.ENERGY_ROUND_OFF:g} x (KE0 + sum m g "
              "|z|); impulses with restitution <= 1 and inelastic contact passes can only remove "
              "energy, so anything above float64 round-off of the energy sum is an error;"),
             (f"- deepest overlap (sampled {stability.PROBES} times and at the end): "
              f"{stability.PENETRATION_FRACTION:.0%} of the thinnest dimension in contact;"),
             (f"- drift of a resting configuration: {stability.DRIFT_BOUND * 1e3:g} mm for any "
              "body over the run."), ""]
    if failed:
        lines += ["**Failures**", ""]
        for r in failed:
            bad = "; ".join(f"{c.name} = {fmt(c.value, c.unit)} (bound {fmt(c.bound, c.unit)})"
                            for c in r.checks if not c.passed)
            lines.append(f"- **{r.title}**: {bad}.")
        lines.append("")
    lines += ["| case | result | check | value | bound | why this bound |",
              "|---|---|---|---:|---:|---|"]
    for r in results.stiff:
        for k, c in enumerate(r.checks):
            head = (f"{r.title} | {'PASS' if r.passed else '**FAIL**'}" if k == 0 else " | ")
            sign = ">=" if c.at_least else "<="
            lines.append(f"| {head} | {c.name}: {'ok' if c.passed else '**fails**'} | "
                         f"{fmt(c.value, c.unit)} | {sign} {fmt(c.bound, c.unit)} | {c.reason} |")
    for r in results.stiff:
        if r.table or r.note:
            lines += ["", f"**{r.title}.** {r.note}", ""]
            if r.table:
                header, rows = r.table
                lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
                lines += ["| " + " | ".join(row) + " |" for row in rows]
    lines.append("")
    return lines


def phase_section(results: Results) -> list[str]:
    lines = ["## 4. Solver phases used", "",
             ("`SolverConfig.for_scene` leaves out what a scene cannot need (no shock "
              "propagation without gravity or supports) and the collision phase when every "
              "restitution is 0 (impacts are then the contact phase's alone, which ends at "
              "e = 0 too). Below: what each closed-form case left out at dt = 1/240 and the "
              "cost against every phase on (`SolverConfig()`), with the first error of each "
              "(equal where leaving the phase out cannot change the answer; where it differs, "
              "the phase left out changed how an impact spread); differences of a few percent "
              "in cost are timing noise."), "",
             "| case | left out | cost (s/s) | all phases on (s/s) | saved | error | error, all on |",
             "|---|---|---:|---:|---:|---:|---:|"]
    for case in CASES:
        s = results.savings.get(case.key)
        if s is None:
            continue
        saved = 1.0 - s["cost"] / s["cost_all_on"]
        lines.append(f"| {case.title} | {', '.join(s['left_out']) or 'nothing'} | "
                     f"{fmt(s['cost'])} | {fmt(s['cost_all_on'])} | {saved:.0%} | "
                     f"{fmt(s['error'])} | {fmt(s['error_all_on'])} |")
    lines += ["",
              ("Share of step time by phase (`World.profile()`; off: phases that did not run), "
               "closed-form cases at dt = 1/240 with `for_scene`, then the stiff cases:"), "",
              "| case | cost (s/s) | phases run: share of step time |", "|---|---:|---|"]
    rows = [(case.title, s["cost"], s["profile"]) for case in CASES
            if (s := results.savings.get(case.key))]
    rows += [(r.title, r.cost, r.phases) for r in results.stiff if r.phases]
    for title, cost, phases in rows:
        lines.append(f"| {title} | {fmt(cost)} | {phase_shares(phases)} |")
    lines.append("")
    return lines


def phase_shares(profile: dict) -> str:
    """'contact 75%, ...; off: collision' from a ``World.profile()`` dict."""
    total = sum(p["seconds"] for p in profile.values()) or 1.0
    shares = ", ".join(f"{name} {p['seconds'] / total:.0%}" for name, p in profile.items()
                       if p["on"])
    off = [name for name, p in profile.items() if not p["on"]]
    return shares + (f"; off: {', '.join(off)}" if off else "")


def write(results: Results, out: Path) -> Path:
    """Write ``out/report.md`` and its figures; returns the markdown file's path."""
    import matplotlib

    matplotlib.use("Agg")
    out = Path(out)
    images = out / IMAGES
    images.mkdir(parents=True, exist_ok=True)
    figure_work_precision(results, images / "work_precision.png")
    torque_free = next(c for c in CASES if c.key == "torque_free")
    figure_case_metrics(results, torque_free, images / "torque_free.png")
    figure_mass_properties(results, images / "mass_properties.png")
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    lines = ["# Accuracy and stability report", "",
             (f"Generated by `rigid-gym report{' --quick' if results.quick else ''}` "
              f"({'quick: a tiny sweep, numbers not representative' if results.quick else 'full'}"
              f") on {stamp}, {platform.machine()} {platform.system()}, Python "
              f"{platform.python_version()}; the run took {results.seconds / 60:.1f} min. "
              "Timings depend on the machine and its load; errors do not."), ""]
    lines += accuracy_section(results) + mass_section(results)
    lines += stiff_section(results) + phase_section(results)
    path = out / "report.md"
    path.write_text("\n".join(lines))
    return path
