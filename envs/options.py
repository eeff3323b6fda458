"""The arguments every task takes, checked once for the single and the batched env, and the
check of the actions both are given."""

from __future__ import annotations

import math
import reprlib
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from rigid_gym.checks import in_range, integer, vector

from .pixels import DEFAULT_SIZE, PixelOptions

RENDER_MODES = ("rgb_array", "human")
REWARD_TYPES = ("sparse", "dense", "shaped")
"""sparse -1 / 0 and dense -distance (Fetch's and panda-gym's, goals only: HER recomputes
them); shaped: staged by the task's phases (``Task.shaped_reward``), in [0, 1], reading the
pad and the grip as well as the goals."""
RANDOMIZATION = {
    "mass": (0.5, 2.0),
    "friction": (0.5, 1.5),
    "restitution": (0.0, 0.3),
    "size": (0.8, 1.2),
}
"""Default domain-randomisation ranges (low, high), each drawn uniformly once per reset:
``mass`` and ``size`` scale each cube's mass and edge, ``friction`` scales every body's
friction (one factor per body), ``restitution`` is each cube's coefficient."""

ARGUMENTS_TABLE = """| argument | default | meaning |
    |---|---|---|
    | render_mode | None | "rgb_array" (frames (render_height, render_width, 3), no display needed) or "human" (rerun viewer) |
    | reward_type | "sparse" | "sparse", "dense" (the ``Dense`` ids) or "shaped" (staged, for on-policy learners) |
    | terminate_on_success | False | end the episode when the goal is reached |
    | randomize | False | True, or a dict of ranges, to redraw cube mass, size, restitution and friction each reset (``rigid_gym.envs.options.RANDOMIZATION``) |
    | observation_noise | 0.0 | standard deviation of Gaussian noise on ``observation`` |
    | obs_mode | "state" | "state", "pixels" (``pixels`` (height, width, 3) uint8 and the goals) or "state+pixels" (``rigid_gym.envs.pixels``) |
    | width, height | 84 | frame size of ``pixels``, in [16, 1024] pixels; given, also of ``render()`` |
    | camera | "front" | the frame's camera: "front", "top", "side" (``rigid_gym.envs.pixels.CAMERAS``) or a ``rigid_gym.render.Camera`` |
    | goal_marker | True | draw the goal marker in ``pixels`` |
    | effector | "pad" | "pad" (the suction pad, ``rigid_gym.envs.effector``) or "gripper" (Stack, Throw, PickAndPlace, Tower, Insert: a two-finger gripper that holds by friction, ``rigid_gym.envs.gripper``; its fourth action entry opens (> 0) or closes (< 0) the fingers, and ``observation`` gains their opening) |
    | render_width, render_height | width, height if given, else 480 | frame size of ``render()``, in [16, 4096] pixels (panda-gym's names) |
    | render_target_position, render_distance, render_yaw, render_pitch | the task's view | ``render()``'s camera as panda-gym (PyBullet) places it: looking at the target (3,) m from ``distance`` m, turned ``yaw`` degrees about z (0: from -y) and ``pitch`` degrees about the horizontal (-30: from above), in (-90, 90); each not given keeps the task's view's |"""
"""The constructor arguments every task shares, as its docstring's "Arguments" table."""


RENDER_SIZE = 480
"""render()'s frame width and height by default, pixels (where ``width``/``height`` are not
given)."""
RENDER_SIZE_RANGE = (16, 4096)
ARGUMENTS = ("render_mode", "reward_type", "terminate_on_success", "randomize",
             "observation_noise", "obs_mode", "width", "height", "camera", "goal_marker",
             "render_width", "render_height", "render_target_position", "render_distance",
             "render_yaw", "render_pitch")
"""Every task's constructor arguments (ARGUMENTS_TABLE), in order."""


def refuse_unknown(where: str, given) -> None:
    """A ValueError naming the arguments in ``given`` (names) that no task takes, and the
    ones they take; nothing when every name is known."""
    unknown = sorted(set(given) - set(ARGUMENTS))
    if unknown:
        raise ValueError(f"{where}: unknown argument(s) {unknown}; the arguments are "
                         f"{', '.join(ARGUMENTS)}")


