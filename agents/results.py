"""What the trained baselines achieved: the results table and the learning curves.

    python -m rigid_gym.agents.results runs --episodes 100 --plots docs/images

For every env id under ``runs`` (folders written by ``rigid_gym.agents.train``) it evaluates
each seed's final model over ``--episodes`` seeded episodes, prints a markdown table (mean and
spread over seeds) and draws success rate against env steps, one PNG per task, the mean over
seeds as a line and the range between seeds shaded.
"""

from __future__ import annotations

import argparse
import csv
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from rigid_gym.agents.evaluate import evaluate


def find_runs(root: Path) -> dict[str, list[Path]]:
    """Run folders under ``root`` holding a model.zip, grouped by env id."""
    runs = defaultdict(list)
    for meta in sorted(Path(root).glob("**/run.json")):
        if (meta.parent / "model.zip").is_file():
            runs[json.loads(meta.read_text())["env_id"]].append(meta.parent)
    return dict(runs)


def learning_curve(folder: Path) -> tuple[np.ndarray, np.ndarray]:
    """(timesteps (k,), success_rate (k,)) from a run's evaluations.csv."""
    with open(folder / "evaluations.csv") as f:
        rows = list(csv.DictReader(f))
    return (np.array([int(r["timesteps"]) for r in rows]),
            np.array([float(r["success_rate"]) for r in rows]))


def plot_curves(env_id: str, folders: list[Path], path: Path) -> None:
    """Success rate vs env steps: mean over seeds, the seeds' range shaded."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    curves = [learning_curve(f) for f in folders]
    length = min(len(t) for t, _ in curves)
    steps = curves[0][0][:length]
    rates = np.array([r[:length] for _, r in curves])
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.fill_between(steps, rates.min(axis=0), rates.max(axis=0), alpha=0.25,
                    label=f"range over {len(folders)} seeds")
    ax.plot(steps, rates.mean(axis=0), lw=2, label="mean")
    ax.set(xlabel="env steps", ylabel="success rate (evaluation)", ylim=(-0.02, 1.02),
           title=f"{env_id}: {method(json.loads((folders[0] / 'run.json').read_text()))}")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def method(run: dict) -> str:
    """The algorithm as the table names it, e.g. "SAC + HER + 200 demos"."""
    name = run["algo"].upper()
    if "HerReplayBuffer" in str(run["kwargs"].get("replay_buffer_class", "")):
        name += " + HER"
    demos = run.get("demonstrations")
    return f"{name} + {demos['episodes']} demos" if demos else name


def env_steps(run: dict) -> str:
    """Training env steps, plus the demonstrations' steps where there were any."""
    demos = run.get("demonstrations")
    return f"{run['timesteps']:,}" + (f" + {demos['env_steps']:,} demo" if demos else "")


def minutes(runs: list[dict], key: str) -> str:
    """Mean of ``key`` (seconds) over the runs that recorded it, in minutes (seconds under one
    minute); older runs have no cpu_seconds."""
    known = [run[key] for run in runs if key in run]
    if not known:
        return "—"
    mean = np.mean(known)
    text = f"{mean / 60:.0f} min" if mean >= 60 else f"{mean:.0f} s"
    return text + ("" if len(known) == len(runs) else f" ({len(known)} of {len(runs)} runs)")


TABLE_HEADER = ("| task | algorithm | env steps | wall time per seed | CPU time per seed | seeds | "
                "success rate (mean ± std over seeds) |\n|---|---|---|---|---|---|---|")
"""The results table's header rows (markdown)."""


def table_row(task: str, runs: list[dict], rates: list[float]) -> str:
    """One row of the results table: ``task`` (an env id, maybe with its settings), the runs'
    run.json records (one per seed, the first naming the method and budget) and their success
    rates (fractions)."""
    return (f"| {task} | {method(runs[0])} | {env_steps(runs[0])} | "
            f"{minutes(runs, 'wall_seconds')} | {minutes(runs, 'cpu_seconds')} | {len(runs)} | "
            f"{np.mean(rates):.0%} ± {np.std(rates):.0%} "
            f"({', '.join(f'{r:.0%}' for r in rates)}) |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", type=Path)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--plots", type=Path, default=Path("docs/images"))
    args = parser.parse_args()
    print(TABLE_HEADER)
    args.plots.mkdir(parents=True, exist_ok=True)
    for env_id, folders in find_runs(args.runs).items():
        metas = [json.loads((f / "run.json").read_text()) for f in folders]
        rates = [evaluate(f / "model.zip", env_id, args.episodes)["success_rate"]
                 for f in folders]
        print(table_row(env_id, metas, rates), flush=True)
        with_curves = [f for f in folders if (f / "evaluations.csv").is_file()]
        if with_curves:
            plot_curves(env_id, with_curves, args.plots / f"curve_{env_id.split('/')[-1]}.png")


if __name__ == "__main__":
    main()
