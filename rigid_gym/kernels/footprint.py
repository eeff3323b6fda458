"""How low a box may go before it lands on the table or on top of another box.

The envs' gripper stops a downward move where the pad, or the object it holds, would rest on
the table (z = 0) or on the top of a free box under its footprint (``envs/effector.py``).
Footprints are the boxes' shadows on the table, compared by separating axes in the plane.
"""

import math

from rigid_gym.kernels.jit import kernel

FOOTPRINT_SLACK = 1e-3
"""m: footprints must overlap by more than this for a box to count as under another."""


@kernel(inline=True)
def corner(centre, rotation, half, k, axis):
    """Coordinate ``axis`` of corner k (0-7, signs by its bits: x slowest) of a box, m."""
    sx = -1.0 if k < 4 else 1.0
    sy = -1.0 if k % 4 < 2 else 1.0
    sz = -1.0 if k % 2 == 0 else 1.0
    return (centre[axis] + rotation[axis, 0] * sx * half[0] + rotation[axis, 1] * sy * half[1]
            + rotation[axis, 2] * sz * half[2])


@kernel
def z_range(centre, rotation, half):
    """(lowest, highest) z of a box's corners, m."""
    low, high = math.inf, -math.inf
    for k in range(8):
        z = corner(centre, rotation, half, k, 2)
        low, high = min(low, z), max(high, z)
    return low, high


@kernel
def separated_along(ax, ay, xa, ra, ha, xb, rb, hb):
    """Do the shadows of boxes a and b on the table overlap by at most FOOTPRINT_SLACK along
    the in-plane axis (ax, ay)?"""
    low_a = low_b = math.inf
    high_a = high_b = -math.inf
    for k in range(8):
        pa = corner(xa, ra, ha, k, 0) * ax + corner(xa, ra, ha, k, 1) * ay
        pb = corner(xb, rb, hb, k, 0) * ax + corner(xb, rb, hb, k, 1) * ay
        low_a, high_a = min(low_a, pa), max(high_a, pa)
        low_b, high_b = min(low_b, pb), max(high_b, pb)
    return min(high_a, high_b) - max(low_a, low_b) <= FOOTPRINT_SLACK


@kernel
def footprints_overlap(xa, ra, ha, xb, rb, hb):
    """Whether boxes a and b (centre (3,) m, rotation (3, 3), half extents (3,) m) overlap in
    their shadows on the table by more than FOOTPRINT_SLACK: separating axes x, y and the
    normals of the projected box edges."""
    if separated_along(1.0, 0.0, xa, ra, ha, xb, rb, hb):
        return False
    if separated_along(0.0, 1.0, xa, ra, ha, xb, rb, hb):
        return False
    for r in (ra, rb):
        for k in range(3):  # box axis k projected on the table
            ex, ey = r[0, k], r[1, k]
            norm = math.sqrt(ex * ex + ey * ey)
            if norm > 1e-9 and separated_along(-ey / norm, ex / norm, xa, ra, ha, xb, rb, hb):
                return False
    return True


@kernel
def lowest_centre(target_z, drop, parts_x, parts_r, parts_half, parts, boxes_x, boxes_r,
                  boxes_half, skip):
    """The lowest z (m) the gripper's centre may take at a target of height ``target_z``:
    where one of its ``parts`` (the pad, and the object it holds, at the target: centres
    (P, 3) m, rotations (P, 3, 3), half extents (P, 3)) would rest on the table or on the top
    of one of the boxes (centres (K, 3), rotations (K, 3, 3), half extents (K, 3)) under its
    footprint. A box counts as under a part if its top is below the part's bottom before the
    move (the part's bottom at the target minus ``drop``, the move's z, m); box ``skip`` (the
    held one, or -1) is ignored."""
    lowest = -math.inf
    for p in range(parts):
        bottom, _ = z_range(parts_x[p], parts_r[p], parts_half[p])
        height = target_z - bottom  # from this part's bottom to the pad's centre
        lowest = max(lowest, height)  # resting on the table (z = 0)
        for k in range(boxes_x.shape[0]):
            if k == skip:
                continue
            _, top = z_range(boxes_x[k], boxes_r[k], boxes_half[k])
            if top <= bottom - drop + FOOTPRINT_SLACK and footprints_overlap(
                    parts_x[p], parts_r[p], parts_half[p], boxes_x[k], boxes_r[k], boxes_half[k]):
                lowest = max(lowest, top + height)
    return lowest


@kernel
def lowest_centres(targets, positions, rotations, pad, pad_half, objects, halves, held,
                   parts_x, parts_r, parts_half, boxes_x, boxes_r, out):
    """``lowest_centre`` for the gripper of every world at once: targets (B, 3) m, the pad's
    centre at its target; positions (B, n, 3) m, rotations (B, n, 3, 3) of every body; pad:
    the pad's body index, pad_half (3,) m; objects (K,) int64 the boxes' body indices and
    halves (K, 3) m their half extents (the same in every world); held (B,) int64 the held
    box (an index into objects, -1: none). Work arrays: parts_x (2, 3), parts_r (2, 3, 3),
    parts_half (2, 3), boxes_x (K, 3), boxes_r (K, 3, 3). out (B,) m, written."""
    for w in range(targets.shape[0]):
        for c in range(3):
            parts_x[0, c] = targets[w, c]
            parts_half[0, c] = pad_half[c]
            for d in range(3):
                parts_r[0, c, d] = rotations[w, pad, c, d]
        count = 1
        h = held[w]
        if h >= 0:
            body = objects[h]
            for c in range(3):
                parts_x[1, c] = positions[w, body, c] + (targets[w, c] - positions[w, pad, c])
                parts_half[1, c] = halves[h, c]
                for d in range(3):
                    parts_r[1, c, d] = rotations[w, body, c, d]
            count = 2
        for k in range(objects.shape[0]):
            for c in range(3):
                boxes_x[k, c] = positions[w, objects[k], c]
                for d in range(3):
                    boxes_r[k, c, d] = rotations[w, objects[k], c, d]
        out[w] = lowest_centre(targets[w, 2], targets[w, 2] - positions[w, pad, 2], parts_x,
                               parts_r, parts_half, count, boxes_x, boxes_r, halves, h)
