"""The floating suction gripper every task is driven through by default, one per world of a
World, and what it shares with the two-finger gripper (``envs/gripper.py``): a kinematic body
moved by a displacement action, with the arm's force limit (``FloatingEffector``).

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
  of a free object under its footprint, the top of a static fixture's box part under it
  (Insert's block, Throw's bin), or the table. Sideways, nothing stops the pad: it and what
  it holds pass through a fixture they are driven into.

Everything else (pushing, tipping, sliding, flight after release) is the solver's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rigid_gym._core import Pads

from rigid_gym.shapes import Box, Compound, Pose

from .task import FRICTION, GRIPPER_START, SOLVER_SETTINGS

STEP_DISTANCE = 0.05
"""m the gripper moves per env step along an axis at action 1 (panda-gym's and Fetch's scale)."""
PAD_HALF_EXTENTS = (0.02, 0.02, 0.015)
"""Half extents (m) of the gripper's pad."""
GRIP_MARGIN = 0.004
"""m: how close the pad must be to an object for suction to grip it."""
REACH_SLACK = 1e-3
"""m added to the distance within which a grip is looked for, so that rounding never hides a
contact (``SuctionGripper.grip``)."""


@dataclass(frozen=True)
class Workspace:
    """The box the gripper's centre stays in, m (world frame, z up; the table top is z = 0)."""

    low: tuple[float, float, float] = (-0.25, -0.25, PAD_HALF_EXTENTS[2])
    high: tuple[float, float, float] = (0.25, 0.25, 0.3)


