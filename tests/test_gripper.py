"""The two-finger parallel gripper (``effector="gripper"``, envs/gripper.py): its option,
spaces and checkers in every obs_mode, the fingers' motion and force limit, a grasp that
holds by friction alone (and slips where friction or the grip cannot hold), the scripted
policies, snapshots, the vector env and frames."""

import copy
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from rigid_gym.envs.effector import STEP_DISTANCE
from rigid_gym.envs.gripper import (
    FINGER_DROP,
    FINGER_SPEED,
    GRIP_FORCE,
    GRIPPER_START,
    MAX_OPENING,
)
from rigid_gym.envs.scripted import scripted_policy
from rigid_gym.envs.task import CUBE_HALF, STEP_TIME
from stable_baselines3.common.env_checker import check_env as sb3_check_env

GRASPING = ["Stack", "Throw", "PickAndPlace", "Tower", "Insert"]
OBS_MODES = ["state", "pixels", "state+pixels"]
G = 9.81


def make(task, **kwargs):
    return gym.make(f"rigid_gym/{task}-v0", effector="gripper", **kwargs).unwrapped


@pytest.mark.parametrize("task", GRASPING)
@pytest.mark.parametrize("mode", OBS_MODES)
def test_checkers_pass_in_every_mode(task, mode):
    """Gymnasium's and SB3's check_env (determinism of reset(seed) and step included) pass
    with the gripper; the action has the finger command, the observation the opening."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*(infinity|needs a display).*")
        env = make(task, obs_mode=mode, width=36, height=36)
        check_env(env)
        sb3_check_env(make(task, obs_mode=mode, width=36, height=36))
    assert env.action_space.shape == (4,)
    obs, _ = env.reset(seed=0)
    if mode != "pixels":
        layout = env.task.observation_layout
        assert obs["observation"].shape == (layout.size,)
        assert obs["observation"][layout.slice("fingers.width")] == pytest.approx(MAX_OPENING)
    if mode != "state":
        assert obs["pixels"].shape == (36, 36, 3)


@pytest.mark.parametrize("task", ["Push", "Reach", "Slide", "Flip"])
def test_the_gripper_is_refused_where_nothing_is_picked_up(task):
    with pytest.raises(ValueError, match=r"effector='gripper' is for the tasks that pick "):
        gym.make(f"rigid_gym/{task}-v0", effector="gripper")
    with pytest.raises(ValueError, match=r"effector='gripper' is for the tasks that pick "):
        gym.make_vec(f"rigid_gym/{task}-v0", num_envs=2, effector="gripper")


@pytest.mark.parametrize("effector", ["suction", "", None, 1, "Gripper"])
def test_a_bad_effector_is_refused_before_anything_is_built(effector):
    with pytest.raises(ValueError, match=r"StackEnv: effector must be one of \['pad', "
                                         r"'gripper'\], got"):
        gym.make("rigid_gym/Stack-v0", effector=effector)
    with pytest.raises(ValueError, match=r"TowerEnv: effector must be one of"):
        gym.make_vec("rigid_gym/Tower-v0", num_envs=2, num_cubes=4, effector=effector)


def test_the_pad_stays_the_default_and_the_layouts_differ_only_by_the_effector():
    pad = gym.make("rigid_gym/Stack-v0").unwrapped
    gripper = make("Stack")
    assert pad.task.effector == "pad" and gripper.task.effector == "gripper"
    assert type(pad.task) is type(gripper.task) and pad.task is not gripper.task
    names = [f.name for f in gripper.task.observation_layout.fields]
    assert names[:4] == ["hand.position", "hand.velocity", "holding", "fingers.width"]
    assert names[4:] == [f.name for f in pad.task.observation_layout.fields][3:]
    assert gripper.scalar_series[1].labels == ("x", "y", "z", "fingers")
    assert make("Tower", num_cubes=4).task.num_cubes == 4


def drive(env, target, finger, steps=40):
    """Step ``env`` with the hand moving towards ``target`` (3,) m and finger command
    ``finger``, until the hand is there (or ``steps`` steps); returns the last observation."""
    for _ in range(steps):
        hand = env.gripper.position
        motion = np.clip((np.asarray(target) - hand) / STEP_DISTANCE, -1.0, 1.0)
        obs, *_ = env.step(np.append(motion, finger))
        if np.abs(env.gripper.position - target).max() < 1e-9:
            break
    return obs


def test_the_fingers_move_at_the_commanded_rate_within_their_travel():
    """The opening changes by FINGER_SPEED a STEP_TIME a step (the motors reach their speed
    within the first solver step: 80 g at 0.25 m/s takes 5 N), and stops at 8 cm (the
    limits) and where the pads meet (their contact stops them as their predicted poses meet:
    within the 2 mm they close in a solver step)."""
    env = make("PickAndPlace")
    env.reset(seed=0)
    env.world.set_pose(env.cubes[0], (0.2, 0.2, CUBE_HALF))  # nothing between the fingers
    widths = [env.gripper.grasp(slice(None))[1][0]]
    for finger in (-1.0, -0.5, 1.0):
        env.step([0, 0, 0, finger])
        widths.append(env.gripper.grasp(slice(None))[1][0])
    np.testing.assert_allclose(np.diff(widths), np.array([-1.0, -0.5, 1.0]) * FINGER_SPEED
                               * STEP_TIME, atol=1e-9)
    for finger, (low, high) in ((-1.0, (0.0, FINGER_SPEED * env.world.dt)),
                                (1.0, (MAX_OPENING - 1e-9, MAX_OPENING + 1e-9))):
        for _ in range(6):
            obs, *_ = env.step([0, 0, 0, finger])
        assert low <= env.gripper.grasp(slice(None))[1][0] <= high
        assert obs["observation"][7] == np.float32(env.gripper.grasp(slice(None))[1][0])


def test_the_force_limit_stops_the_fingers_on_the_table_and_on_a_cube():
    """A downward move stops where the finger tips rest on the table (the hand's centre
    FINGER_DROP up), or, closing over a cube, on its top, which is left where it was."""
    env = make("PickAndPlace")
    env.reset(seed=0)
    cube = env.world.position[env.cubes[0]].copy()
    away = cube[:2] + (0.08 if cube[0] < 0 else -0.08, 0.0)
    drive(env, (*away, GRIPPER_START[2]), 1.0)
    for _ in range(6):
        env.step([0, 0, -1, 1])
    assert env.gripper.position[2] == pytest.approx(FINGER_DROP, abs=1e-9)
    # over the cube, half closed and closing as it goes down: the fingers sweep over the
    # cube's top within the first step down, so they stop on it
    drive(env, (cube[0], cube[1], GRIPPER_START[2]), -1.0)
    assert 2 * CUBE_HALF - 0.01 < env.gripper.grasp(slice(None))[1][0] < 2 * CUBE_HALF + 0.01
    for _ in range(6):
        env.step([0, 0, -1, -1])
    assert env.gripper.position[2] == pytest.approx(2 * CUBE_HALF + FINGER_DROP, abs=1e-9)
    np.testing.assert_allclose(env.world.position[env.cubes[0]], cube, atol=1e-6)


def grasped(seed=0, mass=None, friction=None):
    """PickAndPlace with the gripper closed on its cube (the cube's mass and friction set
    first where given) and the pads pressing it, at rest: (env, the hand's height above the
    cube's centre)."""
    env = make("PickAndPlace")
    env.reset(seed=seed)
    cube = env.cubes[0]
    if mass is not None or friction is not None:
        env.world.set_material(cube, mass=mass, friction=friction)
    centre = env.world.position[cube].copy()
    drive(env, (centre[0], centre[1], GRIPPER_START[2]), 1.0)
    drive(env, (centre[0], centre[1], FINGER_DROP + 0.01), 1.0)
    for _ in range(4):
        env.step([0, 0, 0, -1])
    assert env.gripper.held[0] == 0
    return env, env.gripper.position[2] - env.world.position[cube][2]


def test_a_cube_is_held_by_friction_with_the_grip_force():
    """Closed on the cube, each pad presses it with GRIP_FORCE (the contact's impulse over a
    step, to 1%), and lifted at 0.75 m/s for 8 steps it rises with the hand without slipping
    (to 1e-9 m): m g = 1 N, with the hand's jump to 0.75 m/s in a solver step 20 N, is well
    within 2 mu F = 70 N, and static friction holds exactly (contact patches)."""
    env, height = grasped()
    # a pad may rest up to a solver step's travel at the pressing speed away: its contact is
    # found where the predicted poses meet
    contacts = env.world.contacts(margin=env.gripper.press_speed * env.world.dt)
    pads = {(int(a), int(b)): abs(impulse[1]) / env.world.dt  # along y, the pads' normal
            for a, b, impulse in zip(contacts.body_a, contacts.body_b, contacts.pair_impulse)
            if env.cubes[0] in (a, b) and {a, b} & set(env.gripper.fingers.tolist())}
    assert len(pads) == 2 and np.allclose(list(pads.values()), GRIP_FORCE, rtol=0.01), pads
    for _ in range(8):
        obs, *_ = env.step([0, 0, 0.6, -1])
    assert obs["observation"][6] == 1.0
    assert env.gripper.position[2] - env.world.position[env.cubes[0]][2] == pytest.approx(
        height, abs=1e-9)


def test_without_friction_or_with_too_heavy_a_cube_it_slips():
    """No weld anywhere: lifted 1 cm slowly (1 mm a step: the hand's jump to 0.025 m/s in a
    solver step adds 6 m/s^2), a cube of friction 0 stays on the table, one of 10 kg
    (m (g + a) = 160 N > 2 mu F = 70 N, mu = 0.5) slides out and stays too, while 3 kg
    (48 N) rises with the hand."""
    for mass, friction, holds in ((None, 0.0, False), (10.0, None, False), (3.0, None, True)):
        env, _ = grasped(mass=mass, friction=friction)
        hand, cube = env.gripper.position[2], env.world.position[env.cubes[0]][2]
        for _ in range(10):
            env.step([0, 0, 0.02, -1])
        rise = env.world.position[env.cubes[0]][2] - cube
        assert env.gripper.position[2] - hand == pytest.approx(0.01, abs=1e-9)
        assert (rise > 0.009) == holds and (rise < 1e-3) == (not holds), (mass, friction, rise)


@pytest.mark.parametrize("task", GRASPING)
def test_the_scripted_policies_succeed_with_the_gripper(task):
    """The scripted policy with the gripper (approach open, close, lift, carry, place and
    open; Throw opens in flight) reaches the goal on the first three seeds."""
    env = gym.make(f"rigid_gym/{task}-v0", effector="gripper")
    policy = scripted_policy(env)
    for seed in range(3):
        obs, _ = env.reset(seed=seed)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            done = terminated or truncated
        assert info["is_success"], (task, seed)


def trace(env, actions):
    out = []
    for action in actions:
        obs, reward, *_ = env.step(action)
        out.append(b"".join(np.ascontiguousarray(v).tobytes() for v in obs.values())
                   + np.float64(reward).tobytes())
    return out


def test_snapshots_deepcopy_and_pickle_step_on_bit_for_bit_while_holding():
    """Saved while the fingers press a cube (the motors' targets are part of the state):
    restoring, a deep copy and a pickled copy step on as the original does."""
    env = make("Stack", randomize={"mass": (0.5, 2.0), "friction": (0.5, 1.5)})
    obs, _ = env.reset(seed=3)
    policy = scripted_policy(env)
    for _ in range(60):
        obs, *_ = env.step(policy(obs))
        if env.gripper.held[0] >= 0 and obs["observation"][7] < 2 * CUBE_HALF + 1e-3:
            break
    assert env.gripper.held[0] >= 0
    state_id = env.save_state()
    copies = [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]
    actions = [policy(obs)] * 5 + list(np.random.default_rng(0).uniform(-1, 1, (40, 4)))
    first = trace(env, actions)
    env.restore_state(state_id)
    assert trace(env, actions) == first
    for other in copies:
        assert trace(other, actions) == first


def test_the_vector_env_plays_what_single_envs_play():
    """Copy i of make_vec(effector="gripper") reset with seed s plays the single env reset
    with s + i, bit for bit, under the same actions."""
    envs = gym.make_vec("rigid_gym/PickAndPlace-v0", num_envs=3, effector="gripper")
    actions = np.random.default_rng(1).uniform(-1, 1, (30, 3, 4))
    obs, _ = envs.reset(seed=7)
    batched = [obs["observation"]]
    for a in actions:
        batched.append(envs.step(a)[0]["observation"])
    for i in range(3):
        env = gym.make("rigid_gym/PickAndPlace-v0", effector="gripper")
        single = [env.reset(seed=7 + i)[0]["observation"]]
        for a in actions:
            single.append(env.step(a[i])[0]["observation"])
        np.testing.assert_array_equal(np.array(single), np.array(batched)[:, i])


def test_frames_show_the_fingers():
    """In an rgb_array frame the fingers are drawn (in the hand's lighter grey, not a cube's
    colour): where a finger stands open, the picture changes when the fingers close."""
    from rigid_gym.render import DRIVEN_COLOR, body_colors

    env = make("PickAndPlace", render_mode="rgb_array", render_width=160, render_height=160)
    env.reset(seed=0)
    env.world.set_pose(env.cubes[0], (0.2, 0.2, CUBE_HALF))
    colors = body_colors(env.scene)
    for finger in env.gripper.fingers.tolist():
        np.testing.assert_array_equal(colors[finger], DRIVEN_COLOR)
    open_frame = env.render().astype(int)
    camera = env.renderer.camera
    points, _ = camera.project(env.world.position[env.gripper.fingers], 160, 160)
    for _ in range(3):
        env.step([0, 0, 0, -1])
    closed = env.render().astype(int)
    for x, y in points:
        pixel = open_frame[int(y), int(x)]
        assert np.ptp(pixel) < 12 and pixel.max() < 200  # a grey, darker than the floor
        assert np.abs(closed[int(y), int(x)] - pixel).max() > 20  # the finger moved away
