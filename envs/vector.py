"""Natively batched tasks: B copies of a task in one batched World.

    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=256)   # registered vector_entry_point

Every copy is the task's own env class (the same gripper, observations, rewards and seeding),
but their worlds are the worlds of one ``World(num_worlds=B)``: the solver steps all of them in
one kernel call, in parallel over worlds. Stepping copy i gives bit-identical results to a
single env reset with the same seed (``tests/test_vector.py``).

Autoreset is ``SAME_STEP``: an episode that ends is reset within the same ``step``, whose
observation is then the new episode's first; the last one is in ``infos["final_obs"]`` and its
info in ``infos["final_info"]`` (masks ``infos["_final_obs"]``, ``infos["_final_info"]``).
Episodes are truncated after ``max_episode_steps`` (the id's, as ``gym.make`` does).
The worlds share their geometry, so cube sizes cannot be randomized per copy.
"""

from __future__ import annotations

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from rigid_gym.envs.base import (
    SOLVER_STEPS,
    STEP_TIME,
    RigidGymEnv,
    observations_from,
    observe,
    real_array,
)
from rigid_gym.envs.effector import command_all
from rigid_gym.envs.push import PushEnv
from rigid_gym.envs.stack import StackEnv
from rigid_gym.envs.throw import ThrowEnv
from rigid_gym.world import World


