"""Broad phase: which pairs of bodies might touch, from world-space bounding boxes.

Bounded bodies are tested with each other by brute force (all pairs, O(n^2)) or by sort and
sweep along x (O(n log n) plus the overlaps); unbounded bodies (planes) are tested against
every bounded body's box. Both methods return the same pairs in the same order: sorted by
(a, b), with a the body of higher motion class (dynamic > kinematic > static; ties: the lower
index), so contact normals point from the ground or gripper towards what they touch.
Pairs in which neither body is dynamic are skipped: nothing could respond.
"""

import numpy as np

from rigid_gym.kernels.integrate import DYNAMIC
from rigid_gym.kernels.jit import kernel, prange


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
def sort_pairs(pair_a, pair_b, count, num_bodies):
    """Sort the first ``count`` pairs by (a, b)."""
    keys = np.empty(count, dtype=np.int64)
    for k in range(count):
        keys[k] = np.int64(pair_a[k]) * num_bodies + pair_b[k]
    order = np.argsort(keys, kind="mergesort")
    for k in range(count):
        pair_a[k] = keys[order[k]] // num_bodies
        pair_b[k] = keys[order[k]] % num_bodies


@kernel(parallel=True)
def find_pairs(position, rotation, velocity, angular_velocity, motion, geo, margin, dt,
               acceleration, sweep, bounds, pair_a, pair_b, pair_count):
    """Candidate pairs of every world, for poses anywhere within the next dt.

    position (B, n, 3), rotation (B, n, 3, 3), velocity and angular_velocity (B, n, 3): body
    states; every box is grown by ``swept_margin`` (margin m, dt s, acceleration bound m/s^2;
    dt = 0 for the current poses only). A plane is tested against the grown boxes too.
    sweep: sort and sweep (True) or brute force; bounds (B, n, 6): scratch;
    pair_a, pair_b (B, P) int32 out; pair_count (B,) int32 out: pairs found (may exceed P,
    in which case only P were written and the caller must grow the buffers).
    """
    num_worlds, n = position.shape[0], position.shape[1]
    unbounded = geo.body_unbounded
    for w in prange(num_worlds):
        for i in range(n):
            if unbounded[i] == 0:
                grown = swept_margin(velocity[w, i], angular_velocity[w, i], geo, i, margin, dt,
                                     acceleration)
                write_bounds(position[w, i], rotation[w, i], geo, i, grown, bounds[w, i])
        count = 0
        for p in range(n):
            if unbounded[p] == 0:
                continue
            for i in range(n):
                if unbounded[i] == 0 and box_below_plane(position[w], rotation[w], bounds[w], i, p, 0.0):
                    count = add_pair(i, p, motion, pair_a[w], pair_b[w], count)
        if sweep:
            order = np.argsort(bounds[w, :, 0], kind="mergesort")
            for oi in range(n):
                i = order[oi]
                if unbounded[i] != 0:
                    continue
                for oj in range(oi + 1, n):
                    j = order[oj]
                    if unbounded[j] != 0:
                        continue
                    if bounds[w, j, 0] > bounds[w, i, 3]:
                        break
                    if boxes_overlap(bounds[w], i, j):
                        count = add_pair(i, j, motion, pair_a[w], pair_b[w], count)
        else:
            for i in range(n):
                if unbounded[i] != 0:
                    continue
                for j in range(i + 1, n):
                    if unbounded[j] == 0 and boxes_overlap(bounds[w], i, j):
                        count = add_pair(i, j, motion, pair_a[w], pair_b[w], count)
        pair_count[w] = count
        if count <= pair_a.shape[1]:
            sort_pairs(pair_a[w], pair_b[w], count, n)
