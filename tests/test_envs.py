"""The Gymnasium tasks: API conformance, determinism, rewards, the gripper, bad input."""

import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.error import ResetNeeded
from gymnasium.utils.env_checker import check_env
from rigid_gym._core import Pads, gather_observations
from rigid_gym.envs.core import ALL
from rigid_gym.envs.effector import PAD_HALF_EXTENTS, STEP_DISTANCE, Workspace
from rigid_gym.envs.scripted import scripted_policy
from rigid_gym.envs.task import CUBE_HALF, CUBE_MASS, STEP_TIME
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import rigid_gym

TASK_IDS = ["rigid_gym/Push-v0", "rigid_gym/Stack-v0", "rigid_gym/Throw-v0"]
TASK_IDS += ["rigid_gym/Reach-v0", "rigid_gym/PickAndPlace-v0", "rigid_gym/Slide-v0",
             "rigid_gym/Flip-v0", "rigid_gym/Tower-v0", "rigid_gym/Insert-v0"]


def make(env_id, **kwargs):
    return gym.make(env_id, **kwargs).unwrapped


def without_a_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")


def test_every_id_is_registered_on_import():
    assert rigid_gym.ENV_IDS == [
        "rigid_gym/Push-v0", "rigid_gym/PushDense-v0", "rigid_gym/Stack-v0",
        "rigid_gym/StackDense-v0", "rigid_gym/Throw-v0", "rigid_gym/ThrowDense-v0",
        "rigid_gym/Reach-v0", "rigid_gym/ReachDense-v0",
        "rigid_gym/PickAndPlace-v0", "rigid_gym/PickAndPlaceDense-v0",
        "rigid_gym/Slide-v0", "rigid_gym/SlideDense-v0", "rigid_gym/Flip-v0", "rigid_gym/FlipDense-v0",
        "rigid_gym/Tower-v0", "rigid_gym/TowerDense-v0",
        "rigid_gym/Insert-v0", "rigid_gym/InsertDense-v0"]
    assert [gym.spec(i).max_episode_steps for i in rigid_gym.ENV_IDS] == [
        50, 50, 100, 100, 50, 50,
        50, 50, 50, 50, 50, 50, 50, 50,
        150, 150,
        50, 50]


@pytest.mark.parametrize("env_id", rigid_gym.ENV_IDS)
def test_gymnasium_and_sb3_checkers_pass_headless(env_id, monkeypatch):
    without_a_display(monkeypatch)  # as on a server or CI: render_mode="human" has no viewer
    # both checkers warn that the observation bounds are infinite: velocities are unbounded
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*(infinity|needs a display).*")
        # every check, the render modes' included (human too: it says there is no display)
        check_env(make(env_id))  # includes reset(seed) then reset()
        sb3_check_env(make(env_id))  # includes compute_reward on a batch of 2


def run(env, actions, seed):
    observations = [env.reset(seed=seed)[0]]
    for action in actions:
        observations.append(env.step(action)[0])
    return observations


@pytest.mark.parametrize("env_id", TASK_IDS)
def test_same_seed_and_actions_give_bit_identical_observations(env_id):
    env_a = gym.make(env_id, max_episode_steps=200)
    env_b = gym.make(env_id, max_episode_steps=200)
    actions = np.random.default_rng(3).uniform(-1, 1, (200,) + env_a.action_space.shape)
    for obs_a, obs_b in zip(run(env_a, actions, 11), run(env_b, actions, 11)):
        for key in obs_a:
            assert obs_a[key].tobytes() == obs_b[key].tobytes()
    # a different seed gives a different episode
    other = run(env_b, actions[:1], 12)[0]["desired_goal"]
    assert other.tobytes() != run(env_a, actions[:1], 11)[0]["desired_goal"].tobytes()



