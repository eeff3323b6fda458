"""The pixel recipe (rigid_gym.agents.distill): what the student sees, and a tiny run that
trains, saves, resumes, evaluates and records."""

import json

import gymnasium as gym
import numpy as np
import pytest
import torch
from rigid_gym.agents.distill import (
    DistilledPolicy,
    make_network,
    observation_kwargs,
    proprioception_index,
    student_inputs,
)
from rigid_gym.agents.evaluate import evaluate
from rigid_gym.agents.train import RESULT_KEYS, train

from rigid_gym.cli import main

PUSH = "rigid_gym/Push-v0"
STACK = "rigid_gym/Stack-v0"
TINY = {"n_envs": 2, "episodes": 2, "updates": 3, "batch_size": 8, "beta_iterations": 2,
        "network": {"channels": 4}}
"""A recipe of one 100-step iteration and three updates: the loop, not the learning."""


def student(env_id=PUSH, size=64):
    index = proprioception_index(env_id)
    goal = gym.make(env_id).observation_space["desired_goal"].shape[0]
    config = {"size": size, "vector_size": goal + len(index), "action_size": 3,
              "proprioception_index": index.tolist(), "network": {"channels": 4}}
    torch.manual_seed(0)
    return DistilledPolicy(make_network(size, config["vector_size"], 3, channels=4), config)


@pytest.mark.parametrize("env_id, pad", [(PUSH, ("pad.position", "pad.velocity")),
                                         (STACK, ("pad.position", "pad.velocity", "holding"))])
def test_the_student_sees_the_frame_the_goal_and_the_pad_never_the_cube(env_id, pad):
    env = gym.make(env_id, **observation_kwargs(64))
    obs, _ = env.reset(seed=3)
    layout = env.unwrapped.task.observation_layout
    index = proprioception_index(env_id)
    assert index.tolist() == layout.entries(pad).tolist()
    frames, vector = student_inputs(obs, index)
    assert frames.shape == (64, 64, 3) and frames.dtype == np.uint8
    np.testing.assert_array_equal(vector, np.concatenate(
        [obs["desired_goal"], *(obs["observation"][layout.slices[name]] for name in pad)]
    ).astype(np.float32))
    policy = student(env_id)
    action = policy.predict(obs)[0]
    # every entry of the cubes' state, and the achieved goal (their positions), changed: the
    # action is the same bit for bit
    hidden = dict(obs, achieved_goal=obs["achieved_goal"] + 0.1,
                  observation=obs["observation"].copy())
    cubes = [name for name in layout.slices if name.startswith("cube")]
    assert len(cubes) == 5 * env.unwrapped.task.num_cubes
    for name in cubes:
        hidden["observation"][layout.slices[name]] += 0.37
    np.testing.assert_array_equal(policy.predict(hidden)[0], action)
    # what it does see moves it: the frame, the goal, the pad
    for changed in (dict(obs, pixels=255 - obs["pixels"]),
                    dict(obs, desired_goal=obs["desired_goal"] + 0.1),
                    dict(obs, observation=obs["observation"] + 0.1)):
        assert not np.array_equal(policy.predict(changed)[0], action)


def test_a_student_does_not_load_into_an_env_of_other_frames(tmp_path):
    from rigid_gym.agents.distill import save_policy

    policy = student()
    save_policy(tmp_path / "model.zip", policy.network, policy.config)
    DistilledPolicy.load(tmp_path / "model.zip", gym.make(PUSH, **observation_kwargs(64)))
    for env in (gym.make(PUSH), gym.make(PUSH, **observation_kwargs(48))):
        with pytest.raises(ValueError, match=r"takes state\+pixels observations of \(64, 64, 3\)"):
            DistilledPolicy.load(tmp_path / "model.zip", env)


