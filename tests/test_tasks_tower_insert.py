"""Tower (n cubes stacked in order) and Insert (a peg into a fixture's hole): registration,
the goal tests, the shaped rewards, the physics of the fit, the scripted policies, seeding,
and bad arguments. Gymnasium's and SB3's checkers run on every id in tests/test_envs.py
(state) and tests/test_pixels.py (every obs_mode)."""

import itertools

import gymnasium as gym
import numpy as np
import pytest
from rigid_gym.envs.effector import fixture_boxes
from rigid_gym.envs.insert import (
    CLEARANCE,
    HOLE_DEPTH,
    HOLE_HALF,
    IN_HOLE,
    PEG_HALF_EXTENTS,
    Insert,
    fixture_shape,
)
from rigid_gym.envs.scripted import scripted_policy
from rigid_gym.envs.task import CUBE_HALF, Task
from rigid_gym.envs.tower import Tower

import rigid_gym
from rigid_gym.render import Camera
from rigid_gym.shapes import Compound, Pose, Sphere

HALF3 = np.full((1, 3), CUBE_HALF)
NONE = np.array([-1])


def play(env, seed, steps=None):
    """A scripted episode of ``env`` from reset(seed): (last observation, last info, rewards)."""
    policy = scripted_policy(env)
    obs, info = env.reset(seed=seed)
    rewards = []
    for _ in range(steps or env.spec.max_episode_steps):
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        rewards.append(reward)
        if terminated or truncated:
            break
    return obs, info, rewards


def test_the_ids_are_registered_with_their_lengths_and_vector_entry_points():
    for task, steps in (("Tower", 150), ("Insert", 50)):
        for suffix, reward_type in (("", "sparse"), ("Dense", "dense")):
            env_id = f"rigid_gym/{task}{suffix}-v0"
            assert env_id in rigid_gym.ENV_IDS
            spec = gym.spec(env_id)
            assert spec.max_episode_steps == steps
            assert spec.kwargs == {"reward_type": reward_type}
            assert spec.vector_entry_point == f"rigid_gym.envs.vector:{task.lower()}"


# -- Tower ---------------------------------------------------------------------------------

def tower_goal(xy=(0.05, -0.02), n=3, half=CUBE_HALF):
    """The targets (1, 3 n) of a tower of n cubes at ``xy``."""
    return np.array([[xy[0], xy[1], (2 * k + 1) * half] for k in range(n)]).reshape(1, -1)


def test_tower_goals_are_a_tower_in_order_at_a_target_away_from_the_cubes():
    env = gym.make("rigid_gym/Tower-v0", num_cubes=4, max_episode_steps=200)
    for seed in range(5):
        obs, _ = env.reset(seed=seed)
        goal = obs["desired_goal"].reshape(4, 3)
        cubes = obs["achieved_goal"].reshape(4, 3)
        assert obs["observation"].shape == (7 + 18 * 4,) and obs["desired_goal"].shape == (12,)
        np.testing.assert_allclose(goal[:, :2], np.repeat(goal[:1, :2], 4, axis=0))
        np.testing.assert_allclose(goal[:, 2], [0.02, 0.06, 0.1, 0.14], atol=1e-7)
        assert np.all(np.linalg.norm(cubes[:, :2] - goal[0, :2], axis=1) >= 0.08 - 1e-6)
        apart = np.linalg.norm(cubes[:, None, :2] - cubes[None, :, :2], axis=-1)
        assert np.all(apart[~np.eye(4, dtype=bool)] >= 0.08 - 1e-6)
        np.testing.assert_allclose(cubes[:, 2], CUBE_HALF, atol=1e-6)


