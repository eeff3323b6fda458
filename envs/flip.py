"""Flip: turn a cube over on the table until it rests in a target orientation."""

from __future__ import annotations

import functools
import itertools

import numpy as np

from rigid_gym import quaternion
from rigid_gym.recordable import Marker
from rigid_gym.render import DYNAMIC_PALETTE
from rigid_gym.shapes import Box

from .base import RigidGymEnv
from .task import (
    CUBE_HALF,
    GOAL_COLOR,
    MARKER_ALPHA,
    Task,
    closeness,
    cube_anywhere,
    sparse_reward,
    staged,
)

ANGLE_THRESHOLD = 0.2
"""The goal is reached where the orientation distance 1 - <q, q*>^2 (``angle_distance``) is
below this: a turn of less than 2 asin(sqrt 0.2) = 53.1 deg from the target (panda-gym's)."""
OBJECT_RANGE = 0.1
"""m: the cube starts at x, y uniform in [-0.1, 0.1] (rolls move it 4-9 cm each: the
pad's 0.25 m reach leaves room for the three the farthest targets need)."""
TABLE_FRICTION = 2.0
"""The table's Coulomb coefficient (a rubber mat): with the cube's 0.5 the pair's is 1.0. A
cube of half edge a pushed at height h tips over its far edge before it slides when
mu > a / h; a pad whose bottom is 5 mm below the cube's top pushes at h = 0.0375 m
(a / h = 0.53), so the cube rolls over where a table of 0.5 (pair 0.5) lets it slide
(tests/test_tasks.py)."""
TILTED = np.deg2rad(5.0)
"""rad: a cube whose face nearest to up is tilted more than this is being rolled."""
MARKER_PLACE = (-0.2, 0.2, 0.06)
"""m: where rgb_array frames draw the target orientation (a ghost cube, the back left)."""
FACE_COLORS = ((0.84, 0.24, 0.22), (0.30, 0.66, 0.30), (0.92, 0.78, 0.25), (0.58, 0.42, 0.76),
               DYNAMIC_PALETTE[0], DYNAMIC_PALETTE[1])
"""The cube's faces in frames, towards its +x, -x, +y, -y, +z, -z: red, green, yellow,
purple, and the blue and orange of the other tasks' cubes on top and bottom at the start, so
that its orientation shows in pixels (as panda-gym's coloured cube's)."""
ROLLS = {"+x": ((0, 1, 0), 1.0), "-x": ((0, 1, 0), -1.0),
         "+y": ((1, 0, 0), -1.0), "-y": ((1, 0, 0), 1.0)}
"""Push direction -> (world axis, sign of the quarter turn about it): a cube pushed at its top
along +x rolls a quarter turn about +y (its top goes to +x), along +y one about -x."""
PUSH_DIRECTIONS = {"+x": (1.0, 0.0), "-x": (-1.0, 0.0), "+y": (0.0, 1.0), "-y": (0.0, -1.0)}


def quarter_turn(axis, sign: float) -> np.ndarray:
    """(3, 3) rotation by sign x 90 deg about the unit coordinate axis ``axis``."""
    k = int(np.argmax(axis))
    r = np.zeros((3, 3))
    i, j = (k + 1) % 3, (k + 2) % 3
    r[k, k] = 1.0
    r[j, i], r[i, j] = sign, -sign
    return r


@functools.cache
def cube_rotations() -> np.ndarray:
    """The 24 rotations (24, 3, 3) that map the cube onto itself (signed permutation matrices
    of determinant 1), the identity first."""
    found = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            r = np.zeros((3, 3))
            r[range(3), perm] = signs
            if np.linalg.det(r) > 0:
                found.append(r)
    found.sort(key=lambda r: -np.trace(r))
    return np.array(found)


@functools.cache
def roll_table() -> tuple[np.ndarray, np.ndarray]:
    """(after (24, 4) int: the rotation index a roll in each of ROLLS' directions leads to from
    each, rolls (24, 24) int: the fewest rolls from each rotation to each other)."""
    elements = cube_rotations()
    after = np.array([[nearest_rotation(quarter_turn(*ROLLS[d]) @ e) for d in ROLLS]
                      for e in elements])
    rolls = np.full((24, 24), -1)
    for start in range(24):
        rolls[start, start], frontier = 0, [start]
        while frontier:
            nxt = []
            for i in frontier:
                for j in after[i]:
                    if rolls[start, j] < 0:
                        rolls[start, j] = rolls[start, i] + 1
                        nxt.append(j)
            frontier = nxt
    return after, rolls