def test_the_pixel_recipe_trains_resumes_evaluates_and_records(tmp_path, capsys):
    # the recipe's teacher, the committed Push SAC + HER model, was trained with SBX (JAX):
    # loading it needs the `fast` extra
    pytest.importorskip("sbx", reason="the committed teacher is an SBX model (the fast extra)")
    out, results = tmp_path / "runs", tmp_path / "results"
    folder = train(PUSH, obs_mode="pixels", timesteps=100, out=out, eval_episodes=2,
                   overrides=TINY, final_episodes=0)
    assert not (folder / "result.json").exists()
    assert sorted(p.name for p in (folder / "checkpoints").iterdir()) == [
        "data_0.npz", "latest.pt", "student_1.zip"]
    data = np.load(folder / "checkpoints" / "data_0.npz")
    assert data["frames"].shape == (100, 64, 64, 3) and data["frames"].dtype == np.uint8
    assert data["vectors"].shape == (100, 9) and data["labels"].shape == (100, 3)
    first = json.loads((folder / "run.json").read_text())
    assert first["obs_mode"] == "pixels" and first["wall_seconds"] > first[
        "teacher_wall_seconds"] > 0
    # a data file of an iteration that latest.pt does not count (a stop while it was written)
    (folder / "checkpoints" / "data_1.npz").write_bytes(b"cut short")
    # goes on to a second iteration from the checkpoint, the curve kept
    folder = train(PUSH, obs_mode="pixels", timesteps=200, out=out, eval_episodes=2,
                   overrides=TINY, final_episodes=2, results=results, resume=folder / "checkpoints")
    assert (folder / "checkpoints" / "data_1.npz").is_file()
    resumed = json.loads((folder / "run.json").read_text())
    assert resumed["resumed_at"] == [100] and resumed["iterations"] == 2
    # the final evaluation's student: the second half's best on validation (both, here)
    assert (folder / "selected_model.zip").is_file()
    saved = json.loads((results / f"{folder.name}.json").read_text())
    assert saved == json.loads((folder / "result.json").read_text())
    assert set(RESULT_KEYS) <= set(saved) and saved["obs_mode"] == "pixels"
    assert (saved["algo"], saved["env_steps"], saved["episodes"]) == ("distill", 200, 2)
    assert saved["selected_env_steps"] in (100, 200)
    assert [p["env_steps"] for p in saved["curve"]] == [100, 200, 200]
    assert saved["wall_s"] > first["wall_seconds"] and saved["cpu_s"] > first["cpu_seconds"]
    # evaluate and record take it as they take the others
    assert evaluate(folder / "model.zip", episodes=1)["episodes"] == 1
    assert main(["record", PUSH, "--policy", str(folder / "model.zip"), "--out",
                 str(tmp_path / "rec")]) == 0
    assert list((tmp_path / "rec").rglob("*.rrd"))
    assert "episode 0: 50 steps" in capsys.readouterr().out


def test_the_pixel_recipe_is_distill_and_resumes_only_from_a_checkpoint(tmp_path):
    with pytest.raises(ValueError, match=r"the pixel recipes are algos \('distill', 'drq'\)"):
        train(PUSH, obs_mode="pixels", algo="sac", out=tmp_path)
    with pytest.raises(ValueError, match="a teacher teaches the distill recipe only"):
        train(PUSH, obs_mode="pixels", algo="drq", out=tmp_path, teacher="x.zip")
    with pytest.raises(ValueError, match="obs_mode must be 'state' or 'pixels'"):
        train(PUSH, obs_mode="rgb", out=tmp_path)
    with pytest.raises(ValueError, match="--resume: no checkpoint"):
        train(PUSH, obs_mode="pixels", out=tmp_path, overrides=TINY, resume=tmp_path / "x")


def test_a_stack_student_reads_out_both_cubes_and_sees_the_grip(tmp_path):
    pytest.importorskip("sbx", reason="the committed Stack teacher is an SBX model")
    folder = train(STACK, obs_mode="pixels", timesteps=1, out=tmp_path, eval_episodes=0,
                   overrides={**TINY, "updates": 1}, final_episodes=0)
    data = np.load(folder / "checkpoints" / "data_0.npz")
    # 2 episodes of 100 steps; the goal (6) and the pad's position, velocity and grip (7)
    assert data["vectors"].shape == (200, 13) and data["cubes"].shape == (200, 6)
    # the read-out learns both cubes: the achieved goal, scaled
    policy = DistilledPolicy.load(folder / "model.zip")
    assert policy.network.locator.out_features == 6
    assert json.loads((folder / "run.json").read_text())["student_inputs"]["vector"] == [
        "desired_goal", "pad.position", "pad.velocity", "holding"]
