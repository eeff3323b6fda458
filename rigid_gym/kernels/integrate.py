"""Time integration of free motion (course notes slides 10-16; Buss, JCP 164, 2000).

State per body, with a leading world axis B and a body axis n:
    position          (B, n, 3)    centre of mass X, m
    orientation       (B, n, 4)    unit quaternion q (w, x, y, z), principal body frame -> world
    velocity          (B, n, 3)    V, m/s
    angular_momentum  (B, n, 3)    L about the centre of mass, world frame, kg m^2/s
    angular_velocity  (B, n, 3)    omega = I(t)^-1 L, rad/s (input for kinematic bodies)
    rotation          (B, n, 3, 3) R(q), refreshed whenever q changes
Model per body:
    motion            (n,) int32   STATIC, KINEMATIC or DYNAMIC
    inverse_mass      (B, n)       1/kg, 0 for static and kinematic bodies
    inverse_moments   (B, n, 3)    principal 1/kg m^2, 0 on degenerate axes (slide 4)

Linear motion is symplectic Euler: V += dt (g + F/M), X += dt V_new. Angular: L += dt tau, then q
is advanced by the exact rotation of slide 13 with an effective angular velocity omega_bar:
    order 1: omega_bar = omega
    order 2: omega_bar = omega + h/2 alpha                            (Buss's second order)
    order 3: omega_bar = omega + h/2 alpha + h^2/6 omega'' + h^2/12 alpha x omega
             (Buss's third order), alpha = I^-1 (L x omega + tau).
A step is cut into sub-steps of at most a quarter turn (|omega| h <= pi/2, slide 14).
"""

import math

from rigid_gym.kernels.jit import kernel
from rigid_gym.kernels.quaternion import (
    apply_inverse_inertia,
    cross,
    normalize_quaternion,
    rotate_by_angular_velocity,
    rotation_from_quaternion,
)

STATIC = 0
KINEMATIC = 1
DYNAMIC = 2

QUARTER_TURN = 0.5 * math.pi


@kernel
def refresh_rotation_and_angular_velocity(
    orientation, angular_momentum, inverse_moments, motion, rotation, angular_velocity
):
    """Recompute R(q) for every body and omega = I(t)^-1 L for dynamic bodies (after q or L
    were set from outside)."""
    num_worlds, num_bodies = orientation.shape[0], orientation.shape[1]
    for w in range(num_worlds):
        for i in range(num_bodies):
            rotation_from_quaternion(orientation[w, i], rotation[w, i])
            if motion[i] == DYNAMIC:
                lx, ly, lz = angular_momentum[w, i, 0], angular_momentum[w, i, 1], angular_momentum[w, i, 2]
                ox, oy, oz = apply_inverse_inertia(rotation[w, i], inverse_moments[w, i], lx, ly, lz)
                angular_velocity[w, i, 0] = ox
                angular_velocity[w, i, 1] = oy
                angular_velocity[w, i, 2] = oz


@kernel
def update_world_velocities(
    w, velocity, angular_momentum, angular_velocity, rotation, force, torque,
    inverse_mass, inverse_moments, motion, gravity, dt,
):
    """V += dt (g + F/M), L += dt tau, omega = I(t)^-1 L, for the dynamic bodies of world w.

    force, torque: (B, n, 3) external force (N) and torque about the centre of mass (N m),
    held constant over the step; gravity: (3,) m/s^2; dt: s.
    """
    for i in range(velocity.shape[1]):
        if motion[i] != DYNAMIC:
            continue
        for k in range(3):
            velocity[w, i, k] += dt * (gravity[k] + force[w, i, k] * inverse_mass[w, i])
            angular_momentum[w, i, k] += dt * torque[w, i, k]
        lx, ly, lz = angular_momentum[w, i, 0], angular_momentum[w, i, 1], angular_momentum[w, i, 2]
        ox, oy, oz = apply_inverse_inertia(rotation[w, i], inverse_moments[w, i], lx, ly, lz)
        angular_velocity[w, i, 0] = ox
        angular_velocity[w, i, 1] = oy
        angular_velocity[w, i, 2] = oz


