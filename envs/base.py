"""The shared goal-conditioned env: a World, the suction gripper, and a task.

A task subclass says which cubes it has, where they start, what the goal is and when it is
reached; this class does everything else the same way for every task: spaces, seeding,
domain randomisation, stepping the solver, rewards, observations and rendering.

Conventions (those of panda-gym and Gymnasium-Robotics Fetch, so their HER settings transfer):
0.04 s per env step (10 solver steps of 4 ms), Dict observations ``observation`` /
``achieved_goal`` / ``desired_goal`` (float32), sparse reward -1 / 0 or dense -distance,
``compute_reward`` vectorised over any leading batch shape, ``info["is_success"]``.
"""

from __future__ import annotations

import os
import reprlib
import sys

import numpy as np
import gymnasium as gym
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from rigid_gym.scene import Scene
from rigid_gym.shapes import Box
from rigid_gym.world import World, WorldView
from rigid_gym.envs.effector import SuctionGripper, Workspace

STEP_TIME = 0.04
"""s of simulated time per env step."""
SOLVER_STEPS = 10
"""solver steps per env step (dt = 4 ms, as panda-gym's 2 ms x 20 and Fetch's 2 ms x 20)."""
DISTANCE_THRESHOLD = 0.05
"""m: a goal position is reached within this distance."""
CUBE_HALF = 0.02
"""m: half the edge of every task's cubes (4 cm cubes, as panda-gym's)."""
CUBE_MASS = 0.1
"""kg"""
FRICTION = 0.5
"""Coulomb coefficient of table, cubes and gripper (a pair uses sqrt(mu_a mu_b))."""
GRIPPER_START = (0.0, 0.0, 0.12)
"""m: the gripper's centre at reset."""
RANDOMIZATION = {
    "mass": (0.5, 2.0),
    "friction": (0.5, 1.5),
    "restitution": (0.0, 0.3),
    "size": (0.8, 1.2),
}
"""Default domain-randomisation ranges (low, high), each drawn uniformly once per reset:
``mass`` and ``size`` scale each cube's mass and edge, ``friction`` scales every body's
friction (one factor per body), ``restitution`` is each cube's coefficient."""
ROTATION_FEATURES = 6
"""An orientation is observed as the first two columns of its rotation matrix (continuous,
unlike a quaternion's sign or Euler angles)."""
OBJECT_FEATURES = 3 + 3 + ROTATION_FEATURES + 3 + 3
MARKER_ALPHA = 0.45
"""Opacity of goal markers in rendered frames."""


ARGUMENTS_TABLE = """| argument | default | meaning |
    |---|---|---|
    | render_mode | None | "rgb_array" (480 x 480 frames, no display needed) or "human" (rerun viewer) |
    | reward_type | "sparse" | "sparse" or "dense" (the ``Dense`` ids) |
    | terminate_on_success | False | end the episode when the goal is reached |
    | randomize | False | True, or a dict of ranges, to redraw cube mass, size, restitution and friction each reset (``rigid_gym.envs.base.RANDOMIZATION``) |
    | observation_noise | 0.0 | standard deviation of Gaussian noise on ``observation`` |"""
"""The constructor arguments every task shares, as its docstring's "Arguments" table."""


