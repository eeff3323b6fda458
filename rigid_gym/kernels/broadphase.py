"""Broad phase: which pairs of bodies might touch, from bounding boxes.

Every bounded body has a box in its own frame (``Geometry.body_bound_*``), grown on every side
by how far the body can move in the step. Bounded bodies are paired by the world-aligned boxes
holding those boxes, by brute force (all pairs, O(n^2)) or by sort and sweep along x
(O(n log n) plus the overlaps), and a pair whose world-aligned boxes overlap is kept only if
the turned boxes themselves overlap (separating axes): a turned box's world-aligned box is up
to sqrt(3) times as wide, and every pair listed is narrow-phased in every contact pass (the
settled 1000-body pile of ``report.scenes``: 5,336 pairs by world-aligned boxes, 3,478 by
turned ones). Unbounded bodies (planes) are tested against every bounded body's world-aligned
box. Both methods return the same pairs in the same order: sorted by (a, b), with a the body
of higher motion class (dynamic > kinematic > static; ties: the lower index), so contact
normals point from the ground or gripper towards what they touch. Pairs in which neither body
is dynamic are skipped: nothing could respond.
"""

import numpy as np

from rigid_gym.kernels.integrate import DYNAMIC
from rigid_gym.kernels.jit import kernel


@kernel
def swept_margin(velocity, angular_velocity, geo, i, margin, dt, acceleration):
    """How far (m) any point of body i can move in dt: |V| dt + |omega| dt (its reach from the
    centre of mass) + |a| dt^2 for an acceleration bound |a| (gravity), plus ``margin``."""
    c = geo.body_bound_center[i]
    e = geo.body_bound_half[i]
    reach = ((abs(c[0]) + e[0]) ** 2 + (abs(c[1]) + e[1]) ** 2 + (abs(c[2]) + e[2]) ** 2) ** 0.5
    speed = (velocity[0] ** 2 + velocity[1] ** 2 + velocity[2] ** 2) ** 0.5
    spin = (angular_velocity[0] ** 2 + angular_velocity[1] ** 2 + angular_velocity[2] ** 2) ** 0.5
    return margin + dt * (speed + spin * reach + acceleration * dt)


@kernel
def write_bounds(position, rotation, geo, i, margin, out):
    """World box of body i into out (6,) = (lo xyz, hi xyz), grown by ``margin`` (m)."""
    c = geo.body_bound_center[i]
    e = geo.body_bound_half[i]
    r = rotation
    for k in range(3):
        centre = position[k] + r[k, 0] * c[0] + r[k, 1] * c[1] + r[k, 2] * c[2]
        half = abs(r[k, 0]) * e[0] + abs(r[k, 1]) * e[1] + abs(r[k, 2]) * e[2] + margin
        out[k] = centre - half
        out[3 + k] = centre + half


@kernel
def boxes_overlap(bounds, i, j):
    for k in range(3):
        if bounds[i, k] > bounds[j, 3 + k] or bounds[j, k] > bounds[i, 3 + k]:
            return False
    return True


BOX_AXIS_SLACK = 1e-9
"""Added to |cos| between two boxes' axes in the separating-axis test: for nearly parallel
edges the cross-product axis is nearly zero and its projections are round-off, which must not
separate the boxes (Ericson, Real-Time Collision Detection, 4.4.1)."""


@kernel
def axis_cosine(ra, rb, k, l):
    """Cosine between axis k of frame ra and axis l of frame rb (3, 3 rotations: columns)."""
    return ra[0, k] * rb[0, l] + ra[1, k] * rb[1, l] + ra[2, k] * rb[2, l]


