"""Reach, PickAndPlace, Slide and Flip: their goals, goal tests and rewards at and off the goal,
the physics each relies on (against closed forms), and their shaped stages. Registration,
the checkers, determinism, batch rewards and scripted success are tests/test_envs.py's, over
every task."""

import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from rigid_gym.envs.flip import (
    ANGLE_THRESHOLD,
    TABLE_FRICTION,
    Flip,
    angle_distance,
    cube_rotations,
    roll_table,
)
from rigid_gym.envs.pick_and_place import GOAL_LIFT, ON_TABLE, PickAndPlace
from rigid_gym.envs.reach import Reach
from rigid_gym.envs.scripted import scripted_policy
from rigid_gym.envs.slide import PAD_REACH_X, PUCK_FRICTION, PUCK_RADIUS, Slide
from rigid_gym.envs.task import CUBE_HALF, DISTANCE_THRESHOLD, FRICTION
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import rigid_gym
from rigid_gym import quaternion

NEW_IDS = [f"rigid_gym/{t}{d}-v0" for t in ("Reach", "PickAndPlace", "Slide", "Flip")
           for d in ("", "Dense")]
G = 9.81


def make(env_id, **kwargs):
    return gym.make(env_id, **kwargs).unwrapped


def rngs(n, seed=0):
    return [np.random.default_rng(seed + k) for k in range(n)]


def test_every_id_is_registered_with_panda_gym_s_episode_length():
    assert set(NEW_IDS) <= set(rigid_gym.ENV_IDS)
    assert all(gym.spec(i).max_episode_steps == 50 for i in NEW_IDS)
    assert [gym.spec(i).kwargs["reward_type"] for i in NEW_IDS[:2]] == ["sparse", "dense"]


@pytest.mark.parametrize("env_id", NEW_IDS[::2])
@pytest.mark.parametrize("obs_mode", ["state", "pixels"])
def test_both_checkers_pass_in_state_and_pixels(env_id, obs_mode):
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*infinity.*")
        check_env(make(env_id, obs_mode=obs_mode), skip_render_check=True)
        sb3_check_env(make(env_id, obs_mode=obs_mode))


# -- Reach -------------------------------------------------------------------------------------

def test_reach_goals_span_panda_gym_s_box_and_the_pad_is_the_achieved_goal():
    goals = Reach().sample_goals(rngs(2000), None, None, None)
    assert goals.min(axis=0) == pytest.approx([-0.15, -0.15, 0.0], abs=0.01)
    assert goals.max(axis=0) == pytest.approx([0.15, 0.15, 0.3], abs=0.01)
    env = make("rigid_gym/Reach-v0")
    obs, _ = env.reset(seed=0)
    np.testing.assert_array_equal(obs["achieved_goal"], np.float32([0.0, 0.0, 0.12]))


@pytest.mark.parametrize("offset, reached", [(0.0, True), (0.049, True), (0.051, False)])
def test_reach_is_reached_within_the_threshold(offset, reached):
    env = make("rigid_gym/Reach-v0")
    env.reset(seed=3)
    goal = env.goal.copy()
    goal[2] = max(goal[2], 0.1)  # a target the pad's centre can sit at
    env.core.goals[0] = env.core.desired[0] = env.core.desired64[0] = goal
    env.world.set_pose(env.gripper.body, goal + [offset, 0.0, 0.0])
    obs, reward, _, _, info = env.step(np.zeros(3))
    assert info["is_success"] == reached and reward == (0.0 if reached else -1.0)
    assert env.compute_reward(obs["achieved_goal"], obs["desired_goal"], None) == reward
    assert make("rigid_gym/ReachDense-v0").compute_reward(
        obs["achieved_goal"], obs["desired_goal"], None) == pytest.approx(-offset, abs=1e-6)


# -- PickAndPlace ------------------------------------------------------------------------------

