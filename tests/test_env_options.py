"""What a user passes to an env beyond the task: render()'s size and panda-gym's camera
arguments, unknown arguments, reset options."""

import math

import gymnasium as gym
import numpy as np
import pytest
from rigid_gym.envs.options import ARGUMENTS, RenderOptions


@pytest.mark.parametrize("kwargs, shape", [
    ({}, (480, 480, 3)),
    ({"width": 128, "height": 96}, (96, 128, 3)),
    ({"width": 128, "height": 96, "render_width": 200}, (96, 200, 3)),
    ({"render_width": 64, "render_height": 48}, (48, 64, 3)),
])
def test_render_is_at_the_envs_size(kwargs, shape):
    env = gym.make("rigid_gym/Push-v0", render_mode="rgb_array", **kwargs)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == shape and frame.dtype == np.uint8
    assert frame.std() > 10  # a picture, not a blank


def test_panda_gym_camera_arguments_place_the_camera_as_pybullet_does():
    """eye = target + d (cos p sin y, -cos p cos y, -sin p) (PyBullet's
    computeViewMatrixFromYawPitchRoll with z up); an argument not given keeps the task's
    view's, which the default decomposes into exactly."""
    env = gym.make("rigid_gym/Push-v0", render_mode="rgb_array", render_target_position=(0.1, 0, 0),
                   render_distance=1.4, render_yaw=45, render_pitch=-30).unwrapped
    eye, target, _ = env.camera_view
    c = math.cos(math.radians(-30))
    expected = np.array([0.1, 0, 0]) + 1.4 * np.array([c * math.sin(math.radians(45)),
                                                       -c * math.cos(math.radians(45)),
                                                       -math.sin(math.radians(-30))])
    np.testing.assert_allclose(eye, expected, rtol=0, atol=1e-12)
    assert target == (0.1, 0.0, 0.0)
    plain = gym.make("rigid_gym/Push-v0").unwrapped
    assert plain.camera_view == plain.task.camera_view
    for key, value in (("render_yaw", None), ("render_distance", None)):
        kept = gym.make("rigid_gym/Push-v0", **{key: value}).unwrapped.camera_view
        assert kept == plain.task.camera_view
    # only the yaw given: the same distance, pitch and target, turned about z
    turned = RenderOptions.checked("t", None, None, render_yaw=0.0).view(plain.task.camera_view)
    eye0, target0, _ = plain.task.camera_view
    offset = np.subtract(turned[0], target0)
    assert offset[0] == pytest.approx(0.0, abs=1e-12) and offset[1] < 0
    assert np.linalg.norm(offset) == pytest.approx(np.linalg.norm(np.subtract(eye0, target0)))
    assert offset[2] == pytest.approx(eye0[2] - target0[2])


@pytest.mark.parametrize("kwargs, message", [
    ({"render_pitch": 90}, "render_pitch: must be finite and in [-89.9, 89.9] degrees"),
    ({"render_distance": 0}, "render_distance: must be finite and in (0, 100] m"),
    ({"render_width": 8}, "render_width: must be an int in [16, 4096] pixels"),
    ({"render_target_position": (0, 0)}, "render_target_position: expected shape (3,)"),
])
def test_bad_render_arguments_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=r"PushEnv: " + __import__("re").escape(message)):
        gym.make("rigid_gym/Push-v0", render_mode="rgb_array", **kwargs)


def test_unknown_arguments_list_the_valid_ones_through_make_and_make_vec():
    listed = ", ".join(ARGUMENTS)
    with pytest.raises(ValueError, match=r"PushEnv: unknown argument\(s\) \['rewrd_type'\]") as e:
        gym.make("rigid_gym/Push-v0", rewrd_type="dense")
    assert listed in str(e.value)
    with pytest.raises(ValueError, match=r"PushEnv vector env: unknown argument\(s\) "
                                         r"\['rewrd_type'\]") as e:
        gym.make_vec("rigid_gym/Push-v0", num_envs=2, rewrd_type="dense")
    assert listed in str(e.value) and "checked" not in str(e.value)
    with pytest.raises(ValueError, match="render_yaw must be None"):
        gym.make_vec("rigid_gym/Push-v0", num_envs=2, render_yaw=10)


def test_reset_options_are_refused_not_ignored():
    env = gym.make("rigid_gym/Push-v0")
    first = env.reset(seed=1, options={})[0]
    assert np.array_equal(env.reset(seed=1, options=None)[0]["desired_goal"],
                          first["desired_goal"])
    with pytest.raises(ValueError, match=r"PushEnv.reset: options: the tasks take no reset "
                                         r"options .* got \{'goal': 1\}"):
        env.reset(options={"goal": 1})
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=2)
    with pytest.raises(ValueError, match="RigidGymVectorEnv.reset: options"):
        envs.reset(options={"goal": 1})
