"""Throw: pick a cube up and throw it into a bin that the gripper cannot reach."""

from __future__ import annotations

import functools

import numpy as np

from rigid_gym.recordable import Marker
from rigid_gym.shapes import Box, Compound, Pose, Sphere

from .base import RigidGymEnv
from .task import GOAL_COLOR, MARKER_ALPHA, Task, closeness, cube_anywhere, staged

OBJECT_RANGE = 0.1
"""m: the cube starts at x, y uniform in [-0.1, 0.1]."""
BIN_X = (0.5, 0.65)
"""m: range of the bin centre's x (the gripper's centre stops at x = 0.25)."""
BIN_Y = (-0.15, 0.15)
"""m: range of the bin centre's y."""
BIN_INNER_HALF = 0.08
"""m: half the inside width of the (square) bin."""
BIN_WALL = (0.005, 0.04)
"""m: half thickness and half height of its walls (8 cm high; the table is its floor)."""
IN_BIN_HEIGHT = 0.05
"""m: the cube counts as in the bin up to this far above its resting height there."""
BIN_FRICTION = 0.5
THROW_SCALE = 2.0
"""1/m: the shaped reward's closeness of the cube to the bin, 1 - tanh(2 d): the bin is 0.25
to 0.65 m away, where tanh(5 d) has no slope left."""


@functools.cache
def bin_shape() -> Compound:
    """Four walls around a square of side 2 BIN_INNER_HALF; frame at the centre, on the table.
    One shared (immutable) shape, so that a vector env's copies can share its geometry."""
    t, h = BIN_WALL
    a = BIN_INNER_HALF + t
    parts = []
    for axis in (0, 1):
        for sign in (-1.0, 1.0):
            half = [a + t, a + t, h]
            half[axis] = t
            centre = [0.0, 0.0, h]
            centre[axis] = sign * a
            parts.append((Box(tuple(half)), Pose(centre)))
    return Compound(tuple(parts))


class Throw(Task):
    """The cube starts near the middle, the bin beyond the gripper's reach; reached when the
    cube lies in the bin."""

    num_cubes = 1
    has_grip = True
    grasps = True
    goal_size = 3
    num_fixtures = 1
    camera_view = ((0.2, -0.8, 0.8), (0.26, 0.0, 0.02), 42.0)

    def place_cubes(self, rngs, half):
        return cube_anywhere(rngs, half, OBJECT_RANGE)

    def place_fixtures(self, rngs, starts):
        places = np.zeros((len(rngs), 1, 3))
        for k, rng in enumerate(rngs):
            places[k, 0, 0] = rng.uniform(*BIN_X)
            places[k, 0, 1] = rng.uniform(*BIN_Y)
        return places

    def add_fixtures(self, scene):
        return [scene.add_body(bin_shape(), static=True, friction=BIN_FRICTION, name="bin")]

    def sample_goals(self, rngs, starts, half, places):
        # the bin's centre at the height of a cube resting in it
        return places[:, 0] + np.column_stack([np.zeros((len(half), 2)), half[:, 0]])

    def goal_reached(self, achieved_goal, desired_goal):
        error = np.abs(achieved_goal - desired_goal)
        return ((error[..., 0] <= BIN_INNER_HALF) & (error[..., 1] <= BIN_INNER_HALF)
                & (error[..., 2] <= IN_BIN_HEIGHT))

    def markers(self, goal, half):
        return [Marker(Sphere(0.015), tuple(goal), GOAL_COLOR, MARKER_ALPHA)]

    def shaped(self, vectors, held, achieved_goal, desired_goal, half, released):
        layout = self.observation_layout
        pad = vectors[:, layout.slice(f"{layout.effector}.position")]
        return self.shaped_reward(pad, held, achieved_goal, desired_goal, half, released)

    def shaped_reward(self, pad, held, achieved_goal, desired_goal, half, released=None):
        """Reach, carry, then thrown: ``released`` (k,) bool, whether the pad has let go of
        the cube this episode (``TaskBatch.released``; None: never). Carrying pays 2 + the
        cube's closeness to the bin, a thrown cube not held 4 + the same closeness, so
        letting go anywhere is worth more than any hold, and where the cube lands sets how
        much more; divided by 5."""
        thrown = (held < 0) & (False if released is None else released)
        toward = closeness(achieved_goal - desired_goal, THROW_SCALE)
        carry = staged(closeness(pad - achieved_goal), held == 0, toward)
        return np.where(thrown, 4.0 + toward, carry) / 5.0