class RigidGymEnv(gym.Env):
    """Base of every task; see a task's docstring (PushEnv, StackEnv, ThrowEnv) for its tables.

    Subclasses set ``num_cubes``, ``has_grip`` and ``goal_size`` and implement
    ``_place_cubes``, ``_place_fixtures``, ``_add_fixtures``, ``_sample_goal`` and
    ``goal_reached``.
    """

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.__doc__ and "{arguments}" in cls.__doc__:  # the shared table, written once
            cls.__doc__ = cls.__doc__.replace("{arguments}", ARGUMENTS_TABLE)

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": round(1 / STEP_TIME)}
    num_cubes: int = 1
    has_grip: bool = False
    goal_size: int = 3
    camera_view = ((0.36, -0.48, 0.4), (0.0, 0.0, 0.03), 30.0)
    """(eye (m), target (m), vertical field of view (deg)) of the rgb_array camera: the
    workspace from the front right, above."""

    def __init__(self, render_mode: str | None = None, reward_type: str = "sparse",
                 terminate_on_success: bool = False, randomize: bool | dict = False,
                 observation_noise: float = 0.0):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"{type(self).__name__}: render_mode must be None or one of "
                             f"{self.metadata['render_modes']}, got {render_mode!r}")
        if reward_type not in ("sparse", "dense"):
            raise ValueError(f"{type(self).__name__}: reward_type must be 'sparse' or 'dense', "
                             f"got {reward_type!r}")
        if not isinstance(terminate_on_success, bool):
            raise ValueError(f"{type(self).__name__}: terminate_on_success must be a bool, "
                             f"got {terminate_on_success!r}")
        noise = float(observation_noise)
        if not np.isfinite(noise) or noise < 0.0:
            raise ValueError(f"{type(self).__name__}: observation_noise must be a finite standard "
                             f"deviation >= 0, got {observation_noise!r}")
        self.render_mode = render_mode
        self.reward_type = reward_type
        self.terminate_on_success = terminate_on_success
        self.randomization = _randomization_ranges(randomize, type(self).__name__)
        self.observation_noise = noise
        size = 6 + int(self.has_grip) + OBJECT_FEATURES * self.num_cubes
        vector = lambda n: spaces.Box(-np.inf, np.inf, shape=(n,), dtype=np.float32)  # noqa: E731
        self.observation_space = spaces.Dict({
            "observation": vector(size),
            "achieved_goal": vector(self.goal_size),
            "desired_goal": vector(self.goal_size),
        })
        self.action_space = spaces.Box(-1.0, 1.0, shape=(3 + int(self.has_grip),),
                                       dtype=np.float32)
        self.scene: Scene | None = None  # the bodies and shapes; poses are set each reset
        self.world: World | WorldView | None = None
        self.batch: WorldView | None = None  # set by a vector env: this env's world in its batch
        self.gripper: SuctionGripper | None = None
        self.goal = np.zeros(self.goal_size)
        self._renderer = None
        self._viewer: bool | None = None
        """render_mode='human': whether frames go to the rerun viewer (a display was found at
        the first render), None until then."""

    # -- the Gymnasium API -------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        n = self.num_cubes
        # one factor per body and quantity: bodies are the cubes, then the gripper and the table
        factors = {name: self.np_random.uniform(low, high, size=n + 2)
                   for name, (low, high) in self.randomization.items()}
        factor = lambda name: factors.get(name, np.ones(n + 2))  # noqa: E731
        half = CUBE_HALF * factor("size")[:n]
        mass = CUBE_MASS * factor("mass")[:n]
        friction = FRICTION * factor("friction")
        restitution = factors.get("restitution", np.zeros(n + 2))[:n]

        self.cube_half = half
        starts = self._place_cubes(half)
        places = self._place_fixtures()
        if self.scene is None or "size" in self.randomization:
            self._build_scene(half, starts, places, friction, restitution)
            self.world = None
        if self.batch is not None:
            self.world = self.batch  # this env's world in a vector env's batch
        elif self.world is None:  # compiles the scene's geometry: ~4 ms
            self.world = World(self.scene, dt=STEP_TIME / SOLVER_STEPS)
        # the episode's state, the same way whether the World is new or not: the scene's
        # start (the gripper's, nothing moving, nothing held), then the episode's draws
        self.world.reset()
        for body, place in zip(self.cubes + self.fixtures, starts + places):
            self.world.set_pose(body, place)  # a cube's centre of mass is its centre
        if self.randomization:
            for cube, m, f, e in zip(self.cubes, mass, friction, restitution):
                self.world.set_material(cube, mass=m, friction=f, restitution=e)
            self.world.set_material(self.gripper_body, friction=friction[-2])
            self.world.set_material(self.table, friction=friction[-1])
        self.gripper = SuctionGripper(self.world, self.gripper_body, self.cubes,
                                      [(h, h, h) for h in half], STEP_TIME, Workspace())
        self.goal = self._sample_goal()
        self._renderer = None
        observation = self._observation()
        return observation, {"is_success": self._is_success(observation)}

    def _build_scene(self, half: np.ndarray, starts: list, places: list, friction: np.ndarray,
                     restitution: np.ndarray) -> None:
        """The Scene of cubes with half edges ``half`` (k,) m at ``starts`` and fixtures at
        ``places`` ((3,) m each), and the bodies' indices: built at the first reset, and again
        only when sizes are randomised. Cubes get the nominal mass (a reset sets each
        episode's through ``set_material``, so every episode's inertia comes from the same
        arithmetic); friction (k + 2,) and restitution (k,) are this episode's (restitution
        > 0 puts the collision phase in the World's config)."""
        scene = Scene()
        self.table = scene.add_ground(friction=friction[-1], name="table")
        self.cubes = [scene.add_body(Box((h, h, h)), mass=CUBE_MASS, position=p, friction=f,
                                     restitution=e, name=f"cube{k}")
                      for k, (h, p, f, e) in enumerate(zip(half, starts, friction, restitution))]
        self.gripper_body = scene.add_body(SuctionGripper.shape, kinematic=True,
                                           position=GRIPPER_START, friction=friction[-2],
                                           name="gripper")
        self.fixtures = self._add_fixtures(scene, places)
        self.scene = scene

    def step(self, action):
        self.act(action)
        self.world.step(SOLVER_STEPS)  # one kernel call, held objects carried in it
        return self.outcome()

    def act(self, action) -> None:
        """The first half of ``step``: check ``action`` and command the gripper with it."""
        if self.world is None:
            raise ResetNeeded(f"{type(self).__name__}.step: call reset() before step()")
        action = real_array(action, f"{type(self).__name__}.step: action", self.action_space)
        if action.shape != self.action_space.shape:
            raise ValueError(f"{type(self).__name__}.step: action must have shape "
                             f"{self.action_space.shape}, got {action.shape}")
        if not np.isfinite(action).all():
            raise ValueError(f"{type(self).__name__}.step: action must be finite (NaN and inf "
                             f"are refused), got {action.tolist()}")
        action = np.minimum(np.maximum(action, -1.0), 1.0)  # documented: outside [-1, 1] is clipped
        self.gripper.command(action[:3], action[3] if self.has_grip else None)

    def outcome(self):
        """The second half of ``step``, once the solver has run SOLVER_STEPS steps: the step's
        (observation, reward, terminated, truncated, info)."""
        observation = self._observation()
        success = self._is_success(observation)
        info = {"is_success": success}
        reward = float(self.compute_reward(observation["achieved_goal"],
                                           observation["desired_goal"], info))
        terminated = self.terminate_on_success and success
        if self.render_mode == "human":
            self.render()
        return observation, reward, terminated, False, info

    def compute_reward(self, achieved_goal, desired_goal, info=None):
        """Reward for goals of shape (..., goal_size) -> shape (...): sparse -1 / 0 (0 when
        ``goal_reached``), dense minus the Euclidean distance between the goals (m). ``info``
        is not used (HER passes a list of dicts)."""
        achieved_goal = np.asarray(achieved_goal, dtype=np.float64)
        desired_goal = np.asarray(desired_goal, dtype=np.float64)
        if self.reward_type == "dense":
            return -np.linalg.norm(achieved_goal - desired_goal, axis=-1)
        return self.goal_reached(achieved_goal, desired_goal).astype(np.float64) - 1.0

    def render(self):
        if self.render_mode is None:
            gym.logger.warn(f"{type(self).__name__}.render: no render_mode was given at "
                            "construction; pass render_mode='rgb_array' or 'human'")
            return None
        if self.world is None:
            raise ResetNeeded(f"{type(self).__name__}.render: call reset() before render()")
        if self.render_mode == "human":
            if self._viewer is None:
                self._viewer = _display_available()
                if not self._viewer:
                    gym.logger.warn(
                        f"{type(self).__name__}.render: render_mode='human' shows frames in the "
                        "rerun viewer, which needs a display, and none was found (DISPLAY and "
                        "WAYLAND_DISPLAY are unset): frames are not shown. Use "
                        "render_mode='rgb_array', or record episodes with rigid_gym.recording "
                        "and replay them where a display exists")
            if self._viewer:
                _show_in_viewer(self._render_frame())
            return None
        return self._render_frame()

    def close(self):
        self._renderer = None

    # -- what every task shares --------------------------------------------------------------

    def _observation(self) -> dict:
        w = self.world
        held = None if not self.has_grip else np.array([self.gripper.held is not None])
        vectors, achieved = observe(w.position[None], w.velocity[None], w.rotation[None],
                                    w.angular_velocity[None], self.gripper.body, self.cubes, held)
        batch = observations_from([self], vectors, achieved, self.goal[None], w.time)
        return {key: value[0] for key, value in batch.items()}

    def _is_success(self, observation: dict) -> bool:
        """Judged on the observed (float32) goals, exactly as ``compute_reward`` sees them."""
        return bool(self.goal_reached(np.asarray(observation["achieved_goal"], np.float64),
                                      np.asarray(observation["desired_goal"], np.float64)))

    def _render_frame(self) -> np.ndarray:
        from rigid_gym.render import Camera, Renderer

        if self._renderer is None:
            eye, target, fov = self.camera_view
            self._renderer = Renderer(self.scene, camera=Camera(eye, target, fov_deg=fov))
            self._add_markers(self._renderer)
        return self._renderer.render(self.world.position, self.world.orientation)

    # -- what a task says --------------------------------------------------------------------

    def _place_cubes(self, half: np.ndarray) -> list:
        """Start positions (3,) m of the cubes with half edges ``half`` (k,), from np_random."""
        raise NotImplementedError

    def _place_fixtures(self) -> list:
        """Places (3,) m of the static bodies beyond the table (the bin of Throw), drawn from
        np_random after the cubes' starts; none by default."""
        return []

    def _add_fixtures(self, scene: Scene, places: list) -> list:
        """Add the static bodies beyond the table at ``places`` (``_place_fixtures``);
        returns their body indices."""
        return []

    def _sample_goal(self) -> np.ndarray:
        raise NotImplementedError

    def goal_reached(self, achieved_goal: np.ndarray, desired_goal: np.ndarray) -> np.ndarray:
        """(..., goal_size) goals -> (...) bool."""
        raise NotImplementedError

    def _add_markers(self, renderer) -> None:
        """Goal markers for rgb_array frames (translucent: MARKER_ALPHA)."""
        raise NotImplementedError


