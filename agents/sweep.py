"""Training runs farmed out to a Ray cluster: every task x seed x setting is one Ray Tune trial.

    rigid-gym sweep rigid_gym/Push-v0 rigid_gym/Throw-v0 --seeds 0 1 2 --param tau=0.05,0.02
    RAY_AUTH_MODE=token RAY_ADDRESS=HEAD:6379 rigid-gym sweep ... --out /shared/runs/sweeps
    rigid-gym sweep --resume runs/sweeps/sweep-20260101-120000               # after a failure

Each trial is one ``rigid_gym.agents.train.train`` run with hyperparams.yml's settings, a
``--param`` grid's values replacing the algorithm arguments they name. Ray connects to the
cluster that RAY_ADDRESS names (unset: the one ``ray start`` runs on this machine, else a new
local one; ``local``: always a new one) and does the rest: Tune places the trials on the
cluster's CPUs (``cpus_per_trial`` each), copies every
checkpoint (``train``'s, one per evaluation: model, replay buffer, learning curve so far) to
the experiment folder, retries a failed trial from its newest checkpoint up to
``max_failures`` times, and ``resume`` restores a stopped sweep: finished trials stay
finished, failed and unfinished ones go on from their newest checkpoints.

The experiment folder, ``<out>/<name>/``, holds Tune's state, one folder per trial (its
``checkpoint_<k>/`` is a run folder as ``train`` writes it: ``rigid-gym evaluate
.../checkpoint_<k>/model.zip`` works) and, when the sweep ends, ``results.md`` (the results
table: final evaluation per seed, mean and spread over seeds, per task and setting, then the
failed trials) and ``curve_<task>[_<setting>].png`` (success rate against env steps). On a
cluster of several machines ``out`` must be a folder every machine sees at the same path
(a shared file system): the trials write their checkpoints there.
"""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import time
from pathlib import Path

import yaml

from .results import plot_task, table
from .train import train


def parse_param(text: str) -> tuple[str, list]:
    """``"key=v1,v2,..."`` -> (key, [v1, v2, ...]), each value read as YAML (``3e-4``,
    ``true``, ``{net_arch: [64, 64]}``, ``auto``); commas inside brackets or braces stay in
    their value."""
    key, sep, values = text.partition("=")
    if not sep or not key.strip() or not values.strip():
        raise ValueError(f"sweep: --param must be KEY=VALUE[,VALUE...], got {text!r}")
    parts, depth, start = [], 0, 0
    for i, char in enumerate(values):
        depth += (char in "[{(") - (char in "]})")
        if char == "," and depth == 0:
            parts.append(values[start:i])
            start = i + 1
    parts.append(values[start:])
    if any(part.strip() == "" for part in parts):
        raise ValueError(f"sweep: --param {text!r} has an empty value")
    try:
        return key.strip(), [number_or_text(yaml.safe_load(part)) for part in parts]
    except yaml.YAMLError as exc:
        raise ValueError(f"sweep: --param {text!r}: a value is not valid YAML ({exc})") from None


def number_or_text(value):
    """A YAML value, with the text YAML 1.1 leaves as a string but Python reads as a float
    (``1e-3``, ``3E4``) made a float."""
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return value
    return value


def setting_label(params: dict) -> str:
    """A trial's --param values as text, e.g. ``tau=0.05 learning_rate=0.001`` ('' for none)."""
    return " ".join(f"{key}={value}" for key, value in params.items())


def run_trial(config: dict) -> None:
    """A Tune trial: one ``train`` run (config: env_id, seed, steps, eval_freq, eval_episodes,
    params), in the trial's working folder, resumed from Tune's checkpoint when it has one.
    Each checkpoint is reported with the evaluation before it (timesteps, success_rate,
    mean_return) and then left to Tune's copy."""
    from ray import tune

    checkpoint = tune.get_checkpoint()
    resume = Path(checkpoint.to_directory()) if checkpoint is not None else None

    def report(folder: Path) -> None:
        with open(folder / "evaluations.csv") as f:
            last = list(csv.DictReader(f))[-1]
        tune.report({"timesteps": int(last["timesteps"]),
                     "success_rate": float(last["success_rate"]),
                     "mean_return": float(last["mean_return"])},
                    checkpoint=tune.Checkpoint.from_directory(folder))
        shutil.rmtree(folder, ignore_errors=True)  # Tune has its copy

    train(config["env_id"], seed=config["seed"], timesteps=config["steps"], out=Path.cwd(),
          eval_freq=config["eval_freq"], eval_episodes=config["eval_episodes"],
          checkpoint_freq=config["eval_freq"], overrides=config["params"], resume=resume,
          on_checkpoint=report, final_episodes=0)


def trial_folder_name(trial) -> str:
    """``<task>-seed<seed>[-<key>=<value>...]-<index>``, file-name safe."""
    config = trial.config
    name = f"{config['env_id'].split('/')[-1]}-seed{config['seed']}"
    name += "".join(f"-{key}={value}" for key, value in config["params"].items())
    return re.sub(r"[^A-Za-z0-9=._-]+", "_", name)[:120] + "-" + trial.trial_id.split("_")[-1]