def nearest_rotation(r: np.ndarray) -> int:
    """The index of the cube rotation nearest to the rotation ``r`` (3, 3)."""
    return int(np.argmax(np.einsum("kij,ij->k", cube_rotations(), r)))


def angle_distance(q: np.ndarray, target: np.ndarray) -> np.ndarray:
    """1 - <q, target>^2 of unit quaternions (..., 4) -> (...) in [0, 1]: 0 for the same
    orientation (whatever the quaternions' signs), sin^2 of half the angle between them;
    elementwise over a batch (panda-gym's ``np.inner`` made an N x N matrix of N goals)."""
    inner = np.add.reduce(q * target, axis=-1)
    return 1.0 - inner * inner


def rotation_matrices(orientation: np.ndarray) -> np.ndarray:
    """(k, 6) orientation fields (the first two columns of each rotation matrix) -> (k, 3, 3)."""
    first, second = orientation[:, 0:3], orientation[:, 3:6]
    return np.stack([first, second, np.cross(first, second)], axis=-1)


def tilt(rotations: np.ndarray) -> np.ndarray:
    """(k, 3, 3) -> (k,) rad: the angle between world up and the cube's face nearest to up."""
    return np.arccos(np.clip(np.abs(rotations[:, 2, :]).max(axis=-1), -1.0, 1.0))


def resting_orientation(rng: np.random.Generator) -> np.ndarray:
    """A target (4,) unit quaternion (w, x, y, z), w >= 0: one of the five faces other than the
    start's top turned up (uniform), then a turn about up uniform in [0, 2 pi)."""
    faces = cube_rotations()[[i for i in range(24)
                              if cube_rotations()[i][2, 2] < 0.5]]  # top not up
    ups = {tuple(np.round(f[2])) for f in faces}  # the world z of each body axis: 5 kinds
    up = sorted(ups)[rng.integers(len(ups))]
    face = next(f for f in faces if tuple(np.round(f[2])) == up)
    yaw = rng.uniform(0.0, 2.0 * np.pi)
    spin = np.array([[np.cos(yaw), -np.sin(yaw), 0.0], [np.sin(yaw), np.cos(yaw), 0.0],
                     [0.0, 0.0, 1.0]])
    return quaternion.from_matrix(spin @ face)


class Flip(Task):
    """The cube starts unrotated anywhere in the range; the target is a resting orientation
    with another face up; reached where ``angle_distance`` < ANGLE_THRESHOLD."""

    num_cubes = 1
    has_grip = True
    goal_size = 4
    table_friction = TABLE_FRICTION
    markers_in_pixels = False
    object_faces = FACE_COLORS

    def achieved_goal(self, vectors, state, worlds, cubes):
        # the World's own quaternion of the cube (its principal frame is its shape frame), the
        # sign made w >= 0
        q = state.orientation[worlds, cubes[0]]
        return np.where(q[:, :1] < 0.0, -q, q)

    def place_cubes(self, rngs, half):
        return cube_anywhere(rngs, half, OBJECT_RANGE)

    def sample_goals(self, rngs, starts, half, places):
        return np.array([resting_orientation(rng) for rng in rngs])

    def goal_reached(self, achieved_goal, desired_goal):
        return angle_distance(achieved_goal, desired_goal) < ANGLE_THRESHOLD

    def reward(self, achieved_goal, desired_goal, reward_type):
        if reward_type == "dense":
            return -angle_distance(achieved_goal, desired_goal)
        return sparse_reward(self.goal_reached(achieved_goal, desired_goal))

    def markers(self, goal, half):
        h = float(half[0]) if len(half) else CUBE_HALF
        norm = np.linalg.norm(goal)
        orientation = tuple(goal / norm) if norm > 0 else (1.0, 0.0, 0.0, 0.0)
        return [Marker(Box((h, h, h)), MARKER_PLACE, GOAL_COLOR, MARKER_ALPHA, orientation,
                       FACE_COLORS)]

    def shaped(self, vectors, held, achieved_goal, desired_goal, half, released):
        layout = self.observation_layout
        pad = vectors[:, layout.slice("pad.position")]
        cube = vectors[:, layout.slice("cube0.position")]
        rotations = rotation_matrices(vectors[:, layout.slice("cube0.orientation")])
        rolls = roll_table()[1]
        left = np.array([rolls[nearest_rotation(r), nearest_target(g)]
                         for r, g in zip(rotations, desired_goal)])
        angle = tilt(rotations)
        stage = np.where(left > 0, staged(closeness(pad - cube), angle > TILTED,
                                          np.minimum(angle / (np.pi / 4), 1.0)) / 3.0, 0.0)
        most = rolls.max()
        return (most - left + stage) / (most + 1.0)


