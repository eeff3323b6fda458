"""Joints of a scene: revolute, prismatic and fixed, each with limits and a motor.

Built with ``Scene.add_revolute_joint``, ``add_prismatic_joint`` and ``add_fixed_joint``;
solved inside the step as impulses (``src/solver/joints.h``: a velocity solve after the
velocity update, position pre-stabilisation before the position update). Joined bodies do
not collide with each other and sleep as one island.

Conventions: ``body_a`` is the dynamic body the joint moves; ``body_b`` is what it is held
to (any body, or None for the world frame). The anchor (m) and axis are given in the world
frame at the scene's initial poses and fixed in each body from then on. The coordinate is
a's angle about the axis relative to b (revolute, rad, right-handed about the axis, 0 at
the initial poses, in (-pi, pi]) or the travel of a's anchor along b's axis from b's anchor
(prismatic, m, 0 at the initial poses); a motor drives the coordinate's rate towards
``motor_speed`` with at most its maximum torque (N m) or force (N).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigid_gym import quaternion as quat
from rigid_gym._core import DYNAMIC
from rigid_gym.checks import in_range, number, real, vector

REVOLUTE, PRISMATIC, FIXED = 0, 1, 2
KIND_NAMES = {REVOLUTE: "revolute", PRISMATIC: "prismatic", FIXED: "fixed"}
WORLD = -1
"""body_b of a joint held to the world frame."""


@dataclass(frozen=True, eq=False)
class JointSpec:
    """One validated joint.

    kind: REVOLUTE, PRISMATIC or FIXED. body_a: dynamic body index; body_b: body index or
    WORLD (-1). anchor_a, anchor_b (3,) m and axis_a, axis_b (3,) unit: the anchor and axis
    in each body's principal frame (the world frame for WORLD). reference (4,): a's
    orientation in b's frame at coordinate 0. lower, upper: limits, rad (revolute) or m
    (prismatic), -inf/inf for none. motor_speed rad/s or m/s; max_motor N m or N (0: none).
    """

    index: int
    name: str
    kind: int
    body_a: int
    body_b: int
    anchor_a: np.ndarray
    anchor_b: np.ndarray
    axis_a: np.ndarray
    axis_b: np.ndarray
    reference: np.ndarray
    lower: float
    upper: float
    motor_speed: float
    max_motor: float


def body_reference(scene, body, where: str, allow_world: bool) -> int:
    """The index of ``body`` (an index or a name; None for the world where allowed)."""
    if body is None and allow_world:
        return WORLD
    if isinstance(body, str):
        try:
            return scene.index(body)
        except KeyError as exc:
            raise ValueError(f"{where}: {exc.args[0]}") from None
    count = len(scene.bodies)
    world = " or None (the world)" if allow_world else ""
    if isinstance(body, bool) or not isinstance(body, (int, np.integer)) or not 0 <= body < count:
        raise ValueError(f"{where}: must be a body name or an index in [0, {count - 1}]{world}, "
                         f"got {body!r}")
    return int(body)


def limits_of(limits, kind: int, where: str) -> tuple[float, float]:
    """(lower, upper) from ``limits``: None for none, or (lo, hi) with lo <= hi (either may
    be -inf/inf); a revolute joint's in [-pi, pi]."""
    if limits is None:
        return -np.inf, np.inf
    try:
        low, high = limits
    except (TypeError, ValueError):
        raise ValueError(f"{where}: limits must be None or (lower, upper), got {limits!r}") from None
    low, high = real(low, f"{where}: lower limit"), real(high, f"{where}: upper limit")
    if np.isnan(low) or np.isnan(high) or low > high or low == np.inf or high == -np.inf:
        raise ValueError(f"{where}: limits must be (lower, upper) with lower <= upper, not NaN, "
                         f"got {limits!r}")
    if kind == REVOLUTE and (low < -np.pi or high > np.pi):
        raise ValueError(f"{where}: a revolute joint's limits must be in [-pi, pi] rad "
                         f"(its angle is measured in (-pi, pi]), got {limits!r}")
    return low, high


