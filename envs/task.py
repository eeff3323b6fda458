"""What a task is (Push, Stack, Throw): its cubes, fixtures, goal, goal test and markers, written
once over a batch of copies, and the constants every task shares.

A ``Task`` holds no state. Its methods take the copies being reset as arrays with a leading
axis of k copies (``half`` (k, cubes) m, ...), and one random generator per copy, from which
each copy draws exactly what one env alone would draw, in the same order: a copy of a batch
plays what a single env reset with the same seed plays (``envs/core.py`` runs the batch).

Conventions (those of panda-gym and Gymnasium-Robotics Fetch, so their HER settings transfer):
0.04 s per env step (10 solver steps of 4 ms), goals of 3 numbers per cube, 0.05 m thresholds.
"""

from __future__ import annotations

import copy
import functools

import numpy as np

from rigid_gym.recordable import Marker
from rigid_gym.scene import Scene
from rigid_gym.shapes import Box

from .observation import Layout, observation_layout

STEP_TIME = 0.04
"""s of simulated time per env step."""
SOLVER_STEPS = 10
"""solver steps per env step (dt = 4 ms, as panda-gym's 2 ms x 20 and Fetch's 2 ms x 20)."""
SOLVER_SETTINGS = {"overlap_correction": 0.2, "overlap_energy": False, "continuous": False,
                   "contact_patches": False, "patch_reactions": False, "exact_symmetric": False}
"""SolverConfig fields where the v0 tasks differ from the library's defaults. An env id's
dynamics are fixed with its version (Gymnasium's rule): the v0 ids' results, models and
datasets were made removing 20% of an excess overlap per step, its lifts free of cost; the
library's default removes all of it, which changes Throw's and Stack's episodes in their bits,
and takes a lift's potential energy from the body's kinetic energy. They were made without
continuous collision too: ``for_scene`` leaves it out of the built scenes (nothing moves
until the gripper does), but a thrown cube moves up to 9 mm a step against the bin's 5 mm
half walls, so with it Throw's episodes change in their bits. They resolved patches between
two cubes by one impulse, without shock propagation's friction reactions and with Insert's
peg (two equal moments) turned by the rotation update, which the defaults
(``contact_patches``, ``patch_reactions``, ``exact_symmetric``) change too. A v1 of a task would take the
defaults."""
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
MARKER_ALPHA = 0.45
"""Opacity of goal markers in rendered frames and recordings."""
GOAL_COLOR = (0.2, 0.8, 0.3)
"""Colour of a goal marker that belongs to no cube in particular."""


EFFECTORS = ("pad", "gripper")
"""What drives a task (the ``effector`` argument): "pad", the suction pad
(``rigid_gym.envs.effector``, every task's default), or "gripper", the two-finger parallel
gripper that holds by friction (``rigid_gym.envs.gripper``, the tasks that grasp)."""