class RigidGymVectorEnv(VectorEnv):
    """``num_envs`` copies of ``env_class`` (a RigidGymEnv task) in one batched World.

    kwargs: the task's constructor arguments (``render_mode`` must be None; ``randomize``
    may not name ``size``).
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, env_class: type[RigidGymEnv], num_envs: int, max_episode_steps: int,
                 **kwargs):
        name = f"{env_class.__name__} vector env"
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) \
                or num_envs < 1:
            raise ValueError(f"{name}: num_envs must be an int >= 1, got {num_envs!r}")
        if isinstance(max_episode_steps, bool) or not isinstance(max_episode_steps, (int, np.integer)) \
                or max_episode_steps < 1:
            raise ValueError(f"{name}: max_episode_steps must be an int >= 1, "
                             f"got {max_episode_steps!r}")
        if kwargs.get("render_mode") is not None:
            raise ValueError(f"{name}: render_mode must be None (render a single env, or record "
                             "one with rigid_gym.recording)")
        randomize = kwargs.get("randomize", False)
        if randomize is True or (isinstance(randomize, dict) and "size" in randomize):
            raise ValueError(f"{name}: the copies share one geometry, so randomize cannot include "
                             "'size'; pass a dict of the other ranges (mass, friction, "
                             "restitution)")
        self.envs = [env_class(**kwargs) for _ in range(num_envs)]
        first = self.envs[0]
        first.reset(seed=0)  # builds the scene every copy's world starts from
        self.world = World(first.scene, dt=STEP_TIME / SOLVER_STEPS, num_worlds=int(num_envs))
        for index, env in enumerate(self.envs):
            env.batch = self.world.view(index)
        self.num_envs = int(num_envs)
        self.max_episode_steps = int(max_episode_steps)
        self.single_observation_space = first.observation_space
        self.single_action_space = first.action_space
        self.observation_space = batch_space(first.observation_space, self.num_envs)
        self.action_space = batch_space(first.action_space, self.num_envs)
        self.elapsed = np.zeros(self.num_envs, dtype=np.int64)
        self.goals = np.zeros((self.num_envs, first.goal_size))
        """Every copy's goal (B, goal_size), kept as each copy resets."""
        self.grippers = [env.gripper for env in self.envs]
        """Every copy's SuctionGripper (a reset makes a new one), kept as each copy resets."""

    def reset(self, *, seed: int | list | None = None, options: dict | None = None):
        """Reset every copy; ``seed``: None, an int (copy i gets seed + i) or one per copy."""
        if seed is None or isinstance(seed, (int, np.integer)):
            seeds = [None if seed is None else int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"{type(self).__name__}.reset: seed must be None, an int or "
                                 f"{self.num_envs} seeds, got {len(seeds)}")
        observations, infos = [], {}
        for i, env in enumerate(self.envs):
            observation, info = self._reset_copy(i, seed=seeds[i], options=options)
            observations.append(observation)
            infos = self._add_info(infos, info, i)
        self.elapsed[:] = 0
        return {key: np.stack([o[key] for o in observations])
                for key in self.single_observation_space.spaces}, infos

    def step(self, actions):
        actions = real_array(actions, f"{type(self).__name__}.step: actions", self.action_space)
        expected = self.action_space.shape
        if actions.shape != expected:
            raise ValueError(f"{type(self).__name__}.step: actions must have shape {expected}, "
                             f"got {actions.shape}")
        if not np.all(np.isfinite(actions)):
            bad = sorted(set(np.flatnonzero(~np.all(np.isfinite(actions), axis=1)).tolist()))
            raise ValueError(f"{type(self).__name__}.step: actions must be finite (NaN and inf "
                             f"are refused); copies {bad} are not")
        actions = np.clip(actions, -1.0, 1.0)  # as the single env: outside [-1, 1] is clipped
        grips = actions[:, 3] if self.envs[0].has_grip else None
        command_all(self.world, self.grippers, actions[:, :3], grips)
        self.world.step(SOLVER_STEPS)  # every copy in one kernel call, held objects carried in it
        self.elapsed += 1
        observations, rewards, terminated, successes = self._outcomes()
        truncated = self.elapsed >= self.max_episode_steps
        infos = {}
        for i in np.flatnonzero(terminated | truncated):
            final_info = {"is_success": bool(successes[i])}
            final_obs = {key: value[i].copy() for key, value in observations.items()}
            infos = self._add_info(infos, {"final_obs": final_obs, "final_info": final_info}, i)
            observation, reset_info = self._reset_copy(i)
            for key, value in observation.items():
                observations[key][i] = value
            successes[i] = reset_info["is_success"]
            self.elapsed[i] = 0
        infos["is_success"] = successes  # every copy's, as _add_info would batch them
        infos["_is_success"] = np.ones(self.num_envs, dtype=bool)
        return observations, rewards, terminated, truncated, infos

    def _reset_copy(self, i: int, **kwargs):
        """Reset copy i (``kwargs``: its reset's seed and options) and keep its new goal and
        gripper; returns its reset's (observation, info)."""
        env = self.envs[i]
        result = env.reset(**kwargs)
        self.goals[i] = env.goal
        self.grippers[i] = env.gripper
        return result

    def _outcomes(self):
        """Every copy's step result at once, as ``RigidGymEnv.outcome`` gives each:
        observations (dict of (B, ...) arrays), rewards (B,), terminated (B,) and successes
        (B,) bool."""
        first = self.envs[0]
        s = self.world
        held = np.array([gripper.held is not None for gripper in self.grippers]) \
            if first.has_grip else None
        vectors, achieved = observe(s.position, s.velocity, s.rotation, s.angular_velocity,
                                    first.gripper.body, first.cubes, held)
        observations = observations_from(self.envs, vectors, achieved, self.goals, s.time)
        achieved32 = observations["achieved_goal"].astype(np.float64)
        desired32 = observations["desired_goal"].astype(np.float64)
        successes = np.asarray(first.goal_reached(achieved32, desired32), dtype=bool)
        rewards = np.asarray(first.compute_reward(achieved32, desired32), dtype=np.float64)
        terminated = successes & first.terminate_on_success
        return observations, rewards, terminated, successes

    def compute_reward(self, achieved_goal, desired_goal, info=None):
        """The task's reward for goals of shape (..., goal_size) (as the single env's)."""
        return self.envs[0].compute_reward(achieved_goal, desired_goal, info)

    def close_extras(self, **kwargs):
        for env in self.envs:
            env.close()


def vector_entry_point(env_class: type[RigidGymEnv]):
    """The function ``gym.make_vec`` calls for ``env_class``'s ids."""
    def make(num_envs: int = 1, max_episode_steps: int = 50, **kwargs) -> RigidGymVectorEnv:
        return RigidGymVectorEnv(env_class, num_envs, max_episode_steps, **kwargs)
    return make


push = vector_entry_point(PushEnv)
stack = vector_entry_point(StackEnv)
throw = vector_entry_point(ThrowEnv)
