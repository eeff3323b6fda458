"""Pixel observations (envs/pixels.py): spaces and checkers in every mode, the pictures, the
batch's frames, determinism across copies, threads and processes, bad arguments, SB3."""

import itertools
import subprocess
import sys
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pixel_digest import frame_digest
from rigid_gym.envs.pixels import CAMERA_NAMES, CAMERAS, OBS_MODES, VIEWED
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import rigid_gym
from rigid_gym.render import Camera

HERE = Path(__file__).parent

TASK_IDS = ["rigid_gym/Push-v0", "rigid_gym/Stack-v0", "rigid_gym/Throw-v0"]
MODE_KEYS = {"state": {"observation", "achieved_goal", "desired_goal"},
             "pixels": {"pixels", "achieved_goal", "desired_goal"},
             "state+pixels": {"observation", "pixels", "achieved_goal", "desired_goal"}}


def random_actions(env, steps, seed=0):
    return np.random.default_rng(seed).uniform(-1, 1, (steps,) + env.action_space.shape)


@pytest.mark.parametrize("env_id", rigid_gym.ENV_IDS)
@pytest.mark.parametrize("mode", OBS_MODES)
def test_checkers_pass_in_every_mode(env_id, mode):
    """Gymnasium's and SB3's check_env (determinism of reset(seed) and step included) pass;
    the spaces hold exactly the mode's keys, the frame (84, 84, 3) uint8 by default."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*(infinity|needs a display).*")
        env = gym.make(env_id, obs_mode=mode).unwrapped
        check_env(env)
        sb3_check_env(gym.make(env_id, obs_mode=mode).unwrapped)
    assert set(env.observation_space.spaces) == MODE_KEYS[mode]
    obs, _ = env.reset(seed=0)
    assert set(obs) == MODE_KEYS[mode]
    if mode != "state":
        assert obs["pixels"].shape == (84, 84, 3) and obs["pixels"].dtype == np.uint8
        assert env.observation_space["pixels"].shape == (84, 84, 3)


def test_width_height_and_the_vector_env_batch():
    """width x height frames; make_vec's pixels are (B, H, W, 3), copy i's frame the single
    env's with seed s + i, also after steps."""
    env = gym.make("rigid_gym/Push-v0", obs_mode="pixels", width=64, height=48)
    obs, _ = env.reset(seed=5)
    assert obs["pixels"].shape == (48, 64, 3)
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=3, obs_mode="state+pixels", width=64,
                        height=48)
    assert envs.single_observation_space["pixels"].shape == (48, 64, 3)
    batch, _ = envs.reset(seed=5)
    assert batch["pixels"].shape == (3, 48, 64, 3)
    singles = [gym.make("rigid_gym/Push-v0", obs_mode="state+pixels", width=64, height=48)
               for _ in range(3)]
    firsts = [s.reset(seed=5 + i)[0] for i, s in enumerate(singles)]
    actions = random_actions(env, 10)
    for step in range(11):
        for i in range(3):
            single = firsts[i] if step == 0 else singles[i].step(actions[step - 1])[0]
            np.testing.assert_array_equal(batch["pixels"][i], single["pixels"])
            np.testing.assert_array_equal(batch["observation"][i], single["observation"])
        if step < 10:
            batch = envs.step(np.tile(actions[step], (3, 1)))[0]
    assert len({batch["pixels"][i].tobytes() for i in range(3)}) == 3  # the copies differ


def test_the_autoreset_step_shows_the_new_episode_and_keeps_the_last_frame():
    """At a same-step autoreset the observation's frame is the new episode's first (as a
    single env's after reset()) and final_obs holds the ended episode's last frame."""
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=2, obs_mode="pixels", width=32,
                        height=32, max_episode_steps=3)
    single = gym.make("rigid_gym/Push-v0", obs_mode="pixels", width=32, height=32,
                      max_episode_steps=3)
    envs.reset(seed=1)
    single.reset(seed=1)
    actions = random_actions(single, 3)
    for k in range(3):
        obs, _, _, truncated, infos = envs.step(np.tile(actions[k], (2, 1)))
        last = single.step(actions[k])[0]
    assert truncated.all()
    np.testing.assert_array_equal(infos["final_obs"][0]["pixels"], last["pixels"])
    np.testing.assert_array_equal(obs["pixels"][0], single.reset()[0]["pixels"])


def test_the_same_seed_gives_the_same_bytes_in_other_processes_and_thread_counts():
    """A batch of 5 Throw copies drawn on 1 and on 3 threads in fresh processes (the copies
    shared out differently) gives every frame's bytes as this process does."""
    here = frame_digest("rigid_gym/Throw-v0", 5, 20)
    for threads in (1, 3):
        script = (f"import sys; sys.path.insert(0, {str(HERE)!r})\n"
                  f"from rigid_gym import _core; _core.set_num_threads({threads})\n"
                  "from pixel_digest import frame_digest\n"
                  "print(frame_digest('rigid_gym/Throw-v0', 5, 20))")
        out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                             check=True)
        assert out.stdout.strip() == here, f"{threads} threads"


