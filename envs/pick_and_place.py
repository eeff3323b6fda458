"""PickAndPlace: carry a cube to a target that is in the air 70% of the time."""

from __future__ import annotations

import numpy as np

from rigid_gym.recordable import Marker
from rigid_gym.shapes import Box

from .base import RigidGymEnv
from .task import (
    DISTANCE_THRESHOLD,
    GOAL_COLOR,
    MARKER_ALPHA,
    Task,
    closeness,
    cube_anywhere,
    distance,
    sample_apart,
    staged,
)

OBJECT_RANGE = 0.15
"""m: the cube starts at x, y uniform in [-0.15, 0.15] (panda-gym's and Fetch's range)."""
GOAL_RANGE = 0.15
"""m: the target's x, y are uniform in [-0.15, 0.15] ..."""
GOAL_LIFT = 0.2
"""m: ... its height above a resting cube's uniform in [0, 0.2] (panda-gym's) ..."""
ON_TABLE = 0.3
"""... except with this probability, where it is on the table (panda-gym's 30%)."""


class PickAndPlace(Task):
    """The cube starts anywhere in the range; the target is at least a threshold away in x, y,
    on the table or in the air; reached within DISTANCE_THRESHOLD."""

    num_cubes = 1
    has_grip = True
    grasps = True
    goal_size = 3

    def place_cubes(self, rngs, half):
        return cube_anywhere(rngs, half, OBJECT_RANGE)

    def sample_goals(self, rngs, starts, half, places):
        goals = np.zeros((len(rngs), 3))
        for k, (rng, cube) in enumerate(zip(rngs, starts[:, 0])):
            goals[k, :2] = sample_apart(rng, GOAL_RANGE, [cube], DISTANCE_THRESHOLD)
            lift = rng.uniform(0.0, GOAL_LIFT)
            goals[k, 2] = half[k, 0] + (0.0 if rng.random() < ON_TABLE else lift)
        return goals

    def goal_reached(self, achieved_goal, desired_goal):
        return distance(achieved_goal - desired_goal) < DISTANCE_THRESHOLD

    def markers(self, goal, half):
        h = float(half[0])
        return [Marker(Box((h, h, h)), tuple(goal), GOAL_COLOR, MARKER_ALPHA)]

    def shaped_reward(self, pad, held, achieved_goal, desired_goal, half):
        return staged(closeness(pad - achieved_goal), held == 0,
                      closeness(achieved_goal - desired_goal)) / 3.0


class PickAndPlaceEnv(RigidGymEnv):
    """Pick a 4 cm cube up and bring it to a target, in the air or on the table (panda-gym's and
    Fetch's PickAndPlace).

    The floating pad grips by suction (see ``rigid_gym.envs.effector``): close it on the cube
    to carry it, open it to let go. A target in the air is reached by holding the cube there.

    ## Action space
    ``Box(-1, 1, (4,), float32)``: the pad's displacement this step (x 0.05 m per unit along
    x, y, z: at most 1.25 m/s per axis) and the grip (> 0 close, <= 0 open). Values outside
    [-1, 1] are clipped; NaN or inf raise ``ValueError``. The pad's centre stays in x, y in
    [-0.25, 0.25] m, z in [0.015, 0.3] m (a held cube's centre up to 0.265 m, above every
    target), and a downward move stops where the pad, or the cube it holds, meets the cube or
    the table (the arm's force limit).

    ## Observation space
    ``Dict`` of float32 vectors:

    | key | size | content |
    |---|---|---|
    | observation | {observation_size} | the fields below (``task.observation_layout``) |
    | achieved_goal | 3 | cube position, m |
    | desired_goal | 3 | target position, m |

    {observation_fields}

    ## Rewards
    sparse (``reward_type="sparse"``, the default): 0 when the cube's centre is within 0.05 m
    of the target, else -1. dense: minus the distance, m. ``compute_reward`` takes batches.
    shaped (for on-policy learners; staged as ManiSkill's dense rewards), in [0, 1]: reach,
    1 - tanh(5 d) of the pad's distance d to the cube, until the pad holds it; then carry,
    2 + (1 - tanh(5 d)) of the cube's distance d to the target; divided by 3; 1 when the goal
    is reached (holding is no reward of its own: the carry stage pays for the distance left).

    ## Starting state
    Cube at x, y uniform in [-0.15, 0.15] m, resting on the table, unrotated; target x, y
    uniform in [-0.15, 0.15] m at least 0.05 m from the cube's start, and with probability 0.3
    on the table (z = the cube's half edge), else z uniform in [0, 0.2] m above that
    (panda-gym's ranges); pad at (0, 0, 0.12) m, open.

    ## Episode end
    Truncated after 50 steps (2 s) by ``gym.make``'s TimeLimit; terminated on success only
    with ``terminate_on_success=True`` (default False). ``info["is_success"]``.

    ## Arguments
    {arguments}
    """

    task = PickAndPlace()
