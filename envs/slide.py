"""Slide: strike a low-friction puck so that it slides to a target beyond the pad's reach."""

from __future__ import annotations

import functools

import numpy as np

from rigid_gym.meshes import prism_mesh

from .base import RigidGymEnv
from .effector import PAD_HALF_EXTENTS, Workspace
from .push import PUSHING, Push, push_point
from .task import closeness, distance, staged

PUCK_FRICTION = 0.04
"""Coulomb coefficient of the puck and of the table (panda-gym's puck: 0.04): the pair's is
sqrt(0.04 x 0.04) = 0.04, so a puck at v m/s slides v^2 / (2 x 0.04 x 9.81) m (0.32 m at
0.5 m/s)."""
PUCK_RADIUS = 1.5
"""The puck's radius in units of its half height (the task's ``half``, 0.02 m): 0.03 m, as
panda-gym's; it is 0.04 m high (panda-gym's 0.03 m)."""
PUCK_SIDES = 24
"""Sides of the prism that stands for the cylinder."""
GOAL_X = (0.35, 0.55)
"""m: the target's x range: panda-gym's [0.25, 0.55] less the part that a push reaches ..."""
GOAL_Y = (-0.15, 0.15)
"""m: ... and its y range (panda-gym's)."""
SLIDING = 0.02
"""m/s: the shaped reward counts a puck faster than this as struck (sliding)."""
PAD_REACH_X = Workspace().high[0] + PAD_HALF_EXTENTS[0]
"""m: the farthest x of the pad's face (0.27): a puck pushed there has its centre at 0.30 m, a
threshold short of the nearest target, so every target needs a slide."""


@functools.cache
def puck_shape(half: float):
    """The puck of half height ``half`` m: a PUCK_SIDES-gon prism of radius PUCK_RADIUS x half
    (the polygon's corners on the circle), its frame at its centre. One shared (immutable) shape
    per size, so that a vector env's copies share its geometry."""
    angles = np.linspace(0.0, 2.0 * np.pi, PUCK_SIDES, endpoint=False)
    circle = PUCK_RADIUS * half * np.column_stack([np.cos(angles), np.sin(angles)])
    return prism_mesh(circle, -half, half)


class Slide(Push):
    """Push's start, goal test and marker (the puck anywhere in x, y [-0.15, 0.15], panda-gym's
    range; reached within DISTANCE_THRESHOLD), with the target beyond the pad's reach."""

    object_friction = PUCK_FRICTION
    table_friction = PUCK_FRICTION
    camera_view = ((0.1, -0.75, 0.6), (0.2, 0.0, 0.02), 40.0)

    def half_extents(self, half):
        half = np.asarray(half, dtype=np.float64)[..., None]
        return np.concatenate([PUCK_RADIUS * half, PUCK_RADIUS * half, half], axis=-1)

    def object_shape(self, extents):
        return puck_shape(extents[2])

    def sample_goals(self, rngs, starts, half, places):
        low, high = [GOAL_X[0], GOAL_Y[0]], [GOAL_X[1], GOAL_Y[1]]
        xy = np.array([rng.uniform(low, high) for rng in rngs])
        return np.concatenate([xy, half[:, :1]], axis=1)

    def shaped(self, vectors, held, achieved_goal, desired_goal, half, released):
        layout = self.observation_layout
        sliding = distance(vectors[:, layout.slice("cube0.velocity")]) > SLIDING
        return self.stages(vectors[:, layout.slice("pad.position")], sliding, achieved_goal,
                           desired_goal, half)

    def shaped_reward(self, pad, held, achieved_goal, desired_goal, half):
        """The stages of a puck at rest (``shaped`` reads whether it slides)."""
        return self.stages(pad, np.zeros(len(pad), dtype=bool), achieved_goal, desired_goal,
                           half)

    def stages(self, pad, sliding, achieved_goal, desired_goal, half):
        """The shaped reward (k,) of copies whose pad is at ``pad`` (k, 3) m and whose puck
        slides where ``sliding`` (k,) bool: reach the push point, then (the pad at it, the
        puck sliding, or the puck beyond the pad's reach) the puck's closeness to the target."""
        radius = PUCK_RADIUS * half[:, 0]
        point = push_point(achieved_goal, desired_goal, radius)
        struck = sliding | (achieved_goal[:, 0] > PAD_REACH_X + radius)
        return staged(closeness(pad - point), (distance(pad - point) < PUSHING) | struck,
                      closeness(achieved_goal - desired_goal)) / 3.0


class SlideEnv(RigidGymEnv):
    """Strike a puck on a low-friction table so that it slides to a target the pad cannot
    reach (panda-gym's and Fetch's Slide).

    The puck (a 24-sided prism of radius 0.03 m, 0.04 m high, 0.1 kg) and the table have
    friction 0.04: struck at v, the puck slides v^2 / (2 x 0.04 x 9.81) m. The pad cannot grip;
    it can push the puck's centre no farther than x = 0.30 m, and every target lies at
    x >= 0.35 m: the puck must be let go at the right speed, in the right direction.

    ## Action space
    ``Box(-1, 1, (3,), float32)``: the pad's displacement this step, x 0.05 m per unit along
    x, y, z (at most 1.25 m/s per axis). Values outside [-1, 1] are clipped; NaN or inf raise
    ``ValueError``. The pad's centre stays in x, y in [-0.25, 0.25] m, z in [0.015, 0.3] m,
    and a downward move stops on the puck or the table (the arm's force limit).

    ## Observation space
    ``Dict`` of float32 vectors (the puck's fields are named ``cube0``):

    | key | size | content |
    |---|---|---|
    | observation | {observation_size} | the fields below (``task.observation_layout``) |
    | achieved_goal | 3 | puck position, m |
    | desired_goal | 3 | target position, m (z = the puck's half height: on the table) |

    {observation_fields}

    ## Rewards
    sparse (``reward_type="sparse"``, the default): 0 when the puck's centre is within 0.05 m
    of the target, else -1. dense: minus the distance, m. ``compute_reward`` takes batches.
    shaped (for on-policy learners; staged as ManiSkill's dense rewards), in [0, 1]: reach,
    1 - tanh(5 d) of the pad's distance d to the push point (behind the puck, away from the
    target), until the pad is within 0.03 m of it, or the puck slides (faster than 0.02 m/s),
    or it lies past the pad's reach (x > 0.30 m); then 2 + (1 - tanh(5 d)) of the puck's
    distance d to the target; divided by 3; 1 when the goal is reached.

    ## Starting state
    Puck at x, y uniform in [-0.15, 0.15] m, resting on the table; target x uniform in
    [0.35, 0.55] m, y in [-0.15, 0.15] m (panda-gym's x range is [0.25, 0.55]: its part that a
    push reaches is left out); pad at (0, 0, 0.12) m, at rest.

    ## Episode end
    Truncated after 50 steps (2 s) by ``gym.make``'s TimeLimit; terminated on success only
    with ``terminate_on_success=True`` (default False: the puck must stop at the target).

    ## Arguments
    {arguments}
    """

    task = Slide()
