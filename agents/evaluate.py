"""Evaluate a trained baseline: success rate and returns over seeded episodes.

    from rigid_gym.agents.evaluate import evaluate
    evaluate("runs/Push/tqc-seed0/model.zip", episodes=100)

    rigid-gym evaluate runs/Push/tqc-seed0/model.zip --episodes 100

The env id and algorithm come from the run's ``run.json`` beside the model, or are given.
"""

from __future__ import annotations

import importlib
import json
import zipfile
from pathlib import Path

import gymnasium as gym
import numpy as np

import rigid_gym  # noqa: F401  (registers the env ids)

EVAL_SEED = 1_000_000
"""Evaluation episodes use seeds EVAL_SEED, EVAL_SEED + 1, ...; training uses small seeds."""


def success_rate(model, env: gym.Env, episodes: int, seed: int = EVAL_SEED,
                 deterministic: bool = True) -> dict:
    """Run ``model`` for ``episodes`` episodes of ``env`` on seeds ``seed``, ``seed + 1``, ...
    Success is ``info["is_success"]`` at an episode's end. Returns episodes, success_rate,
    mean_return and std_return."""
    successes, returns = [], []
    for k in range(episodes):
        obs, info = env.reset(seed=seed + k)
        total, done = 0.0, False
        while not done:
            action, _ = model.predict(obs, deterministic=deterministic)
            obs, reward, terminated, truncated, info = env.step(action)
            total += float(reward)
            done = terminated or truncated
        successes.append(float(info["is_success"]))
        returns.append(total)
    return {"episodes": episodes, "success_rate": float(np.mean(successes)),
            "mean_return": float(np.mean(returns)), "std_return": float(np.std(returns))}


SB3_PACKAGES = ("stable_baselines3", "sb3_contrib")
"""Where algorithm classes (SAC, TQC, PPO, ...) are looked up."""


def load_model(path: str | Path, env: gym.Env, algo: str | None = None):
    """Load a stable-baselines3 model zip for ``env`` (HER models need their env to load).
    ``algo``: a class name (SAC, TQC, PPO, ...), default read from the zip
    (:func:`algorithm_of`)."""
    if not Path(path).is_file():
        raise ValueError(f"load_model: no model file at {path}")
    name = algo or algorithm_of(path)
    for package in SB3_PACKAGES:
        try:
            module = importlib.import_module(package)
        except ImportError:
            continue
        found = [attr for attr in dir(module) if attr.lower() == name.lower()]
        if found:
            try:
                return getattr(module, found[0]).load(path, env=env, device="cpu")
            except ValueError as exc:  # spaces that differ from the env's
                raise ValueError(f"load_model: {path} does not fit "
                                 f"{env.unwrapped.spec.id}: {exc}") from None
    raise ValueError(f"load_model: no algorithm {name!r} in {' or '.join(SB3_PACKAGES)} (pip "
                     "install stable-baselines3 sb3-contrib); pass a class name such as SAC")


def algorithm_of(path: str | Path) -> str:
    """The algorithm of a stable-baselines3 zip, from its policy class's module
    (``stable_baselines3.sac.policies`` -> ``sac``); PPO and A2C share
    ``stable_baselines3.common.policies`` and only PPO saves a ``clip_range``."""
    try:
        with zipfile.ZipFile(path) as archive:
            data = json.loads(archive.read("data"))
        module = data["policy_class"]["__module__"].split(".")
        if module[1] == "common":
            return "PPO" if "clip_range" in data else "A2C"
        return module[1]
    except (zipfile.BadZipFile, KeyError, ValueError, IndexError) as exc:
        raise ValueError(f"load_model: {path} is not a stable-baselines3 model zip whose "
                         f"algorithm can be read ({exc}); pass the algorithm") from None


def run_metadata(path: Path) -> dict:
    """run.json beside a model, or {} when there is none."""
    meta = Path(path).with_name("run.json")
    return json.loads(meta.read_text()) if meta.is_file() else {}


def evaluate(model_path: str | Path, env_id: str | None = None, episodes: int = 100,
             seed: int = EVAL_SEED, algo: str | None = None, deterministic: bool = True) -> dict:
    """Success rate and returns of a saved model over ``episodes`` seeded episodes."""
    env_id = env_id or run_metadata(Path(model_path)).get("env_id")
    if env_id is None:
        raise ValueError(f"evaluate: no run.json beside {model_path}; pass the env id")
    env = gym.make(env_id)
    model = load_model(model_path, env, algo)
    result = success_rate(model, env, episodes, seed, deterministic)
    return {"env_id": env_id, **result}