@pytest.mark.parametrize("env_id", TASK_IDS)
def test_a_reset_after_an_episode_equals_a_fresh_env(env_id):
    """A reset reuses the env's World (only poses and materials are written; Throw's bin
    moves): after an episode with other draws, reset(seed) and the same actions give the bits
    a new env gives, with mass, friction and restitution randomised."""
    randomize = {"mass": (0.5, 2.0), "friction": (0.5, 1.5), "restitution": (0.0, 0.3)}
    used, fresh = make(env_id, randomize=randomize), make(env_id, randomize=randomize)
    actions = np.random.default_rng(5).uniform(-1, 1, (60,) + used.action_space.shape)
    run(used, actions, 4)
    for obs_used, obs_fresh in zip(run(used, actions, 11), run(fresh, actions, 11)):
        for key in obs_used:
            assert obs_used[key].tobytes() == obs_fresh[key].tobytes()
    for name in ("inverse_mass", "inverse_moments", "friction", "restitution"):
        np.testing.assert_array_equal(getattr(used.world.model, name),
                                      getattr(fresh.world.model, name))

@pytest.mark.parametrize("env_id", rigid_gym.ENV_IDS)
def test_compute_reward_on_a_batch_equals_the_step_rewards(env_id):
    env = gym.make(env_id)
    task = env.unwrapped
    policy = scripted_policy(env)  # reaches the goal: both sparse values occur
    achieved, desired, rewards = [], [], []
    for seed, random_share in ((0, 0.0), (1, 0.3)):
        obs, _ = env.reset(seed=seed)
        rng = np.random.default_rng(seed)
        for _ in range(env.spec.max_episode_steps):
            action = env.action_space.sample() if rng.uniform() < random_share else policy(obs)
            obs, reward, _, _, info = env.step(action)
            achieved.append(obs["achieved_goal"])
            desired.append(obs["desired_goal"])
            rewards.append(reward)
            assert reward == task.compute_reward(obs["achieved_goal"], obs["desired_goal"], info)
    batch = task.compute_reward(np.array(achieved), np.array(desired), [{}] * len(rewards))
    assert batch.shape == (len(rewards),)
    np.testing.assert_array_equal(batch, rewards)
    if task.reward_type == "sparse":
        assert set(rewards) == {-1.0, 0.0}


def test_max_episode_steps_override():
    env = gym.make("rigid_gym/Push-v0", max_episode_steps=7)
    env.reset(seed=0)
    truncated = [env.step(np.zeros(3))[3] for _ in range(7)]
    assert truncated == [False] * 6 + [True]


@pytest.mark.parametrize("env_id", TASK_IDS)
def test_scripted_policy_solves_most_seeded_episodes(env_id):
    env = gym.make(env_id)
    policy = scripted_policy(env)
    successes = 0
    for seed in range(6):
        obs, info = env.reset(seed=seed)
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs))
            done = terminated or truncated
        successes += info["is_success"]
    assert successes >= 5  # benchmarks/envs.py measures the rates over 100 seeds


def test_terminate_on_success_ends_the_episode():
    env = gym.make("rigid_gym/Push-v0", terminate_on_success=True)
    policy = scripted_policy(env)
    obs, _ = env.reset(seed=0)
    for step in range(50):
        obs, reward, terminated, _truncated, info = env.step(policy(obs))
        if terminated:
            break
    assert terminated and info["is_success"] and reward == 0.0 and step < 49



def test_stack_needs_the_tower_but_a_relabelled_goal_of_cubes_apart_is_reachable():
    env = make("rigid_gym/Stack-v0")
    env.reset(seed=0)
    h = CUBE_HALF
    tower = np.array([0.1, 0.0, h, 0.1, 0.0, 3 * h])  # the kind of target the env samples
    assert env.goal_reached(tower, tower)
    assert env.goal_reached(tower + [0.03, 0, 0, 0.03, 0.01, 0.004], tower)  # near, still a tower
    # both cubes within 5 cm of their targets but side by side on the table: no tower
    side_by_side = np.array([0.1, 0.0, h, 0.1 + 0.03, 0.0, h])
    assert np.linalg.norm(side_by_side[3:] - tower[3:]) < 0.05
    assert not env.goal_reached(side_by_side, tower)
    assert not env.goal_reached(tower + [0, 0, 0, 0.025, 0, 0], tower)  # overhanging by > h
    # a goal relabelled from where the cubes lay apart is reached by cubes lying that way
    apart = np.array([-0.1, 0.05, h, 0.1, -0.05, h])
    assert env.goal_reached(apart + 0.01, apart)
    assert not env.goal_reached(apart, tower) and not env.goal_reached(tower, apart)


