"""Tower: stack ``num_cubes`` cubes (2 to 5) into a tower at a target, in a given order."""

from __future__ import annotations

import numpy as np

from rigid_gym.checks import in_range, integer
from rigid_gym.recordable import Marker
from rigid_gym.render import DYNAMIC_PALETTE
from rigid_gym.shapes import Box

from .base import RigidGymEnv
from .task import (
    CUBE_HALF,
    DISTANCE_THRESHOLD,
    MARKER_ALPHA,
    Task,
    closeness,
    distance,
    sample_apart,
    staged,
)

OBJECT_RANGE = 0.15
"""m: each cube starts at x, y uniform in [-0.15, 0.15] (Stack's range)."""
CUBE_SPACING = 0.08
"""m: the cubes start at least this far apart (x, y), so none starts on another."""
TOWER_RANGE = 0.15
"""m: the tower's x, y are uniform in [-0.15, 0.15] ..."""
TOWER_CLEARANCE = 0.08
"""m: ... and at least this far from every cube's start."""
NUM_CUBES = 3
"""Cubes in a tower by default."""
CUBES_RANGE = (2, 5)
"""The allowed ``num_cubes``: 2 (Stack's tower) to 5 (a 20 cm tower of 4 cm cubes, within the
pad's reach with the top cube held under it)."""
PLACE_STAGE = 4.0
"""The shaped reward's worth (before its division by 4 n) of each cube placed (let go of at
its place) below the one being worked on: 1 more than carrying that cube to its target pays
(3), so that a cube is put down, not held."""
PLACED = CUBE_HALF
"""m: the shaped reward counts a cube as placed within 2 cm of its place (cube 0's target,
cube k's spot on cube k - 1), as the goal test's pair test places a cube on the one below:
with the goal test's 5 cm, a cube 0 let go of anywhere within 5 cm of its target would pay
in full, and a tower built on it there can miss the test."""
PLACE_SCALE = 20.0
"""1/m: the carry stage's sharp closeness, 1 - tanh(20 d), half of its worth (the other half
the stages' 1 - tanh(5 d)): it doubles the pay for the last 2 cm to a cube's place, where a
cube set on a cube must land within 1-2 cm."""
TALL_VIEW = ((0.45, -0.6, 0.55), (0.0, 0.0, 0.08), 40.0)
"""The rgb_array camera of towers of 4 and 5 (20 cm) cubes: the pixel observations' "front"
camera, wider than the default, which frames towers of up to 3 anywhere in the range."""


