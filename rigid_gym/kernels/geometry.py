"""Signed distances phi(p) and their gradients for every geom type (GBF 2003's representation).

A geom is one primitive of a body: its type, size and pose in the body frame live in the
``Geometry`` arrays (see ``rigid_gym.geometry``). Distances are evaluated in the geom's own
frame; phi < 0 inside, and the gradient (unit length) is the outward normal.

    SPHERE   size (r, -, -)          exact
    CAPSULE  size (r, half_length, -) exact, axis z
    BOX      size (hx, hy, hz)       exact
    MESH     a signed distance sampled on a grid, trilinear inside the grid; outside it, the
             distance to the grid box plus the value at the nearest grid point (an upper
             bound, >= the gap to the box), or, through ``geom_distance_within`` where that
             gap is small enough to matter, the exact distance to the triangles
    PLANE    the half-space z <= 0   exact
"""

import math

from rigid_gym.kernels.jit import kernel

SPHERE = 0
CAPSULE = 1
BOX = 2
MESH = 3
PLANE = 4


@kernel
def sphere_distance(radius, px, py, pz):
    """phi and unit gradient of a sphere of ``radius`` at the origin; returns (phi, nx, ny, nz)."""
    d = math.sqrt(px * px + py * py + pz * pz)
    if d == 0.0:
        return -radius, 0.0, 0.0, 1.0
    return d - radius, px / d, py / d, pz / d


@kernel
def capsule_distance(radius, half_length, px, py, pz):
    """phi and gradient of a capsule along z; returns (phi, nx, ny, nz)."""
    dz = pz - min(max(pz, -half_length), half_length)
    if px == 0.0 and py == 0.0 and dz == 0.0:
        return -radius, 1.0, 0.0, 0.0  # on the axis: any radial direction is a gradient
    return sphere_distance(radius, px, py, dz)


@kernel
def box_distance(hx, hy, hz, px, py, pz):
    """Exact phi and gradient of the box |x| <= hx, |y| <= hy, |z| <= hz."""
    qx, qy, qz = abs(px) - hx, abs(py) - hy, abs(pz) - hz
    sx = 1.0 if px >= 0.0 else -1.0
    sy = 1.0 if py >= 0.0 else -1.0
    sz = 1.0 if pz >= 0.0 else -1.0
    ox, oy, oz = max(qx, 0.0), max(qy, 0.0), max(qz, 0.0)
    outside = math.sqrt(ox * ox + oy * oy + oz * oz)
    if outside > 0.0:
        return outside, sx * ox / outside, sy * oy / outside, sz * oz / outside
    # inside: the nearest face is the one with the largest (least negative) q
    if qx >= qy and qx >= qz:
        return qx, sx, 0.0, 0.0
    if qy >= qz:
        return qy, 0.0, sy, 0.0
    return qz, 0.0, 0.0, sz