def test_the_tower_test_needs_every_cube_near_its_target_in_order_and_standing():
    task = Tower(3)
    goal = tower_goal()
    assert task.goal_reached(goal, goal)[0]
    swapped = goal.reshape(3, 3)[[0, 2, 1]].reshape(1, -1)  # cubes 1 and 2 in each other's place
    # each cube is within 0.04 m of its target (inside the 0.05 m threshold), but the order
    # is wrong
    assert np.all(np.linalg.norm((swapped - goal).reshape(3, 3), axis=1) < 0.05)
    assert not task.goal_reached(swapped, goal)[0]
    # the top cube 0.025 m off the one below in x: within the threshold, but not on it
    slid = goal.copy()
    slid[0, 6] += 0.025
    assert not task.goal_reached(slid, goal)[0]
    slid[0, 6] -= 0.01  # 0.015 m: it rests on it
    assert task.goal_reached(slid, goal)[0]
    # the top cube held 0.012 m above its place: not standing on the tower
    lifted = goal.copy()
    lifted[0, 8] += 0.012
    assert not task.goal_reached(lifted, goal)[0]
    # the whole tower 0.04 m from the target: reached (the threshold); 0.06 m: not
    moved = goal + np.tile([0.04, 0.0, 0.0], 3)
    assert task.goal_reached(moved, goal)[0]
    assert not task.goal_reached(goal + np.tile([0.06, 0.0, 0.0], 3), goal)[0]
    # batched over any leading shape, as HER calls it
    batch = np.stack([goal[0], swapped[0], moved[0]])
    assert task.goal_reached(batch[None], np.repeat(goal[None], 3, axis=1)).tolist() == [
        [True, False, True]]


def test_a_scripted_tower_of_three_stands_after_the_pad_leaves():
    env = gym.make("rigid_gym/Tower-v0", max_episode_steps=175)
    for seed in range(4):
        obs, info, rewards = play(env, seed)
        assert info["is_success"], seed
        assert rewards[-25:] == [0.0] * 25  # still standing 25 steps (1 s) after the pad left
        pad = obs["observation"][:3]
        assert pad[2] > obs["achieved_goal"][-1] + 0.05  # the pad is up and away


@pytest.mark.parametrize("num_cubes", [2, 5])
def test_the_scripted_policy_builds_the_smallest_and_the_tallest_tower(num_cubes):
    env = gym.make("rigid_gym/Tower-v0", num_cubes=num_cubes,
                   max_episode_steps=50 * num_cubes)
    for seed in range(2):
        _, info, _ = play(env, seed)
        assert info["is_success"], (num_cubes, seed)


@pytest.mark.parametrize("bad", [1, 6, 0, -3, 2.5, 3.0, True, "3", None])
def test_num_cubes_outside_2_to_5_is_refused_by_name(bad):
    with pytest.raises(ValueError, match=r"TowerEnv: num_cubes: must be an int in \[2, 5\]"):
        gym.make("rigid_gym/Tower-v0", num_cubes=bad)
    with pytest.raises(ValueError, match=r"TowerEnv: num_cubes: must be an int in \[2, 5\]"):
        gym.make_vec("rigid_gym/Tower-v0", num_envs=2, num_cubes=bad)


def test_a_vector_tower_of_four_plays_the_single_envs_episodes_bit_for_bit():
    vector = gym.make_vec("rigid_gym/Tower-v0", num_envs=3, num_cubes=4)
    singles = [gym.make("rigid_gym/Tower-v0", num_cubes=4) for _ in range(3)]
    observations, _ = vector.reset(seed=7)
    firsts = [env.reset(seed=7 + i)[0] for i, env in enumerate(singles)]
    actions = np.random.default_rng(2).uniform(-1, 1, (40, 3, 4))
    for step in range(41):
        for i, single in enumerate(firsts):
            for key, value in single.items():
                assert observations[key][i].tobytes() == value.tobytes()
        if step == 40:
            break
        observations = vector.step(actions[step])[0]
        firsts = [env.step(a)[0] for env, a in zip(singles, actions[step])]
    assert observations["desired_goal"].shape == (3, 12)


