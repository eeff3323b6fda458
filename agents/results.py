"""The results table and the learning curves, from the runs' result files alone.

    python -m rigid_gym.agents.results                       # agents/results -> README's table
    python -m rigid_gym.agents.results agents/results --plots docs/images

Every finished run of the table (``rigid_gym.agents.table``, or ``train(results=...)``)
writes ``<name>-<algo>-seed<k>.json`` (``train.RESULT_KEYS``). This prints a markdown table,
one row per env id and method: mean and spread of the final success rate over the seeds (each
a deterministic evaluation of 100 episodes), env steps, wall and CPU time per run and the
machine; and draws ``curve_<task>.png`` per task: success rate against env steps and against
wall minutes, one line per method (the mean over seeds), the range between seeds shaded.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).with_name("results")


def method(run: dict) -> str:
    """The algorithm as the table names it, from a run.json record, e.g. "SAC + HER + 200
    demos", "PPO, shaped reward", "SAC + HER, two-finger gripper" (``effector``) or, with
    Stack's curriculum (``start_placed``), "PPO, shaped reward, 50% of episodes start with
    cube 0 placed"."""
    name = run["algo"].upper()
    if "HerReplayBuffer" in str(run["kwargs"].get("replay_buffer_class", "")):
        name += " + HER"
    demos = run.get("demonstrations")
    if demos:
        name += f" + {demos['episodes']} demos"
    env_kwargs = run.get("env_kwargs") or {}
    reward = env_kwargs.get("reward_type")
    name += f", {reward} reward" if reward else ""
    name += ", two-finger gripper" if env_kwargs.get("effector") == "gripper" else ""
    placed = env_kwargs.get("start_placed")
    return name + (f", {placed:.0%} of episodes start with cube 0 placed" if placed else "")


def load_results(folder: str | Path) -> list[dict]:
    """Every result file (``*.json``) in ``folder``, sorted by name."""
    return [json.loads(path.read_text()) for path in sorted(Path(folder).glob("*.json"))]


def grouped(results: list[dict]) -> dict[tuple[str, str], list[dict]]:
    """Results by (env id, method), each group sorted by seed, in order of first appearance."""
    groups = defaultdict(list)
    for result in results:
        groups[(result["env_id"], result["method"])].append(result)
    return {key: sorted(runs, key=lambda r: r["seed"]) for key, runs in groups.items()}


def duration(seconds: float) -> str:
    """Seconds as the table shows them: "12 s" under a minute, else "3.5 min"."""
    return f"{seconds:.0f} s" if seconds < 60 else f"{seconds / 60:.1f} min"


def steps(count: float) -> str:
    """An env step count as the table shows it: 40k, 1.2M, 950."""
    if count >= 1e6:
        return f"{count / 1e6:.3g}M"
    return f"{count / 1e3:.3g}k" if count >= 1e3 else f"{count:.0f}"


TABLE_HEADER = ("| task | method | learner | env steps | wall time per run | CPU time per run | "
                "seeds | success (mean ± std over seeds) |\n"
                "|---|---|---|---|---|---|---|---|")
"""The results table's header rows (markdown)."""


def table_row(runs: list[dict]) -> str:
    """The row of one (env id, method)'s runs (result dicts, one per seed): env steps (plus
    the demonstrations'), mean wall and CPU time with their range, the seeds, and the mean and
    standard deviation of the final success rates with every seed's."""
    first = runs[0]
    rates = np.array([r["success"] for r in runs])
    wall = np.array([r["wall_s"] for r in runs])
    cpu = np.array([r["cpu_s"] for r in runs])
    demo = first.get("demo_env_steps", 0)
    spent = steps(first["env_steps"]) + (f" + {steps(demo)} demo" if demo else "")

    def spread(values: np.ndarray) -> str:
        text = duration(values.mean())
        return text + (f" ({duration(values.min())}-{duration(values.max())})"
                       if len(values) > 1 else "")

    return (f"| {first['env_id']} | {first['method']} | {first.get('learner', '')} | {spent} | "
            f"{spread(wall)} | {spread(cpu)} | {len(runs)} | "
            f"**{rates.mean():.0%}** ± {rates.std():.0%} "
            f"({', '.join(f'{r:.0%}' for r in rates)}) |")