@kernel
def grid_distance(values, offset, nx, ny, nz, ox, oy, oz, h, px, py, pz):
    """phi and gradient from a sampled signed distance.

    values: flat float64 node values; the grid's nodes are values[offset + (i * ny + j) * nz + k]
    at (ox + i h, oy + j h, oz + k h), i < nx, j < ny, k < nz; h: node spacing, m.
    """
    # clamp into the grid; outside, add the distance to it and point away from it
    cx = min(max(px, ox), ox + (nx - 1) * h)
    cy = min(max(py, oy), oy + (ny - 1) * h)
    cz = min(max(pz, oz), oz + (nz - 1) * h)
    ex, ey, ez = px - cx, py - cy, pz - cz
    gap = math.sqrt(ex * ex + ey * ey + ez * ez)
    fx, fy, fz = (cx - ox) / h, (cy - oy) / h, (cz - oz) / h
    i = min(int(fx), nx - 2)
    j = min(int(fy), ny - 2)
    k = min(int(fz), nz - 2)
    tx, ty, tz = fx - i, fy - j, fz - k
    base = offset + (i * ny + j) * nz + k
    sy_, sx_ = nz, ny * nz
    c000 = values[base]
    c001 = values[base + 1]
    c010 = values[base + sy_]
    c011 = values[base + sy_ + 1]
    c100 = values[base + sx_]
    c101 = values[base + sx_ + 1]
    c110 = values[base + sx_ + sy_]
    c111 = values[base + sx_ + sy_ + 1]
    # trilinear interpolation and its exact gradient
    c00 = c000 + (c001 - c000) * tz
    c01 = c010 + (c011 - c010) * tz
    c10 = c100 + (c101 - c100) * tz
    c11 = c110 + (c111 - c110) * tz
    c0 = c00 + (c01 - c00) * ty
    c1 = c10 + (c11 - c10) * ty
    phi = c0 + (c1 - c0) * tx
    if gap > 0.0:
        return phi + gap, ex / gap, ey / gap, ez / gap
    gx = (c1 - c0) / h
    gy = ((c01 - c00) * (1.0 - tx) + (c11 - c10) * tx) / h
    d0 = (c001 - c000) * (1.0 - ty) + (c011 - c010) * ty
    d1 = (c101 - c100) * (1.0 - ty) + (c111 - c110) * ty
    gz = (d0 * (1.0 - tx) + d1 * tx) / h
    norm = math.sqrt(gx * gx + gy * gy + gz * gz)
    if norm == 0.0:
        return phi, 0.0, 0.0, 1.0
    return phi, gx / norm, gy / norm, gz / norm


@kernel(inline=True)
def geom_distance(geo, g, px, py, pz):
    """phi and unit gradient of geom ``g`` at (px, py, pz) in the geom's frame."""
    t = geo.geom_type[g]
    s = geo.geom_size[g]
    if t == SPHERE:
        return sphere_distance(s[0], px, py, pz)
    if t == CAPSULE:
        return capsule_distance(s[0], s[1], px, py, pz)
    if t == BOX:
        return box_distance(s[0], s[1], s[2], px, py, pz)
    if t == PLANE:
        return pz, 0.0, 0.0, 1.0
    m = geo.geom_grid[g]
    shape = geo.grid_shape[m]
    origin = geo.grid_origin[m]
    return grid_distance(geo.grid_values, geo.grid_offset[m], shape[0], shape[1], shape[2],
                         origin[0], origin[1], origin[2], geo.grid_spacing[m], px, py, pz)


@kernel
def axis_gap(p, lo, hi):
    """How far p lies outside the interval [lo, hi]; 0 inside it."""
    return lo - p if p < lo else p - hi if p > hi else 0.0


@kernel
def grid_gap(geo, m, px, py, pz):
    """Distance (m) from p (the mesh's frame) to the box of grid m; 0 inside it."""
    shape = geo.grid_shape[m]
    o = geo.grid_origin[m]
    h = geo.grid_spacing[m]
    gx = axis_gap(px, o[0], o[0] + (shape[0] - 1) * h)
    gy = axis_gap(py, o[1], o[1] + (shape[1] - 1) * h)
    gz = axis_gap(pz, o[2], o[2] + (shape[2] - 1) * h)
    return math.sqrt(gx * gx + gy * gy + gz * gz)


@kernel
def closest_on_segment(px, py, pz, ax, ay, az, bx, by, bz):
    """The point of segment [a, b] nearest to p; returns a 3-tuple."""
    abx, aby, abz = bx - ax, by - ay, bz - az
    length2 = abx * abx + aby * aby + abz * abz
    t = 0.0
    if length2 > 0.0:
        t = min(max(((px - ax) * abx + (py - ay) * aby + (pz - az) * abz) / length2, 0.0), 1.0)
    return ax + t * abx, ay + t * aby, az + t * abz


@kernel
def normal_area(ax, ay, az, bx, by, bz, nx, ny, nz):
    """(a x b) . n: twice the signed area of the triangle (0, a, b) seen along n, times |n|."""
    return (ay * bz - az * by) * nx + (az * bx - ax * bz) * ny + (ax * by - ay * bx) * nz