def test_tower_shaped_reward_pays_cube_by_cube_and_keeps_a_placed_cube():
    task = Tower(3)
    goal = tower_goal()
    cubes = np.array([[0.15, 0.0, 0.02, -0.1, 0.1, 0.02, -0.1, -0.1, 0.02]])
    none_placed = task.shaped_reward(np.array([[0.0, 0.0, 0.2]]), NONE, cubes, goal, HALF3)[0]
    assert 0.0 < none_placed < 1 / 12  # reaching cube 0
    one = cubes.copy()
    one[0, :3] = goal[0, :3]
    two = one.copy()
    two[0, 3:6] = goal[0, 3:6]
    # cube 0 placed, the pad gone: cube 1's reach stage, above all of cube 0's stages (4 of
    # the 12 a cube placed, against at most 3 for one held at its target)
    r1 = task.shaped_reward(np.array([[0.0, 0.0, 0.2]]), NONE, one, goal, HALF3)[0]
    r2 = task.shaped_reward(np.array([[0.0, 0.0, 0.2]]), NONE, two, goal, HALF3)[0]
    assert 4 / 12 < r1 < 5 / 12 and 8 / 12 < r2 < 9 / 12
    held_there = task.shaped_reward(goal[:, 3:6] + [0, 0, 0.035], np.array([1]), two, goal,
                                    HALF3)[0]
    assert 6 / 12 < held_there <= 7 / 12 < 8 / 12 < r2  # cube 1 held at its target
    # holding cube 2 (index 2) and carrying it nearer its target grows the reward
    carried = []
    for z in (0.2, 0.15, 0.11):
        achieved = two.copy()
        achieved[0, 6:] = [goal[0, 6], goal[0, 7], z]
        carried.append(task.shaped_reward(achieved[:, 6:] + [0, 0, 0.035], np.array([2]),
                                          achieved, goal, HALF3)[0])
    assert 10 / 12 < carried[0] < carried[1] < carried[2] < 11 / 12
    rng = np.random.default_rng(0)
    k = 2000
    reward = task.shaped_reward(rng.uniform(-0.5, 0.8, (k, 3)), rng.integers(-1, 3, k),
                                rng.uniform(-0.3, 0.3, (k, 9)), rng.uniform(-0.3, 0.3, (k, 9)),
                                np.repeat(HALF3, k, axis=0))
    assert np.isfinite(reward).all() and (reward >= 0).all() and (reward < 1).all()


@pytest.mark.parametrize("env_id", ["rigid_gym/Stack-v0", "rigid_gym/Tower-v0"])
def test_start_placed_puts_the_tower_on_cube_0_at_the_chance_asked(env_id):
    """The training curriculum: with chance start_placed the tower stands where cube 0
    starts (cube 0 placed from the start, the shaped reward past its stages); the default
    draws the env id's episodes."""
    plain, always = gym.make(env_id), gym.make(env_id, start_placed=1.0)
    assert type(always.unwrapped.task).__name__ == type(plain.unwrapped.task).__name__
    shaped = gym.make(env_id, start_placed=1.0, reward_type="shaped")
    n = plain.unwrapped.task.num_cubes
    for seed in range(5):
        obs, _ = always.reset(seed=seed)
        goal, cubes = obs["desired_goal"].reshape(n, 3), obs["achieved_goal"].reshape(n, 3)
        assert np.array_equal(goal[0], cubes[0])  # float32 of the same float64
        assert np.allclose(goal[1:, :2], cubes[0, :2]) and np.all(np.diff(goal[:, 2]) > 0)
        shaped.reset(seed=seed)
        assert shaped.step(np.zeros(4))[1] > 4 / (4 * n)  # cube 0 placed, let go of
    half = gym.make(env_id, start_placed=0.5)
    placed = []
    for seed in range(200):
        obs = half.reset(seed=seed)[0]
        placed.append(np.array_equal(obs["desired_goal"][:3], obs["achieved_goal"][:3]))
        # the cubes are drawn before the goal, so each seed starts them where the id does
        assert np.array_equal(obs["achieved_goal"], plain.reset(seed=seed)[0]["achieved_goal"])
    assert 0.4 < np.mean(placed) < 0.6  # 200 draws: 5 standard deviations are 0.18 wide
    assert not any(np.array_equal(o["desired_goal"][:3], o["achieved_goal"][:3])
                   for o in (plain.reset(seed=s)[0] for s in range(50)))


@pytest.mark.parametrize("bad", [-0.1, 1.5, float("nan"), "half"])
def test_start_placed_outside_0_to_1_is_refused_by_name(bad):
    with pytest.raises(ValueError, match="start_placed"):
        gym.make("rigid_gym/Stack-v0", start_placed=bad)
    with pytest.raises(ValueError, match="start_placed"):
        gym.make_vec("rigid_gym/Tower-v0", num_envs=2, start_placed=bad)


