"""Resting contact over a patch: one impulse and one angular impulse for a face or an edge.

A box standing on an incline needs friction at its base *and* a shift of pressure downhill
to balance the moment that friction makes about its centre of mass. Point impulses, or one
impulse at a fixed point, can only reach that balance over many passes and leave the box
rocking. Here a patch (contacts of one pair with a common normal, see ``solver.resolve_pair``)
gets the wrench (j, m) at its centroid c that does it in one go:

    unknowns   j (3) and m along the patch's constrained rotations D:
               a face: tip about t1, t2 and spin about n; an edge (collinear points) with
               direction e: tip about n x e and spin about n; a single point: none
    targets    relative velocity at c: -v - e v_n n (the notes' static impulse, slide 21),
               relative angular velocity along D: tip -(1 + e) Omega.d, spin -Omega.n
    matrix     [dv; dOmega] = A [j; m],  A = sum over movable bodies of
               [[1/M + r*^T W r*, r*^T W], [W r*, W]],  W = I(t)^-1, r = c - X

It is accepted only if physically admissible: j.n > 0; and, for the patch's total over the
step so far (the impulse F its pairs already transmitted plus j, the earlier part taken as
acting at c): |F_t| <= mu F_n (Coulomb cone), |m.n| <= mu F_n rho (torsional friction; rho:
the points' mean distance from c), and the centre of pressure c + n x m_t / F_n lies within
the patch. If friction cannot hold, the
sliding wrench is tried: j = j_n (n - mu T) (slides 22-23) with only the tip constraints, and
torsional friction applied afterwards within its limit. If the centre of pressure would leave
the patch the body is tipping over an edge, and the caller falls back to a single impulse.
"""

import math

from rigid_gym.kernels.jit import kernel
from rigid_gym.kernels.quaternion import apply_inverse_inertia, cross

POINT = 0
EDGE = 1
FACE = 2

APPLIED = 0
SEPARATING = 1
UNRESOLVED = 2
"""Outcomes of ``resolve_patch``."""
COLLINEAR = 1e-6
"""A patch is an edge when its smaller in-plane spread is below this fraction of its larger."""
REST_SPEED = 1e-9
"""m/s: contacts approaching slower than this are at rest and get no impulse. An exact
resolve leaves round-off (about 1e-17 m/s) behind; without a floor every later pass would
apply a round-off impulse and count as work done, so the passes never stopped early (a cube
resting on the table used all 10 contact passes). Gravity alone brings 0.04 m/s per step of
1/240 s, so nothing below the floor can build up; 1e-9 m/s is 1 nm of drift in 1 s."""
SINGULAR = 1e-12
"""Pivots below this fraction of the largest diagonal entry mean an unsolvable system."""


@kernel
def tangent_basis(nx, ny, nz):
    """Two unit vectors completing n to a right-handed orthonormal frame (t1, t2, n)."""
    if abs(nx) < 0.57735:
        ax, ay, az = 1.0, 0.0, 0.0
    else:
        ax, ay, az = 0.0, 1.0, 0.0
    t1x, t1y, t1z = cross(ax, ay, az, nx, ny, nz)
    norm = math.sqrt(t1x * t1x + t1y * t1y + t1z * t1z)
    t1x, t1y, t1z = t1x / norm, t1y / norm, t1z / norm
    t2x, t2y, t2z = cross(nx, ny, nz, t1x, t1y, t1z)
    return t1x, t1y, t1z, t2x, t2y, t2z


@kernel
def add_body_wrench_matrix(inverse_mass, rotation, inverse_moments, rx, ry, rz, a, work):
    """a (6, 6) += [[1/M + r*^T W r*, r*^T W], [W r*, W]] for one body, lever r, W = I(t)^-1.
    work: (2, 3, 3) scratch."""
    w = work[0]
    wr = work[1]  # W r*
    for i in range(3):
        for j in range(3):
            w[i, j] = (rotation[i, 0] * inverse_moments[0] * rotation[j, 0]
                       + rotation[i, 1] * inverse_moments[1] * rotation[j, 1]
                       + rotation[i, 2] * inverse_moments[2] * rotation[j, 2])
    for i in range(3):
        # (W r*) e_j = W (r x e_j): r x e_x = (0, rz, -ry), r x e_y = (-rz, 0, rx), r x e_z = (ry, -rx, 0)
        wr[i, 0] = w[i, 1] * rz - w[i, 2] * ry
        wr[i, 1] = -w[i, 0] * rz + w[i, 2] * rx
        wr[i, 2] = w[i, 0] * ry - w[i, 1] * rx
    for j in range(3):
        # r*^T x = -r x x = x x r, applied to the columns of W r* and of W
        c0, c1, c2 = cross(wr[0, j], wr[1, j], wr[2, j], rx, ry, rz)
        a[0, j] += c0
        a[1, j] += c1
        a[2, j] += c2
        d0, d1, d2 = cross(w[0, j], w[1, j], w[2, j], rx, ry, rz)
        a[0, 3 + j] += d0
        a[1, 3 + j] += d1
        a[2, 3 + j] += d2
        for i in range(3):
            a[3 + i, j] += wr[i, j]
            a[3 + i, 3 + j] += w[i, j]
        a[j, j] += inverse_mass