class Tower(Task):
    """``num_cubes`` cubes apart on the table; the target is a tower of them, cube 0 on the
    table and cube k on cube k - 1, away from them all; reached when every cube is near its
    target and each rests on the one below as the targets do."""

    has_grip = True
    grasps = True
    finished_by_letting_go = True

    def __init__(self, num_cubes: int = NUM_CUBES, start_placed: float = 0.0):
        self.num_cubes = num_cubes
        self.goal_size = 3 * num_cubes
        self.start_placed = start_placed
        """The chance that an episode's tower stands where cube 0 starts (cube 0 placed from
        the start: a curriculum for training, see TowerEnv); 0 for the env ids' episodes."""
        if num_cubes > 3:  # the default view cuts off a tower of 4 or 5 at the range's edge
            self.camera_view = TALL_VIEW

    def place_cubes(self, rngs, half):
        n = self.num_cubes
        starts = np.zeros((len(rngs), n, 3))
        for k, rng in enumerate(rngs):
            for j in range(n):
                starts[k, j, :2] = sample_apart(rng, OBJECT_RANGE, starts[k, :j], CUBE_SPACING)
        starts[:, :, 2] = half
        return starts

    def sample_goals(self, rngs, starts, half, places):
        # with start_placed > 0 a draw first decides whether the tower stands on cube 0's
        # start (the other cubes are CUBE_SPACING = TOWER_CLEARANCE from it); at 0 nothing is
        # drawn for it, so the env ids' episodes are unchanged
        xy = np.array([cubes[0, :2] if self.start_placed > 0.0
                       and rng.uniform() < self.start_placed
                       else sample_apart(rng, TOWER_RANGE, cubes, TOWER_CLEARANCE)
                       for rng, cubes in zip(rngs, starts)])
        # cube k's centre: the edges of the cubes below it, then its own half edge
        heights = np.cumsum(2.0 * half, axis=1) - half
        goals = np.empty((len(rngs), self.num_cubes, 3))
        goals[:, :, :2] = xy[:, None]
        goals[:, :, 2] = heights
        return goals.reshape(len(rngs), -1)

    def goal_reached(self, achieved_goal, desired_goal):
        shape = achieved_goal.shape[:-1] + (self.num_cubes, 3)
        achieved, desired = achieved_goal.reshape(shape), desired_goal.reshape(shape)
        near = (distance(achieved - desired) < DISTANCE_THRESHOLD).all(axis=-1)
        # every cube placed on the one below as the targets are (Stack's test, pair by pair):
        # the order is part of the goal (two cubes swapped are a quarter edge off in z at
        # least, by two edges), and goals that HER relabels from where the cubes ended up
        # (lying apart) stay reachable
        # (np.diff's subtraction, by slices: a step of a single env pays its overhead twice)
        mismatch = ((achieved[..., 1:, :] - achieved[..., :-1, :])
                    - (desired[..., 1:, :] - desired[..., :-1, :]))
        same_shape = ((distance(mismatch[..., :2]) < CUBE_HALF)
                      & (np.abs(mismatch[..., 2]) < 0.5 * CUBE_HALF)).all(axis=-1)
        return near & same_shape

    def markers(self, goal, half):
        # each target in its cube's colour
        return [Marker(Box((h, h, h)), tuple(goal[3 * k:3 * k + 3]),
                       DYNAMIC_PALETTE[k % len(DYNAMIC_PALETTE)], MARKER_ALPHA)
                for k, h in enumerate(half.tolist())]

    def shaped_reward(self, pad, held, achieved_goal, desired_goal, half):
        n = self.num_cubes
        cubes = achieved_goal.reshape(-1, n, 3)
        targets = desired_goal.reshape(-1, n, 3)
        # where each cube above cube 0 belongs: on the cube below as it lies, as the goal
        # test's pair test reads it (a carry toward the absolute target would set a cube
        # beside the one below wherever that one was put down up to 5 cm off its own)
        on_below = cubes[:, :-1] + (targets[:, 1:] - targets[:, :-1])
        aims = np.concatenate([targets[:, :1], on_below], axis=1)
        # there: within PLACED of its place and near its target (the goal test's threshold);
        # placed: there and let go of (a cube held there is still being carried)
        there = ((distance(cubes - aims) < PLACED)
                 & (distance(cubes - targets) < DISTANCE_THRESHOLD))  # (k, n)
        placed = there & (held[:, None] != np.arange(n))
        # the cube being worked on: the first not placed (the top one when all are)
        current = np.minimum(np.cumprod(placed, axis=1).sum(axis=1), n - 1)
        rows = np.arange(len(cubes))
        cube, aim = cubes[rows, current], aims[rows, current]
        top = cube.copy()
        top[:, 2] += half[rows, current]
        # its stages: reach its top face's centre (where a pad or a hand takes a cube to set
        # it on another: a reach for its centre would pay as much for a pad beside it at the
        # table, whose grip on a side face drags the cube along the table into the one it is
        # to go on), hold it (or it lies there), carry it, in [0, 3]; 4 per cube below it,
        # all placed: placing a cube pays more than carrying it there. The carry's closeness
        # adds a sharp term (1 - tanh(20 d)) to the stages' 1 - tanh(5 d), which gains
        # little over the last centimetres that a cube on a cube must be placed within
        carry = staged(closeness(pad - top), (held == current) | there[rows, current],
                       0.5 * (closeness(cube - aim) + closeness(cube - aim, PLACE_SCALE)))
        return (PLACE_STAGE * current + carry) / (PLACE_STAGE * n)


TOWERS = {n: Tower(n) for n in range(CUBES_RANGE[0], CUBES_RANGE[1] + 1)}
"""The Tower of each allowed size, shared (a Task holds no state)."""


def tower(num_cubes: int, start_placed: float = 0.0) -> Tower:
    """The Tower of ``num_cubes`` cubes (an int in CUBES_RANGE) whose episodes start with
    cube 0 placed with chance ``start_placed`` (in [0, 1]); a ValueError that says so for
    other values."""
    n = integer(num_cubes, "TowerEnv: num_cubes", *CUBES_RANGE)
    chance = in_range(start_placed, 0.0, 1.0, "TowerEnv: start_placed")
    return TOWERS[n] if chance == 0.0 else Tower(n, chance)