def test_pick_and_place_goals_are_in_the_air_seven_times_in_ten():
    task = PickAndPlace()
    n = 4000
    half = np.full((n, 1), CUBE_HALF)
    starts = task.place_cubes(rngs(n), half)
    goals = task.sample_goals(rngs(n, 10_000), starts, half, None)
    lift = goals[:, 2] - CUBE_HALF
    on_table = np.mean(lift == 0.0)
    assert abs(on_table - ON_TABLE) < 3 * np.sqrt(ON_TABLE * (1 - ON_TABLE) / n)
    assert lift.max() <= GOAL_LIFT and lift.max() > 0.95 * GOAL_LIFT
    assert (np.abs(goals[:, :2]) <= 0.15).all()
    assert (np.linalg.norm(goals[:, :2] - starts[:, 0, :2], axis=1) >= DISTANCE_THRESHOLD).all()


def test_a_cube_held_at_a_target_in_the_air_reaches_it():
    """The scripted policy holds the cube at an air target: success while it is held."""
    env = gym.make("rigid_gym/PickAndPlace-v0")
    policy = scripted_policy(env)
    seed = next(s for s in range(50) if env.reset(seed=s)[0]["desired_goal"][2] > 0.1)
    obs, _ = env.reset(seed=seed)
    for _ in range(50):
        obs, reward, _, _, info = env.step(policy(obs))
    assert info["is_success"] and reward == 0.0
    assert env.unwrapped.gripper.held[0] == 0 and obs["achieved_goal"][2] > 0.1


def test_pick_and_place_shaped_stages_reach_then_carry():
    task = PickAndPlace()
    half = np.full((1, 1), CUBE_HALF)
    cube = np.array([[0.1, 0.0, CUBE_HALF]])
    goal = np.array([[-0.1, 0.1, 0.15]])
    approach = [task.shaped_reward(np.array([[0.1, 0.0, z]]), np.array([-1]), cube, goal, half)[0]
                for z in (0.25, 0.15, 0.08, 0.036)]
    assert np.all(np.diff(approach) > 0) and max(approach) < 1 / 3
    carried = [task.shaped_reward(p[None] + [0, 0, 0.035], np.array([0]), p[None], goal, half)[0]
               for p in np.linspace(cube[0], goal[0] + [0.06, 0, 0], 6)]
    assert np.all(np.diff(carried) > 0) and min(carried) > 2 / 3 and max(carried) < 1


# -- Slide -------------------------------------------------------------------------------------

def test_slide_goals_lie_beyond_where_the_pad_can_push_the_puck():
    task = Slide()
    goals = task.sample_goals(rngs(2000), None, np.full((2000, 1), CUBE_HALF), None)
    farthest_push = PAD_REACH_X + PUCK_RADIUS * CUBE_HALF
    assert goals[:, 0].min() >= farthest_push + DISTANCE_THRESHOLD
    assert goals[:, 0].max() <= 0.55 and np.abs(goals[:, 1]).max() <= 0.15


def test_the_pad_pushes_the_puck_to_its_reach_and_no_goal_is_reached_without_a_slide():
    """Pushed at 0.125 m/s until the pad stops at the workspace's edge, the puck leaves the pad
    at x = 0.30 m and slides on v^2 / (2 mu g) = 2 cm: it ends 0.32 m out, short of every
    target (0.35 m and beyond) by more than the threshold less the slide."""
    env = make("rigid_gym/Slide-v0")
    env.reset(seed=0)
    env.world.set_pose(env.cubes[0], (0.1, 0.0, CUBE_HALF))
    env.world.set_pose(env.gripper.body, (0.0, 0.0, CUBE_HALF))
    v = 0.1 * 0.05 / 0.04
    for _ in range(80):
        env.step(np.array([0.1, 0.0, 0.0]))
    assert env.gripper.position[0] == pytest.approx(0.25)
    puck = env.world.position[env.cubes[0]]
    slide = v * v / (2 * PUCK_FRICTION * G)
    assert puck[0] == pytest.approx(PAD_REACH_X + PUCK_RADIUS * CUBE_HALF + slide, abs=0.004)


