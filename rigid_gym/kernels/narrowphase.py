"""Narrow phase: the contacts between two bodies at given poses.

Every contact has a point (world, m), a unit normal pointing from body B to body A (the
direction that separates A from B) and a depth (m, > 0 when they overlap). For each pair of
geoms (one of A's, one of B's):

* sphere/capsule against sphere/capsule: closest points of their cores (a point, a segment)
  in closed form, exact;
* sphere/capsule against box/mesh/plane: the core's points in the other geom's phi, exact for
  boxes and planes (their phi is exact), to the grid's accuracy for meshes (exact outside the
  grid, where a core of large radius may lie: ``geom_distance_within``). A capsule's core
  contributes its two ends (so that a capsule lying on a face has two contacts) and the
  interior minima of phi along it, for edges it crosses: against a plane none (phi is linear
  along the core), against a box the one minimum of its convex phi, found by golden-section
  search (exact), against a mesh the local minima of phi sampled at most a grid cell apart,
  each refined by golden-section search (the deepest ``CAPSULE_CORE_SAMPLES`` - 2 of them);
* box against box: separating axes and face clipping in closed form (``boxbox.py``), since
  sampled distances give sideways normals for boxes stacked face to face;
* box/mesh against mesh/plane, mesh against box: A's surface samples in B's phi and B's in A's (GBF 2003),
  corners first, edge samples only where they can add a contact (``collide_samples_with_field``).

The contact point is the deepest point of one body inside the other: a sample, or a core point
moved by its radius against the normal. The deepest contact of the pair is written first.
"""

import numpy as np

from rigid_gym.kernels.boxbox import collide_boxes
from rigid_gym.kernels.geometry import BOX, CAPSULE, PLANE, SPHERE, geom_distance_within
from rigid_gym.kernels.jit import kernel

CAPSULE_CORE_SAMPLES = 5
"""The most contacts a capsule's core makes with one box or mesh geom: its 2 ends and up to 3
interior minima of phi along it."""
CORE_SEARCH_ITERATIONS = 48
"""Golden-section steps that refine a minimum of phi along a capsule's core; each keeps 0.618
of the bracket, so 48 of them leave 1e-10 of it."""
CORE_MINIMUM_TOLERANCE = 1e-9
"""An interior minimum of phi along a capsule's core is a contact only if it is deeper than
the ends of its bracket by this much, m: a capsule lying on a face has its two ends only."""
CORE_MAX_SAMPLES = 256
"""Cap on the samples of a capsule's core against a mesh (normally one per grid cell of the
part of the core near the mesh's grid)."""

BOX_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64)
"""The 8 corners of a box in units of its half extents, in sample order."""
BOX_EDGES = np.array([(a, b) for a in range(8) for b in range(a + 1, 8)
                      if np.count_nonzero(BOX_CORNERS[a] != BOX_CORNERS[b]) == 1], dtype=np.int32)
"""The 12 edges of a box as corner pairs, in sample order."""


@kernel
def to_world(x, r, px, py, pz):
    """x + R p for a pose (x (3,), R (3, 3)); returns a 3-tuple."""
    return (x[0] + r[0, 0] * px + r[0, 1] * py + r[0, 2] * pz,
            x[1] + r[1, 0] * px + r[1, 1] * py + r[1, 2] * pz,
            x[2] + r[2, 0] * px + r[2, 1] * py + r[2, 2] * pz)


@kernel
def to_local(x, r, px, py, pz):
    """R^T (p - x) for a pose (x (3,), R (3, 3)); returns a 3-tuple."""
    dx, dy, dz = px - x[0], py - x[1], pz - x[2]
    return (r[0, 0] * dx + r[1, 0] * dy + r[2, 0] * dz,
            r[0, 1] * dx + r[1, 1] * dy + r[2, 1] * dz,
            r[0, 2] * dx + r[1, 2] * dy + r[2, 2] * dz)


