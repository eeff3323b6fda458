"""Snapshots: save_state / restore_state / remove_state, copy.deepcopy and pickle of Worlds,
single envs and vector envs (rigid_gym/snapshots.py). Each test plays a whole trajectory
from the saved or copied state and compares it with the original's bit for bit, so a piece
of state left out (the solver's carried-over bookkeeping, the generator, the grip, the goal,
a step count) shows as a difference."""

import copy
import pickle

import gymnasium as gym
import numpy as np
import pytest
from rigid_gym.envs import TASKS
from rigid_gym.envs.scripted import scripted_policy

import rigid_gym as rg
from rigid_gym.report.scenes import cube_stack, pile


def world_trace(world: rg.World, steps: int, sleeping: bool = True) -> bytes:
    """The bytes of every state array after each of ``steps`` steps, and with ``sleeping``
    which bodies slept through it (a pickled World starts without the sleeping bookkeeping:
    its first steps compute what a sleeping step skips, to the same bits)."""
    out = []
    for _ in range(steps):
        world.step(1)
        out.extend(a.tobytes() for a in world.state)
        if sleeping:
            out.append(world.sleeping().tobytes())
    return b"".join(out)


@pytest.mark.parametrize("scene, config", [
    (cube_stack(4), None),                                   # sleeps once settled
    (cube_stack(4), rg.SolverConfig(sleep_speed=0.05)),      # the slow clocks matter
    (pile(20), None),                                        # pair buffers grow
], ids=["stack", "stack-sleep-speed", "pile"])
def test_world_restore_and_deepcopy_step_on_bit_for_bit(scene, config):
    for num_worlds in (None, 2):
        world = rg.World(scene, num_worlds=num_worlds, config=config)
        world.step(60)
        state_id = world.save_state()
        twin = copy.deepcopy(world)
        view = world.position
        first = world_trace(world, 150)
        # what a restore must undo besides the poses: a material, an attachment, a push
        last = len(scene) - 1  # dynamic in each scene
        world.set_material(last, mass=3.0, friction=0.2)
        world.apply_impulse(last - 1, (0.3, 0.0, 0.0))
        world.step(5)
        world.restore_state(state_id)
        assert world.time == pytest.approx(60 * world.dt)
        assert world_trace(world, 150) == first
        assert np.array_equal(view, world.position)  # views taken before stay the World's
        assert world_trace(twin, 150) == first
        world.restore_state(state_id)  # a state restores any number of times
        assert world_trace(world, 150) == first
        if config is None:
            world.restore_state(state_id)
            loaded = pickle.loads(pickle.dumps(world))
            world.restore_state(state_id)
            assert world_trace(loaded, 150, False) == world_trace(world, 150, False)


def test_world_pickle_keeps_saved_states_and_refuses_slow_clocks():
    world = rg.World(cube_stack(3))
    world.step(10)
    state_id = world.save_state()
    first = world_trace(world, 50, False)
    loaded = pickle.loads(pickle.dumps(world))
    loaded.restore_state(state_id)
    assert world_trace(loaded, 50, False) == first
    world.remove_state(state_id)
    with pytest.raises(ValueError, match=r"World.restore_state: no saved state 0; saved: \[\]"):
        world.restore_state(state_id)
    with pytest.raises(ValueError, match="sleep_speed > 0 cannot be pickled"):
        pickle.dumps(rg.World(cube_stack(3), config=rg.SolverConfig(sleep_speed=0.05)))


def env_trace(env, actions) -> list:
    """Every step's observation and reward bytes for ``actions``, with a reset (no seed: the
    env's generator draws the episode) wherever an episode ends and once in the middle."""
    out = []
    for k, action in enumerate(actions):
        obs, reward, terminated, truncated, _ = env.step(action)
        ended = np.any(terminated) or np.any(truncated)
        vector = isinstance(env.unwrapped, gym.vector.VectorEnv)  # which resets by itself
        if k == len(actions) // 2 or (ended and not vector):
            obs, _ = env.reset()
        out.append(b"".join(np.ascontiguousarray(v).tobytes() for v in obs.values())
                   + np.asarray(reward, dtype=np.float64).tobytes())
    return out


CARRIED = {"Stack", "Throw", "PickAndPlace", "Tower", "Insert"}
"""The tasks whose scripted policy holds an object within its first 60 steps."""


@pytest.mark.parametrize("task", TASKS)
def test_env_restore_deepcopy_and_pickle_step_on_bit_for_bit(task):
    """Saved while the pad holds a cube (the tasks that carry one), sizes and materials
    randomised (Insert's hole is made for its peg: materials only): the trace after restoring,
    of a deep copy and of a pickled copy is the original's, through a reset that draws a new
    episode (sizes, materials, starts, goal) from the generator. (Observation noise, drawn in
    every step, is the vector test's.)"""
    randomize = {"mass": (0.5, 2.0), "friction": (0.5, 1.5)} if task == "Insert" else True
    env = gym.make(f"rigid_gym/{task}-v0", randomize=randomize).unwrapped
    obs, _ = env.reset(seed=3)
    policy = scripted_policy(env)
    for _ in range(60):
        obs, *_ = env.step(policy(obs))
        if task not in CARRIED or env.gripper.held[0] >= 0:
            break
    assert task not in CARRIED or env.gripper.held[0] >= 0, "the policy holds a cube by now"
    state_id = env.save_state()
    copies = [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]
    actions = np.random.default_rng(0).uniform(-1, 1, (80, *env.action_space.shape))
    first = env_trace(env, actions)
    env.restore_state(state_id)
    assert env_trace(env, actions) == first
    for other in copies:
        assert env_trace(other, actions) == first
    env.remove_state(state_id)
    with pytest.raises(ValueError, match=f"{type(env).__name__}.restore_state: no saved state"):
        env.restore_state(state_id)


def test_wrapped_env_deepcopy_copies_the_time_limit():
    env = gym.make("rigid_gym/Push-v0", max_episode_steps=30)
    env.reset(seed=0)
    for _ in range(20):
        env.step(env.action_space.sample())
    twin = copy.deepcopy(env)
    ends = []
    for e in (env, twin):
        steps = 0
        while True:
            steps += 1
            if e.step(np.zeros(3, dtype=np.float32))[3]:
                break
        ends.append(steps)
    assert ends == [10, 10]


@pytest.mark.parametrize("effector", ["pad", "gripper"])
def test_vector_env_restore_deepcopy_and_pickle_step_on_bit_for_bit(effector):
    """Every copy, with autoresets inside the trace (short episodes) and their step counts;
    with the two-finger gripper too (its motors' targets live in the World's core)."""
    envs = gym.make_vec("rigid_gym/Stack-v0", num_envs=3, max_episode_steps=25,
                        observation_noise=0.01, effector=effector)
    envs.reset(seed=1)
    actions = np.random.default_rng(1).uniform(-1, 1, (90, *envs.action_space.shape))
    env_trace(envs, actions[:10])
    state_id = envs.save_state()
    copies = [copy.deepcopy(envs), pickle.loads(pickle.dumps(envs))]
    first = env_trace(envs, actions)
    envs.restore_state(state_id)
    assert env_trace(envs, actions) == first
    for other in copies:
        assert env_trace(other, actions) == first
