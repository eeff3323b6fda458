"""The collision impulse at one contact point (course notes slides 17-23).

At contact point x with normal n (from body 2 to body 1), r_i = x - X_i and
    K_i = (1/M_i) 1 + r_i*^T I_i^-1 r_i*        (slide 19; zero for an infinite mass)
the relative velocity v = v_1 - v_2 (v_i = V_i + omega_i x r_i), v_n = v.n. Only approaching
contacts (v_n < 0) get an impulse j, +j on body 1 and -j on body 2:
    frictionless      j = -(1 + e) v_n / (n^T K n) n                          (slide 19)
    static friction   j = K^-1 (-v - e v_n n)   if |j_t| <= mu j_n (the cone)  (slides 20-21)
    sliding friction  j = j_n (n - mu T), T = v_t / |v_t|,
                      j_n = -(1 + e) v_n / (n^T K (n - mu T))                  (slides 22-23)
with K = K_1 + K_2. A non-positive sliding denominator (large mu with coupling, a
Painleve-type case) falls back to the static impulse, which always removes the approach. (In
the plane of n and T such a denominator implies the static impulse is inside the cone, so the
sliding branch is not reached there; tests/test_impulse.py.)
Applying j (``patch.apply_pair``): V += j / M, L += r x j, omega = I(t)^-1 L (slide 18).
"""

import math

from rigid_gym.kernels.jit import kernel
from rigid_gym.kernels.quaternion import apply_inverse_inertia, cross


@kernel
def add_point_mass_matrix(inverse_mass, rotation, inverse_moments, rx, ry, rz, k):
    """k (3, 3) += (1/M) 1 + r*^T I^-1 r*: column c is e_c / M + (I^-1 (r x e_c)) x r."""
    for c in range(3):
        ex = 1.0 if c == 0 else 0.0
        ey = 1.0 if c == 1 else 0.0
        ez = 1.0 if c == 2 else 0.0
        cx, cy, cz = cross(rx, ry, rz, ex, ey, ez)
        ix, iy, iz = apply_inverse_inertia(rotation, inverse_moments, cx, cy, cz)
        tx, ty, tz = cross(ix, iy, iz, rx, ry, rz)
        k[0, c] += tx
        k[1, c] += ty
        k[2, c] += tz
        k[c, c] += inverse_mass


@kernel
def solve3(k, bx, by, bz):
    """k^-1 b for a symmetric positive definite (3, 3) k (adjugate / determinant)."""
    a00, a01, a02 = k[0, 0], k[0, 1], k[0, 2]
    a11, a12, a22 = k[1, 1], k[1, 2], k[2, 2]
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    return ((c00 * bx + c01 * by + c02 * bz) / det,
            (c01 * bx + c11 * by + c12 * bz) / det,
            (c02 * bx + c12 * by + c22 * bz) / det)


@kernel
def contact_impulse(k, vx, vy, vz, nx, ny, nz, e, mu):
    """Impulse (3-tuple, N s) on body 1 that resolves relative velocity v along normal n with
    restitution e (may be negative in the contact phase: it then only slows the approach) and
    friction coefficient mu, given the summed matrix k (3, 3). v_n must be < 0."""
    vn = vx * nx + vy * ny + vz * nz
    if mu == 0.0:
        knn = (nx * (k[0, 0] * nx + k[0, 1] * ny + k[0, 2] * nz)
               + ny * (k[1, 0] * nx + k[1, 1] * ny + k[1, 2] * nz)
               + nz * (k[2, 0] * nx + k[2, 1] * ny + k[2, 2] * nz))
        jn = -(1.0 + e) * vn / knn
        return jn * nx, jn * ny, jn * nz
    # static friction: the impulse that leaves -e v_n n
    jx, jy, jz = solve3(k, -vx - e * vn * nx, -vy - e * vn * ny, -vz - e * vn * nz)
    jn = jx * nx + jy * ny + jz * nz
    tx, ty, tz = jx - jn * nx, jy - jn * ny, jz - jn * nz
    jt = math.sqrt(tx * tx + ty * ty + tz * tz)
    if jt <= mu * jn:
        return jx, jy, jz
    # sliding: friction opposes the tangential velocity (or, if there is none, the static
    # impulse's tangential part shows the direction it would slide; if that is zero too, the
    # static impulse failed by pulling (j_n < 0) and friction has nothing to act on)
    ux, uy, uz = vx - vn * nx, vy - vn * ny, vz - vn * nz
    scale = max(abs(ux), abs(uy), abs(uz))  # normalise u / scale: |u|^2 may underflow
    if scale > 0.0:
        ux, uy, uz = ux / scale, uy / scale, uz / scale
        ut = math.sqrt(ux * ux + uy * uy + uz * uz)
        tx, ty, tz = ux / ut, uy / ut, uz / ut
    elif jt > 0.0:
        tx, ty, tz = -tx / jt, -ty / jt, -tz / jt
    else:
        tx = ty = tz = 0.0
    dx, dy, dz = nx - mu * tx, ny - mu * ty, nz - mu * tz
    denom = (nx * (k[0, 0] * dx + k[0, 1] * dy + k[0, 2] * dz)
             + ny * (k[1, 0] * dx + k[1, 1] * dy + k[1, 2] * dz)
             + nz * (k[2, 0] * dx + k[2, 1] * dy + k[2, 2] * dz))
    if denom <= 0.0:
        return jx, jy, jz
    jn = -(1.0 + e) * vn / denom
    return jn * dx, jn * dy, jn * dz