@kernel
def turned_boxes_overlap(position, rotation, geo, reach, i, j):
    """Do bodies i and j's boxes (their own frames' bound boxes, grown by reach[i] and
    reach[j] m on every side) overlap? Separating axes: the 3 face normals of each box and the
    9 cross products of their edges (Gottschalk, Lin & Manocha 1996; Ericson 4.4.1).
    position (n, 3), rotation (n, 3, 3): the bodies' poses; reach (n,) m."""
    ra, rb = rotation[i], rotation[j]
    ci, cj = geo.body_bound_center[i], geo.body_bound_center[j]
    ea = (geo.body_bound_half[i, 0] + reach[i], geo.body_bound_half[i, 1] + reach[i],
          geo.body_bound_half[i, 2] + reach[i])
    eb = (geo.body_bound_half[j, 0] + reach[j], geo.body_bound_half[j, 1] + reach[j],
          geo.body_bound_half[j, 2] + reach[j])
    # cosines between i's axis k and j's axis l, at [3 k + l]; with the slack where |.| is used
    c = (axis_cosine(ra, rb, 0, 0), axis_cosine(ra, rb, 0, 1), axis_cosine(ra, rb, 0, 2),
         axis_cosine(ra, rb, 1, 0), axis_cosine(ra, rb, 1, 1), axis_cosine(ra, rb, 1, 2),
         axis_cosine(ra, rb, 2, 0), axis_cosine(ra, rb, 2, 1), axis_cosine(ra, rb, 2, 2))
    a = (abs(c[0]) + BOX_AXIS_SLACK, abs(c[1]) + BOX_AXIS_SLACK, abs(c[2]) + BOX_AXIS_SLACK,
         abs(c[3]) + BOX_AXIS_SLACK, abs(c[4]) + BOX_AXIS_SLACK, abs(c[5]) + BOX_AXIS_SLACK,
         abs(c[6]) + BOX_AXIS_SLACK, abs(c[7]) + BOX_AXIS_SLACK, abs(c[8]) + BOX_AXIS_SLACK)
    # centre of j's box minus centre of i's, in i's frame
    t0 = t1 = t2 = 0.0
    for k in range(3):
        d = (position[j, k] + rb[k, 0] * cj[0] + rb[k, 1] * cj[1] + rb[k, 2] * cj[2]
             - position[i, k] - ra[k, 0] * ci[0] - ra[k, 1] * ci[1] - ra[k, 2] * ci[2])
        t0 += ra[k, 0] * d
        t1 += ra[k, 1] * d
        t2 += ra[k, 2] * d
    t = (t0, t1, t2)
    for k in range(3):  # i's face normals
        extent = ea[k]
        for l in range(3):
            extent += eb[l] * a[3 * k + l]
        if abs(t[k]) > extent:
            return False
    for l in range(3):  # j's face normals
        extent = eb[l]
        along = 0.0
        for k in range(3):
            extent += ea[k] * a[3 * k + l]
            along += t[k] * c[3 * k + l]
        if abs(along) > extent:
            return False
    for k in range(3):  # i's edge k crossed with j's edge l
        k1, k2 = (k + 1) % 3, (k + 2) % 3
        for l in range(3):
            l1, l2 = (l + 1) % 3, (l + 2) % 3
            extent = (ea[k1] * a[3 * k2 + l] + ea[k2] * a[3 * k1 + l]
                      + eb[l1] * a[3 * k + l2] + eb[l2] * a[3 * k + l1])
            along = t[k2] * c[3 * k1 + l] - t[k1] * c[3 * k2 + l]
            if abs(along) > extent:
                return False
    return True


@kernel
def box_below_plane(position, rotation, bounds, i, plane, margin):
    """True when some point of body i's box lies within ``margin`` of the plane body's half-space
    (the plane z <= 0 of its frame)."""
    r = rotation[plane]
    height = 0.0
    for k in range(3):
        centre = 0.5 * (bounds[i, k] + bounds[i, 3 + k])
        half = 0.5 * (bounds[i, 3 + k] - bounds[i, k])
        height += r[k, 2] * (centre - position[plane, k]) - abs(r[k, 2]) * half
    return height <= margin


@kernel
def add_pair(i, j, motion, pair_a, pair_b, count):
    """Record (i, j) ordered as described in the module docstring if either is dynamic."""
    if motion[i] != DYNAMIC and motion[j] != DYNAMIC:
        return count
    if motion[i] > motion[j] or (motion[i] == motion[j] and i < j):
        a, b = i, j
    else:
        a, b = j, i
    if count < pair_a.shape[0]:
        pair_a[count] = a
        pair_b[count] = b
    return count + 1


@kernel
def sort_keys(keys, tmp, count):
    """Sort keys[:count] ascending (bottom-up merge sort through ``tmp``, same length)."""
    width = 1
    src, dst = keys, tmp
    in_tmp = False
    while width < count:
        for lo in range(0, count, 2 * width):
            mid = min(lo + width, count)
            hi = min(lo + 2 * width, count)
            i, j = lo, mid
            for k in range(lo, hi):
                if i < mid and (j >= hi or src[i] <= src[j]):
                    dst[k] = src[i]
                    i += 1
                else:
                    dst[k] = src[j]
                    j += 1
        src, dst = dst, src
        in_tmp = not in_tmp
        width *= 2
    if in_tmp:
        for k in range(count):
            keys[k] = src[k]


