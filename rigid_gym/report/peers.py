"""Peer engines on the same closed-form cases (optional extra ``compare``).

:class:`PyBulletWorld` builds a :class:`rigid_gym.Scene` in PyBullet and offers the subset of
the ``World`` interface the cases use (step, reset, steps, time, dt, scene, position,
velocity, rotation, angular_velocity, kinetic_energy), so ``Case.measure`` runs unchanged on
it. Materials: PyBullet multiplies the two bodies' friction and restitution, so each body gets
sqrt(mu) and sqrt(e), which gives the scenes' pair values (equal on both sides in every case).
Damping is switched off and restitution applies at any speed, so the exact answers hold.
MuJoCo is not adapted yet; the report says so, as it does when PyBullet is absent.
"""

from __future__ import annotations

import importlib.util

import numpy as np

import rigid_gym as rg
from rigid_gym import quaternion as quat
from rigid_gym.kernels.integrate import DYNAMIC, STATIC

PEER_CASES = ("free_fall", "bounce_e05", "bounce_e1", "slide", "incline_slide", "incline_stick",
              "rolling", "torque_free", "stack_drift")
"""Keys of the cases of ``rigid_gym.report.cases`` measured on the peers."""


def available() -> dict[str, bool]:
    """Which peer engines are importable here, by name."""
    return {name: importlib.util.find_spec(name) is not None for name in ("pybullet", "mujoco")}


class PyBulletWorld:
    """A rigid_gym Scene simulated by PyBullet (DIRECT mode) with a fixed step ``dt`` (s).

    Supports Sphere, Box, Capsule and Plane shapes whose body frame is the shape frame (true
    for the primitives unless an inertia tensor with off-diagonal terms was given). Arrays
    follow rigid_gym's: (n, 3) positions of the centres of mass, m, etc., body order kept.
    """

    def __init__(self, scene: rg.Scene, dt: float):
        import pybullet

        if not dt > 0.0:
            raise ValueError(f"PyBulletWorld.dt: must be > 0 s, got {dt!r}")
        self.p = pybullet
        self.scene, self.dt, self.steps = scene, float(dt), 0
        self.client = pybullet.connect(pybullet.DIRECT)
        p, c = pybullet, self.client
        p.setGravity(*scene.gravity, physicsClientId=c)
        p.setTimeStep(self.dt, physicsClientId=c)
        p.setPhysicsEngineParameter(restitutionVelocityThreshold=0.0, physicsClientId=c)
        self.ids = [self._add(body) for body in scene.bodies]
        self.dynamic = np.array([b.motion == DYNAMIC for b in scene.bodies])
        self.mass = np.array([b.mass if b.motion == DYNAMIC else 0.0 for b in scene.bodies])
        self.moments = np.array([b.principal_moments for b in scene.bodies])
        self._saved = p.saveState(physicsClientId=c)

    def _add(self, body) -> int:
        p, c, shape = self.p, self.client, body.shape
        if not np.allclose(body.body_from_shape.position, 0.0) or \
                abs(abs(body.body_from_shape.orientation[0]) - 1.0) > 1e-12:
            raise ValueError(f"PyBulletWorld: body {body.name!r} has a body frame off its shape "
                             "frame; only primitives about their own axes are supported")
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

    def step(self, n: int = 1) -> None:
        for _ in range(int(n)):
            self.p.stepSimulation(physicsClientId=self.client)
        self.steps += int(n)

    def reset(self) -> None:
        self.p.restoreState(self._saved, physicsClientId=self.client)
        self.steps = 0

    def close(self) -> None:
        self.p.disconnect(physicsClientId=self.client)

    @property
    def time(self) -> float:
        return self.steps * self.dt

    def _poses(self):
        poses = [self.p.getBasePositionAndOrientation(i, physicsClientId=self.client)
                 for i in self.ids]
        return (np.array([x for x, _ in poses]),
                np.array([(q[3], q[0], q[1], q[2]) for _, q in poses]))

    def _velocities(self):
        v = [self.p.getBaseVelocity(i, physicsClientId=self.client) for i in self.ids]
        return np.array([a for a, _ in v]), np.array([b for _, b in v])

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
