"""Whether anything in a scene can move far enough in one step to need continuous collision.

``SolverConfig.for_scene`` switches ``continuous`` on where :func:`can_move_far` says so. The
core sweeps a pair when its relative motion in a step exceeds the thinner body's half
thickness (``src/solver/continuous.h``). What a scene *can* do, left to itself: the
energy it starts with bounds every speed, since the step can only remove energy (restitution
<= 1, inelastic contact passes). That energy is the dynamic bodies' kinetic energy plus the
potential energy of each falling until its centre is its half thickness above the lowest
point of any static or kinematic body (a tilted plane has none: its fall is unbounded; a
cube resting on the ground has none to release). All of it in the lightest body moves it at
sqrt(2 E / m); all of it spinning the body with the least moment turns its points at
sqrt(2 E / I) times its reach. A kinematic body keeps the speed it is given and can throw a
body at up to twice its own speed (e = 1), adding its points' speed to any relative motion.
A joint's motor is a source of energy too: it drives its body towards its target speed
(a revolute one's points at that rate times the body's reach), which counts as a kinematic
body's speed does.

Not counted, so not foreseen: speed given later (``World.set_velocity``, impulses, forces,
kinematic bodies moved between steps, as the envs' gripper is, motors set by
``World.set_joint_motor``). A World that will be given
such speeds can pass ``continuous=True`` explicitly.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

import numpy as np

from rigid_gym import quaternion as quat
from rigid_gym._core import DYNAMIC, KINEMATIC
from rigid_gym.joints import REVOLUTE
from rigid_gym.shapes import Compound, Plane, Shape

if TYPE_CHECKING:
    from rigid_gym.scene import BodySpec, Scene

def half_thickness(shape) -> float:
    """The shape's least half extent (m), as the core takes it: a box's least half edge, a
    sphere's or capsule's radius, a mesh's least half extent of its bounding box; a
    Compound's thinnest part's; infinite for a Plane."""
    if isinstance(shape, Plane):
        return float("inf")
    if isinstance(shape, Compound):
        return min(half_thickness(part) for part, _ in shape.parts)
    lo, hi = shape.bounds()
    return float(np.min(hi - lo) / 2)


def corners(body: BodySpec) -> np.ndarray:
    """(8, 3) the corners (m) of the body's shape's bounding box, in its body frame."""
    lo, hi = cast(Shape, body.shape).bounds()
    box = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    return body.body_from_shape.apply(box)


def reach(body: BodySpec) -> float:
    """The distance (m) of the body's furthest point from its centre of mass (a bound: the
    corners of its shape's bounding box)."""
    return float(np.linalg.norm(corners(body), axis=1).max())


def lowest_point(body: BodySpec, up: np.ndarray) -> float:
    """The least height (m, along ``up``) of a static or kinematic body (of its bounding box):
    -inf for a plane that does not face ``up``."""
    rotation = quat.to_matrix(body.orientation)
    if isinstance(body.shape, Plane):
        normal = rotation @ body.body_from_shape.rotation()[:, 2]
        return float(body.position @ up) if np.allclose(normal, up) else -np.inf
    return float(body.position @ up + (corners(body) @ rotation.T @ up).min())


def reachable_speed(scene: Scene) -> float:
    """A bound (m/s) on how fast any point of one body can move relative to another, left to
    the scene's own energy (module docstring); 0 where nothing can move, inf where a body can
    fall without end onto something."""
    bodies = scene.bodies
    dynamic = [b for b in bodies if b.motion == DYNAMIC]
    if not dynamic or len(bodies) < 2:
        return 0.0
    gravity = np.asarray(scene.gravity, dtype=np.float64)
    g = float(np.linalg.norm(gravity))
    supports = [b for b in bodies if b.motion != DYNAMIC]
    energy = sum(0.5 * b.mass * float(b.velocity @ b.velocity)
                 + 0.5 * float(b.principal_moments
                               @ (quat.to_matrix(b.orientation).T @ b.angular_velocity) ** 2)
                 for b in dynamic)
    if g > 0.0 and supports:
        up = -gravity / g
        floor = min(lowest_point(b, up) for b in supports)
        if floor == -np.inf:
            return float("inf")
        energy += sum(b.mass * g * max(0.0, float(b.position @ up) - floor
                                       - half_thickness(b.shape)) for b in dynamic)
    thrown = max((float(np.linalg.norm(b.velocity)) + float(np.linalg.norm(b.angular_velocity))
                  * reach(b) for b in bodies if b.motion == KINEMATIC), default=0.0)
    driven = max((abs(j.motor_speed) * (reach(bodies[j.body_a]) if j.kind == REVOLUTE else 1.0)
                  for j in scene.joints if j.max_motor > 0.0), default=0.0)
    thrown = max(thrown, driven)
    linear = max(np.sqrt(2.0 * energy / b.mass) for b in dynamic)
    spin = max(np.sqrt(2.0 * energy / min(b.principal_moments)) * reach(b) for b in dynamic)
    return float(linear + spin + 3.0 * thrown)


def can_move_far(scene: Scene, dt: float | None = None) -> bool:
    """Whether some pair of ``scene`` can move further relative to each other in a step of
    ``dt`` (s) than the thinnest body's half thickness, left to the scene's
    own energy; without ``dt``, whether anything can move at all."""
    speed = reachable_speed(scene)
    if dt is None or speed == 0.0:
        return speed > 0.0
    thinnest = min(half_thickness(b.shape) for b in scene.bodies)
    return speed * dt > thinnest