def sweep(env_ids: list[str] | None = None, seeds: list[int] | None = None,
          params: dict[str, list] | None = None, *, steps: int | None = None,
          out: str | Path = "runs/sweeps", name: str | None = None, eval_freq: int = 10_000,
          eval_episodes: int = 20, cpus_per_trial: float = 1.0, max_failures: int = 0,
          resume: str | Path | None = None) -> tuple[Path, list[str]]:
    """Run the grid ``env_ids`` x ``seeds`` x ``params`` (key -> values; algorithm arguments)
    as Tune trials, or go on with the sweep in the experiment folder ``resume``; write its
    results.md and curves. Returns (experiment folder, one line per failed trial).

    steps: env steps per run (default: hyperparams.yml's budget). eval_freq: env steps
    between evaluations of ``eval_episodes`` episodes, each followed by a checkpoint.
    cpus_per_trial: CPUs Tune reserves per trial (PyTorch runs on one thread). max_failures:
    retries of a failed trial, each from its newest checkpoint.
    """
    import ray
    from ray import tune

    trainable = tune.with_resources(run_trial, {"cpu": cpus_per_trial})
    if not ray.is_initialized():
        try:
            ray.init()  # the cluster at RAY_ADDRESS (see the module docstring)
        except ConnectionError as exc:
            raise ValueError(
                f"sweep: no connection to the Ray cluster ({exc}; RAY_ADDRESS="
                f"{os.environ.get('RAY_ADDRESS')!r}, unset means the one `ray start` runs on "
                "this machine, 'local' a new one). A cluster made by `ray start` asks for its "
                "token: set RAY_AUTH_MODE=token (the token is read from ~/.ray/auth_token, or "
                "RAY_AUTH_TOKEN)") from None
    if resume is not None:
        folder = Path(resume).resolve()
        if not tune.Tuner.can_restore(str(folder)):
            raise ValueError(f"sweep: {folder} is not a sweep's experiment folder (no Tune "
                             "state in it)")
        tuner = tune.Tuner.restore(str(folder), trainable, resume_errored=True)
    else:
        if not env_ids or not seeds:
            raise ValueError("sweep: give at least one env id and one seed, or resume")
        name = name or time.strftime("sweep-%Y%m%d-%H%M%S")
        folder = Path(out).resolve() / name
        space = {"env_id": tune.grid_search(list(env_ids)), "seed": tune.grid_search(list(seeds)),
                 "params": {key: tune.grid_search(list(values))
                            for key, values in (params or {}).items()},
                 "steps": steps, "eval_freq": eval_freq, "eval_episodes": eval_episodes}
        tuner = tune.Tuner(
            trainable, param_space=space,
            tune_config=tune.TuneConfig(trial_dirname_creator=trial_folder_name),
            run_config=tune.RunConfig(
                name=name, storage_path=str(folder.parent), verbose=1,
                failure_config=tune.FailureConfig(max_failures=max_failures),
                checkpoint_config=tune.CheckpointConfig(num_to_keep=1)))
    results = tuner.fit()
    failed = write_results(results, folder)
    return folder, failed


def write_results(results, folder: Path) -> list[str]:
    """Write ``folder/results.md`` and the curves from a Tune ResultGrid of ``run_trial``s;
    returns one line per failed trial (also in results.md)."""
    from .train import curve_of, result_record

    groups: dict[tuple[str, str], list[dict]] = {}
    failed = []
    for result in results:
        config = result.config
        label = setting_label(config["params"])
        if result.error is not None or result.checkpoint is None:
            error = str(result.error).strip().splitlines()[-1] if result.error else "no checkpoint"
            failed.append(f"{config['env_id']} seed {config['seed']} {label}: {error} "
                          f"({result.path})".replace("  ", " "))
            continue
        run = Path(result.checkpoint.path)  # the last evaluation is the trial's result
        record = json.loads((run / "run.json").read_text())
        trial = result_record(record, curve_of(run), config["eval_episodes"], record)
        trial["method"] += f" ({label})" if label else ""
        groups.setdefault((config["env_id"], label), []).append(trial)
    lines = [table([trial for _, runs in sorted(groups.items()) for trial in runs])]
    for (env_id, label), runs in sorted(groups.items()):
        plot = f"curve_{env_id.split('/')[-1]}" + (f"_{label}" if label else "")
        plot_task(env_id, {(env_id, runs[0]["method"]): runs},
                  folder / (re.sub(r"[^A-Za-z0-9=._-]+", "_", plot) + ".png"))
    if failed:
        lines += ["", (f"Failed trials ({len(failed)}; `rigid-gym sweep --resume {folder}` "
                       "goes on from their newest checkpoints):"), ""]
        lines += [f"- {line}" for line in failed]
    (folder / "results.md").write_text("\n".join(lines) + "\n")
    return failed

