"""Peer engines on the same closed-form cases (optional extra ``compare``).

:class:`PyBulletWorld` and :class:`MuJoCoWorld` build a :class:`rigid_gym.Scene` in their
engine and offer, through :class:`PeerWorld`, the subset of the ``World`` interface the cases
use (step, reset, steps, time, dt, scene, position, velocity, rotation, angular_velocity,
kinetic_energy), so ``Case.measure`` runs unchanged on them. ``PEERS`` lists the curves the
report draws (label -> engine, factory).

PyBullet: it multiplies the two bodies' friction and restitution, so each body gets sqrt(mu)
and sqrt(e), which gives the scenes' pair values (equal on both sides in every case). Damping
is switched off and restitution applies at any speed, so the exact answers hold.

MuJoCo: one MJCF model per scene (:func:`mjcf`), stepped by ``mujoco.mj_step`` with the
default semi-implicit Euler integrator or RK4. Friction is the pair's mu (MuJoCo takes the
larger of the two geoms', equal here; pyramidal cone, condim 3, or condim 1 when mu = 0).
MuJoCo has no restitution coefficient: contacts are soft constraints that behave like a
mass-spring-damper, so e is mapped to the damping ratio whose linear spring-damper loses
that much speed in one contact, zeta = -ln e / sqrt(pi^2 + ln^2 e) (:func:`damping_ratio`),
given as the direct solref (-w^2, -2 zeta w) with w = 1 / max(0.02 s, 2 dt): MuJoCo's default
time constant and its 2 dt floor (:func:`solref`). The mapping is approximate: the impedance (solimp) and the integrator change the effective
spring and damping, so the measured e differs from the scene's.
"""

from __future__ import annotations

import importlib.util
from abc import ABC, abstractmethod

import numpy as np

import rigid_gym as rg
from rigid_gym import quaternion as quat
from rigid_gym._core import DYNAMIC, STATIC
from rigid_gym.checks import in_range

PEER_CASES = ("free_fall", "bounce_e05", "bounce_e1", "slide", "incline_slide", "incline_stick",
              "struck_row", "rolling", "wall", "plate", "torque_free", "stack_drift")
"""Keys of the cases of ``rigid_gym.report.cases`` measured on the peers."""


def available() -> dict[str, bool]:
    """Which peer engines are importable here, by name."""
    return {name: importlib.util.find_spec(name) is not None for name in ("pybullet", "mujoco")}


def _check_body(engine: str, body) -> None:
    """Raise ValueError for what the peer adapters cannot build: a body frame off its shape
    frame (an inertia tensor with off-diagonal terms) or a kinematic body."""
    if not np.allclose(body.body_from_shape.position, 0.0) or \
            abs(abs(body.body_from_shape.orientation[0]) - 1.0) > 1e-12:
        raise ValueError(f"{engine}: body {body.name!r} has a body frame off its shape frame; "
                         "only primitives about their own axes are supported")
    if body.motion not in (STATIC, DYNAMIC):
        raise ValueError(f"{engine}: body {body.name!r} is kinematic; only static and dynamic "
                         "bodies are supported")


