"""Smoke tests of the baselines: each task trains for a few hundred steps and is evaluated."""

import csv
import json

import gymnasium as gym
import numpy as np
import pytest

from rigid_gym.agents.evaluate import evaluate, load_model
from rigid_gym.agents.train import DEMO_SEED, add_demonstrations, load_hyperparams, train
from rigid_gym.envs.scripted import scripted_policy


@pytest.mark.parametrize("env_id", ["rigid_gym/Push-v0", "rigid_gym/Stack-v0",
                                    "rigid_gym/Throw-v0", "rigid_gym/PushDense-v0"])
def test_a_short_run_trains_saves_and_evaluates(env_id, tmp_path):
    settings = load_hyperparams(env_id)
    # HER samples only from finished episodes: learning starts after the first one
    start = gym.spec(env_id).max_episode_steps + 10
    small = {"learning_starts": start, "batch_size": 32} if settings["algo"] != "ppo" else \
        {"n_steps": 50, "batch_size": 50}
    steps = start + 40
    demos = 1 if settings.get("demonstrations") else 0  # one, not hyperparams.yml's hundreds
    folder = train(env_id, timesteps=steps, n_envs=2 if settings["algo"] == "ppo" else 1,
                   out=tmp_path, eval_freq=steps // 2, eval_episodes=1, overrides=small,
                   demonstrations=demos)
    run = json.loads((folder / "run.json").read_text())
    assert run["env_id"] == env_id and run["algo"] == settings["algo"]
    assert (run["demonstrations"] or {"episodes": 0})["episodes"] == demos
    assert 0 < run["cpu_seconds"] and 0 < run["wall_seconds"]
    with open(folder / "evaluations.csv") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["timesteps"]) for r in rows] == [steps // 2 * k for k in (1, 2)]
    assert all(0.0 <= float(r["success_rate"]) <= 1.0 for r in rows)
    result = evaluate(folder / "model.zip", episodes=1)
    assert result["env_id"] == env_id and result["episodes"] == 1
    assert load_model(folder / "model.zip", gym.make(env_id)).num_timesteps == steps


def test_demonstrations_are_stored_as_the_scripted_policy_played_them():
    from stable_baselines3 import SAC, HerReplayBuffer
    from stable_baselines3.common.env_util import make_vec_env

    env_id = "rigid_gym/Stack-v0"
    model = SAC("MultiInputPolicy", make_vec_env(env_id, n_envs=1), buffer_size=1000,
                replay_buffer_class=HerReplayBuffer, policy_kwargs={"net_arch": [8]})
    demo = add_demonstrations(model, env_id, episodes=2, seed=3)
    assert demo["episodes"] == 2 and demo["env_steps"] == 200
    assert 0.0 <= demo["success_rate"] <= 1.0
    buffer = model.replay_buffer
    assert buffer.pos == 200 and list(buffer.ep_length[:200, 0]) == [100] * 200
    # replay the first episode by hand: same actions, same observations, and the stored last
    # next-observation is the episode's true end, not the next episode's reset
    env = gym.make(env_id)
    policy = scripted_policy(env)
    obs, _ = env.reset(seed=DEMO_SEED + 1000 * 3)
    for t in range(100):
        action = policy(obs).astype(np.float32)  # as a VecEnv passes it
        # SB3 stores actions rescaled to [-1, 1]: an identity here, up to float32 rounding
        np.testing.assert_allclose(buffer.actions[t, 0], action, rtol=0, atol=1e-7)
        assert (buffer.observations["observation"][t, 0] == obs["observation"]).all()
        obs, reward, *_ = env.step(action)
        assert buffer.rewards[t, 0] == reward
    assert (buffer.next_observations["achieved_goal"][99, 0] == obs["achieved_goal"]).all()
    # the episode ended by truncation: SB3 keeps bootstrapping past it (done and timeout set)
    assert buffer.dones[99, 0] == 1 and buffer.timeouts[99, 0] == 1


def test_bad_arguments_are_refused(tmp_path):
    with pytest.raises(ValueError, match="no settings for"):
        train("rigid_gym/Nope-v0", out=tmp_path)
    with pytest.raises(ValueError, match="algo must be one of"):
        train("rigid_gym/Push-v0", algo="dqn", out=tmp_path)
    with pytest.raises(ValueError, match="timesteps must be an int >= 1"):
        train("rigid_gym/Push-v0", timesteps=0, out=tmp_path)
    with pytest.raises(ValueError, match="ppo has none"):
        train("rigid_gym/PushDense-v0", demonstrations=1, out=tmp_path)
    with pytest.raises(ValueError, match="no model file"):
        evaluate(tmp_path / "missing.zip", env_id="rigid_gym/Push-v0")


def test_learning_curves_are_grouped_by_env_and_drawn(tmp_path):
    from rigid_gym.agents.results import find_runs, learning_curve, plot_curves

    for seed, rates in ((0, "0.0 0.5 0.9"), (1, "0.1 0.4 1.0")):
        folder = tmp_path / "Push-v0" / f"sac-seed{seed}"
        folder.mkdir(parents=True)
        (folder / "run.json").write_text(json.dumps({"env_id": "rigid_gym/Push-v0",
                                                     "algo": "sac", "kwargs": {}}))
        (folder / "model.zip").write_bytes(b"")
        rows = "\n".join(f"{10 * (k + 1)},{r},-1.0,1.0" for k, r in enumerate(rates.split()))
        (folder / "evaluations.csv").write_text(
            "timesteps,success_rate,mean_return,wall_seconds\n" + rows + "\n")
    runs = find_runs(tmp_path)
    assert list(runs) == ["rigid_gym/Push-v0"] and len(runs["rigid_gym/Push-v0"]) == 2
    steps, rates = learning_curve(runs["rigid_gym/Push-v0"][1])
    assert steps.tolist() == [10, 20, 30] and rates.tolist() == [0.1, 0.4, 1.0]
    plot_curves("rigid_gym/Push-v0", runs["rigid_gym/Push-v0"], tmp_path / "curve.png")
    assert (tmp_path / "curve.png").stat().st_size > 10_000


def test_the_table_names_the_method_and_counts_demonstration_steps():
    from rigid_gym.agents.results import env_steps, method, minutes

    run = {"algo": "sac", "timesteps": 150_000, "demonstrations": None,
           "kwargs": {"replay_buffer_class": "<class '...her_replay_buffer.HerReplayBuffer'>"}}
    assert (method(run), env_steps(run)) == ("SAC + HER", "150,000")
    run["demonstrations"] = {"episodes": 100, "env_steps": 5000, "success_rate": 1.0}
    assert (method(run), env_steps(run)) == ("SAC + HER + 100 demos", "150,000 + 5,000 demo")
    assert method({"algo": "ppo", "kwargs": {}}) == "PPO"
    runs = [{"cpu_seconds": 600.0}, {"cpu_seconds": 1200.0}, {}]
    assert minutes(runs[:2], "cpu_seconds") == "15 min"
    assert minutes(runs, "cpu_seconds") == "15 min (2 of 3 runs)"
    assert minutes(runs[2:], "cpu_seconds") == "—"
    assert minutes([{"wall_seconds": 12.4}], "wall_seconds") == "12 s"


def test_bc_sac_keeps_the_demonstrations_apart_and_clones_them():
    from stable_baselines3 import HerReplayBuffer
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.logger import Logger

    from rigid_gym.agents.bc_sac import BCSAC
    from rigid_gym.agents.train import algorithm_class

    assert algorithm_class("bc_sac") is BCSAC
    env_id = "rigid_gym/Stack-v0"
    model = BCSAC("MultiInputPolicy", make_vec_env(env_id, n_envs=1), buffer_size=1000,
                  replay_buffer_class=HerReplayBuffer, policy_kwargs={"net_arch": [32, 32]},
                  bc_weight=100.0, bc_batch_size=64, q_filter=False, learning_rate=3e-3, seed=0)
    add_demonstrations(model, env_id, episodes=1, seed=0)
    demo, replay = model.demo_buffer, model.replay_buffer
    assert demo.pos == replay.pos == 100
    assert (demo.actions[:100] == replay.actions[:100]).all()
    model.set_logger(Logger(None, []))

    def error():
        obs = {key: value[:100, 0] for key, value in demo.observations.items()}
        actions, _ = model.predict(obs, deterministic=True)
        return float(np.mean((actions - demo.actions[:100, 0]) ** 2))

    before = error()
    model.train(gradient_steps=200, batch_size=32)
    assert error() < 0.5 * before  # the BC term dominates: the actor imitates the demos
    assert "train/bc_loss" in model.logger.name_to_value
    # the Q-filter keeps only samples the critic rates above the policy's action
    model.q_filter = True
    loss, kept = model._bc_loss()
    assert 0.0 <= kept <= 1.0 and loss.item() >= 0.0


def test_a_run_resumes_from_its_newest_checkpoint(tmp_path):
    import pickle

    from rigid_gym.agents.train import latest_checkpoint

    small = {"learning_starts": 250, "batch_size": 32}  # gradient steps only after the resume
    seen = []
    folder = train("rigid_gym/Stack-v0", timesteps=200, out=tmp_path, eval_freq=100,
                   eval_episodes=1, checkpoint_freq=100, overrides=small, demonstrations=1,
                   on_checkpoint=seen.append)
    assert [p.name for p in seen] == ["step_100", "step_200"]
    assert latest_checkpoint(folder) == seen[-1]
    # only the newest checkpoint keeps the buffers: 100 demo + 200 run transitions in it
    assert not list(seen[0].glob("*.pkl"))
    with open(seen[-1] / "replay_buffer.pkl", "rb") as f:
        assert pickle.load(f)["pos"] == 300
    with pytest.raises(ValueError, match="no replay buffer"):
        train("rigid_gym/Stack-v0", timesteps=300, out=tmp_path, resume=seen[0])
    with pytest.raises(ValueError, match="not .*rigid_gym/Push-v0"):
        train("rigid_gym/Push-v0", algo="bc_sac", timesteps=300, out=tmp_path, resume=seen[-1])

    # a kill after the last checkpoint: the rows written since are dropped on resume
    with open(folder / "evaluations.csv", "a") as f:
        f.write("250,0.0,-100.0,9.9\n")
    train("rigid_gym/Stack-v0", timesteps=300, out=tmp_path, eval_freq=100, eval_episodes=1,
          checkpoint_freq=100, resume=latest_checkpoint(folder))
    with open(folder / "evaluations.csv") as f:
        assert [int(r["timesteps"]) for r in csv.DictReader(f)] == [100, 200, 300]
    run = json.loads((folder / "run.json").read_text())
    assert run["timesteps"] == 300 and run["resumed_at"] == [200]
    assert run["demonstrations"]["episodes"] == 1  # not added again
    model = load_model(folder / "model.zip", gym.make("rigid_gym/Stack-v0"))
    assert model.num_timesteps == 300
    with open(latest_checkpoint(folder) / "replay_buffer.pkl", "rb") as f:
        assert pickle.load(f)["pos"] == 400  # the restored 300, then 100 more
    with open(latest_checkpoint(folder) / "demo_buffer.pkl", "rb") as f:
        assert pickle.load(f)["pos"] == 100  # bc_sac's demonstrations, restored


def test_sweep_parameters_are_read_as_yaml_lists():
    from rigid_gym.agents.sweep import parse_param, setting_label

    assert parse_param("learning_rate=1e-3,3e-4") == ("learning_rate", [1e-3, 3e-4])
    assert parse_param("policy_kwargs={net_arch: [64, 64]},{net_arch: [256]}") == (
        "policy_kwargs", [{"net_arch": [64, 64]}, {"net_arch": [256]}])
    assert parse_param(" q_filter = true") == ("q_filter", [True])
    assert setting_label({"tau": 0.05, "gamma": 0.9}) == "tau=0.05 gamma=0.9"
    for bad in ("learning_rate", "=1,2", "tau=", "tau=0.1,,0.2", "tau=[1,"):
        with pytest.raises(ValueError, match="--param"):
            parse_param(bad)


def rollout_demonstrations(model, env_id: str, episodes: int, seed: int) -> None:
    """The reference the dataset path must match: the scripted policy played in a
    stable-baselines3 VecEnv seeded DEMO_SEED + 1000 * seed, its transitions added to the
    model's buffers as they come."""
    from stable_baselines3.common.env_util import make_vec_env

    env = make_vec_env(env_id, n_envs=model.n_envs, seed=DEMO_SEED + 1000 * seed)
    policies = [scripted_policy(e) for e in env.envs]
    buffers = [model.replay_buffer]
    if hasattr(model, "make_demo_buffer"):
        buffers.append(model.make_demo_buffer((episodes + model.n_envs) * 100))
    obs, finished = env.reset(), 0
    while finished < episodes:
        actions = np.stack([policy({key: value[i] for key, value in obs.items()})
                            for i, policy in enumerate(policies)]).astype(np.float32)
        next_obs, rewards, dones, infos = env.step(actions)
        stored = {key: value.copy() for key, value in next_obs.items()}
        for i in np.flatnonzero(dones):
            for key in stored:
                stored[key][i] = infos[i]["terminal_observation"][key]
        for buffer in buffers:
            buffer.add(obs, stored, model.policy.scale_action(actions), rewards, dones, infos)
        obs, finished = next_obs, finished + int(dones.sum())


@pytest.mark.parametrize("n_envs", [1, 2])
def test_demonstrations_from_the_dataset_are_the_transitions_a_rollout_gives(n_envs):
    from stable_baselines3 import HerReplayBuffer
    from stable_baselines3.common.env_util import make_vec_env

    from rigid_gym.agents.bc_sac import BCSAC

    env_id = "rigid_gym/Stack-v0"

    def model():
        return BCSAC("MultiInputPolicy", make_vec_env(env_id, n_envs=n_envs), buffer_size=1000,
                     replay_buffer_class=HerReplayBuffer, policy_kwargs={"net_arch": [8]})

    from_dataset, rolled_out = model(), model()
    demo = add_demonstrations(from_dataset, env_id, episodes=3, seed=4)
    rollout_demonstrations(rolled_out, env_id, episodes=3, seed=4)
    assert demo["episodes"] == (3 if n_envs == 1 else 4)  # whole steps of every env
    assert demo["env_steps"] == 100 * demo["episodes"] and demo["dataset"] is None
    for name in ("replay_buffer", "demo_buffer"):
        ours, theirs = getattr(from_dataset, name), getattr(rolled_out, name)
        assert ours.pos == theirs.pos == 100 * demo["episodes"] // n_envs
        for key in ("observations", "next_observations"):
            for field in ours.observations:
                assert np.array_equal(getattr(ours, key)[field], getattr(theirs, key)[field])
        for key in ("actions", "rewards", "dones", "timeouts", "ep_start", "ep_length"):
            assert np.array_equal(getattr(ours, key), getattr(theirs, key)), (name, key)


def test_demonstrations_from_a_named_dataset(tmp_path, monkeypatch):
    from stable_baselines3 import SAC, HerReplayBuffer
    from stable_baselines3.common.env_util import make_vec_env

    from rigid_gym.agents.datasets import write_dataset

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    write_dataset("rigid_gym/throw/demo-test-v0", "rigid_gym/Throw-v0", "scripted", 3, seed=9)
    model = SAC("MultiInputPolicy", make_vec_env("rigid_gym/Throw-v0", n_envs=1),
                buffer_size=1000, replay_buffer_class=HerReplayBuffer,
                policy_kwargs={"net_arch": [8]})
    demo = add_demonstrations(model, "rigid_gym/Throw-v0", 2, 0,
                              dataset="rigid_gym/throw/demo-test-v0")
    assert demo == {"episodes": 2, "env_steps": 100, "success_rate": 1.0,
                    "dataset": "rigid_gym/throw/demo-test-v0"}
    env = gym.make("rigid_gym/Throw-v0")
    obs, _ = env.reset(seed=10)  # the dataset's second episode
    assert np.array_equal(model.replay_buffer.observations["observation"][50, 0],
                          obs["observation"])
    with pytest.raises(ValueError, match="take 4 episodes; dataset rigid_gym/throw/demo-test-v0 has 3"):
        add_demonstrations(model, "rigid_gym/Throw-v0", 4, 0, dataset="rigid_gym/throw/demo-test-v0")
    with pytest.raises(ValueError, match="demonstrations of rigid_gym/Push-v0 wanted"):
        add_demonstrations(model, "rigid_gym/Push-v0", 1, 0, dataset="rigid_gym/throw/demo-test-v0")