@kernel
def rotate(r, vx, vy, vz):
    """R v; returns a 3-tuple."""
    return (r[0, 0] * vx + r[0, 1] * vy + r[0, 2] * vz,
            r[1, 0] * vx + r[1, 1] * vy + r[1, 2] * vz,
            r[2, 0] * vx + r[2, 1] * vy + r[2, 2] * vz)


@kernel(inline=True)
def world_point_in_geom(geo, g, xb, rb, wx, wy, wz, reach):
    """phi of geom ``g`` (of the body at pose xb, rb) at world point w, and its outward normal
    in world coordinates; returns (phi, nx, ny, nz). reach: m, phi is needed only below it
    (``geom_distance_within``)."""
    bx, by, bz = to_local(xb, rb, wx, wy, wz)
    lx, ly, lz = to_local(geo.geom_position[g], geo.geom_rotation[g], bx, by, bz)
    phi, nx, ny, nz = geom_distance_within(geo, g, lx, ly, lz, reach)
    nx, ny, nz = rotate(geo.geom_rotation[g], nx, ny, nz)
    nx, ny, nz = rotate(rb, nx, ny, nz)
    return phi, nx, ny, nz


@kernel(inline=True)
def core_point(geo, g, x, r, t):
    """World position of the point at parameter t in [-1, 1] along geom g's core (a sphere's
    centre; a capsule's axis from -half_length to +half_length)."""
    p = geo.geom_position[g]
    gr = geo.geom_rotation[g]
    s = t * geo.geom_size[g, 1] if geo.geom_type[g] == CAPSULE else 0.0
    return to_world(x, r, p[0] + s * gr[0, 2], p[1] + s * gr[1, 2], p[2] + s * gr[2, 2])


@kernel
def closest_on_segments(p1, q1, p2, q2):
    """Parameters (s, t) in [0, 1] of the closest points p1 + s (q1 - p1), p2 + t (q2 - p2)
    of two segments (Ericson, Real-Time Collision Detection, 5.1.9). Points are 3-tuples."""
    d1 = (q1[0] - p1[0], q1[1] - p1[1], q1[2] - p1[2])
    d2 = (q2[0] - p2[0], q2[1] - p2[1], q2[2] - p2[2])
    rr = (p1[0] - p2[0], p1[1] - p2[1], p1[2] - p2[2])
    a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]
    e = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2]
    f = d2[0] * rr[0] + d2[1] * rr[1] + d2[2] * rr[2]
    if a == 0.0 and e == 0.0:
        return 0.0, 0.0
    if a == 0.0:
        return 0.0, min(max(f / e, 0.0), 1.0)
    c = d1[0] * rr[0] + d1[1] * rr[1] + d1[2] * rr[2]
    if e == 0.0:
        return min(max(-c / a, 0.0), 1.0), 0.0
    b = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2]
    denom = a * e - b * b
    s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > 0.0 else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = min(max(-c / a, 0.0), 1.0)
    elif t > 1.0:
        t = 1.0
        s = min(max((b - c) / a, 0.0), 1.0)
    return s, t


@kernel(inline=True)
def emit(points, normals, depths, index, capacity, px, py, pz, nx, ny, nz, depth):
    """Write one contact at ``index`` if it fits."""
    if index < capacity:
        points[index, 0], points[index, 1], points[index, 2] = px, py, pz
        normals[index, 0], normals[index, 1], normals[index, 2] = nx, ny, nz
        depths[index] = depth


