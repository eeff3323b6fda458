"""Natively batched tasks: a Gymnasium VectorEnv over a batch of B copies (``envs/core.py``).

    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=256)   # registered vector_entry_point

The copies are the task's own (the same gripper, observations, rewards and seeding as
``gym.make``'s env, which is the same core with B = 1), in one ``World(num_worlds=B)``: the
solver steps all of them in one call, in parallel over worlds where the batch measures that
faster than one thread (``src/solver/sharing.h``). Copy i of ``reset(seed=s)`` plays exactly what a
single env reset with seed s + i plays (``tests/test_vector.py``).

Autoreset is ``SAME_STEP``: an episode that ends is reset within the same ``step``, whose
observation is then the new episode's first; the last one is in ``infos["final_obs"]`` and its
info in ``infos["final_info"]`` (masks ``infos["_final_obs"]``, ``infos["_final_info"]``).
Episodes are truncated after ``max_episode_steps`` (the id's, as ``gym.make`` does). With
``stagger=True`` the first episodes after a ``reset`` are cut short at evenly spread lengths
(copy i's after ``max_episode_steps - i * max_episode_steps // num_envs`` steps), so that the
copies' episodes end on different steps from then on instead of all on the same one (an
on-policy learner's rollouts then see every phase of the episodes at once).
The worlds share their geometry, so cube sizes cannot be randomized per copy.
"""

from __future__ import annotations

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from rigid_gym.checks import integer
from rigid_gym.snapshots import SavedStates

from . import TASKS
from .base import RigidGymEnv, refuse_options, task_spaces
from .core import ALL, TaskBatch
from .flip import FlipEnv
from .insert import InsertEnv
from .options import Options, checked_actions, refuse_unknown
from .pick_and_place import PickAndPlaceEnv
from .push import PushEnv
from .reach import ReachEnv
from .slide import SlideEnv
from .stack import StackEnv
from .task import CUBE_HALF
from .throw import ThrowEnv
from .tower import TowerEnv


class RigidGymVectorEnv(VectorEnv):
    """``num_envs`` copies of ``env_class``'s task (a RigidGymEnv class) in one batched World.

    stagger: spread the first episodes' ends (see the module docstring). kwargs: the task's
    constructor arguments (``render_mode`` must be None; ``randomize`` may not name ``size``).
    """

    # Gymnasium's VectorEnv declares metadata as a class-level dict (read, never mutated); a
    # ClassVar here would contradict that declaration
    metadata = {  # noqa: RUF012
        "autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, env_class: type[RigidGymEnv], num_envs: int, max_episode_steps: int,
                 stagger: bool = False, **kwargs):
        name = f"{env_class.__name__} vector env"
        integer(num_envs, f"{name}: num_envs", 1)
        integer(max_episode_steps, f"{name}: max_episode_steps", 1)
        task, kwargs = env_class.split_arguments(kwargs)  # the task's own (Tower's num_cubes)
        refuse_unknown(name, kwargs)
        rendering = sorted(k for k, v in kwargs.items() if k.startswith("render") and v is not None)
        if rendering:
            raise ValueError(f"{name}: {', '.join(rendering)} must be None (a vector env does "
                             "not render: render a single env, or record one with "
                             "rigid_gym.recording)")
        randomize = kwargs.get("randomize", False)
        if randomize is True or (isinstance(randomize, dict) and "size" in randomize):
            raise ValueError(f"{name}: the copies share one geometry, so randomize cannot include "
                             "'size'; pass a dict of the other ranges (mass, friction, "
                             "restitution)")
        self.options = Options.checked(env_class.__name__, **kwargs)
        self.core = TaskBatch(task, self.options, int(num_envs), env_class.__name__)
        self.core.build(np.full(task.num_cubes, CUBE_HALF))
        self.num_envs = int(num_envs)
        self.max_episode_steps = int(max_episode_steps)
        self.single_observation_space, self.single_action_space = task_spaces(
            task, self.options.pixels)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.elapsed = np.zeros(self.num_envs, dtype=np.int64)
        self.first_elapsed = np.arange(self.num_envs) * self.max_episode_steps // self.num_envs \
            if stagger else np.zeros(self.num_envs, dtype=np.int64)
        """The steps counted as elapsed at a reset: 0, or spread with ``stagger``."""
        self.action_argument = f"{type(self).__name__}.step: actions"  # as errors name it
        self.saved: SavedStates[tuple] = SavedStates(type(self).__name__)
        """The states kept by ``save_state`` by id."""

    @property
    def world(self):
        """The batched World of the copies (world i is copy i)."""
        return self.core.world

    def reset(self, *, seed: int | list | None = None, options: dict | None = None):
        """Reset every copy; ``seed``: None, an int (copy i gets seed + i) or one per copy. A
        copy given no seed goes on with its generator (a random one at its first reset), as
        ``gym.Env.reset`` does. ``options``: None or {} (``RigidGymEnv.reset``)."""
        refuse_options(f"{type(self).__name__}.reset", options)
        if seed is None or isinstance(seed, (int, np.integer)):
            seeds = [None if seed is None else int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"{type(self).__name__}.reset: seed must be None, an int or "
                                 f"{self.num_envs} seeds, got {len(seeds)}")
        rngs = [seeding.np_random(s)[0] if s is not None or rng is None else rng
                for s, rng in zip(seeds, self.core.rngs)]
        outcome = self.core.reset(ALL, rngs)
        self.elapsed[:] = self.first_elapsed
        return outcome.observations, every_copy(outcome.successes)

    def step(self, actions):
        outcome = self.core.step(checked_actions(actions, self.action_space, self.action_argument))
        self.elapsed += 1
        observations, successes = outcome.observations, outcome.successes
        truncated = self.elapsed >= self.max_episode_steps
        ended = np.flatnonzero(outcome.terminated | truncated)
        infos = {}
        if ended.size:
            infos = final_infos(self.num_envs, ended, observations, successes)
            first = self.core.reset(ended, [self.core.rngs[i] for i in ended.tolist()])
            for key, value in first.observations.items():
                observations[key][ended] = value
            successes[ended] = first.successes
            self.elapsed[ended] = 0
        infos.update(every_copy(successes))
        return observations, outcome.rewards, outcome.terminated, truncated, infos

    def compute_reward(self, achieved_goal, desired_goal, info=None):
        """The task's reward for goals of shape (..., goal_size) (as the single env's)."""
        return self.core.compute_reward(achieved_goal, desired_goal)

    # -- snapshots (rigid_gym.snapshots) ----------------------------------------------------

    def save_state(self) -> int:
        """Keep a copy of every copy's state (its world, gripper, goal, generator and step
        count in the episode) and return its id (an int); as ``RigidGymEnv.save_state``."""
        return self.saved.save(self.core.copy(self.elapsed))

    def restore_state(self, state_id: int) -> None:
        """Put every copy back to the state saved as ``state_id``, which stays saved; from
        there each steps on bit for bit as it did with the same actions."""
        saved = self.saved.get(state_id, "restore_state")
        self.core, self.elapsed = saved[0].copy(*saved[1:])

    def remove_state(self, state_id: int) -> None:
        """Forget the state saved as ``state_id``, freeing its memory."""
        self.saved.remove(state_id)


