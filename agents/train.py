"""Train a stable-baselines3 baseline on a rigid_gym task.

    from rigid_gym.agents.train import train
    run = train("rigid_gym/Push-v0", seed=0)            # settings from hyperparams.yml

    rigid-gym train rigid_gym/Push-v0 --seed 0 --steps 200000 --progress-bar

A run writes one folder, ``<out>/<task>/<algo>-seed<seed>/``:

    model.zip           the final policy (``rigid-gym evaluate`` loads it)
    run.json            env id, algorithm, seed, budget, settings, the command line, and after
                        training wall_seconds and cpu_seconds (this process's CPU time)
    evaluations.csv     timesteps, success_rate, mean_return: deterministic episodes on fixed
                        seeds, every ``eval_freq`` steps (the learning curve)
    checkpoints/        model_<steps>_steps.zip every ``checkpoint_freq`` steps (if set)
    monitor.csv         every training episode: return, length, is_success
"""

from __future__ import annotations

import csv
import json
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import yaml

from stable_baselines3.common.callbacks import BaseCallback, CallbackList, CheckpointCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import VecCheckNan

import rigid_gym  # noqa: F401  (registers the env ids)
from rigid_gym.agents.evaluate import success_rate

HYPERPARAMS = Path(__file__).with_name("hyperparams.yml")
ALGORITHMS = ("sac", "tqc", "ppo", "bc_sac")
DEMO_SEED = 2_000_000
"""Demonstration episodes use seeds DEMO_SEED + 1000 * seed + rank, apart from the training seeds
(small) and the evaluation seeds (``EVAL_SEED`` = 1,000,000 onwards)."""


def load_hyperparams(env_id: str) -> dict:
    """The settings for ``env_id`` from hyperparams.yml."""
    table = yaml.safe_load(HYPERPARAMS.read_text())
    if env_id not in table:
        raise ValueError(f"train: no settings for {env_id!r} in {HYPERPARAMS.name}; "
                         f"known ids: {sorted(table)}")
    return table[env_id]


def algorithm_class(name: str):
    """The SB3 class for ``name`` (sac, tqc, ppo, or bc_sac: SAC with a behaviour-cloning loss
    on the demonstrations, ``rigid_gym.agents.bc_sac``)."""
    if name == "bc_sac":
        from rigid_gym.agents.bc_sac import BCSAC
        return BCSAC
    if name == "sac":
        from stable_baselines3 import SAC
        return SAC
    if name == "ppo":
        from stable_baselines3 import PPO
        return PPO
    if name == "tqc":
        try:
            from sb3_contrib import TQC
        except ImportError as exc:
            raise ValueError("train: algo 'tqc' needs sb3-contrib (pip install -e '.[train]')"
                             ) from exc
        return TQC
    raise ValueError(f"train: algo must be one of {ALGORITHMS}, got {name!r}")


def run_directory(out: Path, env_id: str, algo: str, seed: int) -> Path:
    task = env_id.split("/")[-1]
    return Path(out) / task / f"{algo}-seed{seed}"