class TowerEnv(RigidGymEnv):
    """Stack ``num_cubes`` 4 cm cubes (default 3, 2 to 5) into a tower at a target, in order:
    cube 0 on the table, cube 1 on cube 0, and so on; left standing.

    The floating pad grips by suction (see ``rigid_gym.envs.effector``): close it on a cube to
    carry the cube, open it to let go. Stack is the tower of two.

    ## Action space
    ``Box(-1, 1, (4,), float32)``: the pad's displacement this step (x 0.05 m per unit along
    x, y, z: at most 1.25 m/s per axis) and the grip (> 0 close, <= 0 open). Values outside
    [-1, 1] are clipped; NaN or inf raise ``ValueError``. The pad's centre stays in x, y in
    [-0.25, 0.25] m, z in [0.015, 0.3] m, and a downward move stops where the pad, or the cube
    it holds, meets a cube or the table (the arm's force limit).

    ## Observation space
    ``Dict`` of float32 vectors (sizes for the default 3 cubes: the observation holds 7 +
    18 n entries, the goals 3 n):

    | key | size | content |
    |---|---|---|
    | observation | {observation_size} | the fields below (``task.observation_layout``) |
    | achieved_goal | 9 | the cubes' positions, cube 0 first, m |
    | desired_goal | 9 | their targets: cube 0 on the table at the tower's x, y; cube k one edge above cube k - 1 |

    {observation_fields}

    ## Rewards
    The goal is reached when each cube is within 0.05 m of its target **and** each cube is
    placed relative to the one below as the targets are: cube k's offset from cube k - 1 is
    within half an edge (0.02 m) of the targets' offset in x, y and within a quarter edge
    (0.01 m) in z. For the env's targets (a tower) that means every cube rests on the one
    below, in the order given: a tower in another order, or one that fell, is not reached. Both
    tests read only the goals, so HER can recompute them, also for goals relabelled from where
    the cubes lay. sparse: 0 when reached, else -1; dense: minus the distance between the
    3 n-vectors, m. shaped (for on-policy learners; staged as ManiSkill's dense rewards), in
    [0, 1]: 4 k + the stages of cube k, where cube k is the first cube not placed (within
    0.02 m of its place and 0.05 m of its target, and not held; the top cube when all are).
    Cube 0's place is its target, cube k's on cube k - 1 as that one lies. A cube's stages
    are reach, 1 - tanh(5 d) of the pad's distance to its top face's centre, until the pad
    holds it (or it lies placed but for the grip), then carry, 2 + the mean of 1 - tanh(5 d)
    and 1 - tanh(20 d) of its distance d to its place; divided by 4 n; 1 when reached and the
    pad holds nothing. Placing pays: letting a cube go at its place takes the reward from at
    most 3 to at least 4 (plus the next cube's reach), so holding a cube at its target is
    worth less than putting it down (the top cube held on the tower too: at most
    (4 n - 1) / 4 n, though the goal test is met), and a placed cube
    keeps paying after the pad lets go.

    ## Starting state
    Cubes at x, y uniform in [-0.15, 0.15] m, at least 0.08 m apart, resting, unrotated; the
    tower at x, y uniform in [-0.15, 0.15] m at least 0.08 m from every cube; pad at
    (0, 0, 0.12) m, open.

    ## Episode end
    Truncated after 150 steps (6 s: 50 per cube for the default 3) by ``gym.make``'s
    TimeLimit: pass ``max_episode_steps=50 * num_cubes`` for other sizes (the id's length is
    fixed). Terminated on success only with ``terminate_on_success=True`` (default False).

    ## Arguments
    ``num_cubes`` (default 3): the cubes in the tower, an int in [2, 5]. ``start_placed``
    (default 0, in [0, 1]): the chance that an episode's tower stands where cube 0 starts, so
    that only the cubes above it are to be moved: a curriculum for training (the env ids'
    episodes, and every evaluation, use 0). And every task's:

    {arguments}
    """

    task = tower(NUM_CUBES)

    def __init__(self, num_cubes: int = NUM_CUBES, start_placed: float = 0.0, **kwargs):
        self.task = tower(num_cubes, start_placed)
        super().__init__(**kwargs)

    @classmethod
    def own_task(cls, kwargs):
        return tower(kwargs.pop("num_cubes", NUM_CUBES), kwargs.pop("start_placed", 0.0))