@kernel
def effective_angular_velocity(rotation, inverse_moments, lx, ly, lz, tx, ty, tz, h, order):
    """omega_bar for one (sub)step of length h: Buss's update of the given order (1, 2 or 3).

    rotation: (3, 3) R at the start of the step; L: angular momentum; tau: torque; returns a
    3-tuple, rad/s.
    """
    ox, oy, oz = apply_inverse_inertia(rotation, inverse_moments, lx, ly, lz)
    if order == 1:
        return ox, oy, oz
    # alpha = d omega/dt = I^-1 (L x omega + tau)
    mx, my, mz = cross(lx, ly, lz, ox, oy, oz)
    mx, my, mz = mx + tx, my + ty, mz + tz
    ax, ay, az = apply_inverse_inertia(rotation, inverse_moments, mx, my, mz)
    bx, by, bz = ox + 0.5 * h * ax, oy + 0.5 * h * ay, oz + 0.5 * h * az
    if order == 2:
        return bx, by, bz
    # omega'' = omega x alpha - I^-1 (omega x M) + I^-1 (tau x omega + L x alpha), M = L x omega + tau
    p1 = cross(ox, oy, oz, ax, ay, az)
    wm = cross(ox, oy, oz, mx, my, mz)
    tw = cross(tx, ty, tz, ox, oy, oz)
    la = cross(lx, ly, lz, ax, ay, az)
    sx, sy, sz = tw[0] + la[0] - wm[0], tw[1] + la[1] - wm[1], tw[2] + la[2] - wm[2]
    p2 = apply_inverse_inertia(rotation, inverse_moments, sx, sy, sz)
    ddx, ddy, ddz = p1[0] + p2[0], p1[1] + p2[1], p1[2] + p2[2]
    # the Magnus commutator term alpha x omega
    cx, cy, cz = cross(ax, ay, az, ox, oy, oz)
    c6 = h * h / 6.0
    c12 = h * h / 12.0
    return bx + c6 * ddx + c12 * cx, by + c6 * ddy + c12 * cy, bz + c6 * ddz + c12 * cz


@kernel
def update_world_positions(
    w, position, orientation, velocity, angular_momentum, angular_velocity, rotation, torque,
    inverse_moments, motion, dt, order,
):
    """X += dt V; advance q by the rotation of the step; refresh R and omega; world w.

    Dynamic bodies rotate in sub-steps of at most a quarter turn, each re-evaluating omega from
    L at the current orientation. Kinematic bodies turn at their set angular velocity (exact).
    order: 1, 2 or 3 (see the module docstring); dt: s.
    """
    for i in range(position.shape[1]):
        if motion[i] == STATIC:
            continue
        for k in range(3):
            position[w, i, k] += dt * velocity[w, i, k]
        q = orientation[w, i]
        r = rotation[w, i]
        if motion[i] == KINEMATIC:
            rotate_by_angular_velocity(
                q, angular_velocity[w, i, 0], angular_velocity[w, i, 1], angular_velocity[w, i, 2], dt
            )
            rotation_from_quaternion(q, r)
            continue
        lx, ly, lz = angular_momentum[w, i, 0], angular_momentum[w, i, 1], angular_momentum[w, i, 2]
        tx, ty, tz = torque[w, i, 0], torque[w, i, 1], torque[w, i, 2]
        speed = math.sqrt(
            angular_velocity[w, i, 0] ** 2 + angular_velocity[w, i, 1] ** 2 + angular_velocity[w, i, 2] ** 2
        )
        substeps = max(1, int(math.ceil(speed * dt / QUARTER_TURN)))
        h = dt / substeps
        for _ in range(substeps):
            bx, by, bz = effective_angular_velocity(
                r, inverse_moments[w, i], lx, ly, lz, tx, ty, tz, h, order
            )
            rotate_by_angular_velocity(q, bx, by, bz, h)
            rotation_from_quaternion(q, r)
        ox, oy, oz = apply_inverse_inertia(r, inverse_moments[w, i], lx, ly, lz)
        angular_velocity[w, i, 0] = ox
        angular_velocity[w, i, 1] = oy
        angular_velocity[w, i, 2] = oz


@kernel
def place_attached(w, position, orientation, velocity, angular_momentum, angular_velocity,
                   rotation, parent, offset_position, offset_orientation):
    """Put every body of world w that is attached (parent (B, n) int32 >= 0) at its offset
    from its parent (offset_position (B, n, 3) m in the parent's frame, offset_orientation
    (B, n, 4) relative quaternion), moving with the parent's velocity and not turning."""
    for i in range(position.shape[1]):
        p = parent[w, i]
        if p < 0:
            continue
        r = rotation[w, p]
        d = offset_position[w, i]
        for c in range(3):
            position[w, i, c] = position[w, p, c] + r[c, 0] * d[0] + r[c, 1] * d[1] + r[c, 2] * d[2]
            velocity[w, i, c] = velocity[w, p, c]
            angular_velocity[w, i, c] = 0.0
            angular_momentum[w, i, c] = 0.0
        a, b, q = orientation[w, p], offset_orientation[w, i], orientation[w, i]
        q[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3]
        q[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2]
        q[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1]
        q[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]
        normalize_quaternion(q)
        rotation_from_quaternion(q, rotation[w, i])