@kernel
def solve_dense(m, rhs, size, out):
    """Solve m[:size, :size] x = rhs[:size] by Gaussian elimination with partial pivoting
    (m and rhs are overwritten); returns False for a (near-)singular matrix."""
    scale = 0.0
    for i in range(size):
        scale = max(scale, abs(m[i, i]))
    if scale == 0.0:
        return False
    for col in range(size):
        pivot = col
        for row in range(col + 1, size):
            if abs(m[row, col]) > abs(m[pivot, col]):
                pivot = row
        if abs(m[pivot, col]) <= SINGULAR * scale:
            return False
        if pivot != col:
            for k in range(size):
                m[col, k], m[pivot, k] = m[pivot, k], m[col, k]
            rhs[col], rhs[pivot] = rhs[pivot], rhs[col]
        for row in range(col + 1, size):
            f = m[row, col] / m[col, col]
            for k in range(col, size):
                m[row, k] -= f * m[col, k]
            rhs[row] -= f * rhs[col]
    for row in range(size - 1, -1, -1):
        acc = rhs[row]
        for k in range(row + 1, size):
            acc -= m[row, k] * out[k]
        out[row] = acc / m[row, row]
    return True


@kernel(inline=True)
def centre_of_pressure_inside(scratch, seed, count, cx, cy, cz, dx, dy, dz):
    """True when the centre of pressure c + d lies within the patch (its support along d reaches
    |d|; exact for the segments and rectangles of box faces and edges up to a slight leniency
    near the corners of a rectangle)."""
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if length == 0.0:
        return True
    reach = 0.0
    for i in range(seed, count):
        if scratch.group[i] == seed:
            p = scratch.point[i]
            reach = max(reach, ((p[0] - cx) * dx + (p[1] - cy) * dy + (p[2] - cz) * dz) / length)
    return length <= reach


@kernel(inline=True)
def patch_shape(scratch, seed, count, cx, cy, cz, t1x, t1y, t1z, t2x, t2y, t2z):
    """Kind of the patch (POINT, EDGE or FACE), its direction (for an edge) and the mean
    distance of its points from the centroid c."""
    sxx = sxy = syy = 0.0
    radius = 0.0
    m = 0
    for i in range(seed, count):
        if scratch.group[i] == seed:
            p = scratch.point[i]
            qx, qy, qz = p[0] - cx, p[1] - cy, p[2] - cz
            u = qx * t1x + qy * t1y + qz * t1z
            v = qx * t2x + qy * t2y + qz * t2z
            sxx += u * u
            sxy += u * v
            syy += v * v
            radius += math.sqrt(qx * qx + qy * qy + qz * qz)
            m += 1
    radius /= m
    # eigenvalues of the in-plane spread [[sxx, sxy], [sxy, syy]]
    mean = 0.5 * (sxx + syy)
    half_gap = math.sqrt(0.25 * (sxx - syy) ** 2 + sxy * sxy)
    big, small = mean + half_gap, mean - half_gap
    if big <= 0.0 or radius == 0.0:
        return POINT, 0.0, 0.0, 0.0, radius
    if small > COLLINEAR * big:
        return FACE, 0.0, 0.0, 0.0, radius
    angle = 0.5 * math.atan2(2.0 * sxy, sxx - syy)
    ca, sa = math.cos(angle), math.sin(angle)
    return EDGE, ca * t1x + sa * t2x, ca * t1y + sa * t2y, ca * t1z + sa * t2z, radius