def nearest_target(goal: np.ndarray) -> int:
    """The index of the cube rotation nearest to the target quaternion ``goal`` (4,)."""
    return nearest_rotation(quaternion.to_matrix(goal / np.linalg.norm(goal)))


class FlipEnv(RigidGymEnv):
    """Roll a 4 cm cube over on the table until it rests in a target orientation (panda-gym's
    Flip, with targets a cube can rest in, and a batch-safe ``compute_reward``).

    The pad cannot turn, so the cube turns by being rolled: pushed at the top of a face it tips
    over its far edge (a quarter turn) on the table, a rubber mat of friction 2.0 (the pair's
    1.0; see ``TABLE_FRICTION``). The pad can also grip by suction, to carry the cube back.

    ## Action space
    ``Box(-1, 1, (4,), float32)``: the pad's displacement this step (x 0.05 m per unit along
    x, y, z: at most 1.25 m/s per axis) and the grip (> 0 close, <= 0 open). Values outside
    [-1, 1] are clipped; NaN or inf raise ``ValueError``. Workspace as PushEnv.

    ## Observation space
    ``Dict`` of float32 vectors:

    | key | size | content |
    |---|---|---|
    | observation | {observation_size} | the fields below (``task.observation_layout``) |
    | achieved_goal | 4 | the cube's orientation, unit quaternion (w, x, y, z), w >= 0 |
    | desired_goal | 4 | the target orientation, unit quaternion (w, x, y, z), w >= 0 |

    {observation_fields}

    ## Rewards
    The orientation distance of quaternions q, q* is d = 1 - <q, q*>^2 in [0, 1] (sin^2 of
    half the angle between them, blind to the quaternions' signs; ``angle_distance``, which
    takes batches: ``compute_reward`` of (B, 4) goals gives (B,)). The goal is reached where
    d < 0.2 (within 53.1 deg; panda-gym's threshold). sparse: 0 when reached, else -1; dense:
    -d. shaped (for on-policy learners), in [0, 1]: with r the fewest rolls from the cube's
    nearest resting orientation to the one nearest the target (``roll_table``, at most R = 4),
    (R - r + s) / (R + 1), s a roll's stages: reach, 1 - tanh(5 d) of the pad's distance to
    the cube, until the cube tilts (> 5 deg); then 2 + its tilt / 45 deg; divided by 3; s = 0
    once r = 0. A roll done lowers r: each pays once it is finished, not while it is under
    way; at most R / (R + 1) = 0.8 until the goal is reached, 1 there.

    ## Starting state
    Cube at x, y uniform in [-0.1, 0.1] m, resting, unrotated. Target: one of the five faces
    other than the top turned up (uniform), then turned about the vertical by an angle
    uniform in [0, 2 pi); every target is within 45 deg (d <= 0.146) of an orientation rolls
    reach. (panda-gym's targets are uniform over all rotations, some of them no resting
    cube's.) Pad at (0, 0, 0.12) m, open. Frames draw the cube's faces in six colours
    (``FACE_COLORS``: blue on top at the start, orange below), so that its orientation shows.
    In ``pixels`` no target is drawn (the copies of a batch share a marker's orientation);
    rgb_array frames draw it as a translucent cube of the same faces at the back left.

    ## Episode end
    Truncated after 50 steps (2 s) by ``gym.make``'s TimeLimit; terminated on success only
    with ``terminate_on_success=True`` (default False).

    ## Arguments
    {arguments}
    """

    task = Flip()
