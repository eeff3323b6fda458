"""Box against box in closed form: separating axes, then face clipping or edge-edge.

Sampled signed distances are ambiguous for boxes stacked face to face: a corner of the upper
box lies exactly on a vertical edge of the lower one, where the nearest face is a side face,
so the sampled normal points sideways. The separating-axis test has no such tie: of the 15
axes (3 face normals of each box, 9 edge-edge cross products) the one of least overlap is the
contact normal. For a face axis, the most anti-parallel face of the other box is clipped
against the reference face's side planes (Sutherland-Hodgman), giving up to 8 points below the
reference face; for an edge axis, the closest points of the two edges give one contact.
Face axes win near-ties (``FACE_PREFERENCE_*``), so resting stacks get stable face contacts.
"""

import math

import numpy as np

from rigid_gym.kernels.jit import kernel

FACE_PREFERENCE_RELATIVE = 0.05
FACE_PREFERENCE_ABSOLUTE = 1e-6
"""An edge axis is chosen only if its overlap is smaller than the best face axis's by more than
5% + 1 micrometre (and B's faces must beat A's likewise): near-ties go to the stable face."""
EDGE_PARALLEL = 1e-9
"""Edge pairs with |e_a x e_b| below this are parallel: their axis is left to the face axes."""


@kernel
def preference(separation):
    """How much better (m) an axis must be than one with ``separation`` to replace it."""
    if separation == -np.inf:
        return 0.0
    return FACE_PREFERENCE_RELATIVE * abs(separation) + FACE_PREFERENCE_ABSOLUTE


@kernel
def box_extent_along(r, h, ax, ay, az):
    """Half-width of a box (rotation r (3, 3), half extents h (3,)) along unit axis a."""
    return (h[0] * abs(r[0, 0] * ax + r[1, 0] * ay + r[2, 0] * az)
            + h[1] * abs(r[0, 1] * ax + r[1, 1] * ay + r[2, 1] * az)
            + h[2] * abs(r[0, 2] * ax + r[1, 2] * ay + r[2, 2] * az))


@kernel
def clip_polygon(poly, count, nx, ny, nz, offset, out):
    """Keep the part of the polygon poly[:count] (rows x, y, z) with n.p <= offset; writes it to
    out and returns its vertex count (Sutherland-Hodgman, one plane)."""
    kept = 0
    for k in range(count):
        j = (k + 1) % count
        dk = nx * poly[k, 0] + ny * poly[k, 1] + nz * poly[k, 2] - offset
        dj = nx * poly[j, 0] + ny * poly[j, 1] + nz * poly[j, 2] - offset
        if dk <= 0.0:
            for c in range(3):
                out[kept, c] = poly[k, c]
            kept += 1
        if (dk < 0.0 < dj) or (dj < 0.0 < dk):
            t = dk / (dk - dj)
            for c in range(3):
                out[kept, c] = poly[k, c] + t * (poly[j, c] - poly[k, c])
            kept += 1
    return kept


@kernel
def collide_boxes(xa, ra, ha, xb, rb, hb, margin, points, normals, depths, index, capacity,
                  scratch):
    """Contacts of box A (centre xa (3,), rotation ra (3, 3), half extents ha (3,)) with box B.

    Normals point from B to A; each point is a point of one box inside the other. scratch:
    (2, 16, 3) float64 work space. Returns the number of contacts found (written while
    index < capacity). margin: m, report contacts deeper than -margin.
    """
    dx, dy, dz = xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]
    best_sep = -np.inf
    best_axis = -1
    bx = by = bz = 0.0
    # face axes: 0-2 of A, 3-5 of B
    for k in range(6):
        r = ra if k < 3 else rb
        c = k % 3
        ux, uy, uz = r[0, c], r[1, c], r[2, c]
        dist = dx * ux + dy * uy + dz * uz
        sep = abs(dist) - box_extent_along(ra, ha, ux, uy, uz) - box_extent_along(rb, hb, ux, uy, uz)
        if sep > margin:
            return 0
        bias = preference(best_sep) if k >= 3 else 0.0
        if sep > best_sep + bias:
            s = 1.0 if dist >= 0.0 else -1.0
            best_sep, best_axis, bx, by, bz = sep, k, s * ux, s * uy, s * uz
    face_sep = best_sep
    # edge-edge axes
    for i in range(3):
        for j in range(3):
            ux = ra[1, i] * rb[2, j] - ra[2, i] * rb[1, j]
            uy = ra[2, i] * rb[0, j] - ra[0, i] * rb[2, j]
            uz = ra[0, i] * rb[1, j] - ra[1, i] * rb[0, j]
            length = math.sqrt(ux * ux + uy * uy + uz * uz)
            if length < EDGE_PARALLEL:
                continue
            ux, uy, uz = ux / length, uy / length, uz / length
            dist = dx * ux + dy * uy + dz * uz
            sep = abs(dist) - box_extent_along(ra, ha, ux, uy, uz) - box_extent_along(rb, hb, ux, uy, uz)
            if sep > margin:
                return 0
            if sep > best_sep and sep > face_sep + preference(face_sep):
                s = 1.0 if dist >= 0.0 else -1.0
                best_sep, best_axis, bx, by, bz = sep, 6 + 3 * i + j, s * ux, s * uy, s * uz
    if best_axis >= 6:
        return edge_contact(xa, ra, ha, xb, rb, hb, (best_axis - 6) // 3, (best_axis - 6) % 3,
                            bx, by, bz, best_sep, points, normals, depths, index, capacity)
    if best_axis < 3:
        # reference face on A; normal (B to A) is -axis from A's view: the axis points B->A
        return face_contact(xa, ra, ha, xb, rb, hb, best_axis, -bx, -by, -bz, margin, -1.0,
                            points, normals, depths, index, capacity, scratch)
    return face_contact(xb, rb, hb, xa, ra, ha, best_axis - 3, bx, by, bz, margin, 1.0,
                        points, normals, depths, index, capacity, scratch)