@kernel(inline=True)
def apply_wrench(state, model, w, i, sign, jx, jy, jz, mx, my, mz, rx, ry, rz):
    """sign * (j at lever r, plus angular impulse m) on body i: V += j/M, L += r x j + m."""
    inv = model.inverse_mass[w, i]
    lx, ly, lz = cross(rx, ry, rz, jx, jy, jz)
    state.velocity[w, i, 0] += sign * jx * inv
    state.velocity[w, i, 1] += sign * jy * inv
    state.velocity[w, i, 2] += sign * jz * inv
    state.angular_momentum[w, i, 0] += sign * (lx + mx)
    state.angular_momentum[w, i, 1] += sign * (ly + my)
    state.angular_momentum[w, i, 2] += sign * (lz + mz)
    ox, oy, oz = apply_inverse_inertia(state.rotation[w, i], model.inverse_moments[w, i],
                                       state.angular_momentum[w, i, 0],
                                       state.angular_momentum[w, i, 1],
                                       state.angular_momentum[w, i, 2])
    state.angular_velocity[w, i, 0] = ox
    state.angular_velocity[w, i, 1] = oy
    state.angular_velocity[w, i, 2] = oz


@kernel(inline=True)
def resolve_patch(state, model, w, a, b, movable_a, movable_b, scratch, seed, count, e, mu,
                  prior_x, prior_y, prior_z):
    """Apply the patch wrench of the module docstring to the pair (a, b) for the patch whose
    contacts have ``scratch.group == seed``. prior: the impulse the patch's pairs already
    transmitted to a this step (N s); the static wrench must keep prior + j inside the friction
    cone. Returns (outcome, linear impulse applied to a): APPLIED; SEPARATING when holding the
    patch would need a pulling impulse (j_n <= 0), or when it is at rest (its points' relative
    speeds below REST_SPEED): nothing to do; or UNRESOLVED (nothing
    applied) for a single point or a body tipping over an edge, which the caller treats with a
    single impulse."""
    # geometric centroid and mean normal of the patch
    cx = cy = cz = nx = ny = nz = 0.0
    m = 0
    for i in range(seed, count):
        if scratch.group[i] == seed:
            cx += scratch.point[i, 0]
            cy += scratch.point[i, 1]
            cz += scratch.point[i, 2]
            nx += scratch.normal[i, 0]
            ny += scratch.normal[i, 1]
            nz += scratch.normal[i, 2]
            m += 1
    if m < 2:
        return UNRESOLVED, 0.0, 0.0, 0.0
    cx, cy, cz = cx / m, cy / m, cz / m
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    nx, ny, nz = nx / norm, ny / norm, nz / norm
    t1x, t1y, t1z, t2x, t2y, t2z = tangent_basis(nx, ny, nz)
    kind, ex, ey, ez, rho = patch_shape(scratch, seed, count, cx, cy, cz, t1x, t1y, t1z,
                                        t2x, t2y, t2z)
    if kind == POINT:
        return UNRESOLVED, 0.0, 0.0, 0.0
    # constrained rotations: tip axes first, spin about n last
    d = scratch.directions
    if kind == FACE:
        tips = 2
        d[0, 0], d[0, 1], d[0, 2] = t1x, t1y, t1z
        d[1, 0], d[1, 1], d[1, 2] = t2x, t2y, t2z
    else:
        tips = 1
        d[0, 0], d[0, 1], d[0, 2] = cross(nx, ny, nz, ex, ey, ez)
    d[tips, 0], d[tips, 1], d[tips, 2] = nx, ny, nz
    # relative velocity at c and relative angular velocity
    rax, ray, raz = cx - scratch.position[a, 0], cy - scratch.position[a, 1], cz - scratch.position[a, 2]
    rbx, rby, rbz = cx - scratch.position[b, 0], cy - scratch.position[b, 1], cz - scratch.position[b, 2]
    vx, vy, vz = relative_point_velocity(state, w, a, b, rax, ray, raz, rbx, rby, rbz)
    vn = vx * nx + vy * ny + vz * nz
    wx = state.angular_velocity[w, a, 0] - state.angular_velocity[w, b, 0]
    wy = state.angular_velocity[w, a, 1] - state.angular_velocity[w, b, 1]
    wz = state.angular_velocity[w, a, 2] - state.angular_velocity[w, b, 2]
    if max(abs(vx), abs(vy), abs(vz), rho * max(abs(wx), abs(wy), abs(wz))) < REST_SPEED:
        return SEPARATING, 0.0, 0.0, 0.0  # at rest: nothing to do
    big = scratch.wrench
    big[:, :] = 0.0
    if movable_a:
        add_body_wrench_matrix(model.inverse_mass[w, a], state.rotation[w, a],
                               model.inverse_moments[w, a], rax, ray, raz, big, scratch.work)
    if movable_b:
        add_body_wrench_matrix(model.inverse_mass[w, b], state.rotation[w, b],
                               model.inverse_moments[w, b], rbx, rby, rbz, big, scratch.work)
    sol = scratch.solution
    if mu > 0.0:
        # static: j (3) and m along every constrained rotation
        size = 3 + tips + 1
        reduced_system(big, d, tips + 1, scratch.system)
        rhs = scratch.rhs
        rhs[0], rhs[1], rhs[2] = -vx - e * vn * nx, -vy - e * vn * ny, -vz - e * vn * nz
        for k in range(tips + 1):
            spin = wx * d[k, 0] + wy * d[k, 1] + wz * d[k, 2]
            rhs[3 + k] = -spin if k == tips else -(1.0 + e) * spin
        if solve_dense(scratch.system, rhs, size, sol):
            jx, jy, jz = sol[0], sol[1], sol[2]
            jn = jx * nx + jy * ny + jz * nz
            mx, my, mz = moment(d, sol, 3, tips + 1)
            mn = mx * nx + my * ny + mz * nz
            if jn <= 0.0:
                return SEPARATING, 0.0, 0.0, 0.0
            # Coulomb on the step's total through this patch
            fx, fy, fz = prior_x + jx, prior_y + jy, prior_z + jz
            fn = fx * nx + fy * ny + fz * nz
            tx, ty, tz = fx - fn * nx, fy - fn * ny, fz - fn * nz
            if (math.sqrt(tx * tx + ty * ty + tz * tz) <= mu * fn and abs(mn) <= mu * fn * rho
                    and pressure_inside(scratch, seed, count, cx, cy, cz, nx, ny, nz,
                                        mx - mn * nx, my - mn * ny, mz - mn * nz, fn)):
                apply_pair(state, model, w, a, b, movable_a, movable_b, jx, jy, jz, mx, my, mz,
                           rax, ray, raz, rbx, rby, rbz)
                return APPLIED, jx, jy, jz
    # sliding (or frictionless): j = j_n s, s = n - mu T, with the tip constraints only
    ux, uy, uz = vx - vn * nx, vy - vn * ny, vz - vn * nz
    ut = math.sqrt(ux * ux + uy * uy + uz * uz)
    friction = mu if ut > 0.0 else 0.0
    sx, sy, sz = nx, ny, nz
    if friction > 0.0:
        sx, sy, sz = nx - friction * ux / ut, ny - friction * uy / ut, nz - friction * uz / ut
    sliding_system(big, d, tips, sx, sy, sz, nx, ny, nz, scratch.system)
    rhs = scratch.rhs
    rhs[0] = -(1.0 + e) * vn
    for k in range(tips):
        rhs[1 + k] = -(1.0 + e) * (wx * d[k, 0] + wy * d[k, 1] + wz * d[k, 2])
    if not solve_dense(scratch.system, rhs, 1 + tips, sol):
        return UNRESOLVED, 0.0, 0.0, 0.0
    jn = sol[0]
    mx, my, mz = moment(d, sol, 1, tips)
    if jn <= 0.0:
        return SEPARATING, 0.0, 0.0, 0.0
    fn = jn + prior_x * nx + prior_y * ny + prior_z * nz
    if not pressure_inside(scratch, seed, count, cx, cy, cz, nx, ny, nz, mx, my, mz, fn):
        return UNRESOLVED, 0.0, 0.0, 0.0
    apply_pair(state, model, w, a, b, movable_a, movable_b, jn * sx, jn * sy, jn * sz, mx, my, mz,
               rax, ray, raz, rbx, rby, rbz)
    if mu > 0.0:
        spin_friction(state, model, w, a, b, movable_a, movable_b, nx, ny, nz, mu * jn * rho)
    return APPLIED, jn * sx, jn * sy, jn * sz


