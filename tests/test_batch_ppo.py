"""The batch learner (agents/batch_ppo.py): PPO in JAX over the batched env, saving SB3 zips."""

import json

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("jax")
pytest.importorskip("optax")

from rigid_gym.agents.batch_ppo import BatchPPO, flatten
from rigid_gym.agents.evaluate import evaluate, load_model
from rigid_gym.agents.train import latest_checkpoint, train

SMALL = {"n_steps": 8, "batch_size": 16, "n_epochs": 2, "policy_kwargs": {"net_arch": [16]}}
"""A tiny setting: rollouts of 8 steps x 4 copies, two minibatches of 16 a pass."""


def ends(envs, steps):
    """The steps (1-based) at which each copy's first episode was truncated."""
    envs.reset(seed=0)
    first = np.zeros(envs.num_envs, dtype=int)
    for t in range(1, steps + 1):
        _, _, _, truncated, _ = envs.step(np.zeros((envs.num_envs, 3), np.float32))
        first[(first == 0) & truncated] = t
    return first


def test_staggered_copies_end_their_first_episodes_apart():
    plain = gym.make_vec("rigid_gym/Push-v0", num_envs=4, max_episode_steps=8)
    staggered = gym.make_vec("rigid_gym/Push-v0", num_envs=4, max_episode_steps=8,
                             stagger=True)
    assert ends(plain, 8).tolist() == [8, 8, 8, 8]
    assert ends(staggered, 8).tolist() == [8, 6, 4, 2]
    # from then on every episode is whole: copy 1 ends again 8 steps after its first end
    staggered.reset(seed=0)
    truncations = [staggered.step(np.zeros((4, 3), np.float32))[3][1] for _ in range(14)]
    assert np.flatnonzero(truncations).tolist() == [5, 13]


def test_the_saved_zip_is_an_sb3_ppo_acting_as_the_learner(tmp_path):
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=4, reward_type="shaped", stagger=True)
    model = BatchPPO("MultiInputPolicy", envs, seed=3, **SMALL)
    model.learn(64)  # two rollouts: two updates, and observation statistics that are not 0, 1
    assert model.num_timesteps == 64 and model.obs_count == 64
    assert not np.allclose(model.obs_mean, 0.0)
    model.save(tmp_path / "model.zip")
    env = gym.make("rigid_gym/Push-v0")
    loaded = load_model(tmp_path / "model.zip", env)
    assert type(loaded).__name__ == "PPO" and loaded.num_timesteps == 64
    observation, _ = env.reset(seed=5)
    for _ in range(5):  # the normalisation folded into the first layers acts the same
        ours = model.predict(observation)[0]
        theirs = loaded.predict(observation, deterministic=True)[0]
        np.testing.assert_allclose(theirs, ours, atol=1e-5)
        observation, *_ = env.step(ours)
    batch = {k: np.stack([v, v]) for k, v in observation.items()}
    assert model.predict(batch)[0].shape == (2, 3)
    # the training state travels in the zip: the loaded learner goes on where it stopped
    again = BatchPPO.load(tmp_path / "model.zip", envs)
    assert again.num_timesteps == 64 and again.settings() == model.settings()
    np.testing.assert_array_equal(again.obs_var, model.obs_var)
    np.testing.assert_array_equal(again.predict(observation)[0], model.predict(observation)[0])


def test_flatten_follows_the_dict_spaces_order():
    observation = {"achieved_goal": np.ones((2, 3)), "desired_goal": np.full((2, 3), 2.0),
                   "observation": np.zeros((2, 4))}
    flat = flatten(observation, ("achieved_goal", "desired_goal", "observation"))
    assert flat.dtype == np.float32 and flat[0].tolist() == [1, 1, 1, 2, 2, 2, 0, 0, 0, 0]


def test_a_batch_run_checkpoints_resumes_and_is_evaluated(tmp_path):
    seen = []
    common = {"algo": "ppo", "out": tmp_path, "n_envs": 4, "eval_freq": 32,
              "eval_episodes": 1, "checkpoint_freq": 32, "final_episodes": 2,
              "results": tmp_path / "results"}
    stopped = train("rigid_gym/Push-v0", timesteps=64, overrides=SMALL,
                    on_checkpoint=seen.append, **common)
    run = json.loads((stopped / "run.json").read_text())
    assert (run["learner"], run["n_envs"], run["env_kwargs"]) == (
        "batch", 4, {"reward_type": "shaped"})
    assert [p.name for p in seen] == ["step_32", "step_64"]
    # resumed to a larger budget from the newest checkpoint: the curve and the steps go on
    folder = train("rigid_gym/Push-v0", timesteps=128, resume=latest_checkpoint(stopped),
                   **common)
    assert folder == stopped
    result = json.loads((tmp_path / "results" / "Push-ppo-seed0.json").read_text())
    assert [p["env_steps"] for p in result["curve"]] == [32, 64, 96, 128, 128]
    assert result["learner"] == "batch" and result["method"] == "PPO, shaped reward"
    assert json.loads((folder / "run.json").read_text())["resumed_at"] == [64]
    assert result["selected_env_steps"] in (64, 96, 128)
    assert load_model(folder / "model.zip", gym.make("rigid_gym/Push-v0")).num_timesteps == 128
    figures = evaluate(folder / "selected_model.zip", episodes=2)
    assert figures["success_rate"] == result["success"]


def test_bad_settings_are_refused():
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=2)
    with pytest.raises(ValueError, match="shorter than one minibatch"):
        BatchPPO("MultiInputPolicy", envs, n_steps=4, batch_size=16)
    with pytest.raises(ValueError, match="net_arch"):
        BatchPPO("MultiInputPolicy", envs, n_steps=8, batch_size=16,
                 policy_kwargs={"net_arch": {"pi": [8]}})
    with pytest.raises(ValueError, match="MultiInputPolicy"):
        BatchPPO("MlpPolicy", envs)
    with pytest.raises(ValueError, match="batch learner trains ppo only"):
        train("rigid_gym/Push-v0", algo="sac", learner="batch", timesteps=10)


def test_advantages_are_gae_cut_at_the_episodes_ends():
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=1)
    model = BatchPPO("MultiInputPolicy", envs, n_steps=16, batch_size=16, gamma=0.5,
                     gae_lambda=0.5)
    # one copy, three steps; the episode ends at the second (its bootstrap, if truncated,
    # is already in that step's reward), so the third's value does not reach back past it
    buffers = {"rewards": np.array([[1.0], [2.0], [4.0]], np.float32),
               "values": np.array([[0.5], [1.0], [2.0]], np.float32),
               "dones": np.array([[False], [True], [False]])}
    last = np.array([8.0], np.float32)
    d2 = 4.0 + 0.5 * 8.0 - 2.0          # step 3: delta, bootstrapped from the last value
    d1 = 2.0 - 1.0                      # step 2: the end, no next value
    d0 = 1.0 + 0.5 * 1.0 - 0.5          # step 1: next value 1.0, then GAE adds step 2's
    expected = [d0 + 0.25 * d1, d1, d2]
    np.testing.assert_allclose(model.advantages(buffers, last)[:, 0], expected)
