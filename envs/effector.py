"""The floating suction gripper every task is driven through.

The gripper is a kinematic body (a flat box, infinite mass): each env step the action sets its
velocity, and the solver moves it and lets it push whatever it meets. Two things are not
plain physics, and both stand for the robot arm that is not simulated:

* **Suction.** Closing the grip while the pad touches an object (a contact within
  ``GRIP_MARGIN``) attaches that object rigidly at its current offset (``World.attach``):
  while held it is put at that offset, with the gripper's velocity, before every solver step
  and after the last. Opening releases it with the gripper's velocity at that instant (the
  velocity of the step being started).
* **Force limit.** An arm stops when it presses a body into the table; a kinematic body would
  not (it would crush the body through the table, which no solver can resolve). So a downward
  move stops where the lowest point of the gripper (or of the object it holds) meets the top
  of a free object under its footprint, or the table.

Everything else (pushing, tipping, sliding, flight after release) is the solver's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigid_gym._core import lowest_centres
from rigid_gym.shapes import Box

STEP_DISTANCE = 0.05
"""m the gripper moves per env step along an axis at action 1 (panda-gym's and Fetch's scale)."""
PAD_HALF_EXTENTS = (0.02, 0.02, 0.015)
"""Half extents (m) of the gripper's pad."""
GRIP_MARGIN = 0.004
"""m: how close the pad must be to an object for suction to grip it."""


@dataclass(frozen=True)
class Workspace:
    """The box the gripper's centre stays in, m (world frame, z up; the table top is z = 0)."""

    low: tuple[float, float, float] = (-0.25, -0.25, PAD_HALF_EXTENTS[2])
    high: tuple[float, float, float] = (0.25, 0.25, 0.3)

    def clip(self, position: np.ndarray) -> np.ndarray:
        """position (..., 3) m, each axis clipped to [low, high] (without np.clip's
        argument checks, ~3x the cost on a 3-vector)."""
        return np.minimum(np.maximum(position, self.low), self.high)


class SuctionGripper:
    """Drives body ``body`` of a world (a kinematic Box of ``PAD_HALF_EXTENTS``).

    objects: indices of the dynamic bodies it may push and grip, each a Box; ``half_extents``
        (k, 3) m their sizes. ``step_time``: s per env step.
    """

    shape = Box(PAD_HALF_EXTENTS)

    def __init__(self, world, body: int, objects, half_extents, step_time: float,
                 workspace: Workspace = Workspace()):
        self.world = world
        self.body = body
        self.objects = list(objects)
        self.half_extents = np.asarray(half_extents, dtype=np.float64).reshape(-1, 3)
        self.step_time = step_time
        self.workspace = workspace
        self.held: int | None = None  # index into self.objects
        k = len(self.objects)
        # lowest_centres' work arrays: the pad and the held object, the objects
        self._work = (np.empty((2, 3)), np.empty((2, 3, 3)), np.empty((2, 3)), np.empty((k, 3)),
                      np.empty((k, 3, 3)))

    @property
    def position(self) -> np.ndarray:
        return self.world.position[self.body]

    @property
    def velocity(self) -> np.ndarray:
        return self.world.velocity[self.body]

    def command(self, motion: np.ndarray, grip: float | None) -> None:
        """Start an env step: ``motion`` (3,) in [-1, 1] scales ``STEP_DISTANCE``; ``grip`` > 0
        closes the suction, <= 0 opens it, None leaves it (tasks without a grip)."""
        target = self.workspace.clip(self.position + STEP_DISTANCE * motion)
        target[2] = max(target[2], min(self.position[2], self._lowest_centre(target)))
        velocity = (target - self.position) / self.step_time
        self.world.set_velocity(self.body, velocity=velocity)  # it never turns: omega stays 0
        self._grip(grip)

    # -- helpers -------------------------------------------------------------------------------

    def _grip(self, grip: float | None) -> None:
        """After the pad's velocity is set: ``grip`` > 0 closes the suction, <= 0 opens it,
        None leaves it."""
        if grip is not None and grip > 0.0 and self.held is None:
            self._try_grip()
        elif grip is not None and grip <= 0.0 and self.held is not None:
            self.world.detach(self.objects[self.held])  # leaves with the pad's new velocity
            self.held = None

    def _try_grip(self) -> None:
        contacts = self.world.contacts(margin=GRIP_MARGIN)
        for k, body in enumerate(self.objects):
            pair = ((contacts.body_a == body) & (contacts.body_b == self.body)) | (
                (contacts.body_a == self.body) & (contacts.body_b == body))
            if np.any(pair):
                self.world.attach(body, self.body)  # carried from now on (World.attach)
                self.held = k
                return

    def _lowest_centre(self, target: np.ndarray) -> float:
        """The lowest z the gripper's centre may take at ``target``'s x, y: where it, or the
        object it holds, would rest on the table or on the top of a free object under it
        (``src/footprint.h``; one world of ``_lowest_centres``)."""
        lowest = np.empty(1)
        _lowest_centres(self, target[None], self.world.position[None],
                        self.world.rotation[None], [self.held], lowest)
        return float(lowest[0])


def command_all(world, grippers: list[SuctionGripper], motions: np.ndarray,
                grips: np.ndarray | None) -> None:
    """``SuctionGripper.command`` for gripper i of world i of a batched ``world``, for all of
    them at once (the same arithmetic, so each world moves exactly as a single env's would):
    motions (B, 3) in [-1, 1], grips (B,) or None (tasks without a grip). The grippers drive
    the same body and boxes in every world (a vector env's copies), and share a workspace."""
    first = grippers[0]
    body = first.body
    s = world.state
    position = s.position[:, body]
    target = first.workspace.clip(position + STEP_DISTANCE * motions)
    lowest = np.empty(len(grippers))
    # without a grip command nothing is ever held: no need to ask every gripper
    held = None if grips is None else [g.held for g in grippers]
    _lowest_centres(first, target, s.position, s.rotation, held, lowest)
    target[:, 2] = np.maximum(target[:, 2], np.minimum(position[:, 2], lowest))
    s.velocity[:, body] = (target - position) / first.step_time  # it never turns
    if grips is not None:
        for gripper, grip in zip(grippers, grips):
            gripper._grip(grip)


def _lowest_centres(first: SuctionGripper, targets: np.ndarray, positions: np.ndarray,
                    rotations: np.ndarray, held: list | None, out: np.ndarray) -> None:
    """``SuctionGripper._lowest_centre`` of the gripper of world i at targets[i] (B, 3) m in
    world i of positions (B, n, 3) and rotations (B, n, 3, 3), into out (B,) m; every world's
    gripper drives the same body and objects as ``first``. held: each gripper's held object
    (an index into its objects, or None), or None when none holds anything
    (``src/footprint.h``)."""
    held = (np.full(len(out), -1, dtype=np.int64) if held is None else
            np.array([-1 if h is None else h for h in held], dtype=np.int64))
    lowest_centres(targets, positions, rotations, first.body, np.array(PAD_HALF_EXTENTS),
                   np.asarray(first.objects, dtype=np.int64), first.half_extents, held,
                   *first._work, out)