def make_joint(scene, kind: int, body_a, body_b, anchor, axis, limits, motor_speed,
               max_motor, name) -> JointSpec:
    """A validated JointSpec for ``scene`` (``Scene.add_*_joint`` documents the arguments)."""
    index = len(scene.joints)
    name = f"joint{index}" if name is None else str(name)
    where = f"{KIND_NAMES[kind]} joint {index} ({name!r})"
    if any(j.name == name for j in scene.joints):
        raise ValueError(f"{where}: name {name!r} is already used by another joint")
    a = body_reference(scene, body_a, f"{where}: body_a", allow_world=False)
    b = body_reference(scene, body_b, f"{where}: body_b", allow_world=True)
    if a == b:
        raise ValueError(f"{where}: body_a and body_b are the same body ({a})")
    spec_a = scene.bodies[a]
    if spec_a.motion != DYNAMIC:
        other = "the world" if b == WORLD else f"body {b} ({scene.bodies[b].name!r})"
        if b != WORLD and scene.bodies[b].motion == DYNAMIC:
            hint = "; give the dynamic body as body_a"
        else:
            hint = ": neither body is dynamic, so the joint could move nothing"
        raise ValueError(f"{where}: body_a, body {a} ({spec_a.name!r}), is not dynamic and "
                         f"body_b is {other}{hint}")
    anchor = vector(anchor, 3, f"{where}: anchor")
    if axis is None:
        axis = np.array([0.0, 0.0, 1.0])
    axis = vector(axis, 3, f"{where}: axis")
    size = float(np.linalg.norm(axis))
    if not size > 1e-12:
        raise ValueError(f"{where}: axis must be a nonzero direction, got {axis.tolist()}")
    axis = axis / size
    lower, upper = limits_of(limits, kind, where) if kind != FIXED else (-np.inf, np.inf)
    unit = "N m" if kind == REVOLUTE else "N"
    speed = number(motor_speed, f"{where}: motor_speed")
    strength = in_range(max_motor, 0.0, np.inf, f"{where}: maximum motor "
                        f"{'torque' if kind == REVOLUTE else 'force'}", unit=unit)
    q_a = spec_a.orientation
    if b == WORLD:
        x_b, q_b = np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])
    else:
        x_b, q_b = scene.bodies[b].position, scene.bodies[b].orientation
    inverse_a, inverse_b = quat.conjugate(q_a), quat.conjugate(q_b)
    return JointSpec(
        index=index, name=name, kind=kind, body_a=a, body_b=b,
        anchor_a=quat.rotate(inverse_a, anchor - spec_a.position),
        anchor_b=quat.rotate(inverse_b, anchor - x_b),
        axis_a=quat.rotate(inverse_a, axis), axis_b=quat.rotate(inverse_b, axis),
        reference=quat.normalize(quat.multiply(inverse_b, q_a)),
        lower=lower, upper=upper, motor_speed=speed, max_motor=strength)


def joint_model(joints: list[JointSpec]) -> tuple:
    """The core's joint model (``StepContext.set_joints``): kind, body_a, body_b (J,) int32,
    anchor_a, anchor_b, axis_a, axis_b (J, 3), reference (J, 4)."""
    ints = lambda field: np.array([getattr(j, field) for j in joints], dtype=np.int32)
    rows = lambda field, width: np.array([getattr(j, field) for j in joints],
                                         dtype=np.float64).reshape(len(joints), width)
    return (ints("kind"), ints("body_a"), ints("body_b"), rows("anchor_a", 3),
            rows("anchor_b", 3), rows("axis_a", 3), rows("axis_b", 3), rows("reference", 4))


def joint_settings(joints: list[JointSpec]) -> tuple:
    """(lower, upper, motor_speed, max_motor), each (J,) float64, as the scene gives them."""
    return tuple(np.array([getattr(j, field) for j in joints], dtype=np.float64)
                 for field in ("lower", "upper", "motor_speed", "max_motor"))
