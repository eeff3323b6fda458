"""The single env of every task: a Gymnasium Env over a batch of one (``envs/core.py``).

A task's env class (PushEnv, StackEnv, ThrowEnv) names its ``task`` and documents its spaces;
this class is the Gymnasium surface: seeding, argument and action checks, the step's return
values, ``compute_reward``, rendering, and the members a recorder reads
(``rigid_gym.recordable``).

Conventions (those of panda-gym and Gymnasium-Robotics Fetch, so their HER settings transfer):
Dict observations ``observation`` / ``achieved_goal`` / ``desired_goal`` (float32), sparse
reward -1 / 0 or dense -distance, ``compute_reward`` vectorised over any leading batch shape,
``info["is_success"]``.
"""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from rigid_gym.recordable import Series
from rigid_gym.snapshots import SavedStates

from .core import ALL, TaskBatch
from .options import ARGUMENTS_TABLE, Options, checked_actions, refuse_unknown
from .pixels import PixelOptions
from .task import STEP_TIME, Task, with_effector

if TYPE_CHECKING:
    from rigid_gym.render import Renderer

ACTION_NAMES = ("x", "y", "z", "grip")
"""The action entries: the pad's motion along x, y, z, and the grip (with
``effector="gripper"``: the hand's motion and the fingers' command, ``GRIPPER_ACTION_NAMES``)."""
GRIPPER_ACTION_NAMES = ("x", "y", "z", "fingers")
ACTION_COLORS = ((0.86, 0.15, 0.15), (0.13, 0.63, 0.20), (0.15, 0.35, 0.90), (0.60, 0.25, 0.75))
"""Their plot colours: x red, y green, z blue (the axes' usual colours), grip purple."""
REWARD_SERIES = Series("reward", ("reward",), ((0.93, 0.52, 0.10),))
SUCCESS_SERIES = Series("success", ("success",), ((0.10, 0.60, 0.60),))


