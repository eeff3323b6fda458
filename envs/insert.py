"""Insert: put a peg into the hole of a fixture, with 3 mm of clearance a side."""

from __future__ import annotations

import functools

import numpy as np

from rigid_gym.recordable import Marker
from rigid_gym.shapes import Box, Compound, Pose

from .base import RigidGymEnv
from .gripper import EFFECTOR_CLASSES
from .task import (
    CUBE_HALF,
    GOAL_COLOR,
    MARKER_ALPHA,
    Task,
    closeness,
    sample_apart,
    staged,
)

PEG_HALF_EXTENTS = (0.015, 0.015, 0.05)
"""m: the peg, a square prism 3 x 3 cm across and 10 cm long, standing on an end."""
CLEARANCE = 0.003
"""m between the peg and each wall of the hole when centred (ManiSkill's PegInsertionSide's
clearance): the hole is 3.6 cm square."""
HOLE_HALF = PEG_HALF_EXTENTS[0] + CLEARANCE
"""m: half the hole's width."""
HOLE_DEPTH = 0.06
"""m: the fixture's height, and the hole's depth (it goes through to the table, its floor)."""
BLOCK_HALF = 0.05
"""m: half the fixture's outer width (a 10 cm square block)."""
OBJECT_RANGE = 0.15
"""m: the peg starts at x, y uniform in [-0.15, 0.15], standing."""
FIXTURE_RANGE = 0.15
"""m: the fixture's centre is at x, y uniform in [-0.15, 0.15] ..."""
FIXTURE_CLEARANCE = 0.11
"""m: ... and at least this far from the peg's start (the block's half diagonal, 0.071 m,
plus the peg's, 0.021 m, plus the pad's overhang and a little): the peg never starts on it."""
IN_HOLE = CLEARANCE + 0.001
"""m: the peg counts as in the hole when its axis is within this of the hole's along x and
along y: a centred peg may move by the clearance, plus 1 mm for the solver's contact slop.
A peg off by more overlaps a wall, so a peg forced down through the block beside the hole
never counts."""
INSERTED_HEIGHT = HOLE_DEPTH - PEG_HALF_EXTENTS[2]
"""m: the peg is in by at least half its length when its centre is at most this far above
the centre of a peg resting on the hole's floor: its centre at or below the block's top."""
ABOVE_HOLE = 0.005
"""m: the shaped reward's carry target holds the peg's bottom this far above the block."""


@functools.cache
def fixture_shape() -> Compound:
    """A 10 cm square block, HOLE_DEPTH high, with a square hole of half width HOLE_HALF
    through it: four boxes (two long walls along x, two short ones between them), so the hole
    is exactly their gap. Frame at the hole's centre, on the table. One shared (immutable)
    shape, so that a vector env's copies can share its geometry."""
    wall = (BLOCK_HALF - HOLE_HALF) / 2.0  # half thickness of each wall
    offset = HOLE_HALF + wall  # from the hole's centre to a wall's
    h = HOLE_DEPTH / 2.0
    long_walls = [(Box((BLOCK_HALF, wall, h)), Pose((0.0, sign * offset, h)))
                  for sign in (-1.0, 1.0)]
    short_walls = [(Box((wall, HOLE_HALF, h)), Pose((sign * offset, 0.0, h)))
                   for sign in (-1.0, 1.0)]
    return Compound(tuple(long_walls + short_walls))


class Insert(Task):
    """The peg stands anywhere in the range, the fixture away from it; reached when the peg is
    in the hole by at least half its length."""

    num_cubes = 1
    has_grip = True
    grasps = True
    goal_size = 3
    num_fixtures = 1

    def half_extents(self, half):
        return np.asarray(half, dtype=np.float64)[..., None] / CUBE_HALF * PEG_HALF_EXTENTS

    def place_cubes(self, rngs, half):
        xy = np.array([rng.uniform(-OBJECT_RANGE, OBJECT_RANGE, size=2) for rng in rngs])
        return np.concatenate([xy, self.half_extents(half[:, :1])[:, :, 2]], axis=1)[:, None]

    def place_fixtures(self, rngs, starts):
        places = np.zeros((len(rngs), 1, 3))
        for k, (rng, peg) in enumerate(zip(rngs, starts[:, 0])):
            places[k, 0, :2] = sample_apart(rng, FIXTURE_RANGE, [peg], FIXTURE_CLEARANCE)
        return places

    def add_fixtures(self, scene):
        return [scene.add_body(fixture_shape(), static=True, name="fixture")]

    def sample_goals(self, rngs, starts, half, places):
        # the centre of a peg resting on the hole's floor
        length = self.half_extents(half[:, :1])[:, 0, 2]
        return places[:, 0] + np.column_stack([np.zeros((len(half), 2)), length])

    def goal_reached(self, achieved_goal, desired_goal):
        error = achieved_goal - desired_goal
        return ((np.abs(error[..., 0]) <= IN_HOLE) & (np.abs(error[..., 1]) <= IN_HOLE)
                & (error[..., 2] <= INSERTED_HEIGHT))

    def markers(self, goal, half):
        return [Marker(Box(self.half_extents(half[:1])[0]), tuple(goal), GOAL_COLOR,
                       MARKER_ALPHA)]

    def shaped_reward(self, pad, held, achieved_goal, desired_goal, half):
        peg_half = self.half_extents(half[:, :1])[:, 0]
        grip = achieved_goal.copy()  # where the pad's (the hand's) centre takes the peg's top
        grip[:, 2] += peg_half[:, 2] + EFFECTOR_CLASSES[self.effector].top_grip
        above = desired_goal.copy()  # the peg over the hole, its bottom just above the block
        above[:, 2] += HOLE_DEPTH + ABOVE_HOLE
        error = np.abs(achieved_goal - desired_goal)
        lined_up = (error[:, 0] <= IN_HOLE) & (error[:, 1] <= IN_HOLE)
        carry = staged(closeness(pad - grip), (held == 0) | lined_up,
                       closeness(achieved_goal - above))
        return np.where(lined_up, 4.0 + closeness(achieved_goal - desired_goal), carry) / 5.0