@kernel
def face_contact(xr, rr, hr, xi, ri, hi, axis, nx, ny, nz, margin, sign, points, normals,
                 depths, index, capacity, scratch):
    """Clip the incident box's face against the reference box's face ``axis`` whose outward
    normal (towards the incident box) is n. Contact points are incident-face points below the
    reference face; their normals are sign * n (sign = +1 when the incident box is A)."""
    # incident face: the face of the incident box most anti-parallel to n
    best = np.inf
    face_axis, face_sign = 0, 1.0
    for c in range(3):
        dot = ri[0, c] * nx + ri[1, c] * ny + ri[2, c] * nz
        if dot < best:
            best, face_axis, face_sign = dot, c, 1.0
        if -dot < best:
            best, face_axis, face_sign = -dot, c, -1.0
    u, v = (face_axis + 1) % 3, (face_axis + 2) % 3
    poly = scratch[0]
    corner_u = (1.0, -1.0, -1.0, 1.0)
    corner_v = (1.0, 1.0, -1.0, -1.0)
    for k in range(4):
        for c in range(3):
            poly[k, c] = (xi[c] + ri[c, face_axis] * face_sign * hi[face_axis]
                          + ri[c, u] * corner_u[k] * hi[u] + ri[c, v] * corner_v[k] * hi[v])
    count = 4
    # clip against the 4 side planes of the reference face
    src, dst = scratch[0], scratch[1]
    ru, rv = (axis + 1) % 3, (axis + 2) % 3
    for side in range(4):
        c = ru if side < 2 else rv
        s = 1.0 if side % 2 == 0 else -1.0
        px, py, pz = s * rr[0, c], s * rr[1, c], s * rr[2, c]
        offset = px * xr[0] + py * xr[1] + pz * xr[2] + hr[c]
        count = clip_polygon(src, count, px, py, pz, offset, dst)
        src, dst = dst, src
        if count == 0:
            return 0
    # keep the points below the reference face
    face_offset = nx * xr[0] + ny * xr[1] + nz * xr[2] + hr[axis]
    found = 0
    for k in range(count):
        depth = face_offset - (nx * src[k, 0] + ny * src[k, 1] + nz * src[k, 2])
        if depth > -margin:
            at = index + found
            if at < capacity:
                for c in range(3):
                    points[at, c] = src[k, c]
                normals[at, 0], normals[at, 1], normals[at, 2] = sign * nx, sign * ny, sign * nz
                depths[at] = depth
            found += 1
    return found


@kernel
def edge_contact(xa, ra, ha, xb, rb, hb, i, j, nx, ny, nz, sep, points, normals, depths, index,
                 capacity):
    """One contact for an edge-edge axis n (from B to A): the point of A's edge (along its axis
    i) closest to B's edge (along axis j), the two edges being the ones facing each other."""
    # A's edge: the one whose corner is furthest along -n; B's: furthest along +n
    pax, pay, paz = xa[0], xa[1], xa[2]
    pbx, pby, pbz = xb[0], xb[1], xb[2]
    for c in range(3):
        if c != i:
            s = -ha[c] if ra[0, c] * nx + ra[1, c] * ny + ra[2, c] * nz > 0.0 else ha[c]
            pax, pay, paz = pax + s * ra[0, c], pay + s * ra[1, c], paz + s * ra[2, c]
        if c != j:
            s = hb[c] if rb[0, c] * nx + rb[1, c] * ny + rb[2, c] * nz > 0.0 else -hb[c]
            pbx, pby, pbz = pbx + s * rb[0, c], pby + s * rb[1, c], pbz + s * rb[2, c]
    # closest points of the lines pa + s ua and pb + t ub, clamped to the edges
    ua = (ra[0, i], ra[1, i], ra[2, i])
    ub = (rb[0, j], rb[1, j], rb[2, j])
    wx, wy, wz = pax - pbx, pay - pby, paz - pbz
    b = ua[0] * ub[0] + ua[1] * ub[1] + ua[2] * ub[2]
    d = ua[0] * wx + ua[1] * wy + ua[2] * wz
    e = ub[0] * wx + ub[1] * wy + ub[2] * wz
    denom = 1.0 - b * b
    s = (b * e - d) / denom if denom > 1e-12 else 0.0
    s = min(max(s, -ha[i]), ha[i])
    if index < capacity:
        points[index, 0] = pax + s * ua[0]
        points[index, 1] = pay + s * ua[1]
        points[index, 2] = paz + s * ua[2]
        normals[index, 0], normals[index, 1], normals[index, 2] = nx, ny, nz
        depths[index] = -sep
    return 1
