"""Pixel SAC + HER with no privileged state (rigid_gym.agents.pixel_sac): the replay buffer's
hindsight goals and rewards, the acting policy's export, and a tiny run that trains, resumes,
evaluates and records."""

import json

import gymnasium as gym
import numpy as np
import torch
from rigid_gym.agents.distill import DistilledPolicy, observation_kwargs, student_inputs
from rigid_gym.agents.evaluate import evaluate
from rigid_gym.agents.pixel_sac import EpisodeBuffer, acting_policy, make_networks
from rigid_gym.agents.train import RESULT_KEYS, train

from rigid_gym.cli import main

PUSH = "rigid_gym/Push-v0"
TINY = {"n_envs": 2, "learning_starts": 0, "gradient_steps": 1, "batch_size": 8,
        "eval_every": 100, "network": {"channels": 4, "features": 8, "hidden": 16}}
"""Rounds of one 50-step episode in 2 envs, an update a vector step: the loop, not the
learning."""


def test_hindsight_goals_are_later_achieved_goals_with_the_env_s_reward():
    steps, env = 10, gym.make(PUSH).unwrapped
    buffer = EpisodeBuffer(capacity=2, steps=steps, size=4, proprio=1, goal=3, action=1)
    achieved = np.zeros((3, steps + 1, 3), np.float32)
    achieved[:, :, 0] = np.arange(steps + 1)  # 1 m apart: a goal is reached at one step only
    achieved[:, :, 1] = np.arange(3)[:, None] * 100  # and each episode has its own
    episodes = {"frames": np.zeros((3, steps + 1, 4, 4, 3), np.uint8),
                "proprio": np.arange(3 * (steps + 1), dtype=np.float32).reshape(3, -1, 1),
                "achieved": achieved, "goal": np.full((3, 3), -50.0, np.float32),
                "actions": np.zeros((3, steps, 1), np.float32)}
    buffer.add(episodes)  # 3 episodes into a ring of 2: the first is overwritten
    assert buffer.count == 2 and buffer.achieved[0, 0, 1] == 200
    _, _, vectors, next_vectors, _, rewards = buffer.sample(
        2000, 4, np.random.default_rng(0), env.compute_reward)
    goals, proprio, next_proprio = vectors[:, :3], vectors[:, 3], next_vectors[:, 3]
    np.testing.assert_array_equal(next_vectors[:, :3], goals)
    np.testing.assert_array_equal(next_proprio, proprio + 1)  # step t's successor
    original = goals[:, 0] == -50
    assert 0.15 < original.mean() < 0.25  # 1 in her_k + 1 keeps its goal
    episode = (proprio // (steps + 1)).astype(int)  # 1 or 2
    t = (proprio % (steps + 1)).astype(int)
    future = goals[~original, 0].astype(int)
    assert np.all(goals[~original, 1] == 100 * episode[~original])  # its own episode's
    assert np.all((future > t[~original]) & (future <= steps))  # a later step's
    expected = np.where(~original & (goals[:, 0] == t + 1), 0.0, -1.0)
    np.testing.assert_array_equal(rewards, expected)
    assert (rewards == 0).any()


def test_the_acting_policy_is_the_actor_s_mean_on_the_critic_s_encoder():
    index = np.arange(6)
    config = {"size": 48, "vector_size": 9, "action_size": 3,
              "proprioception_index": index.tolist(),
              "network": {"channels": 4, "features": 8, "hidden": 16, "located": 0}}
    torch.manual_seed(0)
    critic, actor = make_networks(48, 9, 3, channels=4, features=8, hidden=16)
    policy = acting_policy(critic, actor, config)
    obs = gym.make_vec(PUSH, num_envs=3, **observation_kwargs(48)).reset(seed=0)[0]
    frames, vector = student_inputs(obs, index)
    with torch.no_grad():
        mean, _ = actor(critic.encode(torch.from_numpy(frames).float()),
                        torch.from_numpy(vector))
    np.testing.assert_allclose(policy.predict(obs)[0], torch.tanh(mean).numpy(), atol=1e-6)
    assert not hasattr(policy.network, "locator")


def test_pixel_sac_trains_resumes_evaluates_and_records(tmp_path, capsys):
    out, results = tmp_path / "runs", tmp_path / "results"
    folder = train(PUSH, obs_mode="pixels", algo="drq", timesteps=100, out=out,
                   eval_episodes=2, overrides=TINY, final_episodes=0)
    assert folder.name == "Push-drq-seed0" and not (folder / "result.json").exists()
    assert sorted(p.name for p in (folder / "checkpoints").iterdir()) == [
        "buffer_0.npz", "latest.pt", "student_1.zip"]
    saved = np.load(folder / "checkpoints" / "buffer_0.npz")
    assert saved["frames"].shape == (2, 51, 48, 48, 3) and saved["frames"].dtype == np.uint8
    assert saved["proprio"].shape == (2, 51, 6) and saved["actions"].shape == (2, 50, 3)
    first = json.loads((folder / "run.json").read_text())
    assert first["obs_mode"] == "pixels" and first["inputs"]["vector"] == [
        "desired_goal", "pad.position", "pad.velocity"]
    # the episodes of rounds that latest.pt does not count (a stop while they were written)
    (folder / "checkpoints" / "buffer_1.npz").write_bytes(b"cut short")
    folder = train(PUSH, obs_mode="pixels", algo="drq", timesteps=200, out=out,
                   eval_episodes=2, overrides=TINY, final_episodes=2, results=results,
                   resume=True)
    assert (folder / "checkpoints" / "buffer_1.npz").is_file()
    assert json.loads((folder / "run.json").read_text())["resumed_at"] == [100]
    result = json.loads((results / "Push-drq-seed0.json").read_text())
    assert set(RESULT_KEYS) <= set(result) and result["obs_mode"] == "pixels"
    assert (result["algo"], result["env_steps"], result["episodes"]) == ("drq", 200, 2)
    assert [p["env_steps"] for p in result["curve"]] == [100, 200, 200]
    assert result["cpu_s"] > first["cpu_seconds"] > 0
    assert isinstance(DistilledPolicy.load(folder / "model.zip"), DistilledPolicy)
    assert evaluate(folder / "model.zip", episodes=1)["episodes"] == 1
    assert main(["record", PUSH, "--policy", str(folder / "model.zip"), "--out",
                 str(tmp_path / "rec")]) == 0
    assert "episode 0: 50 steps" in capsys.readouterr().out
