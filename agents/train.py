"""Train a baseline on a rigid_gym task, on SBX (JAX) where it is installed, else on
stable-baselines3 (PyTorch) (``rigid_gym.agents.algorithms``).

    from .train import train
    run = train("rigid_gym/Push-v0", seed=0)            # settings from hyperparams.yml

    rigid-gym train rigid_gym/Push-v0 --seed 0
    rigid-gym train rigid_gym/Push-v0 --seed 0 --checkpoint-freq 10000 --resume   # after a kill

A run writes one folder, ``<out>/<name>-<algo>-seed<seed>/`` (``run_name``: the id's name
without its version, e.g. ``runs/Push-sac-seed0/``):

    model.zip           the final policy (``rigid-gym evaluate`` loads it)
    run.json            env id, algorithm, learner, seed, budget, settings, the command line,
                        and after training wall_seconds and cpu_seconds (this process's CPU
                        time, summed over the sittings of a resumed run); resumed_at: the env
                        steps each resume went on from
    evaluations.csv     timesteps, success_rate, mean_return, wall_seconds: deterministic
                        episodes on fixed seeds, every ``eval_freq`` steps (the learning curve)
    result.json         the finished run's result (``RESULT_KEYS``), written last: the final
                        evaluation (deterministic, ``final_episodes`` episodes on seeds from
                        EVAL_SEED, apart from training's) of the selected policy (``finish``)
                        and the curve; a copy goes to ``results`` (agents/results/ for the
                        table) when given
    selected_model.zip  with checkpoints: the checkpoint's policy that the final evaluation ran
    checkpoints/        step_<steps>/ every ``checkpoint_freq`` steps and at the end (if set):
                        model.zip, run.json and evaluations.csv as they were then, and in the
                        newest one the replay buffer; ``train(resume=...)`` goes on from one

``rigid-gym train ID --obs-mode pixels`` trains the entry's pixel recipe instead
(``train_pixels``: a student on the frame, the goal and the pad's own state, distilled from a
state policy on its own visited states, ``rigid_gym.agents.distill``, whose module docstring
gives its run folder).

Collection runs through the batched env (``SB3VecEnv`` over ``gym.make_vec``): n_envs copies
in one World, one solver call per vector step.
"""

from __future__ import annotations

import csv
import json
import pickle
import shutil
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import yaml
from rigid_gym._core import set_num_threads
from stable_baselines3.common.callbacks import BaseCallback, CallbackList
from stable_baselines3.common.vec_env import VecCheckNan, VecMonitor

import rigid_gym  # noqa: F401  (registers the env ids)
from rigid_gym.checks import integer

from .algorithms import ALGORITHMS, PIXEL_ALGORITHMS, algorithm_class, learner_for
from .evaluate import VALIDATION_SEED, load_model, observation_kwargs, success_rate
from .progress import note
from .vec_env import SB3VecEnv

HYPERPARAMS = Path(__file__).with_name("hyperparams.yml")
RESULT_KEYS = ("env_id", "algo", "seed", "env_steps", "wall_s", "cpu_s", "episodes", "success",
               "selected_env_steps", "curve", "learner", "method", "demo_env_steps", "machine")
"""A result file's keys: env_id, algo, seed; env_steps (training, without the
demonstrations'), wall_s and cpu_s (the run's, making its demonstrations and evaluations
included, over all its sittings);
episodes and success (the final evaluation: deterministic policy, fraction of successes);
selected_env_steps (the env steps of the checkpoint whose policy the final evaluation ran,
``finish``); curve [{"env_steps", "wall_s", "success"}] (the evaluations during training, then
the final one); and for the table: learner, method (e.g. "SAC + HER + 500 demos"),
demo_env_steps, machine (the processor, its cores)."""
SELECT_FROM = 0.5
"""``finish`` chooses among the checkpoints of the last (1 - SELECT_FROM) of the run."""
VALIDATION_EPISODES = 20
"""Episodes per checkpoint in ``finish``'s choice, on seeds from VALIDATION_SEED."""
CURVE_POINTS = 20
"""Evaluations per run when ``eval_freq`` is not given."""
DEMO_SEED = 2_000_000
"""Demonstration episodes use seeds DEMO_SEED + 1000 * seed + rank, apart from the training seeds
(small) and the evaluation seeds (``EVAL_SEED`` = 1,000,000 onwards)."""


def hyperparams_table() -> dict[str, dict]:
    """hyperparams.yml: env id -> its settings (algo, n_timesteps, n_envs, her, demonstrations,
    kwargs)."""
    return yaml.safe_load(HYPERPARAMS.read_text())