@kernel
def collide_cores(geo, ga, gb, xa, ra, xb, rb, margin, points, normals, depths, index, capacity):
    """Sphere/capsule geom ga against sphere/capsule geom gb; returns contacts written (0 or 1)."""
    a0 = core_point(geo, ga, xa, ra, -1.0)
    a1 = core_point(geo, ga, xa, ra, 1.0)
    b0 = core_point(geo, gb, xb, rb, -1.0)
    b1 = core_point(geo, gb, xb, rb, 1.0)
    s, t = closest_on_segments(a0, a1, b0, b1)
    pa = (a0[0] + s * (a1[0] - a0[0]), a0[1] + s * (a1[1] - a0[1]), a0[2] + s * (a1[2] - a0[2]))
    pb = (b0[0] + t * (b1[0] - b0[0]), b0[1] + t * (b1[1] - b0[1]), b0[2] + t * (b1[2] - b0[2]))
    dx, dy, dz = pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]
    dist = (dx * dx + dy * dy + dz * dz) ** 0.5
    radius_a, radius_b = geo.geom_size[ga, 0], geo.geom_size[gb, 0]
    depth = radius_a + radius_b - dist
    if depth <= -margin:
        return 0
    if dist > 0.0:
        nx, ny, nz = dx / dist, dy / dist, dz / dist
    else:
        nx, ny, nz = 0.0, 0.0, 1.0
    emit(points, normals, depths, index, capacity,
         pa[0] - radius_a * nx, pa[1] - radius_a * ny, pa[2] - radius_a * nz, nx, ny, nz, depth)
    return 1


@kernel
def core_contact(geo, gc, xc, rc, gf, xf, rf, t, sign, margin, points, normals, depths, index,
                 capacity):
    """The point at parameter t of sphere/capsule geom gc's core in the phi of geom gf: writes a
    contact at ``index`` if it is one. Returns (contacts written, 0 or 1; phi there, m; phi's
    gradient there, gf's outward normal in world coordinates)."""
    radius = geo.geom_size[gc, 0]
    cx, cy, cz = core_point(geo, gc, xc, rc, t)
    phi, nx, ny, nz = world_point_in_geom(geo, gf, xf, rf, cx, cy, cz, radius + margin)
    depth = radius - phi
    if depth <= -margin:
        return 0, phi, nx, ny, nz
    emit(points, normals, depths, index, capacity, cx - radius * nx, cy - radius * ny,
         cz - radius * nz, sign * nx, sign * ny, sign * nz, depth)
    return 1, phi, nx, ny, nz


@kernel
def core_in_geom_frame(geo, gc, xc, rc, gf, xf, rf):
    """The ends (t = -1, t = 1) of sphere/capsule geom gc's core (pose xc, rc) in the frame of
    geom gf (pose xf, rf); returns a 6-tuple, m."""
    ax, ay, az = core_point(geo, gc, xc, rc, -1.0)
    bx, by, bz = core_point(geo, gc, xc, rc, 1.0)
    ax, ay, az = to_local(xf, rf, ax, ay, az)
    ax, ay, az = to_local(geo.geom_position[gf], geo.geom_rotation[gf], ax, ay, az)
    bx, by, bz = to_local(xf, rf, bx, by, bz)
    bx, by, bz = to_local(geo.geom_position[gf], geo.geom_rotation[gf], bx, by, bz)
    return ax, ay, az, bx, by, bz


@kernel
def core_phi(geo, gf, ends, t, reach):
    """phi of geom gf at the point of parameter t in [-1, 1] of a core whose ends are ``ends``
    (``core_in_geom_frame``), m."""
    ax, ay, az, bx, by, bz = ends
    s = 0.5 * (t + 1.0)
    return geom_distance_within(geo, gf, ax + s * (bx - ax), ay + s * (by - ay),
                                az + s * (bz - az), reach)[0]


@kernel
def core_minimum(geo, gf, ends, reach, lo, hi):
    """Golden-section search for the t in [lo, hi] where phi of geom gf along a core (ends in
    gf's frame: ``core_in_geom_frame``) is least: the global minimum where phi is convex
    along the core (a box's), a local one otherwise. Returns (t, phi)."""
    ratio = 0.6180339887498949
    c = hi - ratio * (hi - lo)
    d = lo + ratio * (hi - lo)
    fc = core_phi(geo, gf, ends, c, reach)
    fd = core_phi(geo, gf, ends, d, reach)
    for _ in range(CORE_SEARCH_ITERATIONS):
        if fc <= fd:
            hi, d, fd = d, c, fc
            c = hi - ratio * (hi - lo)
            fc = core_phi(geo, gf, ends, c, reach)
        else:
            lo, c, fc = c, d, fd
            d = lo + ratio * (hi - lo)
            fd = core_phi(geo, gf, ends, d, reach)
    if fc <= fd:
        return c, fc
    return d, fd