def train(env_id: str, *, algo: str | None = None, timesteps: int | None = None, seed: int = 0,
          n_envs: int | None = None, out: str | Path = "runs", eval_freq: int = 10_000,
          eval_episodes: int = 20, checkpoint_freq: int = 0, progress_bar: bool = False,
          threads: int = 1, verbose: int = 0, overrides: dict | None = None,
          demonstrations: int | None = None) -> Path:
    """Train on ``env_id`` and return the run folder (see the module docstring).

    algo, timesteps (env steps), n_envs: override hyperparams.yml. eval_freq: env steps between
    evaluations of ``eval_episodes`` deterministic episodes (0: none). checkpoint_freq: env
    steps between saved checkpoints (0: none). threads: PyTorch's CPU threads. overrides:
    algorithm arguments that replace those of hyperparams.yml (e.g. learning_starts).
    demonstrations: scripted episodes put in the replay buffer before training (off-policy
    only; default: hyperparams.yml's ``demonstrations``, else 0), see ``add_demonstrations``.
    """
    import torch

    settings = load_hyperparams(env_id)
    algo = algo or settings["algo"]
    cls = algorithm_class(algo)
    timesteps = _count(timesteps if timesteps is not None else settings["n_timesteps"],
                       "timesteps", 1)
    n_envs = _count(n_envs if n_envs is not None else settings.get("n_envs", 1), "n_envs", 1)
    seed = _count(seed, "seed", 0)
    for name, value in (("eval_freq", eval_freq), ("eval_episodes", eval_episodes),
                        ("checkpoint_freq", checkpoint_freq)):
        _count(value, name, 0)
    torch.set_num_threads(_count(threads, "threads", 1))

    folder = run_directory(out, env_id, algo, seed)
    folder.mkdir(parents=True, exist_ok=True)
    env = make_vec_env(env_id, n_envs=n_envs, seed=seed, monitor_dir=str(folder),
                       monitor_kwargs={"info_keywords": ("is_success",)})
    env = VecCheckNan(env, raise_exception=True)  # a diverging network fails where it starts
    kwargs = {**settings.get("kwargs", {}), **(overrides or {})}
    if algo != "ppo" and "her" in settings:
        from stable_baselines3 import HerReplayBuffer
        kwargs.update(replay_buffer_class=HerReplayBuffer,
                      replay_buffer_kwargs=dict(settings["her"]))
    model = cls("MultiInputPolicy", env, seed=seed, verbose=verbose, **kwargs)
    demonstrations = _count(demonstrations if demonstrations is not None
                            else settings.get("demonstrations", 0), "demonstrations", 0)
    if demonstrations and algo == "ppo":
        raise ValueError("train: demonstrations fill a replay buffer; ppo has none")
    demo = add_demonstrations(model, env_id, demonstrations, seed) if demonstrations else None
    _write_run(folder, env_id, algo, seed, timesteps, n_envs, kwargs, demo)

    callbacks = []
    if eval_freq:
        callbacks.append(SuccessEvaluation(env_id, folder / "evaluations.csv",
                                           eval_freq // n_envs or 1, eval_episodes))
    if checkpoint_freq:
        callbacks.append(CheckpointCallback(checkpoint_freq // n_envs or 1,
                                            str(folder / "checkpoints"), name_prefix="model"))
    start, cpu_start = time.perf_counter(), time.process_time()
    model.learn(timesteps, callback=CallbackList(callbacks), progress_bar=progress_bar)
    model.save(folder / "model.zip")
    env.close()
    record = json.loads((folder / "run.json").read_text())
    record["wall_seconds"] = round(time.perf_counter() - start, 1)  # training and evaluations
    # this process's CPU time: what the run costs whatever else shares the machine
    record["cpu_seconds"] = round(time.process_time() - cpu_start, 1)
    (folder / "run.json").write_text(json.dumps(record, indent=2))
    return folder


def _count(value, name: str, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise ValueError(f"train: {name} must be an int >= {low}, got {value!r}")
    return int(value)


def add_demonstrations(model, env_id: str, episodes: int, seed: int) -> dict:
    """Put ``episodes`` episodes of the scripted policy (``rigid_gym.envs.scripted``) into
    ``model``'s replay buffer, as SB3 stores its own transitions, and return
    ``{"episodes", "env_steps", "success_rate"}``.

    Demonstrations in the replay buffer (Vecerik et al. 2017, Nair et al. 2018) show a sparse
    reward off-policy learner what success looks like on tasks that random exploration almost
    never solves (Stack); the learner still has to work out the values and the policy itself.
    Their env steps count towards a run's total in the results table. A model with a
    ``make_demo_buffer`` method (bc_sac) also gets them in a buffer of their own, for its
    behaviour-cloning loss.
    """
    from rigid_gym.envs.scripted import scripted_policy

    n_envs = model.n_envs
    env = make_vec_env(env_id, n_envs=n_envs, seed=DEMO_SEED + 1000 * seed)
    policies = [scripted_policy(e) for e in env.envs]
    obs = env.reset()
    buffers = [model.replay_buffer]
    if hasattr(model, "make_demo_buffer"):
        length = gym.spec(env_id).max_episode_steps
        buffers.append(model.make_demo_buffer((episodes + n_envs) * length))
    finished, successes, steps = 0, 0.0, 0
    while finished < episodes:
        actions = np.stack([policy({key: value[i] for key, value in obs.items()})
                            for i, policy in enumerate(policies)]).astype(np.float32)
        next_obs, rewards, dones, infos = env.step(actions)
        stored = {key: value.copy() for key, value in next_obs.items()}
        for i in np.flatnonzero(dones):  # the VecEnv has reset these; store the true last obs
            for key in stored:
                stored[key][i] = infos[i]["terminal_observation"][key]
            successes += infos[i]["is_success"]
        for buffer in buffers:
            buffer.add(obs, stored, model.policy.scale_action(actions), rewards, dones, infos)
        obs, finished, steps = next_obs, finished + int(dones.sum()), steps + n_envs
    env.close()
    return {"episodes": finished, "env_steps": steps, "success_rate": successes / finished}


def _write_run(folder: Path, env_id, algo, seed, timesteps, n_envs, kwargs, demo) -> None:
    record = {
        "env_id": env_id, "algo": algo, "seed": seed, "timesteps": timesteps,
        "n_envs": n_envs, "demonstrations": demo, "command": " ".join(sys.argv),
        "kwargs": {k: v if isinstance(v, (int, float, str, dict, list)) else repr(v)
                   for k, v in kwargs.items()},
    }
    (folder / "run.json").write_text(json.dumps(record, indent=2))


class SuccessEvaluation(BaseCallback):
    """Every ``every`` calls (env steps / n_envs), evaluate the deterministic policy on fixed
    seeds and append (timesteps, success_rate, mean_return, wall_seconds) to ``path``."""

    def __init__(self, env_id: str, path: Path, every: int, episodes: int):
        super().__init__()
        self.env = gym.make(env_id)
        self.env_id, self.path, self.every, self.episodes = env_id, path, every, episodes
        self.start = time.perf_counter()
        with open(path, "w", newline="") as f:
            csv.writer(f).writerow(["timesteps", "success_rate", "mean_return", "wall_seconds"])

    def _on_step(self) -> bool:
        if self.n_calls % self.every == 0:
            self.write()
        return True

    def _on_training_end(self) -> None:
        if self.n_calls % self.every != 0:
            self.write()

    def write(self) -> None:
        result = success_rate(self.model, self.env, self.episodes)
        row = [self.num_timesteps, result["success_rate"], result["mean_return"],
               round(time.perf_counter() - self.start, 1)]
        with open(self.path, "a", newline="") as f:
            csv.writer(f).writerow(row)
        self.logger.record("eval/success_rate", result["success_rate"])