def observe(position, velocity, rotation, angular_velocity, gripper: int, cubes,
            held=None) -> tuple[np.ndarray, np.ndarray]:
    """Observations and achieved goals of B worlds, float64: ``(B, size)`` and
    ``(B, 3 * len(cubes))``, from their state (position, velocity, angular_velocity (B, n, 3),
    rotation (B, n, 3, 3)), the gripper's body index and the cubes'. held: (B,) bool, whether
    each gripper holds a cube (tasks with a grip), or None. The achieved goal of every task is
    its cubes' positions."""
    pad = position[:, gripper]
    parts = [pad, velocity[:, gripper]]
    if held is not None:
        parts.append(np.asarray(held, dtype=np.float64)[:, None])
    for body in cubes:
        cube = position[:, body]
        axes = rotation[:, body, :, :2].transpose(0, 2, 1).reshape(-1, ROTATION_FEATURES)
        parts += [cube, cube - pad, axes, velocity[:, body], angular_velocity[:, body]]
    achieved = np.concatenate([position[:, body] for body in cubes], axis=1)
    return np.concatenate(parts, axis=1), achieved


def observations_from(envs, vectors: np.ndarray, achieved: np.ndarray, goals: np.ndarray,
                      time: float) -> dict:
    """The observation dict of B envs of one task (``envs``, in the order of the rows) from
    ``observe``'s rows (vectors (B, size), achieved (B, goal_size)) and their goals (B,
    goal_size), float64: rows checked finite, noise added (each env's ``observation_noise``
    from its own np_random, as one env alone would draw it), all cast to float32 (B, ...)
    arrays. ``time``: the worlds' simulated time, s (for the error message)."""
    finite = np.isfinite(vectors).all(axis=1)
    if not finite.all():  # a solver failure: say so here, not in a network
        copy = int(np.flatnonzero(~finite)[0])
        bad = np.flatnonzero(~np.isfinite(vectors[copy])).tolist()
        which = f" (copy {copy})" if len(envs) > 1 else ""
        raise RuntimeError(f"{type(envs[copy]).__name__}{which}: the simulation produced "
                           f"non-finite state (observation entries {bad}) at t = {time:.3f} s")
    if envs[0].observation_noise > 0.0:
        noise = envs[0].observation_noise
        vectors = vectors + np.stack([env.np_random.normal(0.0, noise, vectors.shape[1])
                                      for env in envs])
    return {
        "observation": vectors.astype(np.float32),
        "achieved_goal": achieved.astype(np.float32),
        "desired_goal": goals.astype(np.float32),
    }