@kernel
def core_range_near_grid(geo, gf, ends, reach):
    """The parameters (t0, t1) of the part of a core (ends in mesh geom gf's frame:
    ``core_in_geom_frame``) within ``reach`` (m) of gf's grid box (slab clipping); t0 > t1
    when there is none."""
    ax, ay, az, bx, by, bz = ends
    m = geo.geom_grid[gf]
    h = geo.grid_spacing[m]
    s0, s1 = 0.0, 1.0
    for c in range(3):
        p = ax if c == 0 else ay if c == 1 else az
        q = bx if c == 0 else by if c == 1 else bz
        lo = geo.grid_origin[m, c] - reach
        hi = geo.grid_origin[m, c] + (geo.grid_shape[m, c] - 1) * h + reach
        if p == q:
            if p < lo or p > hi:
                return 1.0, -1.0
            continue
        e0, e1 = (lo - p) / (q - p), (hi - p) / (q - p)
        s0 = max(s0, min(e0, e1))
        s1 = min(s1, max(e0, e1))
    return 2.0 * s0 - 1.0, 2.0 * s1 - 1.0


@kernel
def collide_core_with_field(geo, gc, xc, rc, gf, xf, rf, sign, margin, points, normals, depths,
                            index, capacity):
    """Core of sphere/capsule geom gc (pose xc, rc) in the phi of geom gf (pose xf, rf).

    sign = +1 when gc belongs to body A (normals are gf's outward normals), -1 when it belongs
    to B. Returns the number of contacts found (see the module docstring).
    """
    if geo.geom_type[gc] != CAPSULE:
        return core_contact(geo, gc, xc, rc, gf, xf, rf, 0.0, sign, margin, points, normals,
                            depths, index, capacity)[0]
    found, phi_lo, nx_lo, ny_lo, nz_lo = core_contact(geo, gc, xc, rc, gf, xf, rf, -1.0, sign,
                                                      margin, points, normals, depths, index,
                                                      capacity)
    hit, phi_hi, nx_hi, ny_hi, nz_hi = core_contact(geo, gc, xc, rc, gf, xf, rf, 1.0, sign,
                                                    margin, points, normals, depths,
                                                    index + found, capacity)
    found += hit
    if geo.geom_type[gf] == PLANE:
        return found
    reach = geo.geom_size[gc, 0] + margin
    if geo.geom_type[gf] == BOX:
        # a box's phi is convex, so along the core it falls below both ends' values only if
        # it falls inwards from each end; the gradient at an end (a subgradient where phi
        # has a ridge) bounds that slope from below: where it does not fall, an end is least
        gr = geo.geom_rotation[gc]
        ux, uy, uz = rotate(rc, gr[0, 2], gr[1, 2], gr[2, 2])  # the core's axis, t = -1 to 1
        if (nx_lo * ux + ny_lo * uy + nz_lo * uz >= 0.0
                or nx_hi * ux + ny_hi * uy + nz_hi * uz <= 0.0):
            return found
        t, phi = core_minimum(geo, gf, core_in_geom_frame(geo, gc, xc, rc, gf, xf, rf), reach,
                              -1.0, 1.0)
        if phi < min(phi_lo, phi_hi) - CORE_MINIMUM_TOLERANCE and phi < reach:
            found += core_contact(geo, gc, xc, rc, gf, xf, rf, t, sign, margin, points, normals,
                                  depths, index + found, capacity)[0]
        return found
    # a mesh: local minima of phi sampled at most a grid cell apart along the core near the grid
    ends = core_in_geom_frame(geo, gc, xc, rc, gf, xf, rf)
    t0, t1 = core_range_near_grid(geo, gf, ends, reach)
    if t0 >= t1:
        return found
    length = (t1 - t0) * geo.geom_size[gc, 1]
    count = min(max(int(np.ceil(length / geo.grid_spacing[geo.geom_grid[gf]])), 2),
                CORE_MAX_SAMPLES)
    step = (t1 - t0) / count
    interior = 0
    before = core_phi(geo, gf, ends, t0, reach)
    here = core_phi(geo, gf, ends, t0 + step, reach)
    for k in range(1, count):
        after = core_phi(geo, gf, ends, t0 + (k + 1) * step, reach)
        if here < before and here <= after and here < reach:
            t, phi = core_minimum(geo, gf, ends, reach, t0 + (k - 1) * step,
                                  t0 + (k + 1) * step)
            if phi < min(before, after) - CORE_MINIMUM_TOLERANCE and phi < reach:
                # keep the deepest CAPSULE_CORE_SAMPLES - 2: replace the shallowest if full
                slot = index + found + interior
                if interior == CAPSULE_CORE_SAMPLES - 2:
                    slot = -1
                    end = index + found + interior
                    if end <= capacity:
                        slot = index + found
                        for j in range(index + found + 1, end):
                            if depths[j] < depths[slot]:
                                slot = j
                        if depths[slot] >= geo.geom_size[gc, 0] - phi:
                            slot = -1
                else:
                    interior += 1
                if slot >= 0:
                    core_contact(geo, gc, xc, rc, gf, xf, rf, t, sign, margin, points, normals,
                                 depths, slot, capacity)
        before, here = here, after
    return found + interior