class PeerWorld(ABC):
    """What the peer adapters share: the checks, the step count and the state queries.

    Subclasses build the scene in ``__init__`` (after ``super().__init__``) and implement
    ``_advance(n)`` (n engine steps), ``reset()``, ``_poses()`` -> ((n, 3) m, (n, 4) w-first
    quaternions) and ``_velocities()`` -> ((n, 3) m/s, (n, 3) rad/s world frame). Arrays follow
    rigid_gym's: one row per scene body (static ones included), centres of mass, body order.
    Supports Sphere, Box, Capsule and Plane shapes whose body frame is the shape frame (true
    for the primitives unless an inertia tensor with off-diagonal terms was given).
    """

    engine = "PeerWorld"

    def __init__(self, scene: rg.Scene, dt: float):
        if not isinstance(scene, rg.Scene):
            raise TypeError(f"{self.engine}.scene: expected a rigid_gym.Scene, got "
                            f"{type(scene).__name__}")
        if not (np.isfinite(dt) and dt > 0.0):
            raise ValueError(f"{self.engine}.dt: must be finite and > 0 s, got {dt!r}")
        for body in scene.bodies:
            _check_body(self.engine, body)
        self.scene, self.dt, self.steps = scene, float(dt), 0
        self.dynamic = np.array([b.motion == DYNAMIC for b in scene.bodies])
        self.mass = np.array([b.mass if b.motion == DYNAMIC else 0.0 for b in scene.bodies])
        self.moments = np.array([b.principal_moments for b in scene.bodies])

    @abstractmethod
    def _advance(self, n: int) -> None:
        """Step the engine ``n`` times."""

    @abstractmethod
    def reset(self) -> None:
        """Back to the scene's start."""

    @abstractmethod
    def _poses(self) -> tuple[np.ndarray, np.ndarray]:
        """((n, 3) m, (n, 4) w-first quaternions) of every body."""

    @abstractmethod
    def _velocities(self) -> tuple[np.ndarray, np.ndarray]:
        """((n, 3) m/s, (n, 3) rad/s world frame) of every body."""

    def step(self, n: int = 1) -> None:
        """Advance ``n`` steps of ``dt`` s."""
        self._advance(int(n))
        self.steps += int(n)

    def close(self) -> None:
        """Release the engine (nothing to do unless the engine holds a connection)."""

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.steps * self.dt

    @property
    def position(self) -> np.ndarray:
        """(n, 3) centre-of-mass positions, m."""
        return self._poses()[0]

    @property
    def rotation(self) -> np.ndarray:
        """(n, 3, 3) rotation matrices."""
        return quat.to_matrix(self._poses()[1])

    @property
    def velocity(self) -> np.ndarray:
        """(n, 3) m/s."""
        return self._velocities()[0]

    @property
    def angular_velocity(self) -> np.ndarray:
        """(n, 3) rad/s, world frame."""
        return self._velocities()[1]

    def kinetic_energy(self) -> float:
        """Total kinetic energy of the dynamic bodies, J."""
        v, w = self._velocities()
        body_w = np.einsum("nji,nj->ni", self.rotation, w)
        return float(0.5 * np.sum(self.dynamic * (self.mass * np.sum(v * v, axis=1)
                                                  + np.sum(self.moments * body_w ** 2, axis=1))))


class PyBulletWorld(PeerWorld):
    """A rigid_gym Scene simulated by PyBullet (DIRECT mode) with a fixed step ``dt`` (s)."""

    engine = "PyBulletWorld"

    def __init__(self, scene: rg.Scene, dt: float):
        import pybullet

        super().__init__(scene, dt)
        self.p = pybullet
        self.client = pybullet.connect(pybullet.DIRECT)
        p, c = pybullet, self.client
        p.setGravity(*scene.gravity, physicsClientId=c)
        p.setTimeStep(self.dt, physicsClientId=c)
        p.setPhysicsEngineParameter(restitutionVelocityThreshold=0.0, physicsClientId=c)
        self.ids = [self._add(body) for body in scene.bodies]
        self._saved = p.saveState(physicsClientId=c)

    def _add(self, body) -> int:
        p, c, shape = self.p, self.client, body.shape
        if isinstance(shape, rg.Plane):
            geometry = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=c)
        elif isinstance(shape, rg.Sphere):
            geometry = p.createCollisionShape(p.GEOM_SPHERE, radius=shape.radius,
                                              physicsClientId=c)
        elif isinstance(shape, rg.Box):
            geometry = p.createCollisionShape(p.GEOM_BOX, halfExtents=shape.half_extents,
                                              physicsClientId=c)
        elif isinstance(shape, rg.Capsule):
            geometry = p.createCollisionShape(p.GEOM_CAPSULE, radius=shape.radius,
                                              height=2 * shape.half_length, physicsClientId=c)
        else:
            raise ValueError(f"PyBulletWorld: shape {type(shape).__name__} is not supported")
        w, x, y, z = body.orientation
        mass = 0.0 if body.motion == STATIC else body.mass
        uid = p.createMultiBody(mass, geometry, basePosition=body.position,
                                baseOrientation=(x, y, z, w), physicsClientId=c)
        p.changeDynamics(uid, -1, lateralFriction=np.sqrt(body.friction),
                         restitution=np.sqrt(body.restitution), linearDamping=0.0,
                         angularDamping=0.0, physicsClientId=c)
        if body.motion == DYNAMIC:
            p.changeDynamics(uid, -1, localInertiaDiagonal=body.principal_moments,
                             physicsClientId=c)
            p.resetBaseVelocity(uid, body.velocity, body.angular_velocity, physicsClientId=c)
        return uid

    def _advance(self, n: int) -> None:
        for _ in range(n):
            self.p.stepSimulation(physicsClientId=self.client)

    def reset(self) -> None:
        self.p.restoreState(self._saved, physicsClientId=self.client)
        self.steps = 0

    def close(self) -> None:
        self.p.disconnect(physicsClientId=self.client)

    def _poses(self):
        poses = [self.p.getBasePositionAndOrientation(i, physicsClientId=self.client)
                 for i in self.ids]
        return (np.array([x for x, _ in poses]),
                np.array([(q[3], q[0], q[1], q[2]) for _, q in poses]))

    def _velocities(self):
        v = [self.p.getBaseVelocity(i, physicsClientId=self.client) for i in self.ids]
        return np.array([a for a, _ in v]), np.array([b for _, b in v])