@kernel(inline=True)
def relative_point_velocity(state, w, a, b, rax, ray, raz, rbx, rby, rbz):
    """(V_a + w_a x r_a) - (V_b + w_b x r_b); a 3-tuple."""
    pa = cross(state.angular_velocity[w, a, 0], state.angular_velocity[w, a, 1],
               state.angular_velocity[w, a, 2], rax, ray, raz)
    pb = cross(state.angular_velocity[w, b, 0], state.angular_velocity[w, b, 1],
               state.angular_velocity[w, b, 2], rbx, rby, rbz)
    return (state.velocity[w, a, 0] + pa[0] - state.velocity[w, b, 0] - pb[0],
            state.velocity[w, a, 1] + pa[1] - state.velocity[w, b, 1] - pb[1],
            state.velocity[w, a, 2] + pa[2] - state.velocity[w, b, 2] - pb[2])


@kernel
def reduced_system(big, d, k, out):
    """out[:3+k, :3+k] = [[A_vv, A_vm D], [D^T A_mv, D^T A_mm D]] for the rows d[:k] of D."""
    for i in range(3):
        for j in range(3):
            out[i, j] = big[i, j]
        for c in range(k):
            out[i, 3 + c] = big[i, 3] * d[c, 0] + big[i, 4] * d[c, 1] + big[i, 5] * d[c, 2]
            out[3 + c, i] = d[c, 0] * big[3, i] + d[c, 1] * big[4, i] + d[c, 2] * big[5, i]
    for r in range(k):
        for c in range(k):
            acc = 0.0
            for i in range(3):
                for j in range(3):
                    acc += d[r, i] * big[3 + i, 3 + j] * d[c, j]
            out[3 + r, 3 + c] = acc
    return out


