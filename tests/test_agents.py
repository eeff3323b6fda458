"""Smoke tests of the baselines: each task trains for a few hundred steps and is evaluated."""

import csv
import json
from pathlib import Path

import gymnasium as gym
import matplotlib.colors
import matplotlib.image
import numpy as np
import pytest
import torch as th
from rigid_gym.agents import evaluate as evaluate_module
from rigid_gym.agents.evaluate import evaluate, load_model
from rigid_gym.agents.train import (
    DEMO_SEED,
    RESULT_KEYS,
    add_demonstrations,
    load_hyperparams,
    train,
)
from rigid_gym.envs.scripted import scripted_policy

from rigid_gym.checks import BadFile

COMMITTED = Path(__file__).resolve().parent.parent / "agents" / "models"


@pytest.mark.parametrize("env_id", ["rigid_gym/Push-v0", "rigid_gym/Stack-v0",
                                    "rigid_gym/Throw-v0", "rigid_gym/PushDense-v0"])
def test_a_short_run_trains_saves_and_evaluates(env_id, tmp_path, monkeypatch):
    settings = load_hyperparams(env_id)
    # HER samples only from finished episodes: learning starts after the first one
    start = gym.spec(env_id).max_episode_steps + 10
    small = {"learning_starts": start, "batch_size": 32} if settings["algo"] != "ppo" else \
        {"n_steps": 50, "batch_size": 50}
    steps = start + 40
    demos = 1 if settings.get("demonstrations") else 0  # one, not hyperparams.yml's hundreds
    folder = train(env_id, timesteps=steps, n_envs=2 if settings["algo"] == "ppo" else 1,
                   out=tmp_path, eval_freq=steps // 2, eval_episodes=1, overrides=small,
                   demonstrations=demos, final_episodes=2, results=tmp_path / "results")
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
    # the result file: the keys the table reads, the curve ending in the final evaluation
    saved = json.loads((tmp_path / "results" / f"{folder.name}.json").read_text())
    assert saved == json.loads((folder / "result.json").read_text())
    assert tuple(saved) == RESULT_KEYS
    assert (saved["env_id"], saved["algo"], saved["env_steps"], saved["episodes"]) == (
        env_id, settings["algo"], steps, 2)
    assert [p["env_steps"] for p in saved["curve"]] == [steps // 2, steps, steps]
    assert saved["curve"][-1]["success"] == saved["success"]
    assert saved["wall_s"] >= saved["curve"][-2]["wall_s"] > 0 and saved["cpu_s"] > 0
    # committed as agents/models would hold it: smaller, with its settings and evaluation,
    # and acting as the run's policy does
    monkeypatch.setattr(evaluate_module, "MODELS", tmp_path / "models")
    (tmp_path / "models").mkdir()
    figures = evaluate_module.commit_model(folder, "committed", episodes=1)
    committed = tmp_path / "models" / "committed.zip"
    meta = json.loads(committed.with_suffix(".json").read_text())
    assert meta["env_id"] == env_id and meta["evaluation"]["success_rate"] == figures[
        "success_rate"] and meta["selected_env_steps"] == saved["selected_env_steps"]
    source = Path(meta["source"])  # the run's selected_model.zip, else (no checkpoints) model.zip
    assert source.parent == folder and committed.stat().st_size <= source.stat().st_size
    env = gym.make(env_id)
    run_model, kept = (load_model(path, env) for path in (source, committed))
    obs, _ = env.reset(seed=0)
    np.testing.assert_array_equal(run_model.predict(obs, deterministic=True)[0],
                                  kept.predict(obs, deterministic=True)[0])


def test_a_gripper_recipe_names_its_runs_and_evaluates_with_the_gripper(tmp_path):
    """A recipe that names its algorithm (PickAndPlace's sac_gripper: SAC with
    effector="gripper") trains that algorithm, names the run after the recipe, and validates,
    evaluates and resumes with the gripper, whose observation the pad's env lacks."""
    from rigid_gym.agents.results import method
    from rigid_gym.agents.train import latest_checkpoint

    env_id = "rigid_gym/PickAndPlace-v0"
    settings = load_hyperparams(env_id, "sac_gripper")
    assert settings["algo"] == "sac" and settings["recipe"] == "sac_gripper"
    assert settings["env_kwargs"] == {"effector": "gripper"}
    assert "recipe" not in load_hyperparams(env_id, "ppo")  # named by its algorithm
    small = {"learning_starts": 60, "batch_size": 32}
    folder = train(env_id, algo="sac_gripper", timesteps=100, n_envs=1, out=tmp_path,
                   eval_freq=50, eval_episodes=1, checkpoint_freq=50, overrides=small,
                   final_episodes=1)
    assert folder.name == "PickAndPlace-sac_gripper-seed0"
    run = json.loads((folder / "run.json").read_text())
    assert (run["algo"], run["recipe"], run["env_kwargs"]) == (
        "sac", "sac_gripper", {"effector": "gripper"})
    assert method(run) == "SAC + HER, two-finger gripper"
    gripper = gym.make(env_id, effector="gripper")
    assert load_model(folder / "model.zip", gripper).observation_space == \
        gripper.observation_space != gym.make(env_id).observation_space
    assert evaluate(folder / "model.zip", episodes=1)["episodes"] == 1
    # resumed by its recipe's name; another recipe's checkpoint is refused
    train(env_id, algo="sac_gripper", timesteps=150, out=tmp_path, eval_freq=50,
          eval_episodes=1, checkpoint_freq=50, resume=latest_checkpoint(folder),
          final_episodes=1)
    assert json.loads((folder / "result.json").read_text())["env_steps"] == 150
    with pytest.raises(ValueError, match="recipe, seed .*sac_gripper"):
        train(env_id, algo="sac", timesteps=200, out=tmp_path,
              resume=latest_checkpoint(folder))


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
    with pytest.raises(ValueError, match="train: timesteps: must be an int >= 1"):
        train("rigid_gym/Push-v0", timesteps=0, out=tmp_path)
    with pytest.raises(ValueError, match="ppo has none"):
        train("rigid_gym/PushDense-v0", demonstrations=1, out=tmp_path)
    with pytest.raises(BadFile, match="model file .*missing.zip not found"):
        evaluate(tmp_path / "missing.zip", env_id="rigid_gym/Push-v0")


def synthetic_result(env_id, algo, method, seed, success, wall_s, steps=40_000, demo=0):
    curve = [{"env_steps": steps * k // 10, "wall_s": wall_s * k / 10, "success": success * k / 10}
             for k in range(1, 11)]
    return {"env_id": env_id, "algo": algo, "seed": seed, "env_steps": steps, "wall_s": wall_s,
            "cpu_s": 0.9 * wall_s, "episodes": 100, "success": success, "curve": curve,
            "learner": "sbx", "method": method, "demo_env_steps": demo,
            "machine": "Test CPU, 2 cores"}


def test_the_results_table_and_curves_come_from_the_result_files(tmp_path):
    from rigid_gym.agents.results import main

    folder = tmp_path / "results"
    folder.mkdir()
    runs = [synthetic_result("rigid_gym/Push-v0", "sac", "SAC + HER", s, r, w)
            for s, r, w in ((0, 0.96, 300.0), (1, 0.90, 420.0), (2, 0.99, 360.0))]
    runs.append(synthetic_result("rigid_gym/PushDense-v0", "ppo", "PPO, shaped reward", 0, 0.5,
                                 600.0, steps=80_000))
    runs.append(synthetic_result("rigid_gym/Stack-v0", "bc_sac", "BC_SAC + HER + 500 demos", 0,
                                 0.8, 30.0, demo=50_000))
    for run in runs:
        (folder / f"{run['env_id'][10:-3]}-{run['algo']}-seed{run['seed']}.json").write_text(
            json.dumps(run))
    out = tmp_path / "out.txt"
    import contextlib
    with open(out, "w") as f, contextlib.redirect_stdout(f):
        assert main([str(folder), "--plots", str(tmp_path / "plots")]) == 0
    lines = out.read_text().splitlines()
    push = next(line for line in lines if line.startswith("| rigid_gym/Push-v0"))
    # mean 95%, population std 3.7% (rounds to 4%), wall 6.0 min mean (5.0 to 7.0)
    assert push == ("| rigid_gym/Push-v0 | SAC + HER | sbx | 40k | 6.0 min (5.0 min-7.0 min) | "
                    "5.4 min (4.5 min-6.3 min) | 3 | **95%** ± 4% (96%, 90%, 99%) |")
    stack = next(line for line in lines if line.startswith("| rigid_gym/Stack-v0"))
    assert "| 40k + 50k demo | 30 s | 27 s | 1 | **80%** ± 0% (80%) |" in stack
    assert any("Machine: Test CPU, 2 cores" in line for line in lines)
    # Push's plot: both methods' curves (matplotlib's C0 and C1), rising in either panel;
    # Stack's: its one method's, and no other
    for task, shown in (("Push", ("C0", "C1")), ("Stack", ("C0",))):
        image = matplotlib.image.imread(tmp_path / "plots" / f"curve_{task}.png")[:, :, :3]
        middle = image.shape[1] // 2
        for colour in ("C0", "C1"):
            for panel in (image[:, :middle], image[:, middle:]):
                rows, columns = curve_pixels(panel, colour)
                if colour not in shown:
                    assert rows.size == 0, (task, colour)
                    continue
                assert rows.size > 200, (task, colour)
                # success rises left to right: the curve's right end is drawn higher up
                assert rows[columns == columns.max()].mean() < rows[columns == columns.min()].mean()


def curve_pixels(image: np.ndarray, colour: str) -> tuple[np.ndarray, np.ndarray]:
    """(rows, columns) of the pixels of ``image`` (h, w, 3 floats in [0, 1]) drawn in the
    matplotlib colour ``colour`` (within 0.1 a channel: the line's core, not its antialiased
    edge or the shaded band)."""
    target = np.array(matplotlib.colors.to_rgb(colour))
    return np.nonzero(np.abs(image - target).max(axis=2) < 0.1)


def test_the_curves_average_seeds_on_a_common_axis():
    from rigid_gym.agents.results import band

    runs = [synthetic_result("rigid_gym/Push-v0", "sac", "SAC", s, r, w)
            for s, r, w in ((0, 1.0, 100.0), (1, 0.5, 200.0))]
    x, mean, low, high = band(runs, "wall_s", points=11)
    assert x[0] == 10.0 and x[-1] == 100.0  # up to the shorter run's end
    # at 100 s run 0 is at 1.0, run 1 (half as fast, half the rate) at 0.5 * 0.5
    assert (mean[-1], low[-1], high[-1]) == (0.625, 0.25, 1.0)
    x, mean, _, _ = band(runs, "env_steps", points=10)
    np.testing.assert_allclose(mean, 0.75 * np.arange(1, 11) / 10)


def test_the_table_says_where_a_run_used_more_than_one_thread():
    """One thread per run is claimed as the CPU times show it: a run whose CPU time exceeds
    its wall time is counted, with the largest excess."""
    from rigid_gym.agents.results import table

    runs = [synthetic_result("rigid_gym/Push-v0", "sac", "SAC + HER", s, 0.9, 100.0)
            for s in range(3)]
    assert table(runs).endswith("PyTorch's, XLA's and the solver's pools on one thread.")
    runs[1]["cpu_s"] = 112.0
    assert table(runs).endswith("(CPU time above the wall time in 1 of 3 runs, by at most 12%: "
                                "another thread of the process was busy too).")


def test_the_table_names_the_method():
    from rigid_gym.agents.results import method

    run = {"algo": "sac", "timesteps": 150_000, "demonstrations": None,
           "kwargs": {"replay_buffer_class": "<class '...her_replay_buffer.HerReplayBuffer'>"}}
    assert method(run) == "SAC + HER"
    run["demonstrations"] = {"episodes": 100, "env_steps": 5000, "success_rate": 1.0}
    assert method(run) == "SAC + HER + 100 demos"
    assert method({"algo": "ppo", "kwargs": {}, "env_kwargs": {"reward_type": "shaped"}}) == \
        "PPO, shaped reward"
    assert method({"algo": "ppo", "kwargs": {}, "env_kwargs": {
        "reward_type": "shaped", "start_placed": 0.5}}) == \
        "PPO, shaped reward, 50% of episodes start with cube 0 placed"


def demo_imitation_error(model) -> float:
    """Mean squared error of the deterministic policy against the first 100 demo actions."""
    demo = model.demo_buffer
    obs = {key: value[:100, 0] for key, value in demo.observations.items()}
    actions, _ = model.predict(obs, deterministic=True)
    return float(np.mean((actions - demo.actions[:100, 0]) ** 2))


def test_bc_sac_keeps_the_demonstrations_apart_and_clones_them():
    from rigid_gym.agents.bc_sac import BCSAC
    from rigid_gym.agents.train import algorithm_class
    from stable_baselines3 import HerReplayBuffer
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.logger import Logger

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

    before = demo_imitation_error(model)
    model.train(gradient_steps=200, batch_size=32)
    assert demo_imitation_error(model) < 0.5 * before  # the BC term dominates: the actor imitates the demos
    assert "train/bc_loss" in model.logger.name_to_value
    # the Q-filter keeps only samples the critic rates above the policy's action: recomputed
    # here from the same demo batch (the buffer samples with numpy's global generator)
    model.q_filter = True
    np.random.seed(3)
    loss, kept = model._bc_loss()
    np.random.seed(3)
    batch = demo.sample(model.bc_batch_size)
    with th.no_grad():
        action = model.actor(batch.observations, deterministic=True)
        q_demo = th.cat(model.critic(batch.observations, batch.actions), dim=1).min(dim=1).values
        q_pi = th.cat(model.critic(batch.observations, action), dim=1).min(dim=1).values
    keep = (q_demo > q_pi).numpy()
    error = ((action - batch.actions) ** 2).sum(dim=1).numpy()
    assert kept == pytest.approx(keep.mean())
    assert loss.item() == pytest.approx(error[keep].mean() if keep.any() else 0.0, rel=1e-5)


def test_a_run_resumes_from_its_newest_checkpoint(tmp_path):
    import pickle

    from rigid_gym.agents.train import latest_checkpoint

    small = {"learning_starts": 250, "batch_size": 32}  # gradient steps only after the resume
    seen = []
    folder = train("rigid_gym/Stack-v0", timesteps=200, out=tmp_path, eval_freq=100,
                   eval_episodes=1, checkpoint_freq=100, overrides=small, demonstrations=1,
                   on_checkpoint=seen.append, n_envs=1, final_episodes=1)
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
          checkpoint_freq=100, resume=latest_checkpoint(folder), final_episodes=1)
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
            for key, value in stored.items():
                value[i] = infos[i]["terminal_observation"][key]
        for buffer in buffers:
            buffer.add(obs, stored, model.policy.scale_action(actions), rewards, dones, infos)
        obs, finished = next_obs, finished + int(dones.sum())


@pytest.mark.parametrize("n_envs", [1, 2])
def test_demonstrations_from_the_dataset_are_the_transitions_a_rollout_gives(n_envs):
    from rigid_gym.agents.bc_sac import BCSAC
    from stable_baselines3 import HerReplayBuffer
    from stable_baselines3.common.env_util import make_vec_env

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
    from rigid_gym.agents.datasets import write_dataset
    from stable_baselines3 import SAC, HerReplayBuffer
    from stable_baselines3.common.env_util import make_vec_env

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


def test_a_killed_run_resumes_and_its_result_has_the_whole_curve(tmp_path):
    """A run stopped after a checkpoint leaves no result file; the table's next sitting goes
    on from the checkpoint to the same budget, the curve and the seconds going on."""
    from rigid_gym.agents.table import main as table
    from rigid_gym.agents.train import latest_checkpoint

    class Killed(Exception):
        pass

    def kill_at_200(folder):
        if folder.name == "step_200":
            raise Killed

    small = {"learning_starts": 60, "batch_size": 32}
    runs, results = tmp_path / "runs", tmp_path / "results"
    with pytest.raises(Killed):
        train("rigid_gym/Push-v0", timesteps=400, out=runs, eval_freq=40, eval_episodes=1,
              checkpoint_freq=100, overrides=small, on_checkpoint=kill_at_200,
              results=results, final_episodes=3, n_envs=1)
    folder = runs / "Push-sac-seed0"
    assert not (folder / "result.json").exists() and not results.exists()
    spent = json.loads((latest_checkpoint(folder) / "run.json").read_text())["wall_seconds"]
    # the queue's plan sees it unfinished, then resumes it (here in this process)
    train("rigid_gym/Push-v0", timesteps=400, out=runs, eval_freq=40, eval_episodes=1,
          checkpoint_freq=100, resume=latest_checkpoint(folder), results=results,
          final_episodes=3)
    result = json.loads((results / "Push-sac-seed0.json").read_text())
    assert [p["env_steps"] for p in result["curve"]] == [40 * k for k in range(1, 11)] + [400]
    walls = [p["wall_s"] for p in result["curve"]]
    assert walls == sorted(walls) and result["wall_s"] > spent
    assert json.loads((folder / "run.json").read_text())["resumed_at"] == [200]
    # the final evaluation ran a checkpoint of the run's second half, kept as selected_model
    assert result["selected_env_steps"] in (200, 300, 400)
    chosen = folder / "checkpoints" / f"step_{result['selected_env_steps']}" / "model.zip"
    assert (folder / "selected_model.zip").read_bytes() == chosen.read_bytes()
    assert evaluate(folder / "selected_model.zip", episodes=3)["success_rate"] == \
        result["success"]
    assert table(["--tasks", "push", "--algos", "sac", "--seeds", "0,1", "--runs", str(runs),
                  "--results", str(results), "--dry-run"]) == 0


@pytest.mark.parametrize("validation, chosen", [
    ({200: 0.9, 300: 1.0, 400: 0.5}, 300),   # the best of the second half
    ({100: 1.0, 200: 0.5, 300: 0.5, 400: 0.5}, 400),  # the first half is not a candidate
    ({200: 1.0, 300: 1.0, 400: 0.5}, 300),   # the latest among equals
])
def test_finish_evaluates_the_checkpoint_of_best_validation_success(tmp_path, monkeypatch,
                                                                    validation, chosen):
    from rigid_gym.agents import train as training
    from rigid_gym.agents.evaluate import EVAL_SEED, VALIDATION_SEED

    folder = train("rigid_gym/Push-v0", timesteps=400, out=tmp_path, eval_freq=0,
                   checkpoint_freq=100, final_episodes=0, n_envs=1,
                   overrides={"learning_starts": 60, "batch_size": 32})
    calls = []

    def scripted(model, env, episodes, seed=EVAL_SEED, deterministic=True, progress=False):
        calls.append((model.num_timesteps, episodes, seed))
        rate = validation[model.num_timesteps] if seed == VALIDATION_SEED else \
            model.num_timesteps / 1000  # the final evaluation says which policy it ran
        return {"episodes": episodes, "success_rate": rate, "mean_return": 0.0}

    monkeypatch.setattr(training, "success_rate", scripted)
    model = load_model(folder / "model.zip", gym.make("rigid_gym/Push-v0"))
    result = training.finish(folder, model, training.Clock(), episodes=7)
    assert calls == [(step, training.VALIDATION_EPISODES, VALIDATION_SEED)
                     for step in (200, 300, 400)] + [(chosen, 7, EVAL_SEED)]
    assert (result["selected_env_steps"], result["success"], result["env_steps"]) == (
        chosen, chosen / 1000, 400)


def test_the_queue_plans_done_unfinished_and_new_runs(tmp_path, capsys):
    from rigid_gym.agents.table import PACE, plan
    from rigid_gym.agents.table import main as table

    runs, results = tmp_path / "runs", tmp_path / "results"
    (runs / "Push-sac-seed1" / "checkpoints" / "step_30000").mkdir(parents=True)
    (runs / "Push-sac-seed1" / "checkpoints" / "step_30000" / "model.zip").write_bytes(b"")
    results.mkdir()
    (results / "Push-sac-seed0.json").write_text("{}")
    entries = plan(["push", "stack"], None, [0, 1], runs, results)
    states = {e["name"]: e["state"] for e in entries}
    assert states == {"Push-sac-seed0": "done", "Push-ppo-seed0": "new",
                      "Stack-bc_sac-seed0": "new", "Stack-sac-seed0": "new",
                      "Stack-ppo-seed0": "new", "Push-sac-seed1": "resume at 30,000",
                      "Push-ppo-seed1": "new", "Stack-bc_sac-seed1": "new",
                      "Stack-sac-seed1": "new", "Stack-ppo-seed1": "new"}
    done = next(e for e in entries if e["name"] == "Push-sac-seed0")
    resumed = next(e for e in entries if e["name"] == "Push-sac-seed1")
    new = next(e for e in entries if e["name"] == "Stack-sac-seed1")
    assert done["estimate_s"] == 0 and 0 < new["estimate_s"]
    pace = PACE[("rigid_gym/Push-v0", "sac")]
    assert resumed["estimate_s"] == pytest.approx((resumed["steps"] - 30_000) / pace)
    with pytest.raises(SystemExit):
        table(["--tasks", "push,nope", "--dry-run"])
    assert "unknown task(s) ['nope']" in capsys.readouterr().err


def test_the_plan_takes_its_pace_from_the_results_or_a_kin_recipe(tmp_path):
    """A recipe's estimate divides its steps by the median pace of its own result files, or,
    with none, by that of its kin's (Stack's for Tower)."""
    from rigid_gym.agents.table import plan

    results = tmp_path / "results"
    results.mkdir()
    for seed, wall in enumerate((10.0, 20.0, 40.0)):  # 100, 50, 25 env steps/s
        (results / f"Stack-sac-seed{seed}.json").write_text(json.dumps(
            {"env_id": "rigid_gym/Stack-v0", "algo": "sac", "env_steps": 1000, "wall_s": wall}))
    (tower,) = plan(["tower"], ["sac"], [0], tmp_path / "runs", results)
    assert tower["estimate_s"] == pytest.approx(tower["steps"] / 50.0)
    (results / "Tower-sac-seed1.json").write_text(json.dumps(
        {"env_id": "rigid_gym/Tower-v0", "algo": "sac", "env_steps": 500, "wall_s": 1.0}))
    (tower,) = plan(["tower"], ["sac"], [0], tmp_path / "runs", results)
    assert tower["estimate_s"] == pytest.approx(tower["steps"] / 500.0)


def test_a_model_saved_by_sbx_without_sbx_installed_says_which_extra_it_needs(monkeypatch):
    from rigid_gym.agents import algorithms

    monkeypatch.setattr(algorithms, "learner_available", lambda name: name != "sbx")
    with pytest.raises(ValueError, match=r"trained with SBX \(JAX\): pip install -e '\.\[fast\]'"):
        algorithms.find_algorithm("sbx:sac")


def test_bc_sac_on_sbx_clones_the_demonstrations():
    pytest.importorskip("sbx")
    from rigid_gym.agents.algorithms import algorithm_class
    from rigid_gym.agents.bc_sac import BCSACJax
    from rigid_gym.agents.train import make_env
    from stable_baselines3 import HerReplayBuffer
    from stable_baselines3.common.logger import Logger

    assert algorithm_class("bc_sac", "sbx") is BCSACJax
    env_id = "rigid_gym/Stack-v0"
    model = BCSACJax("MultiInputPolicy", make_env(env_id, 1), buffer_size=1000,
                     replay_buffer_class=HerReplayBuffer, policy_kwargs={"net_arch": [32, 32]},
                     bc_weight=100.0, bc_batch_size=64, q_filter=False, learning_rate=3e-3,
                     seed=0)
    add_demonstrations(model, env_id, episodes=1, seed=0)
    demo = model.demo_buffer
    assert demo.pos == model.replay_buffer.pos == 100
    model.set_logger(Logger(None, []))

    before = demo_imitation_error(model)
    model.train(gradient_steps=200, batch_size=32)
    assert demo_imitation_error(model) < 0.5 * before
    assert model.logger.name_to_value["train/bc_kept"] == 1.0  # no Q-filter: every sample
    model.q_filter = True
    model.train(gradient_steps=5, batch_size=32)
    assert 0.0 <= model.logger.name_to_value["train/bc_kept"] <= 1.0


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(p.stem for p in COMMITTED.glob("*.zip")))
def test_every_committed_model_still_scores_its_recorded_evaluation(name):
    """Each committed model's json carries its 100-episode evaluation
    (``python -m rigid_gym.agents.evaluate`` writes it); the physics or the env changing
    under a model shows here as a score more than 5 points off."""
    recorded = json.loads((COMMITTED / f"{name}.json").read_text())["evaluation"]
    now = evaluate(COMMITTED / f"{name}.zip", episodes=recorded["episodes"], seed=recorded["seed"])
    assert abs(now["success_rate"] - recorded["success_rate"]) <= 0.05, (now, recorded)