def table(results: list[dict]) -> str:
    """The markdown results table of ``results`` (result dicts), with the machine(s) they ran
    on and the evaluation's episodes below it."""
    lines = [TABLE_HEADER] + [table_row(runs) for runs in grouped(results).values()]
    machines = sorted({r.get("machine", "unknown machine") for r in results})
    episodes = sorted({r["episodes"] for r in results})
    lines += ["", (f"Final evaluation: deterministic policy, {', '.join(map(str, episodes))} "
                   f"episodes per seed on seeds apart from training's, of each run's selected "
                   f"checkpoint (the best on held-out validation seeds of its second half, "
                   f"`train.finish`). Machine: {'; '.join(machines)}; one process per run, "
                   "PyTorch's, XLA's and the solver's pools on one thread"
                   f"{threads_note(results)}.")]
    return "\n".join(lines)


def threads_note(results: list[dict]) -> str:
    """What the runs' CPU times say of the one-thread claim: the runs whose CPU time exceeds
    their wall time (so some other thread of the process was busy too), and by how much."""
    over = [r["cpu_s"] / r["wall_s"] - 1.0 for r in results if r["cpu_s"] > r["wall_s"] > 0.0]
    if not over:
        return ""
    return (f" (CPU time above the wall time in {len(over)} of {len(results)} runs, by at "
            f"most {max(over):.0%}: another thread of the process was busy too)")


def band(runs: list[dict], key: str, scale: float = 1.0, points: int = 100):
    """The seeds' curves on a common x (``key``: env_steps or wall_s, times ``scale``) up to
    the shortest run's end: (x (points,), mean (points,), low (points,), high (points,))."""
    curves = [(np.array([p[key] for p in r["curve"]]) * scale,
               np.array([p["success"] for p in r["curve"]])) for r in runs]
    end = min(x[-1] for x, _ in curves)
    grid = np.linspace(min(x[0] for x, _ in curves), end, points)
    values = np.array([np.interp(grid, x, y) for x, y in curves])
    return grid, values.mean(axis=0), values.min(axis=0), values.max(axis=0)


def plot_task(task: str, groups: dict[tuple[str, str], list[dict]], path: Path) -> None:
    """``task``'s learning curves into ``path`` (PNG): success against env steps (left) and
    against wall minutes (right), a line per method (mean over seeds), the seeds' range
    shaded; env steps on a log axis where the budgets differ more than tenfold."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8), sharey=True)
    for k, ((env_id, name), runs) in enumerate(groups.items()):
        color = f"C{k}"
        label = f"{name} ({len(runs)} seed{'s' if len(runs) > 1 else ''})"
        for ax, key, scale in ((axes[0], "env_steps", 1e-3), (axes[1], "wall_s", 1 / 60)):
            x, mean, low, high = band(runs, key, scale)
            ax.fill_between(x, low, high, color=color, alpha=0.2, lw=0)
            ax.plot(x, mean, color=color, lw=2, label=label)
    ends = [runs[0]["curve"][-1]["env_steps"] for runs in groups.values()]
    if max(ends) > 10 * min(ends):  # budgets that far apart (PPO's and SAC's) share a log axis
        axes[0].set_xscale("log")
    axes[0].set(xlabel="env steps (thousands)", ylabel="success rate (evaluation)",
                ylim=(-0.02, 1.02))
    axes[1].set(xlabel="wall time (minutes, one thread)")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[1].legend(loc="lower right", fontsize=8)
    fig.suptitle(f"{task}: mean over seeds, range shaded")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_curves(results: list[dict], folder: Path) -> list[Path]:
    """``curve_<task>.png`` in ``folder`` for every task of ``results``; returns the paths."""
    by_task: dict[str, dict] = defaultdict(dict)
    for (env_id, name), runs in grouped(results).items():
        by_task[env_id.split("/")[-1].split("-v")[0].removesuffix("Dense")][(env_id, name)] = runs
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for task, groups in by_task.items():
        paths.append(folder / f"curve_{task}.png")
        plot_task(task, groups, paths[-1])
    return paths


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, nargs="?", default=RESULTS,
                        help="folder of result files (default agents/results)")
    parser.add_argument("--plots", type=Path, default=Path("docs/images"),
                        help="folder for curve_<task>.png (default docs/images)")
    args = parser.parse_args(argv)
    results = load_results(args.results)
    if not results:
        parser.error(f"no result files (*.json) in {args.results}; the runs of "
                     "`python -m rigid_gym.agents.table` write them")
    print(table(results))
    for path in plot_curves(results, args.plots):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
