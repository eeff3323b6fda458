"""Kernels for closed triangle meshes: generalised winding number and signed distance.

A mesh is ``vertices`` (V, 3) float64 positions in metres and ``triangles`` (T, 3) int32 vertex
indices, wound counter-clockwise seen from outside (outward normals), as :class:`Mesh` stores
them. Points are (P, 3) float64 in the same frame. The public kernels loop over points in
parallel and over every triangle for each point, so they cost O(P T): meant for the small meshes
of a manipulation scene and for offline work such as mass properties.

Callers pass buffers of matching sizes (numba does not bounds-check); :class:`Mesh` validates
the mesh itself (closed, consistently wound, positive volume).
"""

import math

from rigid_gym.kernels.jit import kernel, prange

FOUR_PI = 4.0 * math.pi

DEGENERATE_SINE = 1e-12
"""A triangle whose corner angle at its first vertex has |sin| below this is treated as a
segment by :func:`_point_triangle_distance_squared` (its plane is not well defined)."""


@kernel
def _dot(ax, ay, az, bx, by, bz):
    """a . b of two 3-vectors given as scalars."""
    return ax * bx + ay * by + az * bz


@kernel
def _solid_angle(ax, ay, az, bx, by, bz, cx, cy, cz):
    """Signed solid angle (sr, in (-2 pi, 2 pi]) that triangle (a, b, c) subtends at the origin.

    ``a``, ``b``, ``c`` are the vertices relative to the viewpoint, m. Van Oosterom & Strackee
    (1983): tan(omega / 2) = a . (b x c) / (|a||b||c| + (a . b)|c| + (a . c)|b| + (b . c)|a|).
    Positive when the viewpoint sees the triangle's back (the inside of an outward mesh).
    """
    la = math.sqrt(_dot(ax, ay, az, ax, ay, az))
    lb = math.sqrt(_dot(bx, by, bz, bx, by, bz))
    lc = math.sqrt(_dot(cx, cy, cz, cx, cy, cz))
    triple = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
    denominator = (
        la * lb * lc
        + _dot(ax, ay, az, bx, by, bz) * lc
        + _dot(ax, ay, az, cx, cy, cz) * lb
        + _dot(bx, by, bz, cx, cy, cz) * la
    )
    return 2.0 * math.atan2(triple, denominator)


@kernel
def _point_segment_distance_squared(px, py, pz, ax, ay, az, bx, by, bz):
    """Squared distance (m^2) from point p to the segment [a, b] (a == b allowed)."""
    abx, aby, abz = bx - ax, by - ay, bz - az
    apx, apy, apz = px - ax, py - ay, pz - az
    length2 = _dot(abx, aby, abz, abx, aby, abz)
    t = 0.0
    if length2 > 0.0:
        t = min(max(_dot(apx, apy, apz, abx, aby, abz) / length2, 0.0), 1.0)
    dx, dy, dz = apx - t * abx, apy - t * aby, apz - t * abz
    return _dot(dx, dy, dz, dx, dy, dz)


@kernel
def _degenerate_distance_squared(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz):
    """Squared distance (m^2) from p to a zero-area triangle: the nearest of its three edges."""
    return min(
        _point_segment_distance_squared(px, py, pz, ax, ay, az, bx, by, bz),
        _point_segment_distance_squared(px, py, pz, bx, by, bz, cx, cy, cz),
        _point_segment_distance_squared(px, py, pz, cx, cy, cz, ax, ay, az),
    )