def test_a_vector_stack_with_start_placed_plays_the_single_envs_episodes():
    vector = gym.make_vec("rigid_gym/Stack-v0", num_envs=4, start_placed=0.5)
    singles = [gym.make("rigid_gym/Stack-v0", start_placed=0.5) for _ in range(4)]
    observations = vector.reset(seed=11)[0]
    for i, env in enumerate(singles):
        first = env.reset(seed=11 + i)[0]
        assert observations["desired_goal"][i].tobytes() == first["desired_goal"].tobytes()


# -- Insert --------------------------------------------------------------------------------

def test_the_fixture_is_a_block_with_a_hole_of_the_clearance():
    shape = fixture_shape()
    assert HOLE_HALF == PEG_HALF_EXTENTS[0] + CLEARANCE and CLEARANCE == 0.003
    # signed distances: the hole's axis is 0.018 m from the walls, inside the walls < 0,
    # outside the block > 0
    points = np.array([[0.0, 0.0, 0.03], [HOLE_HALF + 0.001, 0.0, 0.03],
                       [0.0, 0.03, 0.03], [0.06, 0.0, 0.03], [0.0, 0.0, HOLE_DEPTH + 0.01]])
    d = shape.signed_distance(points)
    assert d[0] == pytest.approx(HOLE_HALF)
    assert d[1] < 0 and d[2] < 0
    assert d[3] == pytest.approx(0.01) and d[4] > 0


def test_the_insert_test_needs_half_the_peg_in_and_its_axis_on_the_holes():
    task = Insert()
    goal = np.array([[0.1, -0.05, PEG_HALF_EXTENTS[2]]])
    assert task.goal_reached(goal, goal)[0]
    # half the peg's length (0.05 m) below the block's top is its centre 0.01 m above the goal
    assert task.goal_reached(goal + [0, 0, 0.0099], goal)[0]
    assert not task.goal_reached(goal + [0, 0, 0.0101], goal)[0]
    assert task.goal_reached(goal + [IN_HOLE - 1e-4, -(IN_HOLE - 1e-4), 0], goal)[0]
    assert not task.goal_reached(goal + [IN_HOLE + 1e-4, 0, 0], goal)[0]
    assert not task.goal_reached(goal + [0, -(IN_HOLE + 1e-4), 0], goal)[0]
    # a peg standing on the table beside the block is low enough, but not in the hole
    assert not task.goal_reached(goal + [0.07, 0, 0], goal)[0]


def settle(env, position, steps=50):
    """Put the peg (unheld) at ``position`` upright and at rest; step with the pad up and away;
    returns the peg's final position."""
    u = env.unwrapped
    u.world.set_pose(u.cubes[0], position)
    obs = None
    for _ in range(steps):
        obs = env.step(np.array([0.0, 0.0, 1.0, -1.0]))[0]
    return obs["achieved_goal"].astype(np.float64)


def test_a_released_peg_falls_into_the_hole_without_jamming_and_shows_the_clearance():
    """Dropped 2.5 mm off the hole's axis (inside the 3 mm clearance), from just above the
    block, the peg falls to the hole's floor: nothing holds it in the walls. Centred, its
    contacts with the walls (within a 1 cm margin) are 3 mm away, the clearance."""
    env = gym.make("rigid_gym/Insert-v0", max_episode_steps=200)
    obs, _ = env.reset(seed=3)
    goal = obs["desired_goal"].astype(np.float64)
    top = HOLE_DEPTH + PEG_HALF_EXTENTS[2] + 0.002
    end = settle(env, goal + [0.0025, 0.0, top - goal[2]])
    np.testing.assert_allclose(end, goal + [0.0025, 0.0, 0.0], atol=2e-4)
    end = settle(env, goal + [0.0, 0.0, top - goal[2]])
    np.testing.assert_allclose(end, goal, atol=2e-4)
    u = env.unwrapped
    contacts = u.world.contacts(margin=0.01)
    peg, fixture = u.cubes[0], u.core.fixtures[0]
    pair = ((contacts.body_a == peg) & (contacts.body_b == fixture)) | (
        (contacts.body_a == fixture) & (contacts.body_b == peg))
    assert pair.any()
    assert -contacts.depth[pair].max() == pytest.approx(CLEARANCE, abs=1e-4)
    assert env.unwrapped.goal_reached(end, goal)
    # 3 cm off (its centre of mass over the wall, its edge 3 mm over the hole): it stands on
    # the block, not in the hole
    end = settle(env, goal + [0.03, 0.0, top - goal[2]])
    assert end[2] > HOLE_DEPTH + PEG_HALF_EXTENTS[2] - 1e-3
    assert not env.unwrapped.goal_reached(end, goal)