class RigidGymEnv(gym.Env):
    """Base of every task's env; see a task's docstring (PushEnv, StackEnv, ThrowEnv) for
    its tables. A subclass sets ``task`` (a ``rigid_gym.envs.task.Task``)."""

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.__doc__ and "{arguments}" in cls.__doc__:  # the shared table, written once
            cls.__doc__ = cls.__doc__.replace("{arguments}", ARGUMENTS_TABLE)
        if cls.__doc__ and "{observation" in cls.__doc__:  # written from the task's layout
            layout = cls.task.observation_layout
            cls.__doc__ = cls.__doc__.replace("{observation_size}", str(layout.size)).replace(
                "{observation_fields}", layout.table().replace("\n", "\n    "))

    # Gymnasium's Env declares metadata as a class-level dict (read, never mutated); a ClassVar
    # here would contradict that declaration
    metadata = {  # noqa: RUF012
        "render_modes": ["rgb_array", "human"], "render_fps": round(1 / STEP_TIME)}
    task: Task

    def __init__(self, render_mode: str | None = None, reward_type: str = "sparse",
                 terminate_on_success: bool = False, randomize: bool | dict = False,
                 observation_noise: float = 0.0, obs_mode: str = "state",
                 width: int | None = None, height: int | None = None, camera="front",
                 goal_marker: bool = True, render_width: int | None = None,
                 render_height: int | None = None, render_target_position=None,
                 render_distance: float | None = None, render_yaw: float | None = None,
                 render_pitch: float | None = None, effector: str = "pad", **unknown):
        name = type(self).__name__
        refuse_unknown(name, unknown)
        self.task = with_effector(self.task, effector, name)
        self.options = Options.checked(
            name, render_mode, reward_type, terminate_on_success, randomize, observation_noise,
            obs_mode, width, height, camera, goal_marker, render_width=render_width,
            render_height=render_height, render_target_position=render_target_position,
            render_distance=render_distance, render_yaw=render_yaw, render_pitch=render_pitch)
        self.render_mode = render_mode
        self.observation_space, self.action_space = task_spaces(self.task, self.options.pixels)
        size = self.action_space.shape[0]
        names = GRIPPER_ACTION_NAMES if self.task.effector == "gripper" else ACTION_NAMES
        self.scalar_series = (REWARD_SERIES, Series("action", names[:size],
                                                    ACTION_COLORS[:size]), SUCCESS_SERIES)
        """The plots a recording shows (``rigid_gym.recordable``): the reward, the action's
        entries, success; ``scalars`` gives their values."""
        self.core = TaskBatch(self.task, self.options, None, name)
        self.action_argument = f"{name}.step: action"  # as errors name it
        self.renderer: Renderer | None = None  # made at the first frame of an episode
        self.viewer: bool | None = None
        """render_mode='human': whether frames go to the rerun viewer (a display was found at
        the first render), None until then."""
        self.saved: SavedStates[tuple] = SavedStates(name)
        """The states kept by ``save_state`` by id."""

    @classmethod
    def split_arguments(cls, kwargs: dict) -> tuple[Task, dict]:
        """The task that constructor arguments ``kwargs`` make, and the arguments left for
        ``Options``: the class's task (``own_task``) driven by the ``effector`` argument, and
        the rest. The vector env builds its task with this."""
        rest = dict(kwargs)
        task = cls.own_task(rest)
        return with_effector(task, rest.pop("effector", "pad"), cls.__name__), rest

    @classmethod
    def own_task(cls, kwargs: dict) -> Task:
        """The task of this class for constructor arguments ``kwargs``: the class's ``task``,
        unless the task takes arguments of its own (TowerEnv's ``num_cubes``), which this
        takes out of ``kwargs``."""
        return cls.task

    # -- the Gymnasium API -------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """A new episode, drawn from the env's generator (seeded first where ``seed`` is
        given). ``options``: no task takes any; None or {} only (anything else is refused
        rather than silently ignored)."""
        refuse_options(f"{type(self).__name__}.reset", options)
        super().reset(seed=seed)
        outcome = self.core.reset(ALL, [self.np_random])
        self.renderer = None
        return single(outcome.observations), {"is_success": bool(outcome.successes[0])}

    def step(self, action):
        if self.core.world is None:
            raise ResetNeeded(f"{type(self).__name__}.step: call reset() before step()")
        actions = checked_actions(action, self.action_space, self.action_argument)[None]
        outcome = self.core.step(actions)  # a batch of one
        if self.render_mode == "human":
            self.render()
        return (single(outcome.observations), float(outcome.rewards[0]),
                bool(outcome.terminated[0]), False, {"is_success": bool(outcome.successes[0])})

    def compute_reward(self, achieved_goal, desired_goal, info=None):
        """Reward for goals of shape (..., goal_size) -> shape (...): sparse -1 / 0 (0 when
        ``goal_reached``), dense minus the Euclidean distance between the goals (m). ``info``
        is not used (HER passes a list of dicts)."""
        return self.core.compute_reward(achieved_goal, desired_goal)

    def goal_reached(self, achieved_goal, desired_goal):
        """(..., goal_size) goals -> (...) bool (the task's test)."""
        return self.task.goal_reached(np.asarray(achieved_goal, dtype=np.float64),
                                      np.asarray(desired_goal, dtype=np.float64))

    def render(self):
        if self.render_mode is None:
            gym.logger.warn(f"{type(self).__name__}.render: no render_mode was given at "
                            "construction; pass render_mode='rgb_array' or 'human'")
            return None
        if self.core.world is None:
            raise ResetNeeded(f"{type(self).__name__}.render: call reset() before render()")
        if self.render_mode == "human":
            if self.viewer is None:
                self.viewer = display_available()
                if not self.viewer:
                    gym.logger.warn(
                        f"{type(self).__name__}.render: render_mode='human' shows frames in the "
                        "rerun viewer, which needs a display, and none was found (DISPLAY and "
                        "WAYLAND_DISPLAY are unset): frames are not shown. Use "
                        "render_mode='rgb_array', or record episodes with rigid_gym.recording "
                        "and replay them where a display exists")
            if self.viewer:
                show_in_viewer(self.frame())
            return None
        return self.frame()

    def close(self):
        self.renderer = None

    # -- snapshots (rigid_gym.snapshots) ----------------------------------------------------

    def save_state(self) -> int:
        """Keep a copy of the env's whole state and return its id (an int), as panda-gym's
        ``save_state``: the World (every body, the solver's carried-over bookkeeping), the
        gripper (what it holds), the goal, the generator (so resets and noise draw the same),
        the time. From ``restore_state(id)`` the env steps on bit for bit as it did from here
        with the same actions. Wrappers keep their own state: TimeLimit's step count is not
        the env's (call this on ``env.unwrapped``; ``copy.deepcopy(env)`` copies wrappers
        too)."""
        return self.saved.save(self.core.copy(self._np_random, self._np_random_seed))

    def restore_state(self, state_id: int) -> None:
        """Put the env back to the state saved as ``state_id`` (``save_state``), which stays
        saved. The env's ``world`` and ``gripper`` are then new objects: read them again
        through the env."""
        saved = self.saved.get(state_id, "restore_state")
        self.core, self._np_random, self._np_random_seed = saved[0].copy(*saved[1:])
        self.renderer = None

    def remove_state(self, state_id: int) -> None:
        """Forget the state saved as ``state_id``, freeing its memory."""
        self.saved.remove(state_id)

    # -- what a recorder reads (rigid_gym.recordable) --------------------------------------

    @property
    def world(self):
        """The World (unbatched), None before the first reset."""
        return self.core.world

    @property
    def camera_view(self) -> tuple:
        """(eye (3,) m, target (3,) m, vertical field of view (deg)) of rgb_array frames: the
        task's view, moved by the render_* camera arguments."""
        return self.options.render.view(self.task.camera_view)

    def scalars(self, action, reward, info) -> list[float]:
        """One step's values of ``scalar_series``: the reward, the action as passed to
        ``step``, success as 0 / 1."""
        return [float(reward), *np.ravel(action).tolist(), float(bool(info["is_success"]))]

    def markers(self) -> list:
        """The episode's goal markers (``rigid_gym.recordable.Marker`` each)."""
        return self.core.markers()

    # -- the episode, for users and tests -----------------------------------------------------

    @property
    def scene(self):
        return self.core.scene

    @property
    def cubes(self) -> list[int]:
        """The cubes' body indices."""
        return self.core.cubes

    @property
    def gripper(self):
        """The effector: the SuctionGripper (``rigid_gym.envs.effector``), or with
        ``effector="gripper"`` the ParallelGripper (``rigid_gym.envs.gripper``)."""
        return self.core.gripper

    @property
    def goal(self) -> np.ndarray:
        """The episode's goal (goal_size,) m, float64."""
        return self.core.goals[0]

    @property
    def cube_half(self) -> np.ndarray:
        """The cubes' half edges (cubes,) m."""
        return self.core.half[0]

    @property
    def reward_type(self) -> str:
        return self.options.reward_type

    @property
    def num_cubes(self) -> int:
        return self.task.num_cubes

    def frame(self) -> np.ndarray:
        """The rgb_array frame (render_height, render_width, 3) uint8 of the current state:
        the bodies and the goal markers seen from ``camera_view``."""
        from rigid_gym.render import Camera, Renderer

        if self.renderer is None:
            eye, target, fov = self.camera_view
            size = self.options.render
            self.renderer = Renderer(self.scene, size.width, size.height,
                                     camera=Camera(eye, target, fov_deg=fov),
                                     face_colors=self.task.face_colors(self.cubes))
            for m in self.markers():
                self.renderer.add_marker(m.shape, m.position, m.color, m.alpha, m.orientation,
                                         m.face_colors)
        return self.renderer.render(self.world.position, self.world.orientation)


def task_spaces(task: Task, pixels: PixelOptions) -> tuple[spaces.Dict, spaces.Box]:
    """The observation and action spaces of one copy of ``task`` observed as ``pixels``
    says (its obs_mode and frame size)."""
    size = task.observation_layout.size
    vector = lambda n: spaces.Box(-np.inf, np.inf, shape=(n,), dtype=np.float32)
    keys: dict[str, spaces.Space] = {"achieved_goal": vector(task.goal_size),
                                     "desired_goal": vector(task.goal_size)}
    if pixels.state:
        keys["observation"] = vector(size)
    if pixels.pixels:
        keys["pixels"] = pixels.space()
    return spaces.Dict(keys), spaces.Box(-1.0, 1.0, shape=(3 + int(task.has_grip),),
                                         dtype=np.float32)


def refuse_options(where: str, options) -> None:
    """A ValueError for reset ``options`` other than None or an empty dict: no task has any
    (an episode is drawn from the generator alone, so that a seed replays it)."""
    if options is not None and options != {}:
        raise ValueError(f"{where}: options: the tasks take no reset options (an episode is "
                         f"drawn from the seed alone); pass None, got {options!r}")


def single(observations: dict) -> dict:
    """The observation dict of a batch of one, without the batch axis."""
    return {key: value[0] for key, value in observations.items()}


def display_available() -> bool:
    """Whether a window can open: always off Linux; on Linux, when X11 or Wayland is set."""
    return not sys.platform.startswith("linux") or bool(
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def show_in_viewer(frame: np.ndarray) -> None:
    """render_mode='human': stream the frame to a rerun viewer, started on first use."""
    import rerun as rr

    if rr.get_global_data_recording() is None:
        rr.init("rigid_gym", spawn=True)
    rr.log("camera", rr.Image(frame))