def real_array(values, what: str, space: spaces.Box) -> np.ndarray:
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


def _randomization_ranges(randomize, where: str) -> dict:
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


def _display_available() -> bool:
    """Whether a window can open: always off Linux; on Linux, when X11 or Wayland is set."""
    return not sys.platform.startswith("linux") or bool(
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _show_in_viewer(frame: np.ndarray) -> None:
    """render_mode='human': stream the frame to a rerun viewer, started on first use."""
    import rerun as rr

    if rr.get_global_data_recording() is None:
        rr.init("rigid_gym", spawn=True)
    rr.log("camera", rr.Image(frame))


def sample_apart(rng: np.random.Generator, half_range: float, others, min_distance: float,
                 tries: int = 1000) -> np.ndarray:
    """A point (2,) uniform in [-half_range, half_range]^2 (m) at least ``min_distance`` (m)
    from every point in ``others`` (each (2,)); rejection sampling from ``rng``."""
    for _ in range(tries):
        point = rng.uniform(-half_range, half_range, size=2)
        if all(np.linalg.norm(point - np.asarray(o)[:2]) >= min_distance for o in others):
            return point
    raise RuntimeError(f"sample_apart: no point {min_distance} m from {len(others)} others in "
                       f"{tries} tries; the ranges are too tight")
