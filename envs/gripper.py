"""The floating two-finger parallel gripper (``effector="gripper"``), sized after Franka
Panda's hand: one per world of a World, holding by friction alone.

    env = gym.make("rigid_gym/PickAndPlace-v0", effector="gripper")

* **The hand** is a kinematic box driven exactly as the suction pad is (``envs/effector.py``:
  the first three action entries move it by up to ``STEP_DISTANCE`` per axis per env step,
  within ``GRIPPER_WORKSPACE``; it never turns) with the arm's force limit: a downward move
  stops where the hand, a finger (taken as the box it sweeps as it closes or opens in the
  step) or the cube held between the fingers would rest on the table, on a cube or on a
  fixture's box part under its footprint. Sideways nothing stops it.
* **The fingers** are two dynamic boxes on prismatic joints to the hand, sliding along the
  world's y axis, each driven by a joint motor of at most ``GRIP_FORCE`` (Panda's 70 N
  continuous force): the opening between the pads runs from 0 to ``MAX_OPENING`` (8 cm, as
  Panda's), and the pads (``FINGER_HALF_EXTENTS``: 2 cm wide, 5 cm long) take a 4 cm cube
  over most of a face.
* **The finger command** (the fourth action entry, a in [-1, 1]) is a velocity target of
  the opening: each motor drives its finger at a * ``FINGER_SPEED`` / 2 m/s outward, with at
  most ``GRIP_FORCE``; a > 0 opens, a < 0 closes (panda-gym's and Fetch's sign). It is
  panda-gym's convention in effect: panda-gym sets the target opening to the current opening
  plus 0.2 a each step, a target that moves with the fingers, so a rate; here the rate is
  the joint motor's own input (a velocity motor with a force limit), which needs no position
  gains. The solver's velocity motor presses a finger that what it closes on stops every
  step with the force that would bring it to its target speed within a solver step (its mass
  times the speed over dt: 5 N at the closing speed), so where both pads are on a cube
  (``grasp``) and the command closes, the motors are driven at ``press_speed`` instead,
  the speed at which that force is ``GRIP_FORCE`` (as a real gripper's grasp closes at a
  speed until contact, then holds a force). So closing on a cube at any a < 0 presses it
  with 70 N from the env step after the pads meet it. At a = 0 the motors hold the opening
  but no longer press: a held cube needs a < 0 for as long as it is to be held.
* **Each finger has its own motor.** Two force-limited motors pressing a cube from both
  sides leave the three free to slide together along y but for the motors' difference:
  when the hand's velocity along y jumps, the cube and the fingers lag and are brought back
  by the motor that is not saturated (about a centimetre at a jump of 1.25 m/s; see
  ``FINGER_MASS``). Panda's fingers share one spindle drive, which holds them together.
* **No weld.** A cube is carried only by the friction between it and the pads: it stays
  while its weight and the hand's accelerations need less than 2 mu ``GRIP_FORCE`` (mu the
  pair's Coulomb coefficient) and slips otherwise. ``grasp`` reports the cube lying
  between the pads with both touching it (the observation's ``holding`` flag).

Observations gain the opening (``fingers.width``, m) after the holding flag, as panda-gym's
hold the fingers' width; the hand's fields are named ``hand.position``, ``hand.velocity``.
"""

from __future__ import annotations

import numpy as np

from rigid_gym.shapes import Box

from .effector import FloatingEffector, SuctionGripper, Workspace
from .task import FRICTION

