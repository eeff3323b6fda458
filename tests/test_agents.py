"""Smoke tests of the baselines: each task trains for a few hundred steps and is evaluated."""

import csv
import json

import gymnasium as gym
import pytest

from rigid_gym.agents.evaluate import evaluate, load_model
from rigid_gym.agents.train import load_hyperparams, train


@pytest.mark.parametrize("env_id", ["rigid_gym/Push-v0", "rigid_gym/Stack-v0",
                                    "rigid_gym/Throw-v0", "rigid_gym/PushDense-v0"])
def test_a_short_run_trains_saves_and_evaluates(env_id, tmp_path):
    settings = load_hyperparams(env_id)
    # HER samples only from finished episodes: learning starts after the first one
    start = gym.spec(env_id).max_episode_steps + 10
    small = {"learning_starts": start, "batch_size": 32} if settings["algo"] != "ppo" else \
        {"n_steps": 50, "batch_size": 50}
    steps = start + 40
    folder = train(env_id, timesteps=steps, n_envs=2 if settings["algo"] == "ppo" else 1,
                   out=tmp_path, eval_freq=steps // 2, eval_episodes=1, overrides=small)
    run = json.loads((folder / "run.json").read_text())
    assert run["env_id"] == env_id and run["algo"] == settings["algo"]
    with open(folder / "evaluations.csv") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["timesteps"]) for r in rows] == [steps // 2 * k for k in (1, 2)]
    assert all(0.0 <= float(r["success_rate"]) <= 1.0 for r in rows)
    result = evaluate(folder / "model.zip", episodes=1)
    assert result["env_id"] == env_id and result["episodes"] == 1
    assert load_model(folder / "model.zip", gym.make(env_id)).num_timesteps == steps


def test_bad_arguments_are_refused(tmp_path):
    with pytest.raises(ValueError, match="no settings for"):
        train("rigid_gym/Nope-v0", out=tmp_path)
    with pytest.raises(ValueError, match="algo must be one of"):
        train("rigid_gym/Push-v0", algo="dqn", out=tmp_path)
    with pytest.raises(ValueError, match="timesteps must be an int >= 1"):
        train("rigid_gym/Push-v0", timesteps=0, out=tmp_path)
    with pytest.raises(ValueError, match="no model file"):
        evaluate(tmp_path / "missing.zip", env_id="rigid_gym/Push-v0")