@dataclass(frozen=True)
class RenderOptions:
    """``render()``'s frame size (pixels) and camera, checked (``RenderOptions.checked``):
    panda-gym's arguments; a camera argument of None keeps the task's view's."""

    width: int
    height: int
    target_position: tuple | None = None
    distance: float | None = None
    yaw: float | None = None
    pitch: float | None = None

    @classmethod
    def checked(cls, where: str, width: int | None, height: int | None,
                render_width: int | None = None, render_height: int | None = None,
                render_target_position=None, render_distance: float | None = None,
                render_yaw: float | None = None, render_pitch: float | None = None,
                ) -> RenderOptions:
        """The arguments, or a ValueError that starts with ``where``. The frame is
        render_width x render_height, else the env's width x height where given, else
        RENDER_SIZE."""
        low, high = RENDER_SIZE_RANGE
        size = []
        for name, value, fallback in (("render_width", render_width, width),
                                      ("render_height", render_height, height)):
            value = value if value is not None else fallback if fallback is not None \
                else RENDER_SIZE
            size.append(integer(value, f"{where}: {name}", low, high, unit="pixels"))
        target = None if render_target_position is None else tuple(
            vector(render_target_position, 3, f"{where}: render_target_position").tolist())
        distance = None if render_distance is None else in_range(
            render_distance, 0.0, 100.0, f"{where}: render_distance", open_low=True, unit="m")
        yaw = None if render_yaw is None else in_range(
            render_yaw, -360.0, 360.0, f"{where}: render_yaw", unit="degrees")
        pitch = None if render_pitch is None else in_range(
            render_pitch, -89.9, 89.9, f"{where}: render_pitch", unit="degrees")
        return cls(size[0], size[1], target, distance, yaw, pitch)

    def view(self, default: tuple) -> tuple:
        """(eye (3,) m, target (3,) m, vertical field of view (deg)): ``default`` (the task's
        view, the same form) with the given camera arguments in place of its own. As PyBullet
        places a camera (``computeViewMatrixFromYawPitchRoll``, z up): eye = target +
        distance (cos(pitch) sin(yaw), -cos(pitch) cos(yaw), -sin(pitch))."""
        eye, target, fov = (np.asarray(default[0], float), np.asarray(default[1], float),
                            default[2])
        if self.target_position is None and self.distance is None and self.yaw is None \
                and self.pitch is None:
            return tuple(eye.tolist()), tuple(target.tolist()), fov
        offset = eye - target
        distance = float(np.linalg.norm(offset))
        yaw = math.degrees(math.atan2(offset[0], -offset[1]))
        pitch = -math.degrees(math.asin(offset[2] / distance))
        target = np.asarray(self.target_position if self.target_position is not None
                            else target)
        distance = self.distance if self.distance is not None else distance
        y = math.radians(self.yaw if self.yaw is not None else yaw)
        p = math.radians(self.pitch if self.pitch is not None else pitch)
        eye = target + distance * np.array([math.cos(p) * math.sin(y),
                                            -math.cos(p) * math.cos(y), -math.sin(p)])
        return tuple(eye.tolist()), tuple(target.tolist()), fov


@dataclass(frozen=True)
class Options:
    """A task's arguments, checked (``Options.checked``): render_mode (None or one of
    RENDER_MODES), reward_type (one of REWARD_TYPES), terminate_on_success,
    randomization ({name: (low, high)}, the ranges in use: ``randomize`` resolved),
    observation_noise (standard deviation, >= 0) and pixels (obs_mode and the frames'
    settings, ``rigid_gym.envs.pixels.PixelOptions``)."""

    render_mode: str | None
    reward_type: str
    terminate_on_success: bool
    randomization: dict
    observation_noise: float
    pixels: PixelOptions
    render: RenderOptions

    @classmethod
    def checked(cls, where: str, render_mode: str | None = None, reward_type: str = "sparse",
                terminate_on_success: bool = False, randomize: bool | dict = False,
                observation_noise: float = 0.0, obs_mode: str = "state",
                width: int | None = None, height: int | None = None, camera="front",
                goal_marker: bool = True, **render) -> Options:
        """The arguments of ARGUMENTS_TABLE, or a ValueError that starts with ``where``
        (the env class's name); ``render``: the render_* arguments. A width or height of
        None is DEFAULT_SIZE for ``pixels`` and leaves render()'s size to its default."""
        refuse_unknown(where, render)
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"{where}: render_mode must be None or one of "
                             f"{list(RENDER_MODES)}, got {render_mode!r}")
        if reward_type not in REWARD_TYPES:
            raise ValueError(f"{where}: reward_type must be one of {list(REWARD_TYPES)}, "
                             f"got {reward_type!r}")
        if not isinstance(terminate_on_success, bool):
            raise ValueError(f"{where}: terminate_on_success must be a bool, "
                             f"got {terminate_on_success!r}")
        noise = in_range(observation_noise, 0.0, np.inf, f"{where}: observation_noise")
        return cls(render_mode, reward_type, terminate_on_success,
                   randomization_ranges(randomize, where), noise,
                   PixelOptions.checked(where, obs_mode,
                                        DEFAULT_SIZE if width is None else width,
                                        DEFAULT_SIZE if height is None else height, camera,
                                        goal_marker),
                   RenderOptions.checked(where, width, height, **render))