class FloatingEffector:
    """What the floating effectors share: a kinematic box (the pad, or a parallel gripper's
    hand) driven in every world of ``world`` (a World, batched or not: its ``state`` arrays
    have a leading world axis B) by a displacement each env step, with the arm's force limit
    (the module docstring), and the bodies that move with it (a gripper's fingers).

    bodies: the body indices ``add_to`` returned, the driven body first (``body``), then those
        that move with it (``carried``). objects: indices of the dynamic bodies it may push and
        take, each a Box; ``half_extents`` (k, 3) m their sizes (the same in every world).
        ``step_time``: s per env step. fixtures: (body index, shape, body_from_shape Pose) of
        each static body a downward move stops on (``fixture_boxes``: a Box or a Compound of
        Boxes).

    A subclass sets the class attributes ``body_half`` (m, the driven box's half extents),
    ``carried_half`` (m, each carried body's), ``workspace`` and ``start``, and implements
    ``add_to``, ``command``, ``grasp`` and ``forget``.
    """

    body_half: tuple = PAD_HALF_EXTENTS
    carried_half: tuple = (0.0, 0.0, 0.0)
    workspace = Workspace()
    start: tuple = GRIPPER_START
    """m: the driven body's centre at reset."""
    solver_settings: dict = SOLVER_SETTINGS
    """SolverConfig fields where a task driven by this effector differs from the library's
    defaults: the pad's tasks keep the v0 ids' dynamics (``SOLVER_SETTINGS``)."""
    top_grip: float = PAD_HALF_EXTENTS[2]
    """m from the top of an object taken by its top (Insert's peg) to the driven body's
    centre: the pad rests on it."""

    def __init__(self, world, bodies, objects, half_extents, step_time: float, fixtures=()):
        self.world = world
        self.body = int(bodies[0])
        self.carried = np.asarray(bodies[1:], dtype=np.int64)
        self.objects = np.asarray(objects, dtype=np.int64)
        self.half_extents = np.asarray(half_extents, dtype=np.float64).reshape(-1, 3)
        self.step_time = step_time
        self.num_worlds = world.num_worlds
        self.num_bodies = len(world.scene)
        self.fixed = fixture_boxes(fixtures)
        self.pads = self.made_pads()

    def made_pads(self) -> Pads:
        """The core's command object for these effectors: what every command passes to the
        core, fixed once (the driven box, the bodies carried with it, the boxes, the fixtures'
        box parts, the workspace), and the command's work rows."""
        fixed_bodies, fixed_offsets, fixed_rotations, fixed_halves = self.fixed
        return Pads(num_worlds=self.num_worlds, num_bodies=self.num_bodies, pad=self.body,
                    pad_half=self.body_half, objects=self.objects, halves=self.half_extents,
                    low=self.workspace.low, high=self.workspace.high,
                    fixed_bodies=fixed_bodies, fixed_offsets=fixed_offsets,
                    fixed_rotations=fixed_rotations, fixed_halves=fixed_halves,
                    carried=self.carried,
                    carried_halves=np.tile(self.carried_half, (len(self.carried), 1)),
                    step_distance=STEP_DISTANCE, step_time=self.step_time)

    def __getstate__(self) -> dict:
        """What pickle and copy.deepcopy keep: every field but the core's ``Pads``, which
        ``__setstate__`` makes again from them (it holds nothing between commands)."""
        state = self.__dict__.copy()
        del state["pads"]
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self.pads = self.made_pads()

    @property
    def position(self) -> np.ndarray:
        """The driven body's centre, m: (3,) for an unbatched World, (B, 3) for a batched
        one."""
        return self.world.position[..., self.body, :]

    @property
    def velocity(self) -> np.ndarray:
        """The driven body's velocity, m/s, shaped as ``position``."""
        return self.world.velocity[..., self.body, :]

    def move(self, motions: np.ndarray, held: np.ndarray,
             sweeps: np.ndarray | None = None) -> None:
        """Set the driven body's velocity in every world for this env step: ``motions``
        (B, 3) in [-1, 1] scale ``STEP_DISTANCE``, with the force limit for the held objects
        ``held`` (B,) int64 (indices into ``objects``, -1: none) and the carried bodies, each
        taken as the box it sweeps where ``sweeps`` (B, C, 3) m gives how far it moves
        relative to the driven body over the step. The velocity is written into the state as
        World.set_velocity would (the body never turns: omega stays 0), without its checks:
        the target is finite by construction."""
        s = self.world.state
        self.pads.command(np.ascontiguousarray(motions), s.position, s.rotation, s.velocity, held,
                          sweeps)

    @classmethod
    def add_to(cls, scene) -> list[int]:
        """Add the effector's bodies (and joints) to ``scene`` at ``start``; returns their
        indices, the driven body first."""
        raise NotImplementedError

    def command(self, motions: np.ndarray, grips: np.ndarray | None) -> None:
        """Start an env step in every world: ``motions`` (B, 3) in [-1, 1], and ``grips``
        (B,) in [-1, 1] (None: tasks without a grip)."""
        raise NotImplementedError

    def grasp(self, worlds) -> tuple[np.ndarray, np.ndarray | None]:
        """What ``worlds`` (an index array, or slice(None)) hold now: (k,) int64 the object
        each holds (an index into ``objects``), -1 for none; and (k,) m the opening between
        the fingers of an effector with fingers (observed as ``fingers.width``), else None."""
        raise NotImplementedError

    def forget(self, worlds) -> None:
        """``worlds`` (an index array, or slice(None)) were reset (their World's bodies are
        at the scene's start): nothing is held there any more."""
        raise NotImplementedError