def test_a_puck_slides_the_coulomb_distance_v_squared_over_two_mu_g():
    """Set sliding at v on the table, the puck stops after v^2 / (2 mu g) (mu 0.04 the pair's
    sqrt(0.04 x 0.04)); 3% for the start and stop (a step of 4 ms at v = 0.6 m/s is 2.4 mm of
    0.46 m) and the mesh's contact sampling."""
    env = make("rigid_gym/Slide-v0")
    env.reset(seed=0)
    v = 0.6
    env.world.set_pose(env.cubes[0], (-0.2, 0.0, CUBE_HALF))
    env.world.set_pose(env.gripper.body, (-0.2, 0.0, 0.25))
    env.world.set_velocity(env.cubes[0], (v, 0.0, 0.0))
    for _ in range(50):
        env.step(np.zeros(3))
    travelled = env.world.position[env.cubes[0]][0] + 0.2
    assert np.linalg.norm(env.world.velocity[env.cubes[0]]) < 1e-3
    assert travelled == pytest.approx(v * v / (2 * PUCK_FRICTION * G), rel=0.03)


# -- Flip --------------------------------------------------------------------------------------

def turn(axis, degrees):
    half = np.deg2rad(degrees) / 2
    return np.concatenate([[np.cos(half)], np.sin(half) * np.asarray(axis, dtype=float)])


def test_angle_distance_is_sign_blind_sin_squared_of_half_the_angle_and_batch_safe():
    q = quaternion.normalize(np.random.default_rng(0).normal(size=(5, 4)))
    assert angle_distance(q, -q) == pytest.approx(np.zeros(5), abs=1e-12)
    for degrees in (30.0, 90.0, 180.0):
        turned = quaternion.multiply(turn([0, 0, 1], degrees), q)
        np.testing.assert_allclose(angle_distance(turned, q),
                                   np.sin(np.deg2rad(degrees) / 2) ** 2, atol=1e-12)
    assert angle_distance(q, q[::-1]).shape == (5,)  # elementwise, not panda-gym's 5 x 5


@pytest.mark.parametrize("degrees, reached", [(0.0, True), (50.0, True), (56.0, False),
                                              (90.0, False)])
def test_flip_is_reached_within_53_degrees_and_compute_reward_takes_batches(degrees, reached):
    assert np.rad2deg(2 * np.arcsin(np.sqrt(ANGLE_THRESHOLD))) == pytest.approx(53.13, abs=0.01)
    goal = turn([1, 0, 0], 90.0)
    achieved = quaternion.multiply(turn([0.6, 0.8, 0.0], degrees), goal)
    env = make("rigid_gym/Flip-v0")
    batch = np.stack([achieved, -achieved, goal])
    rewards = env.compute_reward(batch, np.stack([goal] * 3), [{}] * 3)
    assert rewards.shape == (3,)
    assert rewards.tolist() == [0.0 if reached else -1.0] * 2 + [0.0]
    dense = make("rigid_gym/FlipDense-v0").compute_reward(batch, np.stack([goal] * 3), None)
    np.testing.assert_allclose(dense, [-np.sin(np.deg2rad(degrees) / 2) ** 2] * 2 + [0.0],
                               atol=1e-12)


def test_flip_targets_rest_on_a_face_other_than_the_top_and_are_within_reach_of_rolls():
    env = make("rigid_gym/Flip-v0")
    ups, yaws = set(), []
    for seed in range(300):
        obs, info = env.reset(seed=seed)
        goal = obs["desired_goal"].astype(np.float64)
        assert obs["achieved_goal"].tolist() == [1.0, 0.0, 0.0, 0.0] and not info["is_success"]
        r = quaternion.to_matrix(goal / np.linalg.norm(goal))
        up = r[2]  # the world z of each body axis: one of them vertical, not the top
        assert np.sort(np.abs(up))[-1] == pytest.approx(1.0, abs=1e-6) and up[2] < 0.5
        ups.add(tuple(np.round(up).astype(int)))
        nearest = np.einsum("kij,ij->k", cube_rotations(), r).max()  # trace of R_e^T R
        angle = np.arccos(np.clip((nearest - 1) / 2, -1, 1))
        assert angle <= np.pi / 4 + 1e-9  # every target within 45 deg of a resting one
        yaws.append(angle)
    assert len(ups) == 5 and max(yaws) > np.deg2rad(40)