def randomization_ranges(randomize, where: str) -> dict:
    """``randomize``: False (off), True (RANDOMIZATION) or a dict naming some of its keys with
    (low, high) ranges. Returns the ranges in use."""
    if isinstance(randomize, bool):
        return dict(RANDOMIZATION) if randomize else {}
    if not isinstance(randomize, dict):
        raise ValueError(f"{where}: randomize must be a bool or a dict of ranges, "
                         f"got {randomize!r}")
    unknown = set(randomize) - set(RANDOMIZATION)
    if unknown:
        raise ValueError(f"{where}: randomize has unknown key(s) {sorted(unknown)}; "
                         f"allowed: {sorted(RANDOMIZATION)}")
    ranges = {}
    for name, value in randomize.items():
        try:
            low, high = (float(v) for v in value)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{where}: randomize[{name!r}] must be a (low, high) pair, "
                             f"got {value!r}") from exc
        floor, ceiling = (0.0, 1.0) if name == "restitution" else (1e-3, 1e3)
        if not floor <= low <= high <= ceiling:
            raise ValueError(f"{where}: randomize[{name!r}] must satisfy {floor} <= low <= high "
                             f"<= {ceiling}, got {value!r}")
        ranges[name] = (low, high)
    return ranges


def checked_actions(values, space: spaces.Space, what: str) -> np.ndarray:
    """``values`` as float64 clipped to [-1, 1], if they are a real numeric array of
    ``space``'s shape whose entries are all finite; otherwise a ValueError naming ``what``
    (the env and the argument: "PushEnv.step: action"). A batch ((B, a) actions) names the
    copies whose actions are not finite."""
    actions = real_array(values, what, space)
    if actions.shape != space.shape:
        raise ValueError(f"{what} must have shape {space.shape}, got {actions.shape}")
    # a finite sum means every entry is finite; only a sum that is not (an overflow, or a
    # NaN or inf entry) pays for the entry-by-entry test
    if not math.isfinite(np.add.reduce(actions, axis=None)) and not np.isfinite(actions).all():
        if actions.ndim == 1:
            raise ValueError(f"{what} must be finite (NaN and inf are refused), "
                             f"got {actions.tolist()}")
        bad = np.flatnonzero(~np.isfinite(actions).all(axis=1)).tolist()
        raise ValueError(f"{what} must be finite (NaN and inf are refused); copies {bad} "
                         f"are not")
    return np.minimum(np.maximum(actions, -1.0), 1.0)  # documented: outside [-1, 1] is clipped


def real_array(values, what: str, space: spaces.Space) -> np.ndarray:
    """``values`` as a float64 array, if they are a real numeric array (or nested sequence) of
    bool, int or float of any width; otherwise a ValueError naming ``what`` (the env and the
    argument) and the expected ``space``. Strings (even "0.5"), complex numbers, objects and
    dicts are refused: numpy would parse the first, drop the imaginary part of the second and
    fail with a bare message on the rest. Shape and finiteness are the caller's to check."""
    try:
        array = np.asarray(values)
    except (TypeError, ValueError):  # ragged nesting, or an object numpy cannot take
        array = None
    if array is None or array.dtype.kind not in "biuf":
        got = (f"an array of dtype {values.dtype}" if isinstance(values, np.ndarray)
               else f"{type(values).__name__} {reprlib.repr(values)}")
        raise ValueError(f"{what} must be a real numeric array (bool, int or float) in "
                         f"{space}, got {got}")
    return array.astype(np.float64, copy=False)