# -- the gripper -------------------------------------------------------------------------------

def pad_over_cube(env, cube: int = 0):
    """Put the pad right above a cube (teleport for the test) and return the cube's position."""
    position = env.world.position[env.cubes[cube]].copy()
    env.world.set_pose(env.gripper.body,
                       position=position + [0, 0, CUBE_HALF + PAD_HALF_EXTENTS[2] + 0.002])
    return position


def test_suction_grips_carries_and_releases_with_the_pad_velocity():
    env = make("rigid_gym/Stack-v0")
    env.reset(seed=0)
    start = pad_over_cube(env)
    obs = env.step([0, 0, -1, 1])[0]
    assert obs["observation"][6] == 1.0  # holding
    for _ in range(3):
        obs = env.step([0.5, 0, 1, 1])[0]
    cube = env.world.position[env.cubes[0]]
    pad = env.gripper.position
    np.testing.assert_allclose(cube[:2], start[:2] + [0.075, 0], atol=1e-12)
    np.testing.assert_allclose(pad - cube, [0, 0, CUBE_HALF + PAD_HALF_EXTENTS[2]], atol=0.003)
    # open while moving: the cube leaves with the pad's velocity, then flies freely
    before = env.world.position[env.cubes[0]].copy()
    obs = env.step([1, 0, 1, -1])[0]
    assert obs["observation"][6] == 0.0
    velocity = env.world.velocity[env.cubes[0]]
    speed = 0.05 / STEP_TIME
    np.testing.assert_allclose(velocity[:2], [speed, 0], atol=1e-12)
    np.testing.assert_allclose(velocity[2], speed - 9.81 * STEP_TIME, atol=1e-12)
    moved = env.world.position[env.cubes[0]] - before
    np.testing.assert_allclose(moved[0], speed * STEP_TIME, atol=1e-12)


def test_an_open_pad_does_not_grip_and_a_closed_pad_grips_only_what_it_touches():
    env = make("rigid_gym/Stack-v0")
    env.reset(seed=0)
    pad_over_cube(env)
    assert env.step([0, 0, 0, -1])[0]["observation"][6] == 0.0  # open
    env.world.set_pose(env.gripper.body, position=env.gripper.position + [0, 0, 0.05])
    assert env.step([0, 0, 0, 1])[0]["observation"][6] == 0.0  # 5 cm above: nothing to grip


def test_pressing_down_on_a_cube_stops_at_its_top_and_leaves_it_on_the_table():
    env = make("rigid_gym/Push-v0")
    env.reset(seed=0)
    start = pad_over_cube(env)
    for _ in range(10):
        env.step([0, 0, -1])
    np.testing.assert_allclose(env.world.position[env.cubes[0]], start, atol=1e-9)
    assert env.gripper.position[2] == pytest.approx(2 * CUBE_HALF + PAD_HALF_EXTENTS[2], abs=1e-9)


def test_a_cube_gripped_as_the_pad_moves_off_its_top_and_down_stays_on_the_table():
    """The pad rests on a cube's corner, then closes while moving 5 cm aside and 5 cm down,
    clear of the cube at the move's end: the cube is gripped before the move, whose force
    limit counts it, so it is carried along the table's top, not into the table (it went
    4 cm deep when the grip came after the move's limit)."""
    env = make("rigid_gym/Stack-v0")
    env.reset(seed=0)
    start = pad_over_cube(env)
    env.world.set_pose(env.gripper.body, position=env.gripper.position + [-0.017, 0.025, -0.002])
    obs = env.step([0, 1, -1, 1])[0]
    assert obs["observation"][6] == 1.0  # holding
    cube = env.world.position[env.cubes[0]]
    np.testing.assert_allclose(cube, start + [0, 0.05, 0], atol=1e-9)
    assert env.gripper.position[2] == pytest.approx(2 * CUBE_HALF + PAD_HALF_EXTENTS[2], abs=1e-9)