def test_cube_rotations_are_the_24_and_rolls_reach_each_in_at_most_four():
    rotations = cube_rotations()
    assert len({tuple(r.ravel()) for r in rotations}) == 24
    assert all(np.allclose(r @ r.T, np.eye(3)) and np.linalg.det(r) == pytest.approx(1)
               for r in rotations)
    after, rolls = roll_table()
    assert rolls.max() == 4 and (rolls >= 0).all()
    assert (np.diagonal(rolls) == 0).all() and (rolls == rolls.T).all()  # rolls reverse
    assert (rolls[np.arange(24)[:, None], after] == 1).all()  # each roll is one away


@pytest.mark.parametrize("table_friction, tips", [(TABLE_FRICTION, True), (FRICTION, False)])
def test_a_cube_pushed_at_the_top_of_a_face_tips_where_mu_exceeds_a_over_h(table_friction,
                                                                            tips):
    """A cube of half edge a pushed at height h tips over its far edge before sliding when
    the table pair's mu > a / h. The pad pushes the top 5 mm (h = 0.0375 m, a / h = 0.53):
    Flip's mat (pair 1.0) tips it, Push's table (pair 0.5) lets it slide."""
    class Table(Flip):
        pass

    Table.table_friction = table_friction
    from rigid_gym.envs.flip import FlipEnv

    class Env(FlipEnv):
        task = Table()

    env = Env()
    env.reset(seed=0)
    env.world.set_pose(env.cubes[0], (0.0, 0.0, CUBE_HALF))
    env.world.set_pose(env.gripper.body, (-0.045, 0.0, 0.05))
    for t in range(20):  # 7 steps of pushing 1 cm each, then still
        env.step(np.array([0.2 if t < 7 else 0.0, 0.0, 0.0, -1.0]))
    up = env.world.rotation[env.cubes[0]][:, 2]
    assert (abs(up[2]) < 0.1) == tips  # rolled a quarter turn, or still upright
    assert (env.world.position[env.cubes[0]][0] > 0.05) or tips  # slid along instead


def test_a_finished_roll_pays_more_than_any_state_of_the_roll_before():
    task = Flip()
    layout = task.observation_layout
    goal = turn([0, 1, 0], 180.0)[None]  # two rolls from the start
    half = np.full((1, 1), CUBE_HALF)

    def shaped(cube_rotation, pad):
        vectors = np.zeros((1, layout.size))
        vectors[0, layout.slice("pad.position")] = pad
        vectors[0, layout.slice("cube0.position")] = (0.0, 0.0, CUBE_HALF)
        vectors[0, layout.slice("cube0.orientation")] = cube_rotation[:, :2].T.ravel()
        return task.shaped(vectors, np.array([-1]), np.zeros((1, 4)), goal, half,
                           np.array([False]))[0]

    rolling = [shaped(quaternion.to_matrix(turn([0, 1, 0], d)), (-0.04, 0.0, 0.05))
               for d in (0.0, 10.0, 25.0, 40.0)]
    approach = [shaped(np.eye(3), (-0.04, 0.0, z)) for z in (0.3, 0.15, 0.08)]
    after = shaped(quaternion.to_matrix(turn([0, 1, 0], 90.0)), (0.2, 0.2, 0.3))
    assert np.all(np.diff(approach) > 0) and np.all(np.diff(rolling) > 0)
    assert after > max(rolling) > max(approach) and 0.0 <= min(approach) and after < 1.0


def test_flip_s_pixels_show_the_cube_s_orientation():
    """A quarter turn about the vertical leaves a one-coloured cube's picture as it was; Flip's
    faces (FACE_COLORS) change it. The top stays blue: the turn is about the vertical."""
    env = make("rigid_gym/Flip-v0", obs_mode="pixels")
    env.reset(seed=0)
    cube = env.cubes[0]
    before = env.core.observe(slice(None)).observations["pixels"][0]
    env.world.set_pose(cube, env.world.position[cube], turn([0, 0, 1], 90.0))
    after = env.core.observe(slice(None)).observations["pixels"][0]
    assert np.any(before != after)
    env.world.set_pose(cube, env.world.position[cube], turn([0, 0, 1], 360.0))
    np.testing.assert_array_equal(env.core.observe(slice(None)).observations["pixels"][0],
                                  before)


