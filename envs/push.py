"""Push: slide a cube across the table to a target; the gripper cannot grip."""

from __future__ import annotations

import functools

import numpy as np

from rigid_gym.meshes import prism_mesh
from rigid_gym.recordable import Marker

from .base import RigidGymEnv
from .effector import PAD_HALF_EXTENTS
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
"""m: the target is at x, y uniform in [-0.15, 0.15], on the table."""
PUSH_GAP = 0.005
"""m: the shaped reward's push point lies this far behind the cube's face."""
PUSHING = 0.03
"""m: the shaped reward counts the pad as pushing within this distance of the push point."""


class Push(Task):
    """The cube starts anywhere in the range, the target at least a threshold away on the
    table; reached within DISTANCE_THRESHOLD."""

    num_cubes = 1
    has_grip = False
    goal_size = 3

    def place_cubes(self, rngs, half):
        return cube_anywhere(rngs, half, OBJECT_RANGE)

    def sample_goals(self, rngs, starts, half, places):
        xy = np.array([sample_apart(rng, GOAL_RANGE, [cube], DISTANCE_THRESHOLD)
                       for rng, cube in zip(rngs, starts[:, 0])])
        return np.concatenate([xy, half[:, :1]], axis=1)

    def goal_reached(self, achieved_goal, desired_goal):
        return distance(achieved_goal - desired_goal) < DISTANCE_THRESHOLD

    def markers(self, goal, half):
        return [Marker(success_zone(), (goal[0], goal[1], 0.0), GOAL_COLOR, MARKER_ALPHA)]

    def shaped_reward(self, pad, held, achieved_goal, desired_goal, half):
        point = push_point(achieved_goal, desired_goal, half[:, 0])
        near = distance(pad - point)
        return staged(closeness(pad - point), near < PUSHING,
                      closeness(achieved_goal - desired_goal)) / 3.0


def push_point(cube: np.ndarray, target: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Where the pad's centre pushes the cube at ``cube`` (k, 3) m, of half edge ``half`` (k,)
    m, towards ``target`` (k, 3) m: behind the cube on the line from the target through it,
    the pad's half width and PUSH_GAP beyond its face, at the cube's height -> (k, 3) m."""
    away = cube[:, :2] - target[:, :2]
    length = np.maximum(distance(away), 1e-9)[:, None]
    point = cube.copy()
    point[:, :2] += away / length * (half + PAD_HALF_EXTENTS[0] + PUSH_GAP)[:, None]
    return point


class PushEnv(RigidGymEnv):
    """Push a 4 cm cube to a target on the table with a floating pad that cannot grip.

    Friction decides how the cube slides and turns; the pad is a kinematic box, so the cube
    only moves when the pad meets it.

    ## Action space
    ``Box(-1, 1, (3,), float32)``: the pad's displacement this step, x 0.05 m per unit along
    x, y, z (so at most 1.25 m/s per axis). Values outside [-1, 1] are clipped; NaN or inf
    raise ``ValueError``. The pad's centre stays in x, y in [-0.25, 0.25] m, z in
    [0.015, 0.3] m, and a downward move stops on the cube or the table (the arm's force limit,
    see ``rigid_gym.envs.effector``).

    ## Observation space
    ``Dict`` of float32 vectors:

    | key | size | content |
    |---|---|---|
    | observation | {observation_size} | the fields below (``task.observation_layout``) |
    | achieved_goal | 3 | cube position, m |
    | desired_goal | 3 | target position, m (z = the cube's half edge: on the table) |

    {observation_fields}

    ``observation_noise`` adds N(0, sigma^2) to every entry of ``observation`` (not to goals).

    ## Rewards
    sparse (``reward_type="sparse"``, the default): 0 when the cube's centre is within 0.05 m
    of the target, else -1. dense: minus the distance, m. ``compute_reward`` takes batches.
    shaped (for on-policy learners; staged as ManiSkill's dense rewards), in [0, 1]: reach,
    1 - tanh(5 d) of the pad's distance d to the push point (``push_point``: behind the cube,
    away from the target), until the pad is within 0.03 m of it; then push, 2 + (1 - tanh(5 d))
    of the cube's distance d to the target; divided by 3; 1 when the goal is reached.

    ## Starting state
    Cube at x, y uniform in [-0.15, 0.15] m, resting on the table, unrotated; target x, y in
    [-0.15, 0.15] m at least 0.05 m from the cube; pad at (0, 0, 0.12) m, at rest.

    ## Episode end
    Truncated after 50 steps (2 s) by ``gym.make``'s TimeLimit (``max_episode_steps=`` to
    change it). Terminated on success only with ``terminate_on_success=True`` (default False,
    as in Fetch: an agent learns to keep the cube at the target). ``info["is_success"]``.

    ## Arguments
    {arguments}
    """

    task = Push()


@functools.cache
def success_zone():
    """The goal marker: a thin disc (a 48-gon prism, 2 mm high) of the threshold's radius."""
    angles = np.linspace(0.0, 2.0 * np.pi, 48, endpoint=False)
    circle = DISTANCE_THRESHOLD * np.column_stack([np.cos(angles), np.sin(angles)])
    return prism_mesh(circle, 0.0005, 0.002)
