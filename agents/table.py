"""Build the results table: run every missing (task, algo, seed), resuming unfinished ones.

    python -m rigid_gym.agents.table --dry-run                  # the plan and its time
    python -m rigid_gym.agents.table --tasks push,throw,stack --seeds 0,1,2 --jobs 2
    python -m rigid_gym.agents.results                          # then: the table, the curves

Each run is ``rigid_gym.agents.train.train`` with hyperparams.yml's recipe for its (env id,
algo) (``RECIPES``), in its own process with one thread (OMP_NUM_THREADS=1, JAX's XLA on one
thread), at most ``--jobs`` at a time, logging to ``<runs>/<name>.log``. It checkpoints every
``--checkpoint-freq`` env steps into ``<runs>/<name>/`` (model, replay buffer, curve, times);
killed or stopped, the next invocation resumes it from its newest checkpoint (same budget,
the curve and the wall and CPU seconds going on). A finished run writes
``<results>/<name>.json`` (``train.RESULT_KEYS``), and runs whose file exists are skipped.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

RECIPES = {
    "push": [("rigid_gym/Push-v0", "sac"), ("rigid_gym/Push-v0", "ppo")],
    "throw": [("rigid_gym/Throw-v0", "sac"), ("rigid_gym/Throw-v0", "ppo")],
    "stack": [("rigid_gym/Stack-v0", "bc_sac"), ("rigid_gym/Stack-v0", "sac"),
              ("rigid_gym/Stack-v0", "ppo")],
    **{task.lower(): [(f"rigid_gym/{task}-v0", "sac"), (f"rigid_gym/{task}-v0", "ppo")]
       for task in ("Reach", "Slide", "Flip", "Insert")},
    "pickandplace": [("rigid_gym/PickAndPlace-v0", algo)
                     for algo in ("sac", "ppo", "sac_gripper", "ppo_gripper")],
    "tower": [("rigid_gym/Tower-v0", "sac"), ("rigid_gym/Tower-v0", "ppo")],
}
"""task -> its (env id, recipe) pairs in the table (hyperparams.yml: the entry, or its
``algos``): SAC + HER (Throw with demonstrations, the others without), Stack's
behaviour-cloning recipe, PPO on the shaped reward, and PickAndPlace's SAC and PPO with the
two-finger gripper (sac_gripper, ppo_gripper)."""
PACE = {
    ("rigid_gym/Push-v0", "sac"): 767,
    ("rigid_gym/Push-v0", "ppo"): 7754,
    ("rigid_gym/Stack-v0", "sac"): 329,
    ("rigid_gym/Stack-v0", "ppo"): 1814,
}
"""Env steps per wall second of the kin recipes ``pace`` falls back on where the results
folder has none of a recipe (the medians of agents/results: two runs at a time on the
2-core Intel Xeon VM, evaluations included)."""
ONE_THREAD = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
              "XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1",
              "RIGID_GYM_NUM_THREADS": "1"}
"""The environment of every run: one thread for PyTorch, numpy's BLAS, JAX and the solver's
batch (whose pool would otherwise share large batches over the cores)."""


def pace(env_id: str, algo: str, done: list[dict]) -> float:
    """Env steps per wall second of a recipe, for the dry run's estimates: the median of
    env_steps / wall_s over its finished runs' results ``done`` (evaluations, and making the
    demonstrations, included); without any, of the same algo on Stack (several cubes) for
    Tower or on Push (one object) for the other tasks, there or in ``PACE``."""

    def measured(env: str) -> list[float]:
        return [r["env_steps"] / r["wall_s"] for r in done
                if (r.get("env_id"), r.get("algo")) == (env, algo) and r.get("wall_s")]

    kin = "rigid_gym/Stack-v0" if "Tower" in env_id else "rigid_gym/Push-v0"
    rates = measured(env_id) or measured(kin)
    if rates:
        return statistics.median(rates)
    return PACE.get((kin, algo), PACE[(kin, "sac")])


def plan(tasks: list[str], algos: list[str] | None, seeds: list[int], runs: Path,
         results: Path) -> list[dict]:
    """Every (env id, algo, seed) of ``tasks`` (only ``algos`` where given), by seed then
    task: {"env_id", "algo", "seed", "name", "state" (done, resume at N, new), "steps",
    "estimate_s"}."""
    from .results import load_results
    from .train import latest_checkpoint, load_hyperparams, run_name

    unknown = [t for t in tasks if t not in RECIPES]
    if unknown:
        raise ValueError(f"table: unknown task(s) {unknown}; known: {sorted(RECIPES)}")
    finished = load_results(results) if results.is_dir() else []
    entries = []
    for seed in seeds:
        for task in tasks:
            for env_id, algo in RECIPES[task]:
                if algos and algo not in algos:
                    continue
                name = run_name(env_id, algo, seed)
                steps = load_hyperparams(env_id, algo)["n_timesteps"]
                checkpoint = latest_checkpoint(runs / name)
                done_steps = int(checkpoint.name.split("_")[1]) if checkpoint else 0
                state = "done" if (results / f"{name}.json").is_file() else \
                    f"resume at {done_steps:,}" if checkpoint else "new"
                left = 0 if state == "done" else steps - done_steps
                entries.append({"env_id": env_id, "algo": algo, "seed": seed, "name": name,
                                "state": state, "steps": steps,
                                "estimate_s": left / pace(env_id, algo, finished)})
    return entries


def print_plan(entries: list[dict], jobs: int) -> None:
    """The plan as a table, and its total time on ``jobs`` processes (longest first)."""
    print("| run | env steps | state | estimated wall time |\n|---|---|---|---|")
    for e in entries:
        print(f"| {e['name']} | {e['steps']:,} | {e['state']} | {e['estimate_s'] / 60:.0f} min |")
    finish = [0.0] * jobs
    for seconds in sorted((e["estimate_s"] for e in entries), reverse=True):
        finish[finish.index(min(finish))] += seconds
    todo = sum(e["state"] != "done" for e in entries)
    print(f"\n{todo} of {len(entries)} runs to go, {sum(finish) / 3600:.1f} h of runs: about "
          f"{max(finish) / 3600:.1f} h on {jobs} process(es)")


def run_one(env_id: str, algo: str, seed: int, runs: Path, results: Path,
            checkpoint_freq: int) -> None:
    """One run of the table, resumed from its newest checkpoint if it has one."""
    from .train import latest_checkpoint, run_directory, train

    checkpoint = latest_checkpoint(run_directory(runs, env_id, algo, seed))
    print(f"{env_id} {algo} seed {seed}: " +
          (f"resuming from {checkpoint}" if checkpoint else "starting"), flush=True)
    train(env_id, algo=algo, seed=seed, out=runs, checkpoint_freq=checkpoint_freq,
          resume=checkpoint, results=results, progress=True)


def launch(entries: list[dict], jobs: int, runs: Path, results: Path,
           checkpoint_freq: int) -> int:
    """Run the entries not done, at most ``jobs`` processes at once; returns the number that
    failed (their logs say why)."""
    todo = [e for e in entries if e["state"] != "done"]
    running: list[tuple[subprocess.Popen, dict]] = []
    failed = 0
    runs.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, **ONE_THREAD}
    while todo or running:
        while todo and len(running) < jobs:
            e = todo.pop(0)
            log = runs / f"{e['name']}.log"
            command = [sys.executable, "-m", "rigid_gym.agents.table", "--one", e["env_id"],
                       e["algo"], str(e["seed"]), "--runs", str(runs), "--results",
                       str(results), "--checkpoint-freq", str(checkpoint_freq)]
            # the child writes to its own copy of the log's descriptor, so ours can close now
            with open(log, "a") as out:
                process = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, env=env)
            print(f"{time.strftime('%H:%M:%S')} started {e['name']} ({e['state']}), log "
                  f"{log}", flush=True)
            running.append((process, e))
        time.sleep(2.0)
        for item in list(running):
            process, e = item
            if process.poll() is not None:
                running.remove(item)
                ok = process.returncode == 0
                failed += not ok
                print(f"{time.strftime('%H:%M:%S')} {e['name']} "
                      f"{'finished' if ok else f'FAILED (exit {process.returncode})'}",
                      flush=True)
    return failed


def main(argv: list[str] | None = None) -> int:
    from .results import RESULTS

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", default=",".join(RECIPES),
                        help=f"comma-separated, of {', '.join(RECIPES)} (default all)")
    parser.add_argument("--algos", default=None,
                        help="comma-separated recipes to keep (sac, bc_sac, ppo, sac_gripper, ...; "
                             "default all)")
    parser.add_argument("--seeds", default="0,1,2", help="comma-separated (default 0,1,2)")
    parser.add_argument("--jobs", type=int, default=2,
                        help="processes at once, one thread each (default 2)")
    parser.add_argument("--runs", type=Path, default=Path("runs"),
                        help="run folders and logs (default runs)")
    parser.add_argument("--results", type=Path, default=RESULTS,
                        help="result files (default agents/results)")
    parser.add_argument("--checkpoint-freq", type=int, default=10_000,
                        help="env steps between checkpoints (default 10000)")
    parser.add_argument("--dry-run", action="store_true", help="print the plan and stop")
    parser.add_argument("--one", nargs=3, metavar=("ENV_ID", "ALGO", "SEED"),
                        help=argparse.SUPPRESS)  # one run, in the process launch starts
    args = parser.parse_args(argv)
    if args.one:
        env_id, algo, seed = args.one
        run_one(env_id, algo, int(seed), args.runs, args.results, args.checkpoint_freq)
        return 0
    if args.jobs < 1:
        parser.error(f"--jobs must be >= 1, got {args.jobs}")
    try:
        seeds = [int(s) for s in args.seeds.split(",")]
        entries = plan(args.tasks.split(","), args.algos.split(",") if args.algos else None,
                       seeds, args.runs, args.results)
    except ValueError as exc:
        parser.error(str(exc))
    print_plan(entries, args.jobs)
    if args.dry_run:
        return 0
    return 1 if launch(entries, args.jobs, args.runs, args.results, args.checkpoint_freq) else 0


if __name__ == "__main__":
    raise SystemExit(main())