def test_pads_check_what_they_are_made_with_and_commanded():
    """The gripper's bound command object refuses a pad or an object that is no body, a step
    time <= 0, a fixture part on no body and arrays of other shapes, saying which; a command sets only the pads'
    velocities: step_distance x motion / step_time where nothing is below."""
    def pads(**changes):
        kwargs = {"num_worlds": 2, "num_bodies": 3, "pad": 2, "pad_half": PAD_HALF_EXTENTS,
                  "objects": np.array([1], dtype=np.int64), "halves": np.full((1, 3), 0.02),
                  "fixed_bodies": np.array([0], dtype=np.int64),
                  "fixed_offsets": np.zeros((1, 3)), "fixed_rotations": np.eye(3)[None],
                  "fixed_halves": np.full((1, 3), 0.05), "carried": np.zeros(0, dtype=np.int64),
                  "carried_halves": np.zeros((0, 3)), "low": (-1.0, -1.0, 0.0), "high": (1.0, 1.0, 1.0),
                  "step_distance": STEP_DISTANCE, "step_time": 0.04}
        return Pads(**{**kwargs, **changes})

    with pytest.raises(ValueError, match="Pads: pad 3 is not a body"):
        pads(pad=3)
    with pytest.raises(ValueError, match="Pads: step_time must be > 0"):
        pads(step_time=0.0)
    with pytest.raises(ValueError, match="Pads: objects"):
        pads(objects=np.array([5], dtype=np.int64))
    with pytest.raises(ValueError, match="Pads: halves"):
        pads(halves=np.full((2, 3), 0.02))
    with pytest.raises(ValueError, match="Pads: fixed_bodies"):
        pads(fixed_bodies=np.array([3], dtype=np.int64))
    with pytest.raises(ValueError, match="Pads: fixed_rotations"):
        pads(fixed_rotations=np.eye(3))
    with pytest.raises(ValueError, match="Pads: carried"):
        pads(carried=np.array([3], dtype=np.int64), carried_halves=np.full((1, 3), 0.01))
    with pytest.raises(ValueError, match="Pads: carried_halves"):
        pads(carried=np.array([1], dtype=np.int64), carried_halves=np.full((2, 3), 0.01))
    driver = pads()
    positions = np.zeros((2, 3, 3))
    positions[:, 1] = (0.5, 0.5, 0.02)  # the box, away from the pads
    positions[:, 2] = (0.0, 0.0, 0.5)
    rotations = np.tile(np.eye(3), (2, 3, 1, 1))
    velocities = np.zeros((2, 3, 3))
    held = np.array([-1, -1], dtype=np.int64)
    motions = np.array([[1.0, 0.0, -1.0], [0.0, 0.5, 0.0]])
    driver.command(motions, positions, rotations, velocities, held)
    np.testing.assert_allclose(velocities[:, 2], motions * STEP_DISTANCE / 0.04, rtol=1e-12)
    assert not velocities[:, :2].any()
    with pytest.raises(ValueError, match="Pads.command: motions"):
        driver.command(motions[:1], positions, rotations, velocities, held)
    with pytest.raises(ValueError, match="Pads.command: held"):
        driver.command(motions, positions, rotations, velocities, np.array([0, 1]))


def test_pad_stays_in_the_workspace():
    env = make("rigid_gym/Push-v0")
    env.reset(seed=0)
    space = Workspace()
    for action in ([1, 1, 1], [-1, -1, -1], [1, -1, 0]):
        for _ in range(20):
            env.step(action)
            assert np.all(env.gripper.position >= np.array(space.low) - 1e-12)
            assert np.all(env.gripper.position <= np.array(space.high) + 1e-12)


def test_pushing_moves_the_cube():
    env = make("rigid_gym/Push-v0")
    env.reset(seed=0)
    cube = env.world.position[env.cubes[0]].copy()
    env.world.set_pose(env.gripper.body, position=cube - [0.06, 0, CUBE_HALF - PAD_HALF_EXTENTS[2]])
    for _ in range(3):
        env.step([0.5, 0, 0])
    moved = env.world.position[env.cubes[0]] - cube
    assert moved[0] > 0.02 and abs(moved[1]) < 1e-6 and abs(moved[2]) < 1e-6