HAND_HALF_EXTENTS = (0.02, 0.055, 0.02)
"""m: the hand's box (4 x 11 x 4 cm), wide enough along y to carry the fingers at full
opening."""
FINGER_HALF_EXTENTS = (0.01, 0.006, 0.025)
"""m: each finger's box (2 cm wide along x, 1.2 cm thick along y, 5 cm long), hanging from
the hand's bottom."""
FINGER_MASS = 0.08
"""kg: each finger's mass. Panda's finger is about 15 g; the finger here carries its share
of the drive as well, because the fingers' common motion along y (both sliding the same
way, the cube between them) is held only by the difference between the two motors' pushes,
and a velocity motor pushes by at most its finger's mass times the speed it is short of,
per solver step: at 80 g a jump of the hand's velocity of 1.25 m/s along y lets a held cube
lag about 1 cm along the fingers (the scripted policies carry it); at 15 g the hand moves
off and leaves the cube behind."""
FINGER_FRICTION = FRICTION
"""Coulomb coefficient of the fingers' pads (with a cube of 0.5 the pair's is 0.5)."""
MAX_OPENING = 0.08
"""m: the widest opening between the pads (Panda's 8 cm); the narrowest is 0."""
GRIP_FORCE = 70.0
"""N: each finger motor's maximum force (Panda's continuous grip force)."""
FINGER_SPEED = 0.5
"""m/s: the opening's rate at finger command 1 (2 cm per env step; a full close in 4)."""
FINGER_DROP = HAND_HALF_EXTENTS[2] + 2.0 * FINGER_HALF_EXTENTS[2]
"""m from the hand's centre down to the fingers' tips."""
GRIPPER_START = (0.0, 0.0, 0.15)
"""m: the hand's centre at reset (the fingers' tips 8 cm above the table, open)."""
GRIPPER_WORKSPACE = Workspace(low=(-0.25, -0.25, FINGER_DROP), high=(0.25, 0.25, 0.32))
"""The box the hand's centre stays in: the pad's x, y; z from the fingers' tips on the table
up to where a cube held near its bottom is as high as the pad can carry one."""
HOLD_MARGIN = 0.002
"""m: a cube counts as held while both pads are within this of its faces."""
TOP_GRASP = 0.03
"""m of an object's top that the fingers take when it is taken by its top (Insert's peg)."""