MUJOCO_TIMECONST = 0.02
"""Time constant of every MuJoCo contact, s (MuJoCo's default solref[0]): the contact spring's
natural frequency is 1 / MUJOCO_TIMECONST rad/s."""
MUJOCO_INTEGRATORS = ("Euler", "RK4")


def damping_ratio(restitution: float) -> float:
    """Damping ratio zeta of a linear spring-damper whose contact (half a damped oscillation)
    ends at e times the approach speed: zeta = -ln e / sqrt(pi^2 + ln^2 e); 1 (critical, no
    rebound) at e = 0, 0 at e = 1. restitution: e in [0, 1]."""
    e = in_range(restitution, 0.0, 1.0, "damping_ratio: restitution")
    if e == 0.0:
        return 1.0
    return float(-np.log(e) / np.hypot(np.pi, np.log(e)))


def solref(restitution: float, dt: float) -> tuple[float, float]:
    """MuJoCo's direct solref (-stiffness 1/s^2, -damping 1/s) for restitution e at step dt
    (s): natural frequency w = 1 / max(MUJOCO_TIMECONST, 2 dt) (the 2 dt floor is MuJoCo's
    own for time constants), stiffness w^2, damping 2 zeta w. The (timeconst, dampratio) form
    cannot express zeta = 0 (e = 1)."""
    w = 1.0 / max(MUJOCO_TIMECONST, 2.0 * dt)
    return -w * w, -2.0 * damping_ratio(restitution) * w


def _numbers(values) -> str:
    return " ".join(f"{float(v):.17g}" for v in np.atleast_1d(values))


def mjcf(scene: rg.Scene, dt: float, integrator: str = "Euler") -> str:
    """The MJCF text of ``scene``: body k is ``<body name="b{k}">`` with a free joint if
    dynamic (welded to the world if static); inertia at the centre of mass along the shape
    axes; each geom's friction mu (condim 1, frictionless, where mu = 0) and
    solref(e, dt); gravity, timestep ``dt`` (s) and
    ``integrator`` (one of MUJOCO_INTEGRATORS). Initial velocities go into keyframe 0."""
    if integrator not in MUJOCO_INTEGRATORS:
        raise ValueError(f"mjcf: integrator must be one of {MUJOCO_INTEGRATORS}, got "
                         f"{integrator!r}")
    bodies, qvel = [], []
    for k, body in enumerate(scene.bodies):
        _check_body("MuJoCoWorld", body)
        shape = body.shape
        if isinstance(shape, rg.Plane):
            geom = 'type="plane" size="0 0 1"'
        elif isinstance(shape, rg.Sphere):
            geom = f'type="sphere" size="{shape.radius:.17g}"'
        elif isinstance(shape, rg.Box):
            geom = f'type="box" size="{_numbers(shape.half_extents)}"'
        elif isinstance(shape, rg.Capsule):
            geom = f'type="capsule" size="{shape.radius:.17g} {shape.half_length:.17g}"'
        else:
            raise ValueError(f"MuJoCoWorld: shape {type(shape).__name__} is not supported")
        contact = (f'friction="{body.friction:.17g} 0 0" condim="{3 if body.friction > 0 else 1}" '
                   f'solref="{_numbers(solref(body.restitution, dt))}"')
        inside = [f"<geom {geom} {contact}/>"]
        if body.motion == DYNAMIC:
            inertial = (f'<inertial pos="0 0 0" mass="{body.mass:.17g}" '
                        f'diaginertia="{_numbers(body.principal_moments)}"/>')
            inside = ["<freejoint/>", inertial, *inside]
            # a free joint's qvel is (linear, world frame; angular, body frame)
            local_w = quat.to_matrix(np.asarray(body.orientation)).T @ body.angular_velocity
            qvel += [*body.velocity, *local_w]
        bodies.append(f'<body name="b{k}" pos="{_numbers(body.position)}" '
                      f'quat="{_numbers(body.orientation)}">{"".join(inside)}</body>')
    key = f'<keyframe><key name="start" qvel="{_numbers(qvel)}"/></keyframe>' if qvel else ""
    return (f'<mujoco model="rigid_gym"><option timestep="{dt:.17g}" '
            f'gravity="{_numbers(scene.gravity)}" integrator="{integrator}"/>'
            f'<worldbody>{"".join(bodies)}</worldbody>{key}</mujoco>')