def load_hyperparams(env_id: str, algo: str | None = None) -> dict:
    """The settings for ``env_id`` from hyperparams.yml; with ``algo`` named in the entry's
    ``algos`` (another recipe for the same id, e.g. Stack's SAC + HER without demonstrations),
    the entry with that recipe's keys replacing its own. A recipe is named by its algorithm,
    or names it (``algo``: PickAndPlace's ``sac_gripper`` is SAC with the two-finger gripper);
    ``recipe`` is then the recipe's name, the runs' (``run_name``)."""
    table = hyperparams_table()
    if env_id not in table:
        raise ValueError(f"train: no settings for {env_id!r} in {HYPERPARAMS.name}; "
                         f"known ids: {sorted(table)}")
    entry = dict(table[env_id])
    recipes = entry.pop("algos", {})
    if algo is not None and algo != entry["algo"] and algo in recipes:
        entry.update({"algo": algo, **recipes[algo]})
        if entry["algo"] != algo:
            entry["recipe"] = algo
    return entry


def run_name(env_id: str, algo: str, seed: int) -> str:
    """``<name>-<algo>-seed<seed>``, name the id's without namespace and version
    (rigid_gym/Push-v0, sac, 0 -> Push-sac-seed0): a run's folder and result file."""
    return f"{env_id.split('/')[-1].rsplit('-v', 1)[0]}-{algo}-seed{seed}"


def run_directory(out: str | Path, env_id: str, algo: str, seed: int) -> Path:
    return Path(out) / run_name(env_id, algo, seed)


def make_env(env_id: str, n_envs: int, env_kwargs: dict | None = None, learner: str = "sb3"):
    """``n_envs`` copies of ``env_id`` in one batched World, made with ``env_kwargs`` (e.g.
    reward_type): for the batch learner the vector env itself, its first episodes' ends
    spread (``stagger``); else SB3's VecEnv of it (``SB3VecEnv``) with episode statistics
    (VecMonitor) and a check that fails where a NaN first appears."""
    if learner == "batch":
        return gym.make_vec(env_id, num_envs=n_envs, stagger=True, **(env_kwargs or {}))
    venv = gym.make_vec(env_id, num_envs=n_envs, **(env_kwargs or {}))
    return VecCheckNan(VecMonitor(SB3VecEnv(venv)), raise_exception=True)


def build_model(env_id: str, settings: dict, algo: str, learner: str, n_envs: int, seed: int,
                overrides: dict | None = None, verbose: int = 0):
    """A new model of ``algo`` on ``learner`` (sbx or sb3) with ``settings`` (an entry of
    hyperparams.yml: its ``env_kwargs`` make the envs) and ``overrides`` of its arguments, on
    ``make_env``'s envs; returns (model, env)."""
    env = make_env(env_id, n_envs, settings.get("env_kwargs"), learner)
    model = algorithm_class(algo, learner)("MultiInputPolicy", env, seed=seed, verbose=verbose,
                                           **model_kwargs(settings, algo, overrides))
    return model, env


def model_kwargs(settings: dict, algo: str, overrides: dict | None = None) -> dict:
    """The algorithm's arguments: the entry's ``kwargs``, ``overrides`` replacing them, and
    HER's replay buffer where the entry has ``her`` (off-policy only)."""
    kwargs = {**settings.get("kwargs", {}), **(overrides or {})}
    if algo != "ppo" and "her" in settings:
        from stable_baselines3 import HerReplayBuffer
        kwargs.update(replay_buffer_class=HerReplayBuffer,
                      replay_buffer_kwargs=dict(settings["her"]))
    return kwargs


def use_threads(threads: int) -> None:
    """Train on ``threads`` threads: PyTorch's, and the solver's pool, which otherwise shares a
    large batch of copies (the batch learner's 256) out over every core the process may use
    (results are bit for bit the same either way). A run's ``cpu_s`` then counts one core for
    ``threads=1`` but for JAX's own threads (one where XLA_FLAGS says so: agents/table.py)."""
    import torch

    torch.set_num_threads(threads)
    set_num_threads(threads)