class Task:
    """Base of every task. A subclass sets ``num_cubes``, ``has_grip``, ``goal_size`` (and
    ``camera_view`` if the default does not suit; ``half_extents`` where its objects are not
    cubes) and implements ``place_cubes``,
    ``sample_goals``, ``goal_reached`` and ``markers``; a task with static bodies beyond the
    table (Throw's bin) also ``place_fixtures`` and ``add_fixtures``."""

    num_cubes: int = 1
    has_grip: bool = False
    goal_size: int = 3
    grasps: bool = False
    """Whether the task is done by picking objects up, so that the two-finger gripper can drive
    it (``effector="gripper"``)."""
    effector: str = "pad"
    """What drives this task's gripper: one of EFFECTORS (``with_effector`` makes the task
    driven by another)."""
    camera_view = ((0.36, -0.48, 0.4), (0.0, 0.0, 0.03), 30.0)
    """(eye (m), target (m), vertical field of view (deg)) of the rgb_array camera: the
    workspace from the front right, above."""
    num_fixtures: int = 0
    object_friction: float = FRICTION
    """Coulomb coefficient of the task's objects (its cubes, or Slide's puck)."""
    table_friction: float = FRICTION
    """Coulomb coefficient of the table (a pair uses sqrt(mu_a mu_b))."""
    object_faces: tuple | None = None
    """Six (r, g, b): the colours in frames of an object's faces towards +x, -x, +y, -y, +z,
    -z of its frame, for a task whose objects' orientation must be seen (Flip); None: each
    object in one colour."""
    finished_by_letting_go: bool = False
    """Whether the shaped reward pays 1 at the goal only once the pad holds nothing (a task
    finished by putting objects down: a Tower), else ``shaped`` goes on paying there (its
    value for a cube held at its target, below 1), so that a policy lets go rather than
    holds the last cube in place."""
    markers_in_pixels: bool = True
    """Whether ``pixels`` observations draw the goal markers (the copies of a batch share each
    marker's orientation, so a goal that is an orientation is not drawn there)."""

    def half_extents(self, half: np.ndarray) -> np.ndarray:
        """The half extents (..., cubes, 3) m of the objects' unrotated bounding boxes for half
        edges ``half`` (..., cubes) m: cubes by default; a task with other objects (Insert's
        peg, Slide's puck) scales its own proportions by them."""
        return np.repeat(np.asarray(half, dtype=np.float64)[..., None], 3, axis=-1)

    @functools.cached_property
    def observation_layout(self) -> Layout:
        """The fields of this task's ``observation`` vector, in order
        (``rigid_gym.envs.observation``)."""
        return observation_layout(self.num_cubes, self.has_grip, self.effector)

    @functools.cached_property
    def achieved_columns(self) -> np.ndarray:
        """The entries of the ``observation`` vector that make the achieved goal: the cubes'
        positions by default."""
        return self.observation_layout.entries([f"cube{k}.position"
                                                for k in range(self.num_cubes)])

    def face_colors(self, cubes: list[int]) -> dict:
        """The Renderer's ``face_colors`` of the objects with body indices ``cubes``."""
        return {} if self.object_faces is None else {c: self.object_faces for c in cubes}

    def achieved_goal(self, vectors: np.ndarray, state, worlds: np.ndarray,
                      cubes: list[int]) -> np.ndarray:
        """The achieved goals (k, goal_size) float64 of copies ``worlds`` (k,) of the World
        whose ``state`` (World.state) holds them, their observation vectors (noise-free)
        ``vectors`` (k, layout size), the cubes' body indices ``cubes``: the vectors'
        ``achieved_columns`` unless a task reads the state."""
        return vectors[:, self.achieved_columns]

    def object_shape(self, extents):
        """The shape of an object whose unrotated bounding box has half extents ``extents``
        (3,) m (``half_extents``'s rows; what the gripper's force limit and suction reach
        read): a box."""
        return Box(tuple(extents))

    def place_cubes(self, rngs: list, half: np.ndarray) -> np.ndarray:
        """Start positions (k, cubes, 3) m of the cubes with half edges ``half`` (k, cubes) m,
        copy i's from ``rngs[i]``; the cubes start resting and unrotated."""
        raise NotImplementedError

    def place_fixtures(self, rngs: list, starts: np.ndarray) -> np.ndarray:
        """Places (k, fixtures, 3) m of the static bodies beyond the table, drawn after the
        cubes' starts ``starts`` (k, cubes, 3) m; none by default."""
        return np.zeros((len(rngs), 0, 3))

    def add_fixtures(self, scene: Scene) -> list[int]:
        """Add the static bodies beyond the table (placed each reset at ``place_fixtures``'
        places) to ``scene``; returns their body indices."""
        return []

    def sample_goals(self, rngs: list, starts: np.ndarray, half: np.ndarray,
                     places: np.ndarray) -> np.ndarray:
        """Goals (k, goal_size) m of copies whose cubes start at ``starts`` (k, cubes, 3) m
        with half edges ``half`` (k, cubes) and fixtures at ``places`` (k, fixtures, 3) m,
        drawn after the fixtures."""
        raise NotImplementedError

    def goal_reached(self, achieved_goal: np.ndarray, desired_goal: np.ndarray) -> np.ndarray:
        """(..., goal_size) goals -> (...) bool. Reads only the goals, so that HER can
        relabel them."""
        raise NotImplementedError

    def markers(self, goal: np.ndarray, half: np.ndarray) -> list[Marker]:
        """The markers of one copy's goal (goal_size,) m, its cubes' half edges (cubes,) m."""
        raise NotImplementedError

    def reward(self, achieved_goal: np.ndarray, desired_goal: np.ndarray,
               reward_type: str) -> np.ndarray:
        """Reward of goals (..., goal_size) -> (...) float64: ``"sparse"`` -1 / 0 (0 where
        ``goal_reached``), ``"dense"`` minus the Euclidean distance between the goals (m)."""
        if reward_type == "dense":
            return -distance(achieved_goal - desired_goal)
        return sparse_reward(self.goal_reached(achieved_goal, desired_goal))

    def shaped_reward(self, pad: np.ndarray, held: np.ndarray, achieved_goal: np.ndarray,
                      desired_goal: np.ndarray, half: np.ndarray) -> np.ndarray:
        """The shaped reward (``reward_type="shaped"``) of copies whose pad is at ``pad``
        (k, 3) m, holding cube ``held`` (k,) (-1: none), with goals (k, goal_size) m and cube
        half edges ``half`` (k, cubes) m -> (k,) in [0, 1) (the env gives 1 where the goal is
        reached, and, where ``finished_by_letting_go``, nothing is held). Staged as ManiSkill's dense rewards: see ``staged``."""
        raise NotImplementedError

    def shaped(self, vectors: np.ndarray, held: np.ndarray, achieved_goal: np.ndarray,
               desired_goal: np.ndarray, half: np.ndarray, released: np.ndarray) -> np.ndarray:
        """The shaped reward of copies whose noise-free observation vectors are ``vectors``
        (k, layout size) and whose effector has let go of an object it held this episode
        where ``released`` (k,) bool: ``shaped_reward`` of the pad's (or the hand's) position
        read from them. A task whose stages read more of the state than the pad and the goals
        (Flip: the cube's position, which its goal does not hold; Throw: ``released``)
        overrides this."""
        layout = self.observation_layout
        pad = vectors[:, layout.slice(f"{layout.effector}.position")]
        return self.shaped_reward(pad, held, achieved_goal, desired_goal, half)