@kernel(inline=True)
def sample_in_field(geo, k, xs, rs, gf, xf, rf, sign, margin, points, normals, depths, index,
                    capacity):
    """Surface sample k (of a geom at pose xs, rs) in the phi of geom gf; returns 1 if it is a
    contact (written at ``index``), else 0."""
    p = geo.sample_points[k]
    wx, wy, wz = to_world(xs, rs, p[0], p[1], p[2])
    phi, nx, ny, nz = world_point_in_geom(geo, gf, xf, rf, wx, wy, wz, margin)
    if -phi <= -margin:
        return 0
    emit(points, normals, depths, index, capacity, wx, wy, wz, sign * nx, sign * ny, sign * nz, -phi)
    return 1


@kernel(inline=True)
def collide_samples_with_field(geo, gs, xs, rs, gf, xf, rf, sign, margin, points, normals, depths,
                               index, capacity):
    """Surface samples of box or mesh geom gs (pose xs, rs) in the phi of geom gf (pose xf, rf);
    sign as in ``collide_core_with_field``. Returns the number of contacts found.

    The corners/vertices (the first ``sample_vertex_count`` samples) are always tested. Against
    a plane nothing else can be deepest (a polyhedron's deepest point in a half-space is a
    vertex). A box's edge samples are tested only on edges with neither corner inside: that is
    exactly the edge-edge crossing the corners miss, and it keeps a resting face to 4 contacts.
    A mesh's edge samples are always tested (its target may be nonconvex).
    """
    begin, end = geo.sample_start[gs], geo.sample_start[gs + 1]
    vertices = geo.sample_vertex_count[gs]
    found = 0
    corner_inside = 0
    for k in range(begin, begin + vertices):
        hit = sample_in_field(geo, k, xs, rs, gf, xf, rf, sign, margin, points, normals, depths,
                              index + found, capacity)
        found += hit
        if hit and k - begin < 32:
            corner_inside |= 1 << (k - begin)
    if geo.geom_type[gf] == PLANE:
        return found
    if geo.geom_type[gs] != BOX:
        for k in range(begin + vertices, end):
            found += sample_in_field(geo, k, xs, rs, gf, xf, rf, sign, margin, points, normals,
                                     depths, index + found, capacity)
        return found
    per_edge = (end - begin - vertices) // 12
    for e in range(12):
        if (corner_inside >> BOX_EDGES[e, 0]) & 1 or (corner_inside >> BOX_EDGES[e, 1]) & 1:
            continue
        first = begin + vertices + e * per_edge
        for k in range(first, first + per_edge):
            found += sample_in_field(geo, k, xs, rs, gf, xf, rf, sign, margin, points, normals,
                                     depths, index + found, capacity)
    return found