@kernel
def closest_on_triangle(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz):
    """The point of triangle (a, b, c) nearest to p: its projection on the plane when that lies
    inside the triangle, else the nearest point of its edges; returns a 3-tuple."""
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    nx, ny, nz = aby * acz - abz * acy, abz * acx - abx * acz, abx * acy - aby * acx
    area2 = nx * nx + ny * ny + nz * nz
    if area2 > 0.0:
        s = ((px - ax) * nx + (py - ay) * ny + (pz - az) * nz) / area2
        qx, qy, qz = px - s * nx, py - s * ny, pz - s * nz
        # q's barycentric weights, times area2: the sub-triangles opposite a and b
        u = normal_area(bx - qx, by - qy, bz - qz, cx - qx, cy - qy, cz - qz, nx, ny, nz)
        v = normal_area(cx - qx, cy - qy, cz - qz, ax - qx, ay - qy, az - qz, nx, ny, nz)
        if u >= 0.0 and v >= 0.0 and u + v <= area2:
            return qx, qy, qz
    rx, ry, rz = closest_on_segment(px, py, pz, ax, ay, az, bx, by, bz)
    best = (px - rx) ** 2 + (py - ry) ** 2 + (pz - rz) ** 2
    sx, sy, sz = closest_on_segment(px, py, pz, bx, by, bz, cx, cy, cz)
    d2 = (px - sx) ** 2 + (py - sy) ** 2 + (pz - sz) ** 2
    if d2 < best:
        best, rx, ry, rz = d2, sx, sy, sz
    sx, sy, sz = closest_on_segment(px, py, pz, cx, cy, cz, ax, ay, az)
    d2 = (px - sx) ** 2 + (py - sy) ** 2 + (pz - sz) ** 2
    if d2 < best:
        rx, ry, rz = sx, sy, sz
    return rx, ry, rz


@kernel
def mesh_distance(geo, m, px, py, pz):
    """Exact distance (m) from p (the mesh's frame, outside the mesh) to the triangles of mesh m
    and its unit gradient, (p - nearest point) / distance; returns (phi, nx, ny, nz). O(T)."""
    v = geo.mesh_vertices
    best = math.inf
    qx, qy, qz = px, py, pz
    for t in range(geo.mesh_triangle_start[m], geo.mesh_triangle_start[m + 1]):
        a, b, c = geo.mesh_triangles[t, 0], geo.mesh_triangles[t, 1], geo.mesh_triangles[t, 2]
        sx, sy, sz = closest_on_triangle(px, py, pz, v[a, 0], v[a, 1], v[a, 2],
                                         v[b, 0], v[b, 1], v[b, 2], v[c, 0], v[c, 1], v[c, 2])
        d2 = (px - sx) ** 2 + (py - sy) ** 2 + (pz - sz) ** 2
        if d2 < best:
            best, qx, qy, qz = d2, sx, sy, sz
    d = math.sqrt(best)
    if d == 0.0:
        return 0.0, 0.0, 0.0, 1.0
    return d, (px - qx) / d, (py - qy) / d, (pz - qz) / d


@kernel(inline=True)
def geom_distance_within(geo, g, px, py, pz, reach):
    """``geom_distance`` for a caller that needs phi only where phi < reach (m).

    Inside a mesh's grid, and for every other type, it is ``geom_distance``. Outside the grid
    the grid only bounds phi from below (phi >= the gap to the grid box); where that bound is
    below ``reach`` the point may be a contact (a sphere or capsule core, whose radius can
    exceed the grid's padding), so phi is computed exactly from the triangles; elsewhere the
    grid's value (>= reach) is returned and can make no contact.
    """
    if geo.geom_type[g] == MESH:
        m = geo.geom_grid[g]
        gap = grid_gap(geo, m, px, py, pz)
        if 0.0 < gap < reach:
            return mesh_distance(geo, m, px, py, pz)
    return geom_distance(geo, g, px, py, pz)