# -- options -----------------------------------------------------------------------------------

def test_randomize_draws_new_parameters_each_reset_reproducibly():
    env = make("rigid_gym/Stack-v0", randomize=True)
    env.reset(seed=5)
    masses = 1.0 / env.world.model.inverse_mass[0, env.cubes]
    halves = env.cube_half.copy()
    assert np.all((masses >= 0.5 * CUBE_MASS) & (masses <= 2.0 * CUBE_MASS))
    assert np.all((halves >= 0.8 * CUBE_HALF) & (halves <= 1.2 * CUBE_HALF))
    assert env.goal[2] == halves[0]  # the goal follows the drawn size
    env.reset()
    assert not np.array_equal(env.cube_half, halves)
    env.reset(seed=5)
    np.testing.assert_array_equal(env.cube_half, halves)
    plain = make("rigid_gym/Stack-v0")
    plain.reset(seed=5)
    np.testing.assert_array_equal(plain.cube_half, [CUBE_HALF, CUBE_HALF])


def test_randomize_accepts_chosen_ranges():
    env = make("rigid_gym/Push-v0", randomize={"friction": (2.0, 2.0)})
    env.reset(seed=0)
    np.testing.assert_allclose(env.world.model.friction[0], 1.0)  # 0.5 * 2 for every body
    assert env.cube_half[0] == CUBE_HALF


def test_observation_noise_perturbs_the_observation_but_not_the_goals():
    clean, _ = make("rigid_gym/Push-v0").reset(seed=0)
    noisy, _ = make("rigid_gym/Push-v0", observation_noise=0.01).reset(seed=0)
    difference = noisy["observation"] - clean["observation"]
    assert 0.001 < np.std(difference) < 0.02
    np.testing.assert_array_equal(noisy["achieved_goal"], clean["achieved_goal"])
    np.testing.assert_array_equal(noisy["desired_goal"], clean["desired_goal"])


# -- bad input ---------------------------------------------------------------------------------

@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_actions_raise(bad):
    env = make("rigid_gym/Push-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must be finite"):
        env.step([0.0, bad, 0.0])