def with_effector(task: Task, effector, where: str) -> Task:
    """``task`` driven by ``effector`` (one of EFFECTORS): ``task`` itself for its own
    effector, else a copy that differs in ``effector`` only (one per task and effector,
    shared: a Task holds no state). A ValueError that starts with ``where`` (the env's class
    name) for another value, or for the gripper on a task that does not grasp."""
    if not isinstance(effector, str) or effector not in EFFECTORS:
        raise ValueError(f"{where}: effector must be one of {list(EFFECTORS)}, got {effector!r}")
    if effector == task.effector:
        return task
    if effector == "gripper" and not task.grasps:
        raise ValueError(f"{where}: effector='gripper' is for the tasks that pick objects up "
                         "(Stack, Throw, PickAndPlace, Tower, Insert); this task is done by "
                         "pushing, so it takes the pad only (effector='pad')")
    return driven_by(task, effector)


@functools.cache
def driven_by(task: Task, effector: str) -> Task:
    """The copy of ``task`` driven by ``effector`` (``with_effector``), made once."""
    variant = copy.copy(task)
    for name in list(variant.__dict__):  # what is cached is made again for the effector
        if isinstance(getattr(type(task), name, None), functools.cached_property):
            del variant.__dict__[name]
    variant.effector = effector
    return variant


SHAPED_SCALE = 5.0
"""1/m: a shaped stage's closeness is 1 - tanh(SHAPED_SCALE * distance) (ManiSkill's)."""


def sparse_reward(reached: np.ndarray) -> np.ndarray:
    """The sparse reward of goal tests ``reached`` (...) bool -> (...) float64: 0 where the goal
    is reached, else -1 (panda-gym's and Fetch's)."""
    return reached - 1.0


def closeness(offset: np.ndarray, scale: float = SHAPED_SCALE) -> np.ndarray:
    """1 - tanh(scale * |offset|) of offsets (..., 3) m -> (...) in (0, 1]: 1 at zero
    distance, falling with it."""
    return 1.0 - np.tanh(scale * distance(offset))


def staged(reach: np.ndarray, engaged: np.ndarray, place: np.ndarray) -> np.ndarray:
    """One object's stages -> (k,) in [0, 3]: ``reach`` (k,) in [0, 1] (the pad's closeness
    to where it acts on the object) until ``engaged`` (k,) bool (the pad acts on it: pushing
    it, holding it, or it is in flight), then 2 + ``place`` (k,) in [0, 1] (the object's
    closeness to its target). A stage passed is worth more than any value of the one before,
    and once engaged the reward only grows as the object nears its target."""
    return np.where(engaged, 2.0 + place, reach)


def distance(offset: np.ndarray) -> np.ndarray:
    """Euclidean length of ``offset`` (..., d) along its last axis -> (...): the bits of
    ``np.linalg.norm(offset, axis=-1)`` without its argument handling (a few microseconds,
    which a step of a single env would pay several times)."""
    return np.sqrt(np.add.reduce(offset * offset, axis=-1))


def cube_anywhere(rngs: list, half: np.ndarray, half_range: float) -> np.ndarray:
    """Starts (k, 1, 3) m of a task's one cube with half edges ``half`` (k, 1) m: at x, y
    uniform in [-half_range, half_range] m (copy i's from ``rngs[i]``), resting on the table."""
    xy = np.array([rng.uniform(-half_range, half_range, size=2) for rng in rngs])
    return np.concatenate([xy, half[:, :1]], axis=1)[:, None]


def sample_apart(rng: np.random.Generator, half_range: float, others, min_distance: float,
                 tries: int = 1000) -> np.ndarray:
    """A point (2,) uniform in [-half_range, half_range]^2 (m) at least ``min_distance`` (m)
    from every point in ``others`` (each (2,) or more; x, y are used); rejection sampling
    from ``rng``."""
    for _ in range(tries):
        point = rng.uniform(-half_range, half_range, size=2)
        if all(np.linalg.norm(point - np.asarray(o)[:2]) >= min_distance for o in others):
            return point
    raise RuntimeError(f"sample_apart: no point {min_distance} m from {len(others)} others in "
                       f"{tries} tries; the ranges are too tight")
