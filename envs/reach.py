"""Reach: move the pad's centre to a target point in the air or at the table."""

from __future__ import annotations

import numpy as np

from rigid_gym.recordable import Marker
from rigid_gym.shapes import Sphere

from .base import RigidGymEnv
from .task import DISTANCE_THRESHOLD, GOAL_COLOR, MARKER_ALPHA, Task, closeness, distance

GOAL_RANGE = 0.15
"""m: the target's x, y are uniform in [-0.15, 0.15] (panda-gym's and Fetch's range) ..."""
GOAL_HEIGHT = (0.0, 0.3)
"""m: ... and its z in [0, 0.3] (panda-gym's; the pad's centre reaches down to 0.015 m, so
the lowest targets are reached from 0.015 m above them, well within the threshold)."""


class Reach(Task):
    """No objects: the achieved goal is the pad's centre; reached within DISTANCE_THRESHOLD."""

    num_cubes = 0
    has_grip = False
    goal_size = 3

    @property
    def achieved_columns(self) -> np.ndarray:
        return self.observation_layout.entries(["pad.position"])

    def place_cubes(self, rngs, half):
        return np.zeros((len(rngs), 0, 3))

    def sample_goals(self, rngs, starts, half, places):
        low = [-GOAL_RANGE, -GOAL_RANGE, GOAL_HEIGHT[0]]
        high = [GOAL_RANGE, GOAL_RANGE, GOAL_HEIGHT[1]]
        return np.array([rng.uniform(low, high) for rng in rngs])

    def goal_reached(self, achieved_goal, desired_goal):
        return distance(achieved_goal - desired_goal) < DISTANCE_THRESHOLD

    def markers(self, goal, half):
        return [Marker(Sphere(DISTANCE_THRESHOLD), tuple(goal), GOAL_COLOR, MARKER_ALPHA)]

    def shaped_reward(self, pad, held, achieved_goal, desired_goal, half):
        # one stage: the pad nearing the target
        return closeness(achieved_goal - desired_goal)


class ReachEnv(RigidGymEnv):
    """Move a floating pad's centre to within 0.05 m of a target (panda-gym's and Fetch's Reach).

    No objects: the task is the effector's control alone, a first check of a learner.

    ## Action space
    ``Box(-1, 1, (3,), float32)``: the pad's displacement this step, x 0.05 m per unit along
    x, y, z (at most 1.25 m/s per axis). Values outside [-1, 1] are clipped; NaN or inf raise
    ``ValueError``. The pad's centre stays in x, y in [-0.25, 0.25] m, z in [0.015, 0.3] m.

    ## Observation space
    ``Dict`` of float32 vectors:

    | key | size | content |
    |---|---|---|
    | observation | {observation_size} | the fields below (``task.observation_layout``) |
    | achieved_goal | 3 | the pad's centre, m |
    | desired_goal | 3 | the target, m |

    {observation_fields}

    ## Rewards
    sparse (``reward_type="sparse"``, the default): 0 when the pad's centre is within 0.05 m
    of the target, else -1. dense: minus the distance, m. ``compute_reward`` takes batches.
    shaped, in [0, 1]: one stage, 1 - tanh(5 d) of the distance d to the target; 1 when
    reached.

    ## Starting state
    Pad at (0, 0, 0.12) m, at rest; target x, y uniform in [-0.15, 0.15] m, z in [0, 0.3] m
    (panda-gym's ranges; about 2% of targets lie within the threshold of the start).

    ## Episode end
    Truncated after 50 steps (2 s) by ``gym.make``'s TimeLimit; terminated on success only
    with ``terminate_on_success=True`` (default False). ``info["is_success"]``.

    ## Arguments
    {arguments}
    """

    task = Reach()