class SuctionGripper(FloatingEffector):
    """The suction pad: drives body ``body`` (a kinematic Box of ``PAD_HALF_EXTENTS``) and
    grips by suction (the module docstring); ``FloatingEffector`` gives the arguments.

    ``held`` (B,) int64: the object each world's gripper holds (an index into ``objects``),
    -1 for none.
    """

    shape = Box(PAD_HALF_EXTENTS)

    def __init__(self, world, bodies, objects, half_extents, step_time: float, fixtures=()):
        super().__init__(world, bodies, objects, half_extents, step_time, fixtures)
        self.held = np.full(world.num_worlds, -1, dtype=np.int64)
        # a contact within GRIP_MARGIN needs the centres within the two bounding spheres
        reach = (np.linalg.norm(PAD_HALF_EXTENTS) + np.linalg.norm(self.half_extents, axis=1)
                 + GRIP_MARGIN + REACH_SLACK)
        self.reach_squared = reach * reach

    @classmethod
    def add_to(cls, scene) -> list[int]:
        return [scene.add_body(cls.shape, kinematic=True, position=cls.start, friction=FRICTION,
                               name="gripper")]

    def command(self, motions: np.ndarray, grips: np.ndarray | None) -> None:
        """Start an env step in every world: ``motions`` (B, 3) in [-1, 1] scale
        ``STEP_DISTANCE``; ``grips`` (B,): > 0 closes the suction, <= 0 opens it; None
        (tasks without a grip) leaves it open. An object gripped now is gripped before the
        move, whose force limit then counts it (taken up after the limit was set, as the pad
        moves off its top and down, it would be carried into the table and held there). One
        let go of is released after the move, with the pad's new velocity."""
        if grips is not None:
            self.close(grips)
        self.move(motions, self.held)
        if grips is not None:
            self.open(grips)

    def grasp(self, worlds) -> tuple[np.ndarray, None]:
        return self.held[worlds], None

    def close(self, grips: np.ndarray) -> None:
        """In the worlds where ``grips`` (B,) > 0 and nothing is held, attach the first object
        the pad touches (if any)."""
        closing = np.flatnonzero((grips > 0.0) & (self.held < 0))
        if closing.size:  # the contact query only where an object is within reach
            s = self.world.state
            offsets = s.position[closing][:, self.objects] - s.position[closing, self.body][:, None]
            near = np.einsum("wki,wki->wk", offsets, offsets) <= self.reach_squared
            for world in closing[near.any(axis=1)].tolist():
                self.attach_touching(world)

    def open(self, grips: np.ndarray) -> None:
        """After the pad's velocity is set: in the worlds where ``grips`` (B,) <= 0 and an
        object is held, release it (with the pad's new velocity)."""
        for world in np.flatnonzero((grips <= 0.0) & (self.held >= 0)).tolist():
            self.world.detach(int(self.objects[self.held[world]]), world=world)
            self.held[world] = -1

    def attach_touching(self, world: int) -> None:
        """In ``world``, attach the first object (in ``objects``' order) with a contact
        within GRIP_MARGIN of the pad, if there is one (carried from now on: World.attach)."""
        contacts = self.world.contacts(margin=GRIP_MARGIN, world=world)
        a, b = contacts.body_a, contacts.body_b
        for k, body in enumerate(self.objects.tolist()):
            if np.any(((a == body) & (b == self.body)) | ((a == self.body) & (b == body))):
                self.world.attach(body, self.body, world=world)
                self.held[world] = k
                return

    def forget(self, worlds) -> None:
        """Nothing is held any more in ``worlds`` (an index array, or slice(None)): their
        World was reset, which detaches every body."""
        self.held[worlds] = -1


def fixture_boxes(fixtures) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The box parts of static ``fixtures`` ((body index, shape, body_from_shape Pose) each;
    the shape a Box or a Compound of Boxes), as ``Pads`` takes them: the body of each
    part (F,) int64, its centre (F, 3) m and rotation (F, 3, 3) in the body's frame, its half
    extents (F, 3) m."""
    bodies, offsets, rotations, halves = [], [], [], []
    for body, shape, body_from_shape in fixtures:
        parts = shape.parts if isinstance(shape, Compound) else ((shape, Pose()),)
        for k, (part, pose) in enumerate(parts):
            if not isinstance(part, Box):
                raise ValueError(f"SuctionGripper: fixture body {body}'s part {k} is a "
                                 f"{type(part).__name__}; the gripper stops only on boxes")
            bodies.append(body)
            offsets.append(body_from_shape.apply(pose.position))
            rotations.append(body_from_shape.rotation() @ pose.rotation())
            halves.append(part.half_extents)
    return (np.array(bodies, dtype=np.int64), np.array(offsets).reshape(-1, 3),
            np.array(rotations).reshape(-1, 3, 3), np.array(halves).reshape(-1, 3))