class ParallelGripper(FloatingEffector):
    """Drives the hand ``body`` (a kinematic Box of ``HAND_HALF_EXTENTS``) and its two fingers
    ``fingers`` (the carried bodies: the one towards -y, then the one towards +y) in every
    world of ``world``; ``FloatingEffector`` gives the arguments, the module docstring the
    behaviour. ``joints``: the fingers' prismatic joints, in the fingers' order (each one's
    coordinate is its finger's travel inward from the full opening, m)."""

    body_half = HAND_HALF_EXTENTS
    carried_half = FINGER_HALF_EXTENTS
    workspace = GRIPPER_WORKSPACE
    start = GRIPPER_START
    solver_settings: dict = {}  # noqa: RUF012 (read, never mutated)
    """The library's defaults: the v0 settings (``SOLVER_SETTINGS``) resolve a pair's touching
    points by one impulse, which gives a cube squeezed between the pads a lift of about 1%
    of the squeeze with no friction at all, and let a held cube creep down; contact patches
    (the default) hold it still and let a frictionless one drop. The gripper has no published
    results to keep."""
    top_grip = FINGER_DROP - TOP_GRASP
    """m from the top of an object the fingers take by its top to the hand's centre."""

    def __init__(self, world, bodies, objects, half_extents, step_time: float, fixtures=()):
        super().__init__(world, bodies, objects, half_extents, step_time, fixtures)
        self.fingers = self.carried
        self.joints = np.array([next(j.index for j in world.scene.joints if j.body_a == finger)
                                for finger in self.fingers.tolist()], dtype=np.int64)
        self.first_joint = int(self.joints[0])
        self.all_worlds = np.arange(self.num_worlds, dtype=np.int64)
        self.motor_speeds = world.core.joint_motor_speed
        """(B, J) m/s: the core's motor targets, written in place (``command``)."""
        self.idle = np.zeros(self.num_worlds)
        """(B,) m/s: the closing speed of a task without a finger command (none)."""
        self.sweeps = np.zeros((self.num_worlds, 2, 3))
        """(B, 2, 3) m: each finger's sweep over the env step (``command``'s work array; only
        [:, :, 1] is written, the rest stays 0)."""
        self.press_speed = GRIP_FORCE * world.dt / FINGER_MASS
        """m/s: the motors' target while the pads press a cube: the speed GRIP_FORCE gives a
        finger in a solver step, so that a finger the cube stops is pressed with it."""

    @classmethod
    def add_to(cls, scene) -> list[int]:
        """Add the hand, at ``start``, and the fingers, open, each on a prismatic joint along
        y whose motor is limited to GRIP_FORCE and whose travel inward is [0, MAX_OPENING / 2]
        m; returns [hand, finger -y, finger +y]."""
        hand = scene.add_body(Box(HAND_HALF_EXTENTS), kinematic=True, position=cls.start,
                              friction=FRICTION, name="hand")
        bodies = [hand]
        x, y, z = cls.start
        finger_z = z - HAND_HALF_EXTENTS[2] - FINGER_HALF_EXTENTS[2]
        for k, side in enumerate((-1.0, 1.0)):
            centre = (x, y + side * (0.5 * MAX_OPENING + FINGER_HALF_EXTENTS[1]), finger_z)
            finger = scene.add_body(Box(FINGER_HALF_EXTENTS), mass=FINGER_MASS, position=centre,
                                    friction=FINGER_FRICTION, name=f"finger{k}")
            scene.add_prismatic_joint(finger, hand, centre, (0.0, -side, 0.0),
                                      limits=(0.0, 0.5 * MAX_OPENING),
                                      max_motor_force=GRIP_FORCE, name=f"finger{k}_slide")
            bodies.append(finger)
        return bodies

    def command(self, motions: np.ndarray, grips: np.ndarray | None) -> None:
        """Start an env step in every world: ``motions`` (B, 3) in [-1, 1] scale
        ``STEP_DISTANCE``; ``grips`` (B,) in [-1, 1] the finger commands (the opening's rate
        over ``FINGER_SPEED``: > 0 opens, < 0 closes)."""
        held, width = self.grasp(slice(None))
        closing = self.idle if grips is None else -0.5 * FINGER_SPEED * grips
        pressing = closing > 0.0
        pressing &= held >= 0
        # the force limit takes each finger as the box it sweeps this step: its travel inward
        # (outward where < 0) within what is left of it, none while it presses. The bounds
        # are np.clip's, applied in place: this method is a large share of an env step, and
        # numpy's calls on arrays of one world cost more than their arithmetic
        travel = closing * self.step_time
        np.maximum(travel, -0.5 * (MAX_OPENING - width), out=travel)
        np.minimum(travel, 0.5 * width, out=travel)
        travel[pressing] = 0.0
        sweeps = self.sweeps
        sweeps[:, 0, 1] = travel
        sweeps[:, 1, 1] = -travel
        self.move(motions, held, sweeps)
        speeds = closing.copy()
        speeds[pressing] = self.press_speed
        # the motors' targets written as World.set_joint_motor would, without its checks (the
        # commands are finite and clipped); a world whose targets change is woken, as that
        # call wakes it: sleeping cannot see a motor's target
        targets = self.motor_speeds
        changed = targets[:, self.first_joint] != speeds
        if np.count_nonzero(changed):
            targets[:, self.joints] = speeds[:, None]
            for world in np.flatnonzero(changed).tolist():
                self.world.core.forget(world, world + 1)

    def grasp(self, worlds) -> tuple[np.ndarray, np.ndarray]:
        """(held (k,) int64, width (k,) m) of ``worlds`` (an index array, or slice(None)):
        the cube each holds now (an index into ``objects``; the first if several; -1 for
        none) and the opening between the pads. A cube is held where both pads lie within
        HOLD_MARGIN of its faces along y (its bounding box's, whatever its turn) and overlap
        it by more than HOLD_MARGIN along x and z (``rigid_gym._core.Pads.grasps``): a test of
        the poses, which says nothing about whether friction will keep it there."""
        rows = self.all_worlds[worlds]
        held = np.empty(len(rows), dtype=np.int64)
        width = np.empty(len(rows))
        s = self.world.state
        self.pads.grasps(s.position, s.rotation, rows, HOLD_MARGIN, held, width)
        return held, width

    @property
    def held(self) -> np.ndarray:
        """(B,) int64: the cube each world's gripper holds now (``grasp``), -1 for none."""
        return self.grasp(slice(None))[0]

    def forget(self, worlds) -> None:
        """``worlds`` were reset (the fingers are open again, at the scene's start): their
        motors' targets go back to 0 (holding the opening)."""
        for joint in self.joints.tolist():
            self.motor_speeds[worlds, joint] = 0.0

    def __getstate__(self) -> dict:
        """As ``FloatingEffector``'s, without the view of the motor targets (the World's core
        holds them)."""
        state = super().__getstate__()
        del state["motor_speeds"]
        return state

    def __setstate__(self, state: dict) -> None:
        """As ``FloatingEffector``'s, and the motor targets' view is taken from the World
        copied with it (whose core is new)."""
        super().__setstate__(state)
        self.motor_speeds = self.world.core.joint_motor_speed


EFFECTOR_CLASSES = {"pad": SuctionGripper, "gripper": ParallelGripper}
"""Effector name (``rigid_gym.envs.task.EFFECTORS``) -> its class."""