def train(env_id: str, *, algo: str | None = None, timesteps: int | None = None, seed: int = 0,
          n_envs: int | None = None, out: str | Path = "runs", eval_freq: int | None = None,
          eval_episodes: int = 20, checkpoint_freq: int = 0, progress_bar: bool = False,
          threads: int = 1, verbose: int = 0, overrides: dict | None = None,
          demonstrations: int | None = None, demo_dataset: str | None = None,
          resume: str | Path | None = None,
          on_checkpoint: Callable[[Path], None] | None = None, progress: bool = False,
          learner: str | None = None, final_episodes: int = 100,
          results: str | Path | None = None, obs_mode: str = "state",
          teacher: str | None = None) -> Path:
    """Train on ``env_id`` and return the run folder (see the module docstring).

    algo, timesteps (env steps), n_envs: override hyperparams.yml (an ``algo`` that the
    entry's ``algos`` names brings that recipe's settings). learner: sbx, sb3 or batch (None:
    the entry's ``learner``, else ``algorithms.learner_for``'s choice). eval_freq: env steps between evaluations of
    ``eval_episodes`` deterministic episodes (None: CURVE_POINTS over the run; 0: none).
    final_episodes: the final evaluation's episodes (0: none, and no result file); results:
    a folder that also gets the result file, as ``<run_name>.json``. checkpoint_freq: env
    steps between checkpoints (0: none; with it, the end of training is one too). threads:
    PyTorch's CPU threads and the solver's (``use_threads``). overrides: algorithm arguments that replace those of
    hyperparams.yml (e.g. learning_starts). demonstrations: scripted episodes put in the replay
    buffer before training (off-policy only; default: hyperparams.yml's ``demonstrations``,
    else 0), see ``add_demonstrations``; demo_dataset: the Minari dataset id they come from
    (default: the scripted policy's, written for the run into a temporary folder). resume: a checkpoint folder of this run
    (``latest_checkpoint``) to go on from: its model (with the algorithm arguments it was made
    with; ``overrides`` and ``demonstrations`` are not applied again), replay buffer and
    files, trained on to ``timesteps`` in all (not bit-identical to a run never stopped: the
    envs start afresh).
    on_checkpoint: called with each checkpoint's folder once it is complete.
    progress: say on standard error what the run is doing (making the envs and the model,
    the demonstrations and each evaluation with a bar of their episodes); the training
    steps' own bar is ``progress_bar`` (SB3's).
    obs_mode: "state", or "pixels": a pixel recipe, algo ``distill`` (the default,
    ``rigid_gym.agents.distill``: a student on the frame, the goal and the pad's own state,
    taught by the state policy ``teacher``, default the recipe's; ``timesteps`` then sets
    its iterations, whole iterations of the recipe's episodes) or ``drq``
    (``rigid_gym.agents.pixel_sac``: SAC + HER on the same inputs, no privileged state);
    ``overrides`` replace the recipe's settings, ``resume`` is any true value (it goes on
    from checkpoints/latest.pt).
    """

    if obs_mode not in ("state", "pixels"):
        raise ValueError(f"train: obs_mode must be 'state' or 'pixels', got {obs_mode!r}")
    if obs_mode == "pixels" or algo in PIXEL_ALGORITHMS:
        if algo not in (None, *PIXEL_ALGORITHMS) or obs_mode != "pixels":
            raise ValueError(f"train: the pixel recipes are algos {PIXEL_ALGORITHMS} with "
                             f"obs_mode 'pixels' (got algo {algo!r}, obs_mode {obs_mode!r})")
        return train_pixels(env_id, algo or "distill", timesteps=timesteps, seed=seed, out=out,
                            eval_episodes=eval_episodes, threads=threads, overrides=overrides,
                            resume=resume is not None and resume is not False,
                            final_episodes=final_episodes, results=results, teacher=teacher,
                            progress=progress)
    settings = load_hyperparams(env_id, algo)
    recipe = algo or settings["algo"]  # names the run
    # a recipe that names its algorithm (sac_gripper) trains that one
    algo = settings["algo"] if "recipe" in settings else recipe
    if algo not in ALGORITHMS:  # before anything is made
        recipes = sorted(hyperparams_table()[env_id].get("algos", {}))
        raise ValueError(f"train: algo must be one of {ALGORITHMS} or one of {env_id}'s "
                         f"recipes in {HYPERPARAMS.name} {recipes}, got {algo!r}")
    learner = learner_for(algo, learner or settings.get("learner"))
    algorithm_class(algo, learner)  # an algo whose package is missing fails here
    timesteps = _count(timesteps if timesteps is not None else settings["n_timesteps"],
                       "timesteps", 1)
    n_envs = _count(n_envs if n_envs is not None else settings.get("n_envs", 1), "n_envs", 1)
    seed = _count(seed, "seed", 0)
    if eval_freq is None:
        eval_freq = max(1, timesteps // CURVE_POINTS)
    for name, value in (("eval_freq", eval_freq), ("eval_episodes", eval_episodes),
                        ("checkpoint_freq", checkpoint_freq),
                        ("final_episodes", final_episodes)):
        _count(value, name, 0)
    use_threads(_count(threads, "threads", 1))
    demonstrations = _count(demonstrations if demonstrations is not None
                            else settings.get("demonstrations", 0), "demonstrations", 0)
    if demonstrations and algo == "ppo":
        raise ValueError("train: demonstrations fill a replay buffer; ppo has none")

    folder = run_directory(out, env_id, recipe, seed)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "result.json").unlink(missing_ok=True)  # a result only once the run finished
    if resume is None:  # a new run: no checkpoint of an earlier one in this folder is its own
        shutil.rmtree(folder / "checkpoints", ignore_errors=True)
        (folder / "selected_model.zip").unlink(missing_ok=True)
    if resume is not None:
        record = _restore_files(Path(resume), folder, env_id, recipe, seed)
        # the checkpoint's model is of its learner, its buffer of its number of envs
        learner, n_envs = record.get("learner", "sb3"), record["n_envs"]
    note(f"{env_id}: making {n_envs} env(s) and the {algo} model on {learner} (run folder "
         f"{folder})", progress)
    before = record if resume is not None else {}  # the seconds of the parts before a resume
    # from here: making the model and the demonstrations count in the run's time
    clock = Clock(before.get("wall_seconds", 0.0), before.get("cpu_seconds", 0.0))
    if resume is not None:  # the checkpoint's model, with the settings it was made with
        env = make_env(env_id, n_envs, record.get("env_kwargs"), learner)
        if learner != "batch":  # (the batch learner seeds its envs at its first rollout)
            env.seed(seed)  # the envs start afresh, as at the run's start
        model = algorithm_class(algo, learner).load(Path(resume) / "model.zip", env=env,
                                                    device="cpu")
        load_buffers(model, Path(resume))
        record["resumed_at"] = record.get("resumed_at", []) + [model.num_timesteps]
        record["timesteps"] = timesteps
        (folder / "run.json").write_text(json.dumps(record, indent=2))
    else:
        model, env = build_model(env_id, settings, algo, learner, n_envs, seed, overrides,
                                 verbose)
        demo = add_demonstrations(model, env_id, demonstrations, seed, progress,
                                  demo_dataset) \
            if demonstrations else None
        _write_run(folder, env_id, algo, learner, seed, timesteps, n_envs,
                   model_kwargs(settings, algo, overrides), demo, settings.get("env_kwargs", {}),
                   recipe)

    callbacks: list[BaseCallback] = []
    if eval_freq:
        callbacks.append(SuccessEvaluation(env_id, folder / "evaluations.csv", eval_freq,
                                           eval_episodes, clock, append=resume is not None,
                                           progress=progress,
                                           env_kwargs=observation_kwargs(
                                               json.loads((folder / "run.json").read_text()))))
    checkpoints = Checkpoints(folder, checkpoint_freq, clock, on_checkpoint) \
        if checkpoint_freq else None
    callbacks += [checkpoints] if checkpoints else []
    note(f"{env_id}: training {algo} for {max(0, timesteps - model.num_timesteps):,} env steps",
         progress)
    model.learn(max(0, timesteps - model.num_timesteps), callback=CallbackList(callbacks),
                progress_bar=progress_bar, reset_num_timesteps=resume is None)
    model.save(folder / "model.zip")
    env.close()
    _write_seconds(folder, clock)
    if checkpoints and checkpoints.written != model.num_timesteps:
        checkpoints.write()  # the end of training, with its times
    if final_episodes:
        finish(folder, model, clock, final_episodes, results, progress)
    return folder