class InsertEnv(RigidGymEnv):
    """Insert a 3 x 3 x 10 cm peg into the 3.6 cm square hole of a fixture: 3 mm of
    clearance a side.

    The fixture is a static nonconvex body, a 10 cm square block 6 cm high with the hole
    through it (a Compound of four boxes, ``fixture_shape``). The insertion is vertical: the
    suction pad holds a body by the face it presses on and never turns, so the peg starts
    standing on an end, the pad takes it by its top, carries it upright over the hole and
    lowers it in (ManiSkill's PegInsertionSide inserts sideways with a two-finger gripper,
    which turns the peg to the hole). In the observation, "cube 0" is the peg.

    The pad and what it holds are moved, not pushed (the arm is not simulated): a downward move
    stops where the peg's footprint overlaps the block's top by more than 1 mm (the arm's force
    limit, ``rigid_gym.envs.effector``), so a peg pressed down off the hole's axis rests on the
    block; a sideways move is not stopped, so a policy can drive the peg through the block's
    wall. The goal test counts a peg in the hole only when its axis is within the clearance
    (plus 1 mm) of the hole's, where it overlaps no wall.

    ## Action space
    ``Box(-1, 1, (4,), float32)``: the pad's displacement this step (x 0.05 m per unit along
    x, y, z: at most 1.25 m/s per axis) and the grip (> 0 close, <= 0 open). Values outside
    [-1, 1] are clipped; NaN or inf raise ``ValueError``. Workspace as PushEnv; a downward
    move stops where the pad, or the peg it holds, meets the table, the block's top or the
    peg.

    ## Observation space
    ``Dict`` of float32 vectors:

    | key | size | content |
    |---|---|---|
    | observation | {observation_size} | the fields below (``task.observation_layout``; cube 0 is the peg) |
    | achieved_goal | 3 | the peg's centre, m |
    | desired_goal | 3 | the centre of the peg resting on the hole's floor (the table), m |

    {observation_fields}

    ## Rewards
    The goal is reached when the peg is in the hole by at least half its length: its centre
    within 0.004 m (the clearance and 1 mm) of the goal along x and along y, and at most
    0.01 m above it (its bottom at least 5 cm, half its length, below the block's top; the
    hole is 6 cm deep). The test reads only the goals, so HER can recompute it. sparse: 0 when
    reached, else -1; dense: minus the distance, m. shaped (for on-policy learners; staged as
    ManiSkill's dense rewards), in [0, 1]: reach, 1 - tanh(5 d) of the pad's distance to the
    peg's top, until the pad holds the peg; then carry, 2 + (1 - tanh(5 d)) of the peg's
    distance to the point over the hole with its bottom 5 mm above the block; once the peg is
    lined up with the hole (within 0.004 m along x and y, held or not), insert,
    4 + (1 - tanh(5 d)) of its distance to the goal; divided by 5; 1 when reached.

    ## Starting state
    Peg standing at x, y uniform in [-0.15, 0.15] m, unrotated; the fixture's hole at x, y
    uniform in [-0.15, 0.15] m at least 0.11 m from the peg; pad at (0, 0, 0.12) m, open.

    ## Episode end
    Truncated after 50 steps (2 s) by ``gym.make``'s TimeLimit (``max_episode_steps=`` to
    change it); terminated on success only with ``terminate_on_success=True`` (default False).

    ## Arguments
    ``randomize`` may not include ``size``: the hole is made for the peg's size. The
    arguments every task takes:

    {arguments}
    """

    task = Insert()

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        if "size" in self.options.randomization:
            raise ValueError("InsertEnv: randomize cannot include 'size' (the hole is made for "
                             "the peg's size, with 3 mm of clearance); pass a dict of the other "
                             "ranges (mass, friction, restitution)")