@kernel
def _point_triangle_distance_squared(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz):
    """Squared distance (m^2) from point p to the closest point of triangle (a, b, c), m.

    Ericson, *Real-Time Collision Detection* (2005) 5.1.5: find the Voronoi region of p (a
    vertex, an edge or the face) from dot products, then project onto that feature.
    """
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    nx, ny, nz = aby * acz - abz * acy, abz * acx - abx * acz, abx * acy - aby * acx
    area2 = _dot(nx, ny, nz, nx, ny, nz)
    ab2 = _dot(abx, aby, abz, abx, aby, abz)
    ac2 = _dot(acx, acy, acz, acx, acy, acz)
    if area2 <= DEGENERATE_SINE * DEGENERATE_SINE * ab2 * ac2:
        return _degenerate_distance_squared(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz)

    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = _dot(abx, aby, abz, apx, apy, apz)
    d2 = _dot(acx, acy, acz, apx, apy, apz)
    # Each branch sets the closest point q = a + v ab + w ac.
    v = 0.0
    w = 0.0
    bpx, bpy, bpz = px - bx, py - by, pz - bz
    d3 = _dot(abx, aby, abz, bpx, bpy, bpz)
    d4 = _dot(acx, acy, acz, bpx, bpy, bpz)
    cpx, cpy, cpz = px - cx, py - cy, pz - cz
    d5 = _dot(abx, aby, abz, cpx, cpy, cpz)
    d6 = _dot(acx, acy, acz, cpx, cpy, cpz)
    vc = d1 * d4 - d3 * d2
    vb = d5 * d2 - d1 * d6
    va = d3 * d6 - d5 * d4
    if d1 <= 0.0 and d2 <= 0.0:  # vertex a
        pass
    elif d3 >= 0.0 and d4 <= d3:  # vertex b
        v = 1.0
    elif d6 >= 0.0 and d5 <= d6:  # vertex c
        w = 1.0
    elif vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:  # edge ab
        v = d1 / (d1 - d3)
    elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:  # edge ac
        w = d2 / (d2 - d6)
    elif va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:  # edge bc
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        v = 1.0 - w
    else:  # face
        v = vb / (va + vb + vc)
        w = vc / (va + vb + vc)
    dx = apx - v * abx - w * acx
    dy = apy - v * aby - w * acy
    dz = apz - v * abz - w * acz
    return _dot(dx, dy, dz, dx, dy, dz)


@kernel
def _point_winding_number(px, py, pz, vertices, triangles):
    """Winding number of point p (m) with respect to the mesh: sum of solid angles / 4 pi."""
    omega = 0.0
    for t in range(triangles.shape[0]):
        a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        omega += _solid_angle(
            vertices[a, 0] - px, vertices[a, 1] - py, vertices[a, 2] - pz,
            vertices[b, 0] - px, vertices[b, 1] - py, vertices[b, 2] - pz,
            vertices[c, 0] - px, vertices[c, 1] - py, vertices[c, 2] - pz,
        )
    return omega / FOUR_PI


@kernel
def _point_mesh_distance(px, py, pz, vertices, triangles):
    """Distance (m) from point p (m) to the nearest triangle of the mesh."""
    best = math.inf
    for t in range(triangles.shape[0]):
        a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        best = min(best, _point_triangle_distance_squared(
            px, py, pz,
            vertices[a, 0], vertices[a, 1], vertices[a, 2],
            vertices[b, 0], vertices[b, 1], vertices[b, 2],
            vertices[c, 0], vertices[c, 1], vertices[c, 2],
        ))
    return math.sqrt(best)


@kernel(parallel=True)
def winding_number(points, vertices, triangles, out):
    """Generalised winding number of each point: the signed solid angles of all triangles / 4 pi.

    ``points`` (P, 3) float64, m; ``vertices`` (V, 3) float64, m; ``triangles`` (T, 3) int32;
    ``out`` (P,) float64, written: 1 inside a closed outward mesh, 0 outside, 1/2 on the
    surface (up to rounding). Right for nonconvex meshes too (Jacobson et al. 2013).
    """
    for i in prange(points.shape[0]):
        out[i] = _point_winding_number(points[i, 0], points[i, 1], points[i, 2],
                                       vertices, triangles)


@kernel(parallel=True)
def signed_distance(points, vertices, triangles, out):
    """Signed distance of each point to the mesh surface, m.

    ``points`` (P, 3) float64, m; ``vertices`` (V, 3) float64, m; ``triangles`` (T, 3) int32;
    ``out`` (P,) float64, written. Magnitude: exact distance to the nearest triangle. Sign:
    negative where the winding number exceeds 1/2 (inside), positive elsewhere.
    """
    for i in prange(points.shape[0]):
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        distance = _point_mesh_distance(px, py, pz, vertices, triangles)
        inside = _point_winding_number(px, py, pz, vertices, triangles) > 0.5
        out[i] = -distance if inside else distance
