"""Scalar quaternion and small-vector helpers for kernels (no allocation, no np.dot).

Quaternions are (w, x, y, z) stored in float64 arrays of length 4; rotation matrices are (3, 3)
arrays whose columns are the rotated body axes (course notes, slide 15).
"""

import math

from rigid_gym.kernels.jit import kernel


@kernel
def cross(ax, ay, az, bx, by, bz):
    """a x b for vectors given by components; returns a 3-tuple."""
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@kernel
def normalize_quaternion(q):
    """Divide q (4,) by its norm in place."""
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    q[0] /= n
    q[1] /= n
    q[2] /= n
    q[3] /= n


@kernel
def rotation_from_quaternion(q, out):
    """Write the rotation matrix of unit quaternion q (4,) into out (3, 3) (slide 15)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    out[0, 0] = 1.0 - 2.0 * (y * y + z * z)
    out[0, 1] = 2.0 * (x * y - w * z)
    out[0, 2] = 2.0 * (x * z + w * y)
    out[1, 0] = 2.0 * (x * y + w * z)
    out[1, 1] = 1.0 - 2.0 * (x * x + z * z)
    out[1, 2] = 2.0 * (y * z - w * x)
    out[2, 0] = 2.0 * (x * z - w * y)
    out[2, 1] = 2.0 * (y * z + w * x)
    out[2, 2] = 1.0 - 2.0 * (x * x + y * y)


@kernel
def rotate_by_angular_velocity(q, wx, wy, wz, h):
    """q <- (cos|h w/2|, sin|h w/2| w/|w|) q, then renormalise (slide 13).

    q: (4,) unit quaternion, updated in place; w: angular velocity, rad/s (world); h: time, s.
    Exact for an angular velocity that is constant over h.
    """
    speed = math.sqrt(wx * wx + wy * wy + wz * wz)
    if speed == 0.0:
        return
    half_angle = 0.5 * h * speed
    c = math.cos(half_angle)
    s = math.sin(half_angle) / speed
    dw, dx, dy, dz = c, s * wx, s * wy, s * wz
    w, x, y, z = q[0], q[1], q[2], q[3]
    q[0] = dw * w - dx * x - dy * y - dz * z
    q[1] = dw * x + dx * w + dy * z - dz * y
    q[2] = dw * y - dx * z + dy * w + dz * x
    q[3] = dw * z + dx * y - dy * x + dz * w
    normalize_quaternion(q)


@kernel
def apply_inverse_inertia(rotation, inverse_moments, vx, vy, vz):
    """I(t)^-1 v = R diag(inverse_moments) R^T v (slide 3); returns a 3-tuple.

    rotation: (3, 3) body-to-world; inverse_moments: (3,) 1/kg m^2 (0 on degenerate axes).
    """
    r = rotation
    bx = (r[0, 0] * vx + r[1, 0] * vy + r[2, 0] * vz) * inverse_moments[0]
    by = (r[0, 1] * vx + r[1, 1] * vy + r[2, 1] * vz) * inverse_moments[1]
    bz = (r[0, 2] * vx + r[1, 2] * vy + r[2, 2] * vz) * inverse_moments[2]
    return (
        r[0, 0] * bx + r[0, 1] * by + r[0, 2] * bz,
        r[1, 0] * bx + r[1, 1] * by + r[1, 2] * bz,
        r[2, 0] * bx + r[2, 1] * by + r[2, 2] * bz,
    )
