"""Pixel observations: each copy's camera picture, drawn in the core for a whole batch at once.

    env = gym.make("rigid_gym/Push-v0", obs_mode="pixels", width=84, height=84)
    obs, info = env.reset(seed=0)     # obs["pixels"] (84, 84, 3) uint8, achieved_goal, desired_goal
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=64, obs_mode="pixels")
    obs, info = envs.reset(seed=0)    # obs["pixels"] (64, 84, 84, 3) uint8

``obs_mode`` is "state" (the default: observation, achieved_goal, desired_goal), "pixels"
(pixels, achieved_goal, desired_goal: the goals stay for HER, which relabels them) or
"state+pixels" (all four). Frames come from the renderer of ``rgb_array`` (rigid_gym.render:
z-buffer, Lambert light, shadows, translucent goal markers) through one core call per step for
every copy of a batch, shared out over the core's threads; the same state gives the same bytes
in any process on any number of threads. The camera is fixed to the task (CAMERAS: "front",
the default, sees the pad's whole reach, the cubes, the goal marker and Throw's bin); with
``goal_marker=False`` the goal is not drawn, for agents that must read the goal from the
goal vector alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from rigid_gym.checks import integer
from rigid_gym.render import Camera, Renderer

OBS_MODES = ("state", "pixels", "state+pixels")
"""What an observation holds: the state vector, the camera's picture, or both (every mode
keeps achieved_goal and desired_goal)."""
SIZE_RANGE = (16, 1024)
"""Allowed frame width and height, pixels."""
DEFAULT_SIZE = 84
"""Frame width and height by default, pixels (the size of DQN's and DrQ's frames)."""

VIEWED = {"Push": ((-0.18, -0.18, 0.0), (0.18, 0.18, 0.12)),
          "Throw": ((-0.12, -0.24, 0.0), (0.74, 0.24, 0.12))}
"""Each task's box (low corner, high corner), m, that every camera of CAMERAS frames whole:
where the cubes start and their goals lie (x, y in [-0.15, 0.15] m, plus a cube's half edge
and a little), up to a stack's and a lifted cube's height; for Throw, also every place of the
bin (x up to 0.65 m plus its half width, y in [-0.24, 0.24] m). The pad is in view wherever it
works on a cube."""
VIEWED["Stack"] = VIEWED["Push"]
VIEWED.update(Reach=((-0.18, -0.18, 0.0), (0.18, 0.18, 0.3)),
              PickAndPlace=((-0.18, -0.18, 0.0), (0.18, 0.18, 0.25)),
              Slide=((-0.18, -0.18, 0.0), (0.6, 0.2, 0.04)),
              Flip=((-0.22, -0.22, 0.0), (0.22, 0.22, 0.06)))
"""Reach's: every target; PickAndPlace's: the cube and every target, in the air too; Slide's:
the puck's starts and every target; Flip's: where rolls can take the cube."""
CAMERAS = {
    "Push": {
        "front": Camera(eye=(0.45, -0.6, 0.5), target=(0.0, 0.0, 0.04), fov_deg=36.0),
        "top": Camera(eye=(0.0, 0.0, 1.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0),
                      fov_deg=24.0),
        "side": Camera(eye=(0.0, -0.8, 0.3), target=(0.0, 0.0, 0.06), fov_deg=32.0),
    },
    "Throw": {
        "front": Camera(eye=(0.6, -0.9, 0.8), target=(0.3, 0.0, 0.03), fov_deg=48.0),
        "top": Camera(eye=(0.3, 0.0, 1.3), target=(0.3, 0.0, 0.0), up=(0.0, 1.0, 0.0),
                      fov_deg=42.0),
        "side": Camera(eye=(0.3, -1.0, 0.3), target=(0.3, 0.0, 0.06), fov_deg=60.0),
    },
}
"""Each task's named cameras (Stack's are Push's: the same workspace), each framing the task's
VIEWED box: "front" from the front right above (the default), "top" straight down (+x to the
right, +y up the picture), "side" from -y, low, for heights."""
CAMERAS["Stack"] = CAMERAS["Push"]
CAMERAS["Reach"] = {
    "front": Camera(eye=(0.5, -0.7, 0.6), target=(0.0, 0.0, 0.1), fov_deg=40.0),
    "top": Camera(eye=(0.0, 0.0, 1.2), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov_deg=26.0),
    "side": Camera(eye=(0.0, -0.9, 0.15), target=(0.0, 0.0, 0.14), fov_deg=36.0),
}
"""Reach's, PickAndPlace's and Flip's cameras: Push's workspace up to 0.3 m (targets in the
air), and out to +-0.22 m (where rolls take Flip's cube)."""
CAMERAS.update(PickAndPlace=CAMERAS["Reach"], Flip=CAMERAS["Reach"], Slide=CAMERAS["Throw"])
VIEWED["Tower"] = ((-0.18, -0.18, 0.0), (0.18, 0.18, 0.22))  # Push's, up to 5 cubes high
CAMERAS["Tower"] = {
    "front": Camera(eye=(0.45, -0.6, 0.55), target=(0.0, 0.0, 0.08), fov_deg=40.0),
    "top": Camera(eye=(0.0, 0.0, 1.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0),
                  fov_deg=27.0),
    "side": Camera(eye=(0.0, -0.8, 0.3), target=(0.0, 0.0, 0.1), fov_deg=36.0),
}
VIEWED["Insert"] = ((-0.2, -0.2, 0.0), (0.2, 0.2, 0.12))  # the fixture's 5 cm beyond the range
CAMERAS["Insert"] = {
    "front": Camera(eye=(0.45, -0.6, 0.5), target=(0.0, 0.0, 0.04), fov_deg=40.0),
    "top": Camera(eye=(0.0, 0.0, 1.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0),
                  fov_deg=27.0),
    "side": Camera(eye=(0.0, -0.8, 0.3), target=(0.0, 0.0, 0.06), fov_deg=38.0),
}
CAMERA_NAMES = tuple(CAMERAS["Push"])


@dataclass(frozen=True)
class PixelOptions:
    """The observation arguments, checked (``PixelOptions.checked``): ``obs_mode`` (one of
    OBS_MODES), frame ``width`` and ``height`` (pixels), ``camera`` (a name in CAMERA_NAMES or
    a rigid_gym.render.Camera) and ``goal_marker`` (draw the goal)."""

    obs_mode: str = "state"
    width: int = DEFAULT_SIZE
    height: int = DEFAULT_SIZE
    camera: str | Camera = "front"
    goal_marker: bool = True

    @property
    def pixels(self) -> bool:
        """Whether observations hold ``pixels``."""
        return self.obs_mode != "state"

    @property
    def state(self) -> bool:
        """Whether observations hold the state vector ``observation``."""
        return self.obs_mode != "pixels"

    @classmethod
    def checked(cls, where: str, obs_mode: str = "state", width: int = DEFAULT_SIZE,
                height: int = DEFAULT_SIZE, camera: str | Camera = "front",
                goal_marker: bool = True) -> PixelOptions:
        """The arguments, or a ValueError that starts with ``where`` (the env's class name),
        names the argument and gives the allowed values."""
        if not isinstance(obs_mode, str) or obs_mode not in OBS_MODES:
            raise ValueError(f"{where}: obs_mode must be one of {list(OBS_MODES)}, "
                             f"got {obs_mode!r}")
        low, high = SIZE_RANGE
        for name, value in (("width", width), ("height", height)):
            integer(value, f"{where}: {name}", low, high, unit="pixels")
        if not isinstance(camera, Camera) and (not isinstance(camera, str)
                                               or camera not in CAMERA_NAMES):
            raise ValueError(f"{where}: camera must be one of {list(CAMERA_NAMES)} or a "
                             f"rigid_gym.render.Camera, got {camera!r}")
        if not isinstance(goal_marker, bool):
            raise ValueError(f"{where}: goal_marker must be a bool, got {goal_marker!r}")
        return cls(obs_mode, int(width), int(height), camera, goal_marker)

    def camera_for(self, task_name: str) -> Camera:
        """The Camera of ``camera`` for the task named ``task_name`` ("Push", ...)."""
        if isinstance(self.camera, Camera):
            return self.camera
        return CAMERAS[task_name][self.camera]

    def space(self) -> spaces.Box:
        """The space of one copy's frame: (height, width, 3) uint8."""
        return spaces.Box(0, 255, shape=(self.height, self.width, 3), dtype=np.uint8)


class CopyFrames:
    """The frames of a batch's copies: one Renderer of the batch's scene, its goal markers
    placed per copy.

    scene: the batch's Scene; task: its Task; half: the cubes' half edges (cubes,) m (the
    markers' shapes follow them); num_worlds: B copies; cubes: the cubes' body indices (drawn
    with the task's ``object_faces``).
    """

    def __init__(self, scene, task, half: np.ndarray, options: PixelOptions, num_worlds: int,
                 cubes: list[int]):
        self.task = task
        self.renderer = Renderer(scene, options.width, options.height,
                                 camera=options.camera_for(type(task).__name__),
                                 face_colors=task.face_colors(cubes))
        drawn = options.goal_marker and task.markers_in_pixels
        markers = task.markers(np.zeros(task.goal_size), half) if drawn else []
        for m in markers:
            self.renderer.add_marker(m.shape, m.position, m.color, m.alpha, m.orientation)
        self.marker_position = np.zeros((num_worlds, len(markers), 3))
        """(B, markers, 3) m: each copy's goal markers."""

    def place(self, rows: np.ndarray, goals: np.ndarray, half: np.ndarray) -> None:
        """Put the markers of copies ``rows`` (k,) at their goals (k, goal_size) m, with the
        cubes' half edges ``half`` (k, cubes) m."""
        if self.marker_position.shape[1] == 0:
            return
        for row, goal, h in zip(rows.tolist(), goals, half):
            self.marker_position[row] = [m.position for m in self.task.markers(goal, h)]

    def draw(self, state, worlds: np.ndarray) -> np.ndarray:
        """A new (k, height, width, 3) uint8 array: the frames of copies ``worlds`` (k,)
        int64 of the World whose ``state`` (World.state) holds every copy."""
        return self.renderer.render_batch(state.rotation, state.position, self.marker_position,
                                          worlds)