def test_scripted_insert_puts_the_peg_in_and_it_stays():
    env = gym.make("rigid_gym/Insert-v0")
    for seed in range(5):
        _obs, info, rewards = play(env, seed)
        assert info["is_success"], seed
        assert rewards[-20:] == [0.0] * 20
        peg = env.unwrapped.world.position[env.unwrapped.cubes[0]]
        # its bottom at least half its length below the block's top: it rests on the floor
        assert peg[2] - PEG_HALF_EXTENTS[2] == pytest.approx(0.0, abs=1e-4)


def test_insert_shaped_reward_stages_grasp_carry_then_insert():
    env = gym.make("rigid_gym/Insert-v0", reward_type="shaped")
    _obs, info, rewards = play(env, 0)
    assert info["is_success"] and rewards[-1] == 1.0
    first = rewards.index(1.0)
    assert rewards[0] < 1 / 5 and 4 / 5 < max(rewards[:first]) < 1.0
    assert all(0.0 <= r <= 1.0 for r in rewards)
    task = Insert()
    goal = np.array([[0.1, 0.0, 0.05]])
    half = np.full((1, 1), CUBE_HALF)
    peg = np.array([[-0.1, 0.0, 0.05]])
    reach = task.shaped_reward(np.array([[0.0, 0.0, 0.2]]), NONE, peg, goal, half)[0]
    held = task.shaped_reward(peg + [0, 0, 0.065], np.array([0]), peg, goal, half)[0]
    lined_up = task.shaped_reward(np.array([[0.1, 0.0, 0.3]]), NONE,
                                  goal + [0.0, 0.0, 0.12], goal, half)[0]
    assert reach < 1 / 5 < 2 / 5 < held < 3 / 5 < 4 / 5 < lined_up < 1.0


def test_insert_refuses_a_randomized_size_and_takes_the_other_ranges():
    for randomize in (True, {"size": (0.9, 1.1)}):
        with pytest.raises(ValueError, match="InsertEnv: randomize cannot include 'size'"):
            gym.make("rigid_gym/Insert-v0", randomize=randomize)
    env = gym.make("rigid_gym/Insert-v0", randomize={"mass": (0.5, 2.0), "friction": (0.5, 1.5)})
    _, info, _ = play(env, 1)
    assert info["is_success"]


@pytest.mark.parametrize("env_id, kwargs", [("rigid_gym/Tower-v0", {"num_cubes": 4}),
                                            ("rigid_gym/Insert-v0", {})])
def test_the_same_seed_and_actions_give_bit_identical_episodes(env_id, kwargs):
    env_a, env_b = gym.make(env_id, **kwargs), gym.make(env_id, **kwargs)
    actions = np.random.default_rng(4).uniform(-1, 1, (60, 4))
    for env in (env_a, env_b):
        env.reset(seed=1)  # another episode first: the reset must not carry anything over
        for a in actions[:10]:
            env.step(a)
    runs = []
    for env in (env_a, env_b):
        observations = [env.reset(seed=11)[0]]
        observations += [env.step(a)[0] for a in actions]
        runs.append(observations)
    for a, b in zip(*runs):
        for key in a:
            assert a[key].tobytes() == b[key].tobytes()
    assert env_b.reset(seed=12)[0]["desired_goal"].tobytes() != runs[0][0][
        "desired_goal"].tobytes()


def lower(env, offset, steps=12):
    """Take the peg (scripted), carry it over the hole ``offset`` (m, along x) off its axis and
    press it down for ``steps`` steps; returns the peg's position, m."""
    policy = scripted_policy(env)
    obs, _ = env.reset(seed=2)
    goal = obs["desired_goal"].astype(np.float64)
    u = env.unwrapped
    while u.gripper.held[0] < 0 or obs["observation"][2] < 0.2:
        obs = env.step(policy(obs))[0]
    for _ in range(10):  # over the spot, exactly (a move within one step lands on its target)
        pad, peg = obs["observation"][:3], obs["achieved_goal"]
        target = pad + (goal + [offset, 0.0, 0.0] - peg) * [1, 1, 0]
        obs = env.step(np.append(np.clip((target - pad) / 0.05, -1, 1), 1.0))[0]
    for _ in range(steps):
        obs = env.step(np.array([0.0, 0.0, -1.0, 1.0]))[0]
    assert u.gripper.held[0] == 0
    return obs["achieved_goal"].astype(np.float64), goal