class ThrowEnv(RigidGymEnv):
    """Throw a 4 cm cube into a bin placed beyond the gripper's reach.

    Pick the cube up by suction, swing, and open the grip: the cube leaves with the pad's
    velocity, flies, lands (restitution and friction decide the bounce and slide) and must
    stay inside the bin's walls.

    Reach: the pad moves at most 1.25 m/s per axis, so a cube released with v_x = 1.25 m/s
    and v_z = 0 / 0.625 / 1.25 m/s from a centre height z0 lands (centre back at 0.02 m)
    after these distances (x only; moving along x and y at once gives sqrt 2 times more):

    | release height z0 | v_z = 0 | v_z = 0.625 m/s | v_z = 1.25 m/s |
    |---|---|---|---|
    | 0.1 m | 0.16 m | 0.26 m | 0.39 m |
    | 0.2 m | 0.24 m | 0.33 m | 0.45 m |
    | 0.265 m (the highest carry) | 0.28 m | 0.37 m | 0.48 m |

    The pad's centre stops at x = 0.25 m, the bin's centre is 0.25 to 0.4 m beyond that
    (x in [0.5, 0.65], y in [-0.15, 0.15]), and its near wall starts at least 0.14 m beyond
    the farthest edge of the pad or of a cube held under it: every bin can be hit by a throw,
    none by placing.

    ## Action space
    ``Box(-1, 1, (4,), float32)``: the pad's displacement (x 0.05 m per unit per axis per
    step) and the grip (> 0 close, <= 0 open; opening releases with the pad's velocity).
    Outside [-1, 1] is clipped; NaN or inf raise ``ValueError``. Workspace as PushEnv.

    ## Observation space
    | key | size | content |
    |---|---|---|
    | observation | {observation_size} | the fields below (``task.observation_layout``) |
    | achieved_goal | 3 | cube position, m |
    | desired_goal | 3 | the bin's centre at the height of a cube resting in it, m |

    {observation_fields}

    ## Rewards
    The goal is reached when the cube is in the bin: its centre within 0.08 m (the bin's
    inside half width) of the goal in x and in y, and within 0.05 m in z. sparse: 0 when
    reached, else -1; dense: minus the distance, m. shaped (for on-policy learners; staged as
    ManiSkill's dense rewards), in [0, 1]: reach, 1 - tanh(5 d) of the pad's distance to the
    cube; carry, while the pad holds it, 2 + (1 - tanh(2 d)) of the cube's distance to the
    goal; thrown, once the pad has let go of it this episode and while it does not hold it,
    4 + the same closeness; divided by 5; 1 when in the bin. Any release is worth more than
    any hold (a hold pays at most 0.51 a step, at the edge of the reach; a thrown cube at
    least 0.8), and where the cube lands sets how much more. Episode returns of hand-written
    policies (seeds 0-39): the scripted throw 43.3, a throw at 0.8 times its speed (a miss)
    41.7, dropping the cube where it was picked up 30.0, carrying it to the edge of the reach
    and holding it there 22.6.

    ## Starting state
    Cube at x, y uniform in [-0.1, 0.1] m, resting; bin centre x in [0.5, 0.65] m, y in
    [-0.15, 0.15] m; pad at (0, 0, 0.12) m, open.

    ## Episode end
    Truncated after 50 steps (2 s); terminated on success only with
    ``terminate_on_success=True`` (default False: success is judged where the cube ends).

    ## Arguments
    {arguments}
    """

    task = Throw()
