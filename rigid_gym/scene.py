"""Scene: the declarative description of a world, built by the user and validated on entry.

    scene = rg.Scene(gravity=(0, 0, -9.81))
    scene.add_ground(friction=0.5)
    cube = scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0, 0, 0.05))

Poses given to ``add_body`` are those of the shape's own frame (the frame its vertices or
axes are defined in). Internally a body is stored at its centre of mass, in its principal
frame; for primitives and any shape whose inertia is already diagonal
about its origin the two frames coincide. ``BodySpec.body_from_shape`` maps one to the other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigid_gym import quaternion as quat
from rigid_gym._core import DYNAMIC, KINEMATIC, STATIC
from rigid_gym.checks import in_range, vector
from rigid_gym.inertia import MassProperties, inverse_moments, mass_properties, principal_axes
from rigid_gym.joints import FIXED, PRISMATIC, REVOLUTE, JointSpec, body_reference, make_joint
from rigid_gym.shapes import SOLID_SHAPES, Plane, Pose

MOTION_NAMES = {STATIC: "static", KINEMATIC: "kinematic", DYNAMIC: "dynamic"}
INERTIA_TOLERANCE = 1e-9
"""Relative tolerance for checks on a user-given inertia tensor (symmetry, triangle inequality)."""


@dataclass(frozen=True, eq=False)
class BodySpec:
    """One validated body. Arrays are float64; poses are of the principal (body) frame.

    shape: the body's shape, in its shape frame.
    motion: STATIC, KINEMATIC or DYNAMIC (``rigid_gym._core``; ``src/solver/integrate.h``).
    mass: kg (inf for static and kinematic bodies).
    principal_moments: (3,) kg m^2 about the centre of mass, principal axes (0 if not dynamic).
    body_from_shape: Pose of the shape frame in the body frame (centre of mass at the origin).
    position (3,) m, orientation (4,), velocity (3,) m/s, angular_velocity (3,) rad/s: the
        initial state of the body frame in the world.
    friction: Coulomb coefficient >= 0; restitution: in [0, 1].
    """

    index: int
    name: str
    shape: object
    motion: int
    mass: float
    principal_moments: np.ndarray
    body_from_shape: Pose
    position: np.ndarray
    orientation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    friction: float
    restitution: float

    @property
    def inverse_mass(self) -> float:
        return 1.0 / self.mass if self.motion == DYNAMIC else 0.0

    @property
    def inverse_moments(self) -> np.ndarray:
        if self.motion != DYNAMIC:
            return np.zeros(3)
        return inverse_moments(self.principal_moments)


class Scene:
    """A list of bodies and joints plus gravity. Build it, then hand it to
    :class:`rigid_gym.World`.

    gravity: (3,) m/s^2, world frame (z up).
    """

    def __init__(self, gravity=(0.0, 0.0, -9.81)):
        self.gravity = vector(gravity, 3, "Scene.gravity")
        self.bodies: list[BodySpec] = []
        self.joints: list[JointSpec] = []

    # -- building -------------------------------------------------------------------------

    def add_ground(self, friction: float = 0.5, restitution: float = 0.0, height: float = 0.0,
                   name: str = "ground") -> int:
        """Add the static half-space z <= ``height`` (m). Returns its body index."""
        return self.add_body(Plane(), position=(0.0, 0.0, height), static=True,
                             friction=friction, restitution=restitution, name=name)

    def add_body(self, shape, *, mass: float | None = None, density: float | None = None,
                 inertia=None, position=(0.0, 0.0, 0.0), orientation=(1.0, 0.0, 0.0, 0.0),
                 velocity=(0.0, 0.0, 0.0), angular_velocity=(0.0, 0.0, 0.0),
                 friction: float = 0.5, restitution: float = 0.0, name: str | None = None,
                 kinematic: bool = False, static: bool = False) -> int:
        """Add a body and return its index.

        shape: Sphere, Box, Capsule, Mesh or Compound (Plane only for static bodies).
        mass (kg) or density (kg/m^3): exactly one, for dynamic bodies only.
        inertia: optional override of the inertia about the centre of mass, shape-frame axes:
            (3,) diagonal moments or a (3, 3) symmetric tensor, kg m^2. Degenerate tensors
            (a rod (a, a, 0), a point (0, 0, 0)) are allowed: those axes cannot turn.
        position (3,) m and orientation (4,) unit quaternion (w, x, y, z): the shape frame's
            pose in the world. velocity (3,) m/s and angular_velocity (3,) rad/s: world frame.
        friction >= 0 and restitution in [0, 1]: per body; a pair uses sqrt(mu_a mu_b) and
            max(e_a, e_b).
        kinematic: infinite mass, moved only by its set velocity. static: never moves.
        """
        index = len(self.bodies)
        name = f"body{index}" if name is None else str(name)
        where = f"body {index} ({name!r})"
        if any(b.name == name for b in self.bodies):
            raise ValueError(f"{where}: name {name!r} is already used by another body")
        if kinematic and static:
            raise ValueError(f"{where}: a body cannot be both kinematic and static")
        motion = STATIC if static else KINEMATIC if kinematic else DYNAMIC
        if isinstance(shape, Plane):
            if motion != STATIC:
                raise ValueError(f"{where}: a Plane has no volume; only static bodies may use it")
        elif not isinstance(shape, SOLID_SHAPES):
            raise ValueError(f"{where}: shape must be one of Sphere, Box, Capsule, Mesh, Compound,"
                             f" Plane; got {type(shape).__name__}")

        props = self._mass_properties(shape, motion, mass, density, inertia, where)
        moments, axes = principal_axes(props.inertia) if props else (np.zeros(3), np.eye(3))
        body_from_shape = Pose(
            -(axes.T @ props.center) if props else np.zeros(3), quat.conjugate(quat.from_matrix(axes))
        )

        shape_q = vector(orientation, 4, f"{where}: orientation")
        quat.check_unit(shape_q, f"{where}: orientation")
        shape_q = quat.normalize(shape_q)
        shape_x = vector(position, 3, f"{where}: position")
        # world_from_body = world_from_shape * shape_from_body
        body_q = quat.normalize(quat.multiply(shape_q, quat.from_matrix(axes)))
        body_x = shape_x + quat.rotate(shape_q, props.center if props else np.zeros(3))

        spec = BodySpec(
            index=index, name=name, shape=shape, motion=motion,
            mass=props.mass if props else np.inf,
            principal_moments=moments, body_from_shape=body_from_shape,
            position=body_x, orientation=body_q,
            velocity=vector(velocity, 3, f"{where}: velocity"),
            angular_velocity=vector(angular_velocity, 3, f"{where}: angular_velocity"),
            friction=in_range(friction, 0.0, np.inf, f"{where}: friction"),
            restitution=in_range(restitution, 0.0, 1.0, f"{where}: restitution"),
        )
        if motion == STATIC and (np.any(spec.velocity) or np.any(spec.angular_velocity)):
            raise ValueError(f"{where}: a static body cannot have a velocity")
        self.bodies.append(spec)
        return index

    def add_revolute_joint(self, body_a, body_b, anchor, axis, *, limits=None,
                           motor_speed: float = 0.0, max_motor_torque: float = 0.0,
                           name: str | None = None) -> int:
        """Hinge dynamic ``body_a`` to ``body_b`` (a body, or None for the world) about
        ``axis`` through ``anchor``; returns the joint's index (``rigid_gym.joints`` gives the
        conventions).

        body_a, body_b: index or name. anchor (3,) m and axis (3,) (any nonzero length),
            world frame at the scene's initial poses.
        limits: None or (lower, upper) rad in [-pi, pi], lower <= upper: the angle of a
            relative to b about the axis, 0 at the initial poses.
        motor_speed: rad/s the motor drives that angle's rate towards, with at most
            ``max_motor_torque`` N m (0: no motor).
        """
        return self.add_joint(make_joint(self, REVOLUTE, body_a, body_b, anchor, axis, limits,
                                         motor_speed, max_motor_torque, name))

    def add_prismatic_joint(self, body_a, body_b, anchor, axis, *, limits=None,
                            motor_speed: float = 0.0, max_motor_force: float = 0.0,
                            name: str | None = None) -> int:
        """Let dynamic ``body_a`` slide along ``axis`` relative to ``body_b`` (a body, or None
        for the world), without turning relative to it; returns the joint's index.

        body_a, body_b: index or name. anchor (3,) m: a point of a, world frame, which stays
            on the line through it along ``axis`` (3,), fixed in b.
        limits: None or (lower, upper) m, lower <= upper: the travel of the anchor along the
            axis, 0 at the initial poses.
        motor_speed: m/s the motor drives the travel's rate towards, with at most
            ``max_motor_force`` N (0: no motor).
        """
        return self.add_joint(make_joint(self, PRISMATIC, body_a, body_b, anchor, axis, limits,
                                         motor_speed, max_motor_force, name))

    def add_fixed_joint(self, body_a, body_b, anchor=None, *, name: str | None = None) -> int:
        """Weld dynamic ``body_a`` to ``body_b`` (a body, or None for the world) at their
        initial relative pose; returns the joint's index. anchor (3,) m, world frame: the
        point whose two copies, one in each body, the joint holds together (default body_a's
        centre of mass); with the orientations held too, the weld is rigid wherever it is."""
        a = body_reference(self, body_a, "fixed joint: body_a", allow_world=False)
        point = self.bodies[a].position if anchor is None else anchor
        return self.add_joint(make_joint(self, FIXED, a, body_b, point, None, None, 0.0, 0.0,
                                         name))

    def add_joint(self, joint: JointSpec) -> int:
        """Add a JointSpec made by ``rigid_gym.joints.make_joint`` for this scene."""
        if not isinstance(joint, JointSpec) or joint.index != len(self.joints):
            raise ValueError("Scene.add_joint: expected the next JointSpec of this scene")
        self.joints.append(joint)
        return joint.index

    # -- queries ----------------------------------------------------------------------------

    def __len__(self) -> int:
        return len(self.bodies)

    def index(self, name: str) -> int:
        """Body index of ``name``; KeyError listing the names if there is none."""
        for b in self.bodies:
            if b.name == name:
                return b.index
        raise KeyError(f"no body named {name!r}; bodies: {[b.name for b in self.bodies]}")

    # -- helpers ----------------------------------------------------------------------------

    @staticmethod
    def _mass_properties(shape, motion, mass, density, inertia, where) -> MassProperties | None:
        """Mass properties in the shape frame for a dynamic body, None otherwise."""
        if motion != DYNAMIC:
            if mass is not None or density is not None or inertia is not None:
                raise ValueError(f"{where}: a {MOTION_NAMES[motion]} body has infinite mass; "
                                 "do not give mass, density or inertia")
            return None
        if (mass is None) == (density is None):
            raise ValueError(f"{where}: give exactly one of mass (kg) or density (kg/m^3)")
        if density is not None:
            density = in_range(density, 0.0, np.inf, f"{where}: density", open_low=True,
                               unit="kg/m^3")
            props = mass_properties(shape, density)
        else:
            mass = in_range(mass, 0.0, np.inf, f"{where}: mass", open_low=True, unit="kg")
            unit = mass_properties(shape, 1.0)
            scale = mass / unit.mass
            props = MassProperties(mass, unit.center, unit.inertia * scale)
        if inertia is not None:
            props = MassProperties(props.mass, props.center, _inertia_tensor(inertia, where))
        return props


def _inertia_tensor(inertia, where: str) -> np.ndarray:
    """A user-given inertia as a validated (3, 3) tensor."""
    arr = np.array(inertia, dtype=np.float64)
    if arr.shape == (3,):
        arr = np.diag(arr)
    if arr.shape != (3, 3) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{where}: inertia must be 3 finite moments or a finite (3, 3) tensor, "
                         f"got {inertia!r}")
    scale = max(np.abs(arr).max(), np.finfo(float).tiny)
    if np.abs(arr - arr.T).max() > INERTIA_TOLERANCE * scale:
        raise ValueError(f"{where}: inertia tensor must be symmetric, got {arr.tolist()}")
    moments = np.linalg.eigvalsh(arr)
    if moments.min() < -INERTIA_TOLERANCE * scale:
        raise ValueError(f"{where}: inertia moments must be >= 0, got {moments.tolist()}")
    a, b, c = np.sort(moments)
    if a + b < c - INERTIA_TOLERANCE * scale:
        raise ValueError(f"{where}: inertia moments {moments.tolist()} violate the triangle "
                         "inequality I1 + I2 >= I3 that every mass distribution satisfies")
    return 0.5 * (arr + arr.T)
