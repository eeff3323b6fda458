"""Signed distances phi(p) and their gradients for every geom type (GBF 2003's representation).

A geom is one primitive of a body: its type, size and pose in the body frame live in the
``Geometry`` arrays (see ``rigid_gym.geometry``). Distances are evaluated in the geom's own
frame; phi < 0 inside, and the gradient (unit length) is the outward normal.

    SPHERE   size (r, -, -)          exact
    CAPSULE  size (r, half_length, -) exact, axis z
    BOX      size (hx, hy, hz)       exact
    MESH     a signed distance sampled on a grid, trilinear inside the grid; outside it, the
             distance to the grid box plus the value at the nearest grid point
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


@kernel
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