def train_pixels(env_id: str, algo: str, *, timesteps: int | None, seed: int,
                 out: str | Path, eval_episodes: int, threads: int, overrides: dict | None,
                 resume: bool, final_episodes: int, results: str | Path | None,
                 teacher: str | None, progress: bool) -> Path:
    """``train``'s pixel recipe ``algo`` (distill: ``rigid_gym.agents.distill.train_distill``;
    drq: ``rigid_gym.agents.pixel_sac.train_pixel_sac``) with the entry's settings under
    ``algos: {algo: {algo: ...}}``, ``overrides`` replacing them; ``timesteps``: env steps,
    rounded up to whole iterations (distill) or whole episodes of the envs (drq)."""

    settings = load_hyperparams(env_id, algo)
    if algo not in settings:
        raise ValueError(f"train: {env_id} has no pixel recipe {algo!r} (algos: {{{algo}: "
                         f"{{{algo}: ...}}}}) in {HYPERPARAMS.name}")
    if teacher is not None and algo != "distill":
        raise ValueError(f"train: a teacher teaches the distill recipe only, not {algo!r}")
    recipe = {**settings[algo], **(overrides or {})}
    if timesteps is not None:
        timesteps = _count(timesteps, "timesteps", 1)
    use_threads(_count(threads, "threads", 1))
    folder = run_directory(out, env_id, algo, _count(seed, "seed", 0))
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "result.json").unlink(missing_ok=True)  # a result only once the run finished
    common: dict[str, Any] = {
        "seed": seed, "folder": folder, "resume": resume, "results": results,
        "eval_episodes": _count(eval_episodes, "eval_episodes", 0),
        "final_episodes": _count(final_episodes, "final_episodes", 0), "progress": progress}
    if algo == "drq":
        from .pixel_sac import train_pixel_sac

        return train_pixel_sac(env_id, {**settings, algo: recipe}, timesteps=timesteps,
                               **common)
    from .distill import train_distill

    iterations = None
    if timesteps is not None:
        per_iteration = -(-recipe["episodes"] // recipe["n_envs"]) * recipe["n_envs"] \
            * gym.spec(env_id).max_episode_steps
        iterations = -(-timesteps // per_iteration)
    return train_distill(env_id, {**settings, algo: recipe}, teacher=teacher,
                         iterations=iterations, **common)


def finish(folder: Path, model, clock: Clock, episodes: int = 100,
           results: str | Path | None = None, progress: bool = False) -> dict:
    """Choose the run's policy, evaluate it and write the result (``write_result``; a copy
    into ``results`` when given); returns the result.

    An off-policy learner's policy swings between evaluations (Throw SAC: 95% of 20 episodes
    at 380k env steps, 55% at 400k), so the last one is a draw from that swing. With
    checkpoints, each of the last (1 - SELECT_FROM) of the run plays VALIDATION_EPISODES
    episodes on seeds from VALIDATION_SEED (apart from training's and the final
    evaluation's), and the best of them (the latest among equals) is the run's policy, copied
    to ``selected_model.zip`` (model selection on held-out seeds, as the RL Zoo keeps its
    best_model.zip); without, the final ``model``. Then ``episodes`` episodes from EVAL_SEED.
    The choice's evaluations count in the run's wall and CPU seconds (``clock``)."""
    record = json.loads((folder / "run.json").read_text())
    env_id = record["env_id"]
    env = gym.make(env_id, **observation_kwargs(record))
    steps, chosen = model.num_timesteps, model
    candidates = sorted((int(path.name.split("_")[1]), path)
                        for path in folder.glob("checkpoints/step_*")
                        if path.name.split("_")[1].isdigit() and (path / "model.zip").is_file()
                        and SELECT_FROM * steps <= int(path.name.split("_")[1]) <= steps)
    if candidates:
        note(f"{env_id}: choosing among {len(candidates)} checkpoints, "
             f"{VALIDATION_EPISODES} validation episodes each", progress)
        best = -1.0
        for step, path in candidates:
            candidate = load_model(path / "model.zip", env)
            rate = success_rate(candidate, env, VALIDATION_EPISODES, VALIDATION_SEED)
            if rate["success_rate"] >= best:
                best, steps, chosen = rate["success_rate"], step, candidate
        shutil.copy2(folder / "checkpoints" / f"step_{steps}" / "model.zip",
                     folder / "selected_model.zip")
    note(f"{env_id}: final evaluation, {episodes} episodes (the policy of {steps:,} env steps)",
         progress)
    final = success_rate(chosen, env, episodes, progress=progress)
    result = write_result(folder, model.num_timesteps, steps, final, clock)
    if results is not None:
        Path(results).mkdir(parents=True, exist_ok=True)
        target = Path(results) / f"{folder.name}.json"
        target.write_text(json.dumps(result, indent=1) + "\n")
    return result


def machine() -> str:
    """The processor and its core count, as the results table names the machine."""
    import os
    import platform

    name = platform.processor() or platform.machine()
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                name = line.split(":", 1)[1].strip()
                break
    return f"{name}, {os.cpu_count()} cores"


def curve_of(folder: Path) -> list[dict]:
    """A run folder's (or checkpoint's) evaluations.csv as a result's curve: [{"env_steps",
    "wall_s", "success"}] ([] without the file)."""
    if not (folder / "evaluations.csv").is_file():
        return []
    with open(folder / "evaluations.csv") as f:
        return [{"env_steps": int(r["timesteps"]), "wall_s": float(r["wall_seconds"]),
                 "success": float(r["success_rate"])} for r in csv.DictReader(f)]


def result_record(record: dict, curve: list[dict], episodes: int, seconds: dict,
                  selected: int | None = None) -> dict:
    """A result (RESULT_KEYS) from a run.json ``record``, its ``curve`` (the last point the
    final evaluation, of ``episodes`` episodes), its ``seconds`` (``Clock.seconds``) and the
    env steps of the policy evaluated (``selected``; default the run's end)."""
    from .results import method

    demo = record.get("demonstrations") or {}
    return {"env_id": record["env_id"], "algo": record["algo"], "seed": record["seed"],
            "env_steps": curve[-1]["env_steps"], "wall_s": seconds["wall_seconds"],
            "cpu_s": seconds.get("cpu_seconds", 0.0), "episodes": episodes,
            "success": curve[-1]["success"],
            "selected_env_steps": curve[-1]["env_steps"] if selected is None else selected,
            "curve": curve,
            "learner": record.get("learner", "sb3"), "method": method(record),
            "demo_env_steps": demo.get("env_steps", 0), "machine": machine()}


def write_result(folder: Path, env_steps: int, selected: int, final: dict,
                 clock: Clock) -> dict:
    """Write the finished run's ``result.json`` (RESULT_KEYS) from its run.json, its
    evaluations.csv and the final evaluation ``final`` (``success_rate``'s dict) of the policy
    of ``selected`` env steps, last on the curve at the run's ``env_steps``; returns it."""
    record = json.loads((folder / "run.json").read_text())
    seconds = clock.seconds()
    curve = curve_of(folder) + [{"env_steps": env_steps, "wall_s": seconds["wall_seconds"],
                                 "success": final["success_rate"]}]
    result = result_record(record, curve, final["episodes"], seconds, selected)
    (folder / "result.json").write_text(json.dumps(result, indent=1) + "\n")
    return result


class Clock:
    """The wall and CPU seconds a run has spent (training and evaluations), counting those of
    the parts before a resume (``wall``, ``cpu``, s)."""

    def __init__(self, wall: float = 0.0, cpu: float = 0.0):
        self.wall, self.cpu = wall, cpu
        self.start, self.cpu_start = time.perf_counter(), time.process_time()

    def seconds(self) -> dict:
        """{"wall_seconds", "cpu_seconds"}: so far, s (CPU: this process's, what the run costs
        whatever else shares the machine)."""
        return {"wall_seconds": round(self.wall + time.perf_counter() - self.start, 1),
                "cpu_seconds": round(self.cpu + time.process_time() - self.cpu_start, 1)}


def _write_seconds(folder: Path, clock: Clock) -> None:
    record = json.loads((folder / "run.json").read_text())
    record.update(clock.seconds())
    (folder / "run.json").write_text(json.dumps(record, indent=2))


def _count(value, name: str, low: int) -> int:
    return integer(value, f"train: {name}", low)


def add_demonstrations(model, env_id: str, episodes: int, seed: int,
                       progress: bool = False, dataset: str | None = None) -> dict:
    """Put ``episodes`` demonstration episodes into ``model``'s replay buffer, as SB3 stores
    its own transitions, and return ``{"episodes", "env_steps", "success_rate", "dataset"}``.

    The episodes come from a Minari dataset (``rigid_gym.agents.datasets``): ``dataset``, an
    id (its first episodes: env r of the model's n_envs takes the r-th consecutive run of
    ceil(episodes / n_envs) of them), or when None, one written for the call into a temporary
    folder (and deleted after it): the scripted policy (``rigid_gym.envs.scripted``), env r's
    stream of episodes seeded at its first reset with DEMO_SEED + 1000 * seed + r, as a
    stable-baselines3 VecEnv of the model's n_envs made with that seed would play it.

    Demonstrations in the replay buffer (Vecerik et al. 2017, Nair et al. 2018) show a sparse
    reward off-policy learner what success looks like on tasks that random exploration almost
    never solves (Stack); the learner still has to work out the values and the policy itself.
    Their env steps count towards a run's total in the results table. A model with a
    ``make_demo_buffer`` method (bc_sac) also gets them in a buffer of their own, for its
    behaviour-cloning loss. ``progress``: draw a bar of the episodes on standard error.
    """
    from . import datasets

    per_env = -(-episodes // model.n_envs)
    if dataset is not None:
        note(f"{env_id}: demonstrations from the Minari dataset {dataset}", progress)
        return fill_replay_buffer(model, datasets.load(dataset), env_id, episodes) | {
            "dataset": dataset}
    note(f"{env_id}: {per_env * model.n_envs} scripted demonstrations, written as a Minari "
         "dataset to a temporary folder", progress)
    with datasets.temporary_datasets_root():
        seeds = [DEMO_SEED + 1000 * seed + rank for rank in range(model.n_envs)]
        data = datasets.write_streams(f"rigid_gym/{env_id.split('/')[-1]}/demonstrations-v0",
                                      env_id, "scripted", seeds, per_env, progress)
        return fill_replay_buffer(model, data, env_id, episodes) | {"dataset": None}


def fill_replay_buffer(model, dataset, env_id: str, episodes: int) -> dict:
    """Add the first ceil(episodes / n_envs) * n_envs episodes of ``dataset`` (a
    MinariDataset of ``env_id``) to ``model``'s replay buffer (and to a new ``demo_buffer`` if
    the model makes one), env r of the model's n_envs taking the r-th consecutive run of
    ceil(episodes / n_envs), step by step as a VecEnv hands SB3 its transitions (the
    episodes of one step across the envs must be equally long); returns ``{"episodes",
    "env_steps", "success_rate"}``."""
    from . import datasets

    if dataset.env_spec is None or dataset.env_spec.id != env_id:
        raise ValueError(f"train: demonstrations of {env_id} wanted, dataset {dataset.id} is of "
                         f"{dataset.env_spec.id if dataset.env_spec else 'no env'}")
    n_envs = model.n_envs
    per_env = -(-episodes // n_envs)
    if dataset.total_episodes < per_env * n_envs:
        raise ValueError(f"train: {episodes} demonstrations over {n_envs} env(s) take "
                         f"{per_env * n_envs} episodes; dataset {dataset.id} has "
                         f"{dataset.total_episodes}")
    streams = [list(dataset.iterate_episodes(range(r * per_env, (r + 1) * per_env)))
               for r in range(n_envs)]
    buffers = [model.replay_buffer]
    if hasattr(model, "make_demo_buffer"):
        length = gym.spec(env_id).max_episode_steps
        buffers.append(model.make_demo_buffer((episodes + n_envs) * length))
    steps = 0
    for k in range(per_env):
        group = [stream[k] for stream in streams]
        lengths = {len(e) for e in group}
        if len(lengths) != 1:
            raise ValueError(f"train: episodes {[int(e.id) for e in group]} of {dataset.id} go "
                             f"to the envs side by side but differ in length ({sorted(lengths)})")
        for t in range(lengths.pop()):
            obs = {key: np.stack([e.observations[key][t] for e in group]) for key in
                   group[0].observations}
            next_obs = {key: np.stack([e.observations[key][t + 1] for e in group]) for key in
                        group[0].observations}
            actions = np.stack([e.actions[t] for e in group])
            rewards = np.array([e.rewards[t] for e in group], dtype=np.float32)
            terminated = np.array([e.terminations[t] for e in group])
            truncated = np.array([e.truncations[t] for e in group])
            # what SB3's buffers read of a VecEnv's infos (the timeouts; HER keeps the
            # dicts only with copy_info_dict)
            infos = [{"is_success": bool(e.infos["is_success"][t + 1]),
                      "TimeLimit.truncated": bool(truncated[i] and not terminated[i])}
                     for i, e in enumerate(group)]
            for buffer in buffers:
                buffer.add(obs, next_obs, model.policy.scale_action(actions), rewards,
                           terminated | truncated, infos)
            steps += n_envs
    used = [e for stream in streams for e in stream]
    return {"episodes": len(used), "env_steps": steps,
            "success_rate": datasets.success_rate(used)}


def _write_run(folder: Path, env_id, algo, learner, seed, timesteps, n_envs, kwargs, demo,
               env_kwargs, recipe) -> None:
    record = {
        "env_id": env_id, "algo": algo, "learner": learner, "seed": seed, "timesteps": timesteps,
        **({"recipe": recipe} if recipe != algo else {}),
        "env_kwargs": env_kwargs,
        "n_envs": n_envs, "demonstrations": demo, "command": " ".join(sys.argv),
        "kwargs": {k: v if isinstance(v, (int, float, str, dict, list)) else repr(v)
                   for k, v in kwargs.items()},
    }
    (folder / "run.json").write_text(json.dumps(record, indent=2))


class EveryNSteps(BaseCallback):
    """Calls ``act()`` from ``check()`` when the run's env steps have passed a multiple of
    ``every`` since the last time (so a resumed run keeps the cadence); subclasses say what
    ``act`` does and which of SB3's hooks calls ``check``."""

    def __init__(self, every: int):
        super().__init__()
        self.every = every
        self.done_at = 0
        """env steps at the last ``act`` (or at the start of training)"""

    def _on_training_start(self) -> None:
        self.done_at = self.model.num_timesteps

    def check(self) -> None:
        if self.num_timesteps // self.every > self.done_at // self.every:
            self.done_at = self.num_timesteps
            self.act()

    def act(self) -> None:
        raise NotImplementedError


class SuccessEvaluation(EveryNSteps):
    """Every ``every`` env steps, and at the end of training, evaluate the deterministic policy
    on fixed seeds from VALIDATION_SEED (the final evaluation's seeds are touched only by
    ``finish``) and append (timesteps, success_rate, mean_return, wall_seconds of the run)
    to ``path``; ``append``: keep the rows already there (a resumed run); ``progress``: draw
    a bar of each evaluation's episodes."""

    def __init__(self, env_id: str, path: Path, every: int, episodes: int, clock: Clock,
                 append: bool = False, progress: bool = False, env_kwargs: dict | None = None):
        super().__init__(every)
        self.env = gym.make(env_id, **(env_kwargs or {}))
        self.path, self.episodes, self.clock, self.progress = path, episodes, clock, progress
        if not append:
            with open(path, "w", newline="") as f:
                csv.writer(f).writerow(["timesteps", "success_rate", "mean_return",
                                        "wall_seconds"])

    def _on_step(self) -> bool:
        self.check()
        return True

    def _on_training_end(self) -> None:
        if self.done_at != self.num_timesteps:
            self.act()

    def act(self) -> None:
        result = success_rate(self.model, self.env, self.episodes, VALIDATION_SEED,
                              progress=self.progress)
        row = [self.num_timesteps, result["success_rate"], result["mean_return"],
               self.clock.seconds()["wall_seconds"]]
        with open(self.path, "a", newline="") as f:
            csv.writer(f).writerow(row)
        self.logger.record("eval/success_rate", result["success_rate"])


CHECKPOINT_FILES = ("run.json", "evaluations.csv")
"""The run folder's files that a checkpoint copies, as they were at its step."""


class Checkpoints(EveryNSteps):
    """At the first rollout end past every ``every`` env steps (each step for SAC, after
    ``n_steps`` for PPO: the step's transition is in the replay buffer by then), write
    ``folder/checkpoints/step_<timesteps>/``: model.zip, the run's files
    (``CHECKPOINT_FILES``, run.json with the seconds spent so far) and the replay buffer
    (``save_buffers``; off-policy), which only the newest checkpoint keeps. ``on_checkpoint``
    is called with each finished folder."""

    def __init__(self, folder: Path, every: int, clock: Clock,
                 on_checkpoint: Callable[[Path], None] | None = None):
        super().__init__(every)
        self.folder, self.clock, self.on_checkpoint = folder, clock, on_checkpoint
        self.written = -1
        """env steps of the last checkpoint written"""

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        self.check()

    def act(self) -> None:
        self.write()

    def write(self) -> Path:
        """Write the checkpoint of the model as it is now; returns its folder."""
        steps = self.model.num_timesteps
        target = self.folder / "checkpoints" / f"step_{steps}"
        partial = target.with_name(target.name + ".partial")  # a killed write leaves only this
        shutil.rmtree(partial, ignore_errors=True)
        partial.mkdir(parents=True)
        self.model.save(partial / "model.zip")
        save_buffers(self.model, partial)
        for pattern in CHECKPOINT_FILES:
            for path in self.folder.glob(pattern):
                shutil.copy2(path, partial / path.name)
        record = json.loads((partial / "run.json").read_text())
        record.update(self.clock.seconds())
        (partial / "run.json").write_text(json.dumps(record, indent=2))
        shutil.rmtree(target, ignore_errors=True)
        partial.rename(target)
        for older in target.parent.glob("step_*/*_buffer.pkl"):
            if older.parent != target:
                older.unlink()
        self.written = steps
        if self.on_checkpoint is not None:
            self.on_checkpoint(target)
        return target


def latest_checkpoint(folder: str | Path) -> Path | None:
    """The newest complete checkpoint under a run folder (``checkpoints/step_<n>/``), or None."""
    found = [(int(path.name.split("_")[1]), path)
             for path in Path(folder).glob("checkpoints/step_*")
             if path.name.split("_")[1].isdigit() and (path / "model.zip").is_file()]
    return max(found)[1] if found else None


BUFFERS = ("replay_buffer", "demo_buffer")
"""The models' buffers a checkpoint keeps: SB3's replay buffer, bc_sac's demonstrations."""


def _filled(array: np.ndarray, length: int, rows: int) -> np.ndarray:
    """The first ``rows`` of ``array`` if it has a buffer's ``length`` rows, else all of it."""
    return array[:rows] if array.shape[:1] == (length,) else array


def save_buffers(model, folder: Path) -> None:
    """Write each of ``model``'s buffers (``BUFFERS``) that it has to ``folder/<name>.pkl``:
    the filled part of every array of the buffer's length (a 1e6-transition buffer holding
    20k costs 20k rows on disk, not 1e6), the other arrays whole, and ``pos`` and ``full``."""
    for name in BUFFERS:
        buffer = getattr(model, name, None)
        if buffer is None:
            continue
        rows = buffer.buffer_size if buffer.full else buffer.pos
        state = {"capacity": buffer.buffer_size * buffer.n_envs,
                 "buffer_size": buffer.buffer_size, "pos": buffer.pos, "full": buffer.full}
        for key, value in vars(buffer).items():
            if isinstance(value, np.ndarray):
                state[key] = _filled(value, buffer.buffer_size, rows)
            elif isinstance(value, dict) and value and all(
                    isinstance(v, np.ndarray) for v in value.values()):
                state[key] = {k: _filled(v, buffer.buffer_size, rows) for k, v in value.items()}
        with open(folder / f"{name}.pkl", "wb") as f:
            pickle.dump(state, f, protocol=pickle.HIGHEST_PROTOCOL)


def load_buffers(model, folder: Path) -> None:
    """Fill ``model``'s buffers from ``save_buffers``' files in ``folder`` (a bc_sac model's
    demonstration buffer is made first). An episode that the checkpoint cut short ends there
    (HER's ``truncate_last_trajectory``): the resumed run's envs start new ones."""
    for name in BUFFERS:
        path = folder / f"{name}.pkl"
        if not path.is_file():
            if name == "replay_buffer" and hasattr(model, name):  # off-policy: it needs one
                raise ValueError(f"train: {folder} has no replay buffer (only the newest "
                                 "checkpoint of a run keeps it); resume from that one")
            continue
        with open(path, "rb") as f:
            state = pickle.load(f)
        capacity = state.pop("capacity")  # transitions over all envs, as buffers are made
        if name == "demo_buffer":
            model.make_demo_buffer(capacity)
        buffer = getattr(model, name)
        if buffer.buffer_size != state["buffer_size"]:
            raise ValueError(f"train: {path} holds a buffer of {state['buffer_size']} rows, "
                             f"the model's has {buffer.buffer_size}")
        for key, value in state.items():
            target = getattr(buffer, key)
            if isinstance(value, dict):
                for k, v in value.items():
                    target[k][:len(v)] = v
            elif isinstance(value, np.ndarray) and target.shape != value.shape:
                target[:len(value)] = value
            else:
                setattr(buffer, key, value)
        if hasattr(buffer, "truncate_last_trajectory"):
            with warnings.catch_warnings():  # its warning is about SB3's own loading
                warnings.simplefilter("ignore")
                buffer.truncate_last_trajectory()


def _restore_files(checkpoint: Path, folder: Path, env_id: str, recipe: str, seed: int) -> dict:
    """Put a checkpoint's copies of the run's files back in the run folder (rows written after
    it are dropped) and return its run.json, checked to be of this env, recipe and seed."""
    meta = checkpoint / "run.json"
    if not (meta.is_file() and (checkpoint / "model.zip").is_file()):
        raise ValueError(f"train: {checkpoint} is not a checkpoint (model.zip and run.json); "
                         "latest_checkpoint(run folder) finds the newest")
    record = json.loads(meta.read_text())
    found = (record["env_id"], record.get("recipe", record["algo"]), record["seed"])
    if found != (env_id, recipe, seed):
        raise ValueError(f"train: {checkpoint} is a checkpoint of env, recipe, seed {found}, "
                         f"not {(env_id, recipe, seed)}")
    for pattern in CHECKPOINT_FILES:
        for path in checkpoint.glob(pattern):
            if path.parent.resolve() != folder.resolve():
                shutil.copy2(path, folder / path.name)
    return record