@pytest.mark.parametrize("task", ["Push", "Stack", "Throw"])
@pytest.mark.parametrize("name", CAMERA_NAMES)
def test_every_camera_frames_the_task_box(task, name):
    """Every corner of the task's VIEWED box (where the cubes, goals and the bin can be)
    projects inside an 84 x 84 frame, in front of the camera."""
    corners = np.array(list(itertools.product(*zip(*VIEWED[task]))))
    screen, depth = CAMERAS[task][name].project(corners, 84, 84)
    assert np.all(depth > 0)
    assert np.all((screen >= 0) & (screen <= 84))


def project(env, point):
    """The pixel (row, column) of world ``point`` in the env's 84 x 84 front camera."""
    camera = env.unwrapped.core.frames.renderer.camera
    ((x, y),), _ = camera.project([point], 84, 84)
    return int(y), int(x)


@pytest.mark.parametrize("env_id", TASK_IDS)
def test_the_picture_shows_the_cubes_the_pad_and_the_goal(env_id):
    """At a reset the pixel at each cube's centre is that cube's colour (blue, orange), the
    pad's is dark grey; the goal marker changes the pixels at the goal and only near it
    (goal_marker=False leaves it out); Throw's bin (grey) shows at its wall."""
    from rigid_gym.render import DYNAMIC_PALETTE, KINEMATIC_COLOR, STATIC_COLOR

    env = gym.make(env_id, obs_mode="pixels")
    plain = gym.make(env_id, obs_mode="pixels", goal_marker=False)
    frame = env.reset(seed=2)[0]["pixels"].astype(int)
    without = plain.reset(seed=2)[0]["pixels"].astype(int)
    core = env.unwrapped.core
    world = env.unwrapped.world

    def hue(pixel):  # the colour's direction: shading scales all channels alike
        return pixel / max(pixel.sum(), 1)

    def close(pixel, rgb):
        return np.abs(hue(pixel) - hue(np.asarray(rgb))).max() < 0.06

    for k, cube in enumerate(core.cubes):
        top = world.position[cube] + (0, 0, core.half[0, k])  # the top face: lit, unhidden
        assert close(frame[project(env, top)], DYNAMIC_PALETTE[k]), k
    pad = world.position[core.gripper_body] + (0, 0, 0.012)
    assert close(frame[project(env, pad)], KINEMATIC_COLOR) and frame[project(env, pad)].max() < 110
    changed = np.any(frame != without, axis=-1)
    goal = env.unwrapped.goal
    targets = [goal[3 * k:3 * k + 3] for k in range(len(goal) // 3)]
    for target in targets:
        assert changed[project(env, target)]
    rows, columns = np.nonzero(changed)
    near = [min(np.hypot(r - project(env, t)[0], c - project(env, t)[1]) for t in targets)
            for r, c in zip(rows, columns)]
    assert max(near) < 12  # pixels; the Push disc is 0.1 m across, ~11 pixels
    if "Throw" in env_id:
        wall = world.position[core.fixtures[0]] + (0.0, -0.085, 0.08)  # near wall's top edge
        assert close(frame[project(env, wall)], STATIC_COLOR)


def test_frames_follow_the_state():
    """Moving the pad changes the frame where it was and where it goes; the goal vectors stay
    in every mode."""
    env = gym.make("rigid_gym/Push-v0", obs_mode="pixels")
    first = env.reset(seed=0)[0]
    after = first
    for _ in range(4):
        after = env.step(np.array([1.0, 0.0, 0.0], dtype=np.float32))[0]
    assert np.count_nonzero(np.any(first["pixels"] != after["pixels"], axis=-1)) > 20
    np.testing.assert_array_equal(first["desired_goal"], after["desired_goal"])


def test_other_cameras_and_a_camera_object():
    """Named cameras draw other pictures; a Camera is used as given."""
    frames = {name: gym.make("rigid_gym/Stack-v0", obs_mode="pixels", camera=name)
              .reset(seed=0)[0]["pixels"] for name in CAMERA_NAMES}
    assert len({f.tobytes() for f in frames.values()}) == len(CAMERA_NAMES)
    camera = CAMERAS["Stack"]["top"]
    own = gym.make("rigid_gym/Stack-v0", obs_mode="pixels", camera=Camera(
        camera.eye, camera.target, camera.up, camera.fov_deg)).reset(seed=0)[0]["pixels"]
    np.testing.assert_array_equal(own, frames["top"])


def test_rgb_array_frames_are_unchanged_by_the_obs_mode():
    """render() keeps its 480 x 480 rgb_array frame in pixel mode, the same bytes as in state
    mode."""
    frames = []
    for mode in ("state", "pixels"):
        env = gym.make("rigid_gym/Push-v0", obs_mode=mode, render_mode="rgb_array")
        env.reset(seed=3)
        frames.append(env.render())
    assert frames[0].shape == (480, 480, 3)
    np.testing.assert_array_equal(frames[0], frames[1])


@pytest.mark.parametrize("kwargs, message", [
    ({"obs_mode": "rgb"}, r"obs_mode must be one of \['state', 'pixels', 'state\+pixels'\]"),
    ({"obs_mode": "pixels", "width": 8}, r"width: must be an int in \[16, 1024\] pixels, got 8"),
    ({"obs_mode": "pixels", "height": 2000}, r"height: must be an int in \[16, 1024\] pixels, got 2000"),
    ({"obs_mode": "pixels", "width": 84.0}, r"width: must be an int .* got 84.0"),
    ({"obs_mode": "pixels", "width": True}, r"width: must be an int .* got True"),
    ({"obs_mode": "pixels", "camera": "wrist"},
     (r"camera must be one of \['front', 'top', 'side'\] or a rigid_gym.render.Camera, "
      r"got 'wrist'")),
    ({"obs_mode": "pixels", "goal_marker": "no"}, r"goal_marker must be a bool"),
])
def test_bad_arguments_are_refused_before_anything_steps(kwargs, message):
    with pytest.raises(ValueError, match=r"PushEnv: " + message):
        gym.make("rigid_gym/Push-v0", **kwargs)
    with pytest.raises(ValueError, match=message):
        gym.make_vec("rigid_gym/Push-v0", num_envs=2, **kwargs)


def test_sb3_trains_on_pixels_with_its_cnn():
    """SB3's MultiInputPolicy puts its NatureCNN on ``pixels``: PPO on the batched env and SAC
    with HER (relabelling the goal vectors) on the single env train a few hundred steps. The
    learners see the env's frames (channel first) and train the CNN on them; HER's relabelled
    goals earn the rewards ``compute_reward`` gives them."""
    import torch
    from rigid_gym.agents.vec_env import SB3VecEnv
    from stable_baselines3 import PPO, SAC, HerReplayBuffer
    from stable_baselines3.common.torch_layers import NatureCNN

    def cnn_weights(extractor):
        return extractor.extractors["pixels"].cnn[0].weight.detach().clone()

    torch.set_num_threads(1)
    venv = SB3VecEnv(gym.make_vec("rigid_gym/PushDense-v0", num_envs=4, obs_mode="pixels"))
    ppo = PPO("MultiInputPolicy", venv, n_steps=32, batch_size=64, n_epochs=1, seed=0,
              policy_kwargs={"features_extractor_kwargs": {"cnn_output_dim": 32}})
    assert isinstance(ppo.policy.features_extractor.extractors["pixels"], NatureCNN)
    before = cnn_weights(ppo.policy.features_extractor)
    ppo.learn(128)  # one rollout of 32 vector steps, one epoch
    assert ppo.num_timesteps == 128
    assert not torch.equal(cnn_weights(ppo.policy.features_extractor), before)
    # the rollout's first observation: copy i reset with seed i (SB3's seed + i), as (3, h, w)
    first = gym.make_vec("rigid_gym/PushDense-v0", num_envs=4, obs_mode="pixels").reset(
        seed=0)[0]["pixels"]
    # (flattened by training env-major: env i's step t at 32 i + t)
    seen = ppo.rollout_buffer.observations["pixels"].reshape(4, 32, 3, 84, 84)[:, 0]
    np.testing.assert_array_equal(seen, first.transpose(0, 3, 1, 2))
    assert len({frame.tobytes() for frame in first}) == 4  # four different starts

    env = gym.make("rigid_gym/Push-v0", obs_mode="pixels", width=48, height=48)
    sac = SAC("MultiInputPolicy", env, replay_buffer_class=HerReplayBuffer, buffer_size=400,
              learning_starts=100, batch_size=16, seed=0,
              policy_kwargs={"features_extractor_kwargs": {"cnn_output_dim": 16},
                             "net_arch": [32]})
    assert isinstance(sac.actor.features_extractor.extractors["pixels"], NatureCNN)
    before = cnn_weights(sac.actor.features_extractor)
    sac.learn(150)
    assert sac.num_timesteps == 150
    assert not torch.equal(cnn_weights(sac.actor.features_extractor), before)
    batch = sac.replay_buffer.sample(256)
    pixels = batch.observations["pixels"].numpy()
    assert pixels.shape == (256, 3, 48, 48) and pixels.std() > 0
    achieved = batch.next_observations["achieved_goal"].numpy()
    desired = batch.observations["desired_goal"].numpy()
    rewards = env.unwrapped.compute_reward(achieved, desired, {})
    np.testing.assert_array_equal(batch.rewards.numpy()[:, 0], rewards)
    assert (rewards == 0).any()  # relabelled goals the random cube reached