@kernel(inline=True)
def geom_pose(geo, g, x, r, out_x, out_r):
    """World pose of geom g of a body at pose (x, r), written to out_x (3,), out_r (3, 3)."""
    p = geo.geom_position[g]
    gr = geo.geom_rotation[g]
    wx, wy, wz = to_world(x, r, p[0], p[1], p[2])
    out_x[0], out_x[1], out_x[2] = wx, wy, wz
    for c in range(3):
        cx, cy, cz = rotate(r, gr[0, c], gr[1, c], gr[2, c])
        out_r[0, c], out_r[1, c], out_r[2, c] = cx, cy, cz


@kernel(inline=True)
def collide_box_geoms(geo, ga, xa, ra, gb, xb, rb, margin, points, normals, depths, index,
                      capacity, scratch):
    """Box geom ga against box geom gb in closed form (``boxbox.collide_boxes``)."""
    pose = scratch[2]
    geom_pose(geo, ga, xa, ra, pose[0], pose[1:4])
    geom_pose(geo, gb, xb, rb, pose[4], pose[5:8])
    return collide_boxes(pose[0], pose[1:4], geo.geom_size[ga], pose[4], pose[5:8],
                         geo.geom_size[gb], margin, points, normals, depths, index, capacity,
                         scratch)


@kernel(inline=True)
def is_core(geo, g):
    return geo.geom_type[g] == SPHERE or geo.geom_type[g] == CAPSULE


@kernel
def collide_bodies(geo, a, b, xa, ra, xb, rb, margin, points, normals, depths, start, capacity,
                   scratch):
    """All contacts of body a (pose xa (3,), ra (3, 3)) with body b, written to
    points/normals/depths from ``start`` while below ``capacity``, deepest first.
    scratch: (3, 16, 3) float64 work space.

    Reports contacts with depth > -margin (m). Returns how many were found (some may not have
    been written if the buffer was too small: the caller checks and grows it).
    """
    found = 0
    for ga in range(geo.body_geom_start[a], geo.body_geom_start[a + 1]):
        for gb in range(geo.body_geom_start[b], geo.body_geom_start[b + 1]):
            index = start + found
            if is_core(geo, ga) and is_core(geo, gb):
                found += collide_cores(geo, ga, gb, xa, ra, xb, rb, margin, points, normals, depths,
                                       index, capacity)
            elif is_core(geo, ga):
                found += collide_core_with_field(geo, ga, xa, ra, gb, xb, rb, 1.0, margin, points,
                                                 normals, depths, index, capacity)
            elif is_core(geo, gb):
                found += collide_core_with_field(geo, gb, xb, rb, ga, xa, ra, -1.0, margin, points,
                                                 normals, depths, index, capacity)
            elif geo.geom_type[ga] == BOX and geo.geom_type[gb] == BOX:
                found += collide_box_geoms(geo, ga, xa, ra, gb, xb, rb, margin, points, normals,
                                           depths, index, capacity, scratch)
            else:
                found += collide_samples_with_field(geo, ga, xa, ra, gb, xb, rb, 1.0, margin,
                                                    points, normals, depths, index, capacity)
                found += collide_samples_with_field(geo, gb, xb, rb, ga, xa, ra, -1.0, margin,
                                                    points, normals, depths, start + found, capacity)
    if found > 0 and start + found <= capacity:
        move_deepest_first(points, normals, depths, start, start + found)
    return found


@kernel
def move_deepest_first(points, normals, depths, begin, end):
    """Swap the deepest contact in [begin, end) into position ``begin``."""
    deepest = begin
    for k in range(begin + 1, end):
        if depths[k] > depths[deepest]:
            deepest = k
    if deepest != begin:
        for c in range(3):
            points[begin, c], points[deepest, c] = points[deepest, c], points[begin, c]
            normals[begin, c], normals[deepest, c] = normals[deepest, c], normals[begin, c]
        depths[begin], depths[deepest] = depths[deepest], depths[begin]