def every_copy(successes: np.ndarray) -> dict:
    """The info of every copy, batched as Gymnasium batches infos: ``is_success`` (B,) and
    its mask."""
    return {"is_success": successes, "_is_success": np.ones(len(successes), dtype=bool)}


def final_infos(num_envs: int, ended: np.ndarray, observations: dict,
                successes: np.ndarray) -> dict:
    """The infos of the copies ``ended`` (indices) whose episodes ended in this step, as
    Gymnasium's SAME_STEP autoreset gives them: ``final_obs`` an object array of each copy's
    last observation (a dict), ``final_info`` its info batched ({"is_success", mask}), each
    with its mask."""
    mask = np.zeros(num_envs, dtype=bool)
    mask[ended] = True
    final_obs = np.full(num_envs, None, dtype=object)
    for i in ended.tolist():
        final_obs[i] = {key: value[i].copy() for key, value in observations.items()}
    final_success = np.zeros(num_envs, dtype=bool)
    final_success[ended] = successes[ended]
    return {"final_obs": final_obs, "_final_obs": mask,
            "final_info": {"is_success": final_success, "_is_success": mask.copy()},
            "_final_info": mask.copy()}


def vector_entry_point(env_class: type[RigidGymEnv], task: str):
    """The function ``gym.make_vec`` calls for ``env_class``'s ids; episodes last the task's
    registered length (``TASKS[task]`` env steps) unless ``max_episode_steps`` is given."""
    def make(num_envs: int = 1, max_episode_steps: int = TASKS[task], stagger: bool = False,
             **kwargs) -> RigidGymVectorEnv:
        return RigidGymVectorEnv(env_class, num_envs, max_episode_steps, stagger, **kwargs)
    return make


push = vector_entry_point(PushEnv, "Push")
stack = vector_entry_point(StackEnv, "Stack")
throw = vector_entry_point(ThrowEnv, "Throw")
reach = vector_entry_point(ReachEnv, "Reach")
pick_and_place = vector_entry_point(PickAndPlaceEnv, "PickAndPlace")
slide = vector_entry_point(SlideEnv, "Slide")
flip = vector_entry_point(FlipEnv, "Flip")
tower = vector_entry_point(TowerEnv, "Tower")
insert = vector_entry_point(InsertEnv, "Insert")