# -- shaped rewards ----------------------------------------------------------------------------

@pytest.mark.parametrize("env_id, carried", [("rigid_gym/Reach-v0", 0.0),
                                             ("rigid_gym/PickAndPlace-v0", 2 / 3),
                                             ("rigid_gym/Slide-v0", 2 / 3),
                                             ("rigid_gym/Flip-v0", 3 / 5)])
def test_a_scripted_shaped_episode_stays_in_0_1_passes_its_stages_and_ends_at_one(env_id,
                                                                                  carried):
    env = gym.make(env_id, reward_type="shaped")
    policy = scripted_policy(env)
    rewards = []
    for seed in range(3):
        obs, _ = env.reset(seed=seed)
        episode = []
        for _ in range(50):
            obs, reward, _, _, info = env.step(policy(obs))
            episode.append(reward)
        first = episode.index(1.0)  # 1 from the first step at the goal
        assert info["is_success"] and episode[-1] == 1.0
        assert first == 0 or max(episode[:first]) > carried
        rewards += episode
    assert all(0.0 <= r <= 1.0 for r in rewards)


def test_a_sliding_puck_scores_the_slide_stage_and_a_still_one_the_reach_stage():
    env = make("rigid_gym/Slide-v0", reward_type="shaped")
    env.reset(seed=0)
    env.world.set_pose(env.gripper.body, (-0.2, 0.2, 0.25))  # far from the push point
    still = env.step(np.zeros(3))[1]
    env.world.set_velocity(env.cubes[0], (0.3, 0.0, 0.0))
    sliding = env.step(np.zeros(3))[1]
    assert still < 1 / 3 < 2 / 3 < sliding < 1.0


def test_shaped_rewards_are_bounded_for_any_state():
    rng = np.random.default_rng(0)
    k = 2000
    half = np.full((k, 1), CUBE_HALF)
    held = rng.integers(-1, 1, k)
    for task in (Reach(), PickAndPlace(), Slide(), Flip()):
        vectors = rng.uniform(-0.5, 0.8, (k, task.observation_layout.size))
        if task.goal_size == 4:  # Flip: orientations as the observation holds them
            q = quaternion.normalize(rng.normal(size=(k, 4)))
            r = quaternion.to_matrix(q)
            vectors[:, task.observation_layout.slice("cube0.orientation")] = np.concatenate(
                [r[:, :, 0], r[:, :, 1]], axis=1)
            achieved, desired = q, quaternion.normalize(rng.normal(size=(k, 4)))
        else:
            achieved, desired = rng.uniform(-0.5, 0.8, (2, k, 3))
        reward = task.shaped(vectors, held, achieved, desired, half, held >= 0)
        assert reward.shape == (k,) and np.isfinite(reward).all()
        assert (reward >= 0.0).all() and (reward < 1.0).all(), type(task).__name__


def episode_digest(env_id: str, seed: int) -> str:
    """sha256 of every observation and reward of a scripted episode with random actions mixed
    in (so that grips, rolls and slides all happen)."""
    import hashlib

    env = gym.make(env_id)
    policy = scripted_policy(env)
    rng = np.random.default_rng(seed)
    obs, _ = env.reset(seed=seed)
    digest = hashlib.sha256()
    for _ in range(50):
        shape = env.action_space.shape
        action = rng.uniform(-1, 1, shape) if rng.uniform() < 0.2 else policy(obs)
        obs, reward, *_ = env.step(np.asarray(action, dtype=np.float32))
        for value in obs.values():
            digest.update(value.tobytes())
        digest.update(np.float64(reward).tobytes())
    return digest.hexdigest()


def test_episodes_are_bit_identical_in_another_process():
    import subprocess
    import sys

    env_ids = NEW_IDS[::2]
    script = ("import sys; sys.path.insert(0, 'tests'); import gymnasium as gym, rigid_gym\n"
              "from test_tasks import episode_digest, NEW_IDS\n"
              "for i in NEW_IDS[::2]: print(episode_digest(i, 4))")
    here = [episode_digest(i, 4) for i in env_ids]
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True, cwd=Path(__file__).resolve().parent.parent)
    assert out.stdout.split() == here
