"""Stack: build a two-cube tower at a target, the first cube on the table, the second on it."""

from __future__ import annotations

from rigid_gym.checks import in_range

from .base import RigidGymEnv
from .tower import Tower


class Stack(Tower):
    """Two cubes apart on the table; the target is a tower (cube 1 on cube 0) away from both;
    reached when both cubes are near their targets and placed as the targets are: the Tower of
    two (``envs/tower.py``), whose draws, goal test and rewards are Stack's."""

    def __init__(self, start_placed: float = 0.0):
        super().__init__(2, start_placed)


STACK = Stack()
"""The env id's Stack (no episode starts placed), shared (a Task holds no state)."""


def stack(start_placed: float) -> Stack:
    """The Stack whose episodes start with cube 0 placed with chance ``start_placed`` (in
    [0, 1]), else a ValueError that says so."""
    chance = in_range(start_placed, 0.0, 1.0, "StackEnv: start_placed")
    return STACK if chance == 0.0 else Stack(chance)


class StackEnv(RigidGymEnv):
    """Stack two 4 cm cubes into a tower at a target: cube 0 on the table, cube 1 on cube 0.

    The floating pad grips by suction (see ``rigid_gym.envs.effector``): close it on a cube to
    carry the cube, open it to let go.

    ## Action space
    ``Box(-1, 1, (4,), float32)``: the pad's displacement this step (x 0.05 m per unit along
    x, y, z: at most 1.25 m/s per axis) and the grip (> 0 close, <= 0 open). Values outside
    [-1, 1] are clipped; NaN or inf raise ``ValueError``. The pad's centre stays in x, y in
    [-0.25, 0.25] m, z in [0.015, 0.3] m, and a downward move stops where the pad, or the cube
    it holds, meets a cube or the table (the arm's force limit).

    ## Observation space
    ``Dict`` of float32 vectors:

    | key | size | content |
    |---|---|---|
    | observation | {observation_size} | the fields below (``task.observation_layout``) |
    | achieved_goal | 6 | cube 0 position, cube 1 position, m |
    | desired_goal | 6 | the targets: cube 0 on the table at the tower's x, y; cube 1 one edge above it |

    {observation_fields}

    ## Rewards
    The goal is reached when each cube is within 0.05 m of its target **and** the cubes are
    placed relative to each other as the targets are: cube 1's offset from cube 0 is within half
    an edge (0.02 m) of the targets' offset in x, y and within a quarter edge (0.01 m) in z. For
    the env's targets (a tower) that means cube 1 rests on cube 0. Both tests read only the
    goals, so HER can recompute them, also for goals relabelled from where the cubes lay.
    sparse: 0 when reached, else -1; dense: minus the distance between the 6-vectors, m.
    shaped (for on-policy learners; staged as ManiSkill's dense rewards), in [0, 1]: cube 0's
    stages until it is placed (let go of within 0.02 m of its place), then 4 + cube 1's. Cube
    0's place is its target; cube 1's is on cube 0 as cube 0 lies (its target's offset from
    cube 0's added to cube 0's position), as the goal test's pair test reads it. A cube's
    stages are reach, 1 - tanh(5 d) of the pad's distance to its top face's centre, until the
    pad holds it (or it lies placed but for the grip), then carry, 2 + the mean of
    1 - tanh(5 d) and 1 - tanh(20 d) of its distance d to its place; divided by 8; 1 when
    reached and the pad holds nothing. Placing cube 0 takes the reward from at most 3/8
    (holding it at its target) to at least 4/8; holding cube 1 on cube 0 pays at most 7/8,
    though the goal test is met. Episode returns of hand-written policies (seeds 0-39): the
    scripted stack 84.7; the same holding cube 1 2.5 cm above its target 71.9; carrying cube
    0 2.5 cm over its target and holding it 31.3.

    ## Starting state
    Cubes at x, y uniform in [-0.15, 0.15] m, at least 0.08 m apart, resting, unrotated; the
    tower at x, y uniform in [-0.15, 0.15] m at least 0.08 m from both; pad at (0, 0, 0.12) m,
    open.

    ## Episode end
    Truncated after 100 steps (4 s) by ``gym.make``'s TimeLimit (``max_episode_steps=`` to
    change it); terminated on success only with ``terminate_on_success=True`` (default False).

    ## Arguments
    ``start_placed`` (default 0, in [0, 1]): the chance that an episode's tower stands where
    cube 0 starts (cube 0 placed from the start, only cube 1 to be put on it): a curriculum
    for training (the env id's episodes, and every evaluation, use 0). And every task's:

    {arguments}
    """

    task = STACK

    def __init__(self, start_placed: float = 0.0, **kwargs):
        self.task = stack(start_placed)
        super().__init__(**kwargs)

    @classmethod
    def own_task(cls, kwargs):
        return stack(kwargs.pop("start_placed", 0.0))