def test_a_peg_pressed_down_off_the_hole_stops_on_the_block():
    """The arm's force limit holds for the fixture: pressed down 6 mm off the hole's axis (its
    edge 3 mm over the wall), the held peg stops with its bottom on the block's top, where a
    kinematic carry would have driven it through the wall; 2 mm off, it goes down to the
    floor."""
    env = gym.make("rigid_gym/Insert-v0", max_episode_steps=100)
    peg, goal = lower(env, 0.006)
    assert peg[2] - PEG_HALF_EXTENTS[2] == pytest.approx(HOLE_DEPTH, abs=2e-3)
    assert not env.unwrapped.goal_reached(peg, goal)
    peg, goal = lower(env, 0.002)
    np.testing.assert_allclose(peg, goal + [0.002, 0.0, 0.0], atol=1e-4)
    assert env.unwrapped.goal_reached(peg, goal)


def test_the_gripper_stops_only_on_box_parts():
    bodies, offsets, rotations, halves = fixture_boxes([(4, fixture_shape(), Pose())])
    assert bodies.tolist() == [4] * 4 and offsets.shape == (4, 3) and halves.shape == (4, 3)
    np.testing.assert_allclose(rotations, np.repeat(np.eye(3)[None], 4, axis=0))
    with pytest.raises(ValueError, match="part 1 is a Sphere; the gripper stops only on boxes"):
        fixture_boxes([(2, Compound(((fixture_shape().parts[0][0], Pose()),
                                     (Sphere(0.1), Pose()))), Pose())])


def test_scripted_insert_recovers_from_noisy_actions():
    """With Gaussian noise of 0.1 on every action (5 mm per step, more than the clearance),
    the policy lines the peg up again wherever it lands (on the block, in the hole off line)
    and gets it in most of the time; the noisy dataset recipe plays it so."""
    env = gym.make("rigid_gym/Insert-v0")
    policy = scripted_policy(env)
    rng = np.random.default_rng(0)
    successes = 0
    for seed in range(10):
        obs, _ = env.reset(seed=seed)
        for _ in range(50):
            action = np.clip(policy(obs) + rng.normal(0.0, 0.1, 4), -1.0, 1.0)
            obs, _, _, _, info = env.step(action)
        successes += info["is_success"]
    assert successes >= 7


def test_a_scripted_tower_climbs_the_shaped_stages_to_one():
    env = gym.make("rigid_gym/Tower-v0", reward_type="shaped")
    _, info, rewards = play(env, 0)
    assert info["is_success"] and rewards[-1] == 1.0
    first = rewards.index(1.0)
    assert rewards[0] < 1 / 9 and 8 / 9 < max(rewards[:first]) < 1.0
    assert all(0.0 <= r <= 1.0 for r in rewards)


@pytest.mark.parametrize("num_cubes", [4, 5])
def test_the_rgb_array_camera_frames_a_tall_tower_anywhere_in_the_range(num_cubes):
    """Towers of 4 and 5 get a wider rgb_array view than the default (which cut the top of a
    tower of 5 at the range's edge): the whole range, up to the tower's height, is in the
    frame."""
    env = gym.make("rigid_gym/Tower-v0", num_cubes=num_cubes).unwrapped
    eye, target, fov = env.camera_view
    height = 2 * CUBE_HALF * num_cubes
    corners = np.array(list(itertools.product((-0.17, 0.17), (-0.17, 0.17), (0.0, height))))
    screen, depth = Camera(eye, target, fov_deg=fov).project(corners, 480, 480)
    assert np.all(depth > 0) and np.all((screen >= 0) & (screen <= 480))
    assert gym.make("rigid_gym/Tower-v0").unwrapped.camera_view == Task.camera_view