def test_wrong_action_shape_raises():
    env = make("rigid_gym/Push-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"action must have shape \(3,\)"):
        env.step([0.0, 0.0, 0.0, 1.0])


@pytest.mark.parametrize("bad", [
    "abc", "0.5", np.array([0.5, 0.0, 1j]), np.array([0.5, 0.0, 0.0], dtype=object),
    {"x": 0.5}, ["0.5", "0", "0"],
], ids=["str", "numeric str", "complex", "object", "dict", "list of str"])
def test_actions_that_are_not_real_numbers_are_refused(bad):
    env = make("rigid_gym/Push-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"PushEnv\.step: action must be a real numeric array "
                                         r"\(bool, int or float\) in Box\(-1\.0, 1\.0, \(3,\), "
                                         r"float32\), got "):
        env.step(bad)


def test_bool_int_and_float_actions_of_any_width_are_taken_as_their_values():
    expected = make("rigid_gym/Push-v0")
    expected.reset(seed=0)
    observation = expected.step([1.0, 0.0, -1.0])[0]["observation"]
    for action in (np.array([1, 0, -1], dtype=np.int8), [True, False, -1],
                   np.array([1.0, 0.0, -1.0], dtype=np.float16)):
        env = make("rigid_gym/Push-v0")
        env.reset(seed=0)
        np.testing.assert_array_equal(env.step(action)[0]["observation"], observation)


def test_actions_outside_the_box_are_clipped():
    big, small = make("rigid_gym/Push-v0"), make("rigid_gym/Push-v0")
    big.reset(seed=0)
    small.reset(seed=0)
    np.testing.assert_array_equal(big.step([5.0, -3.0, 0.2])[0]["observation"],
                                  small.step([1.0, -1.0, 0.2])[0]["observation"])


def test_stepping_before_reset_is_refused():
    with pytest.raises(ResetNeeded, match="reset"):
        make("rigid_gym/Push-v0").step(np.zeros(3))


@pytest.mark.parametrize("kwargs, message", [
    ({"colour": "red"}, r"unknown argument\(s\) \[.colour.\]; the arguments are render_mode"),
    ({"reward_type": "staged"}, "reward_type must be"),
    ({"render_mode": "ansi"}, "render_mode must be"),
    ({"observation_noise": -0.1}, "observation_noise: must be finite and >= 0, got -0.1"),
    ({"randomize": {"gravity": (0, 1)}}, "unknown key"),
    ({"randomize": {"mass": (2.0, 1.0)}}, "low <= high"),
    ({"randomize": {"restitution": (0.0, 1.5)}}, "<= 1.0"),
    ({"terminate_on_success": 1}, "must be a bool"),
])
def test_bad_constructor_arguments_fail_at_construction(kwargs, message):
    with pytest.raises((TypeError, ValueError), match=message):
        gym.make("rigid_gym/Push-v0", **kwargs)


# -- rendering ---------------------------------------------------------------------------------

@pytest.mark.parametrize("env_id", TASK_IDS)
def test_rgb_array_frames_show_the_task_and_are_reproducible(env_id):
    frames = []
    for _ in range(2):
        env = gym.make(env_id, render_mode="rgb_array")
        env.reset(seed=0)
        env.step(env.action_space.sample() * 0)
        frames.append(env.render())
    frame = frames[0]
    assert frame.shape == (480, 480, 3) and frame.dtype == np.uint8
    assert frame.tobytes() == frames[1].tobytes()
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 50  # shaded, not flat


def test_human_mode_without_a_display_says_so_once_and_shows_nothing(monkeypatch):
    without_a_display(monkeypatch)
    env = make("rigid_gym/Push-v0", render_mode="human")  # constructing never raises
    env.reset(seed=0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(3):
            assert env.step(np.zeros(3))[0] is not None  # step renders in human mode
            assert env.render() is None
    assert [str(w.message).count("needs a display") for w in caught] == [1]


def test_render_needs_a_mode_and_a_reset():
    env = make("rigid_gym/Push-v0", render_mode="rgb_array")
    with pytest.raises(ResetNeeded):
        env.render()
    plain = make("rigid_gym/Push-v0")
    plain.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert plain.render() is None


@pytest.mark.parametrize("env_id", TASK_IDS)
def test_every_task_documents_its_spaces_rewards_start_end_and_arguments(env_id):
    doc = type(make(env_id)).__doc__
    for section in ("## Action space", "## Observation space", "## Rewards", "## Starting state",
                    "## Episode end", "## Arguments", "| observation_noise | 0.0 |"):
        assert section in doc
    assert "{arguments}" not in doc


def test_a_non_finite_state_is_reported_by_the_env_not_passed_on():
    env = make("rigid_gym/Push-v0")
    env.reset(seed=0)
    env.world.state.velocity[0, env.cubes[0], 0] = np.nan  # what a solver failure would leave
    with pytest.raises(RuntimeError, match="non-finite state"):
        env.step(np.zeros(3))


LAYOUTS = {
    "rigid_gym/Push-v0": ["pad.position", "pad.velocity", *(
        f"cube0.{q}" for q in ("position", "offset", "orientation", "velocity",
                               "angular_velocity"))],
    "rigid_gym/Stack-v0": ["pad.position", "pad.velocity", "holding", *(
        f"cube{k}.{q}" for k in (0, 1) for q in ("position", "offset", "orientation", "velocity",
                                                 "angular_velocity"))],
    "rigid_gym/Throw-v0": ["pad.position", "pad.velocity", "holding", *(
        f"cube0.{q}" for q in ("position", "offset", "orientation", "velocity",
                               "angular_velocity"))],
}
LAYOUTS.update({"rigid_gym/Reach-v0": ["pad.position", "pad.velocity"],
                "rigid_gym/PickAndPlace-v0": LAYOUTS["rigid_gym/Throw-v0"],
                "rigid_gym/Slide-v0": LAYOUTS["rigid_gym/Push-v0"],
                "rigid_gym/Flip-v0": LAYOUTS["rigid_gym/Throw-v0"],
                "rigid_gym/Tower-v0": ["pad.position", "pad.velocity", "holding", *(
                    f"cube{k}.{q}" for k in (0, 1, 2) for q in (
                        "position", "offset", "orientation", "velocity", "angular_velocity"))],
                "rigid_gym/Insert-v0": LAYOUTS["rigid_gym/Throw-v0"]})
"""Each task's observation fields in order: the committed models were trained on this order."""


def rotation_of(q):
    """The rotation matrix (3, 3) of a unit quaternion (w, x, y, z), written out."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def expected_fields(env):
    """Every observation field by name, read from the World's API (float64) and the gripper's
    attachment, independently of the layout and the gather index."""
    w, pad = env.world, env.gripper.body
    holding = np.isin(w.attached.parent[0, env.cubes], [pad]).any()
    fields = {"pad.position": w.position[pad], "pad.velocity": w.velocity[pad],
              "holding": np.array([1.0 if holding else 0.0])}
    for k, cube in enumerate(env.cubes):
        fields |= {f"cube{k}.position": w.position[cube],
                   f"cube{k}.offset": w.position[cube] - w.position[pad],
                   f"cube{k}.orientation": w.rotation[cube][:, :2].T.ravel(),
                   f"cube{k}.velocity": w.velocity[cube],
                   f"cube{k}.angular_velocity": w.angular_velocity[cube]}
    return fields


def check_fields(env, obs):
    """Each field of ``obs`` against ``expected_fields`` by name; the orientation also
    against the cube's quaternion; the goals against the cubes and the episode's targets."""
    layout = env.task.observation_layout
    fields = layout.split(obs["observation"])
    expected = expected_fields(env)
    for name, value in fields.items():
        assert value.dtype == np.float32
        np.testing.assert_array_equal(value, expected[name].astype(np.float32), err_msg=name)
    for k, cube in enumerate(env.cubes):
        columns = rotation_of(env.world.orientation[cube])[:, :2].T.ravel()
        np.testing.assert_allclose(fields[f"cube{k}.orientation"], columns, atol=1e-6)
    if env.task.goal_size == 4:  # Flip: the cube's orientation, w >= 0
        q = env.world.orientation[env.cubes[0]]
        np.testing.assert_array_equal(obs["achieved_goal"], (q if q[0] >= 0 else -q).astype(
            np.float32))
    elif not env.cubes:  # Reach: the pad
        np.testing.assert_array_equal(obs["achieved_goal"],
                                      env.world.position[env.gripper.body].astype(np.float32))
    else:
        cubes = np.concatenate([env.world.position[c] for c in env.cubes])
        np.testing.assert_array_equal(obs["achieved_goal"], cubes.astype(np.float32))
    np.testing.assert_array_equal(obs["desired_goal"], env.core.goals[0].astype(np.float32))
    return fields


@pytest.mark.parametrize("env_id", TASK_IDS)
def test_every_observation_field_is_the_world_state_it_names(env_id):
    """The task's layout names its fields in the order the models were trained on, covers
    the vector exactly and is what the env documents; each field, found by name, is the World
    state it names: over a scripted episode (the pad moving, cubes carried, held and let go)
    and in a state where every body's every quantity differs (set through the World's
    setters), so a swapped or shifted entry fails."""
    env = make(env_id)
    layout = env.task.observation_layout
    assert [f.name for f in layout.fields] == LAYOUTS[env_id]
    assert env.observation_space["observation"].shape == (layout.size,)
    ends = np.cumsum([f.size for f in layout.fields])
    assert [(s.start, s.stop) for s in layout.slices.values()] == list(
        zip([0, *ends[:-1]], ends))
    assert ends[-1] == layout.size
    for field, s in zip(layout.fields, layout.slices.values()):
        assert f"| {s.start}:{s.stop} | {field.name} | {field.content} |" in type(env).__doc__
    policy = scripted_policy(env)
    obs, _ = env.reset(seed=1)
    check_fields(env, obs)
    held = []
    for _ in range(gym.spec(env_id).max_episode_steps):
        obs = env.step(policy(obs))[0]
        held.append(check_fields(env, obs).get("holding", [0.0])[0])
    if env.task.has_grip and env_id != "rigid_gym/Flip-v0":  # Flip's policy rolls, not grips
        assert 0.0 in held and 1.0 in held  # the flag read both ways
    rng = np.random.default_rng(7)
    w = env.world
    for body in [env.gripper.body, *env.cubes]:  # the pad never turns
        q = rng.normal(size=4) if body != env.gripper.body else None
        w.set_pose(body, rng.uniform(-0.3, 0.3, 3), None if q is None else q / np.linalg.norm(q))
        w.set_velocity(body, rng.normal(size=3), None if q is None else rng.normal(size=3))
    batch = env.core.observe(ALL).observations  # a batch of one
    fields = check_fields(env, {key: value[0] for key, value in batch.items()})
    values = np.concatenate([fields[name] for name in LAYOUTS[env_id] if name != "holding"])
    assert len(np.unique(values)) == len(values)  # no two entries alike: a mix-up would show


def test_the_readme_task_table_states_each_task_s_sizes():
    """The README's table of tasks (action, observation / goal sizes, episode steps) against
    the envs' spaces, which the tasks' layouts make."""
    readme = (Path(__file__).resolve().parent.parent / "README.md").read_text()
    for env_id in TASK_IDS:
        name = env_id.split("/")[1]
        row = next(line for line in readme.splitlines() if line.startswith(f"| `{name}`"))
        cells = [cell.strip() for cell in row.strip("|").split("|")]
        env = make(env_id)
        space = env.observation_space
        assert cells[2:] == [str(env.action_space.shape[0]),
                             f"{space['observation'].shape[0]} / {space['desired_goal'].shape[0]}",
                             str(gym.spec(env_id).max_episode_steps)]


def test_observations_are_the_state_entries_their_index_names():
    """``gather_observations`` (src/envs/observation.h) against the same index applied by numpy to
    the state laid side by side, over worlds of random state: entry j is state entry index[j]
    minus entry minus[j] (a cube's offset from the pad) in the worlds asked for, and a state
    entry out of range is refused by name before anything is read."""
    envs = gym.make_vec("rigid_gym/Stack-v0", num_envs=5, vectorization_mode="vector_entry_point")
    envs.reset(seed=0)
    core = envs.unwrapped.core
    s = core.world.state
    rng = np.random.default_rng(0)
    for array in (s.position, s.velocity, s.rotation, s.angular_velocity):
        array[...] = rng.normal(size=array.shape)
    worlds = np.array([3, 0, 3], dtype=np.int64)
    out = np.empty((3, len(core.gather)))
    assert gather_observations(s.position, s.velocity, s.rotation, s.angular_velocity, worlds,
                               core.gather, core.minus, out)
    side_by_side = np.concatenate([a.reshape(5, -1) for a in
                                   (s.position, s.velocity, s.rotation, s.angular_velocity)],
                                  axis=1)[worlds]
    expected = side_by_side[:, core.gather] - np.where(core.minus >= 0,
                                                       side_by_side[:, core.minus], 0.0)
    assert out.tobytes() == expected.tobytes()
    assert (core.minus >= 0).sum() == 3 * 2  # each cube's offset from the pad
    s.velocity[1, 0, 1] = np.nan  # the table's, which no observation reads
    assert gather_observations(s.position, s.velocity, s.rotation, s.angular_velocity, worlds,
                               core.gather, core.minus, out)
    s.velocity[3, core.gripper_body, 1] = np.nan  # the pad's, in a world observed
    assert not gather_observations(s.position, s.velocity, s.rotation, s.angular_velocity,
                                   worlds, core.gather, core.minus, out)
    bad = core.gather.copy()
    bad[-1] = 18 * s.position.shape[1]
    with pytest.raises(ValueError, match="gather_observations: index holds"):
        gather_observations(s.position, s.velocity, s.rotation, s.angular_velocity, worlds,
                            bad, core.minus, out)