@kernel
def sort_pairs(pair_a, pair_b, count, num_bodies, keys, tmp):
    """Sort the first ``count`` pairs by (a, b); keys, tmp: (>= count,) int64 scratch."""
    for k in range(count):
        keys[k] = np.int64(pair_a[k]) * num_bodies + pair_b[k]
    sort_keys(keys, tmp, count)
    for k in range(count):
        pair_a[k] = keys[k] // num_bodies
        pair_b[k] = keys[k] % num_bodies


@kernel
def sort_by_lower_x(order, bounds):
    """Insertion-sort the body indices ``order`` (n,) by (lower x bound, index). Bodies move
    little between steps, so the previous step's order is nearly sorted: O(n) typically."""
    for k in range(1, order.shape[0]):
        i = order[k]
        x = bounds[i, 0]
        m = k - 1
        while m >= 0 and (bounds[order[m], 0] > x or (bounds[order[m], 0] == x and order[m] > i)):
            order[m + 1] = order[m]
            m -= 1
        order[m + 1] = i


@kernel
def find_world_pairs(position, rotation, velocity, angular_velocity, motion, geo, margin, dt,
                     acceleration, sweep, bounds, order, pair_a, pair_b, keys, tmp, reach):
    """Candidate pairs of one world, for poses anywhere within the next dt; returns how many.

    position (n, 3), rotation (n, 3, 3), velocity and angular_velocity (n, 3): body states;
    every box is grown by ``swept_margin`` (margin m, dt s, acceleration bound m/s^2;
    dt = 0 for the current poses only), or by reach[i] (m) where that is larger, and reach
    (n,) is raised to the growth used (zero it for the margins alone). A plane is tested
    against the grown boxes too. sweep: sort and sweep (True) or brute force; bounds (n, 6):
    scratch; order (n,) int64: body indices, kept between calls (sort and sweep starts from
    the last order); pair_a, pair_b (P,) int32 out; keys, tmp (P,) int64 scratch. The count
    may exceed P, in which case only P pairs were written and the caller must grow the
    buffers.
    """
    n = position.shape[0]
    unbounded = geo.body_unbounded
    for i in range(n):
        if unbounded[i] == 0:
            grown = swept_margin(velocity[i], angular_velocity[i], geo, i, margin, dt, acceleration)
            reach[i] = max(reach[i], grown)
            write_bounds(position[i], rotation[i], geo, i, reach[i], bounds[i])
    count = 0
    for p in range(n):
        if unbounded[p] == 0:
            continue
        for i in range(n):
            if unbounded[i] == 0 and box_below_plane(position, rotation, bounds, i, p, 0.0):
                count = add_pair(i, p, motion, pair_a, pair_b, count)
    if sweep:
        sort_by_lower_x(order, bounds)
        for oi in range(n):
            i = order[oi]
            if unbounded[i] != 0:
                continue
            for oj in range(oi + 1, n):
                j = order[oj]
                if unbounded[j] != 0:
                    continue
                if bounds[j, 0] > bounds[i, 3]:
                    break
                if boxes_overlap(bounds, i, j) and turned_boxes_overlap(position, rotation, geo,
                                                                         reach, i, j):
                    count = add_pair(i, j, motion, pair_a, pair_b, count)
    else:
        for i in range(n):
            if unbounded[i] != 0:
                continue
            for j in range(i + 1, n):
                if (unbounded[j] == 0 and boxes_overlap(bounds, i, j)
                        and turned_boxes_overlap(position, rotation, geo, reach, i, j)):
                    count = add_pair(i, j, motion, pair_a, pair_b, count)
    if count <= pair_a.shape[0]:
        sort_pairs(pair_a, pair_b, count, n, keys, tmp)
    return count


@kernel
def find_pairs(position, rotation, velocity, angular_velocity, motion, geo, margin, dt,
               acceleration, sweep, bounds, order, pair_a, pair_b, pair_count, keys, tmp, reach):
    """``find_world_pairs`` for every world: arrays as there with a leading world axis B;
    pair_count (B,) int32 out; reach (B, n) is zeroed first (the margins alone)."""
    for w in range(position.shape[0]):
        reach[w] = 0.0
        pair_count[w] = find_world_pairs(position[w], rotation[w], velocity[w],
                                         angular_velocity[w], motion, geo, margin, dt,
                                         acceleration, sweep, bounds[w], order[w], pair_a[w],
                                         pair_b[w], keys[w], tmp[w], reach[w])
