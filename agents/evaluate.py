"""Evaluate a trained baseline: success rate and returns over seeded episodes.

    from rigid_gym.agents.evaluate import evaluate
    evaluate("runs/Push/tqc-seed0/model.zip", episodes=100)

    rigid-gym evaluate runs/Push/tqc-seed0/model.zip --episodes 100

The env id and algorithm come from the run's ``run.json`` beside the model, or are given.
"""

from __future__ import annotations

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


def load_model(path: str | Path, env_id: str | None = None, algo: str | None = None):
    """Load an SB3 model zip for ``env_id`` (HER models need their env to load); env_id and
    algo default to run.json beside the model, algo then to the policy class in the zip."""
    from rigid_gym.agents.train import algorithm_class

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"evaluate: no model file at {path}")
    env_id = env_id or run_metadata(path).get("env_id")
    if env_id is None:
        raise ValueError(f"evaluate: no run.json beside {path}; pass the env id")
    cls = algorithm_class(algo or _recorded_algo(path))
    return cls.load(path, env=gym.make(env_id), device="cpu")


def run_metadata(path: Path) -> dict:
    """run.json beside a model, or {} when there is none."""
    meta = Path(path).with_name("run.json")
    return json.loads(meta.read_text()) if meta.is_file() else {}


def _recorded_algo(path: Path) -> str:
    algo = run_metadata(path).get("algo")
    if algo:
        return algo
    with zipfile.ZipFile(path) as archive:
        module = json.loads(archive.read("data"))["policy_class"]["__module__"]
    for name in ("sac", "tqc", "ppo"):
        if f".{name}." in module:
            return name
    raise ValueError(f"evaluate: cannot tell the algorithm of {path} (policy from {module}); "
                     "pass algo=")


def evaluate(model_path: str | Path, env_id: str | None = None, episodes: int = 100,
             seed: int = EVAL_SEED, algo: str | None = None, deterministic: bool = True) -> dict:
    """Success rate and returns of a saved model over ``episodes`` seeded episodes."""
    env_id = env_id or run_metadata(Path(model_path)).get("env_id")
    model = load_model(model_path, env_id, algo)
    result = success_rate(model, gym.make(env_id), episodes, seed, deterministic)
    return {"env_id": env_id, **result}