@kernel
def sliding_system(big, d, k, sx, sy, sz, nx, ny, nz, out):
    """The (1 + k) square system for j = j_n s and m = sum mu_c d_c: the normal row
    n^T dv and the rows d_r^T dOmega."""
    # columns: j_n (through s), then mu_c (through d_c); rows: n^T dv, then d_r^T dOmega
    for row in range(1 + k):
        for col in range(1 + k):
            acc = 0.0
            for i in range(3):
                left = (nx, ny, nz)[i] if row == 0 else d[row - 1, i]
                li = i if row == 0 else 3 + i
                for j in range(3):
                    right = (sx, sy, sz)[j] if col == 0 else d[col - 1, j]
                    lj = j if col == 0 else 3 + j
                    acc += left * big[li, lj] * right
            out[row, col] = acc
    return out


@kernel
def moment(d, sol, first, k):
    """m = sum over c < k of sol[first + c] d_c (the solved coefficients of the constrained
    rotations); a 3-tuple."""
    mx = my = mz = 0.0
    for c in range(k):
        mx += sol[first + c] * d[c, 0]
        my += sol[first + c] * d[c, 1]
        mz += sol[first + c] * d[c, 2]
    return mx, my, mz


@kernel(inline=True)
def pressure_inside(scratch, seed, count, cx, cy, cz, nx, ny, nz, mx, my, mz, jn):
    """Is the centre of pressure c + n x m_t / j_n (m_t: the tip moment) within the patch?"""
    dx, dy, dz = cross(nx, ny, nz, mx / jn, my / jn, mz / jn)
    return centre_of_pressure_inside(scratch, seed, count, cx, cy, cz, dx, dy, dz)


@kernel(inline=True)
def apply_pair(state, model, w, a, b, movable_a, movable_b, jx, jy, jz, mx, my, mz,
               rax, ray, raz, rbx, rby, rbz):
    """The wrench (j, m) on a and its opposite on b (movable bodies only)."""
    if movable_a:
        apply_wrench(state, model, w, a, 1.0, jx, jy, jz, mx, my, mz, rax, ray, raz)
    if movable_b:
        apply_wrench(state, model, w, b, -1.0, jx, jy, jz, mx, my, mz, rbx, rby, rbz)


@kernel(inline=True)
def spin_friction(state, model, w, a, b, movable_a, movable_b, nx, ny, nz, limit):
    """Angular impulse t n on a (and -t n on b) that stops their relative spin about n,
    |t| <= limit (N m s): torsional friction of a patch."""
    spin = ((state.angular_velocity[w, a, 0] - state.angular_velocity[w, b, 0]) * nx
            + (state.angular_velocity[w, a, 1] - state.angular_velocity[w, b, 1]) * ny
            + (state.angular_velocity[w, a, 2] - state.angular_velocity[w, b, 2]) * nz)
    compliance = 0.0
    if movable_a:
        ix, iy, iz = apply_inverse_inertia(state.rotation[w, a], model.inverse_moments[w, a], nx, ny, nz)
        compliance += ix * nx + iy * ny + iz * nz
    if movable_b:
        ix, iy, iz = apply_inverse_inertia(state.rotation[w, b], model.inverse_moments[w, b], nx, ny, nz)
        compliance += ix * nx + iy * ny + iz * nz
    if compliance <= 0.0:
        return
    t = min(max(-spin / compliance, -limit), limit)
    apply_pair(state, model, w, a, b, movable_a, movable_b, 0.0, 0.0, 0.0, t * nx, t * ny, t * nz,
               0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