class MuJoCoWorld(PeerWorld):
    """A rigid_gym Scene simulated by MuJoCo (``mujoco.mj_step`` in a Python loop) with a
    fixed step ``dt`` (s) and ``integrator`` "Euler" (MuJoCo's default, semi-implicit) or
    "RK4". The model is :func:`mjcf` of the scene; the state is read from qpos/qvel (the
    body poses MuJoCo caches in ``data.xpos`` lag one step behind after ``mj_step``).
    ``sleep``: switch on MuJoCo's island sleeping (``mjENBL_SLEEP``, MuJoCo 4.0 on; its own
    velocity threshold and delay), which a MuJoCo without it refuses with a ValueError."""

    engine = "MuJoCoWorld"

    def __init__(self, scene: rg.Scene, dt: float, integrator: str = "Euler",
                 sleep: bool = False):
        import mujoco

        super().__init__(scene, dt)
        self.mj = mujoco
        self.model = mujoco.MjModel.from_xml_string(mjcf(scene, self.dt, integrator))
        if sleep:
            if not hasattr(mujoco.mjtEnableBit, "mjENBL_SLEEP"):
                raise ValueError(f"MuJoCoWorld: sleep needs MuJoCo 4.0 or later, this is "
                                 f"{mujoco.__version__}")
            self.model.opt.enableflags |= mujoco.mjtEnableBit.mjENBL_SLEEP
        self.data = mujoco.MjData(self.model)
        body_ids = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, f"b{k}")
                    for k in range(len(scene.bodies))]
        joints = [self.model.body_jntadr[i] for i in body_ids]
        self._qpos = np.array([self.model.jnt_qposadr[j] if j >= 0 else -1 for j in joints])
        self._qvel = np.array([self.model.jnt_dofadr[j] if j >= 0 else -1 for j in joints])
        self._fixed = (self.model.body_pos[body_ids].copy(), self.model.body_quat[body_ids].copy())
        self.reset()

    def _advance(self, n: int) -> None:
        step, model, data = self.mj.mj_step, self.model, self.data
        for _ in range(n):
            step(model, data)

    def reset(self) -> None:
        if self.model.nkey:
            self.mj.mj_resetDataKeyframe(self.model, self.data, 0)
        else:
            self.mj.mj_resetData(self.model, self.data)
        self.steps = 0

    def _poses(self):
        position, orientation = (a.copy() for a in self._fixed)
        for k in np.nonzero(self._qpos >= 0)[0]:
            q = self.data.qpos[self._qpos[k]:self._qpos[k] + 7]
            position[k], orientation[k] = q[:3], q[3:] / np.linalg.norm(q[3:])
        return position, orientation

    def _velocities(self):
        v, w = np.zeros((len(self._qvel), 3)), np.zeros((len(self._qvel), 3))
        rotation = quat.to_matrix(self._poses()[1])
        for k in np.nonzero(self._qvel >= 0)[0]:
            u = self.data.qvel[self._qvel[k]:self._qvel[k] + 6]
            v[k], w[k] = u[:3], rotation[k] @ u[3:]
        return v, w


PEERS = {
    "PyBullet": ("pybullet", PyBulletWorld),
    "MuJoCo": ("mujoco", MuJoCoWorld),
    "MuJoCo RK4": ("mujoco", lambda scene, dt: MuJoCoWorld(scene, dt, "RK4")),
}
"""Peer curves of the report: label -> (engine name as in ``available``, factory
(Scene, dt) -> world)."""
