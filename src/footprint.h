// How low a box may go before it lands on the table or on top of another box.
//
// The envs' gripper stops a downward move where the pad, or the object it holds, would rest on
// the table (z = 0) or on the top of a free box under its footprint (envs/effector.py).
// Footprints are the boxes' shadows on the table, compared by separating axes in the plane.
#pragma once

#include <cstdint>

#include "math.h"
#include "span.h"

namespace rg {

// The batch of worlds lowest_centres reads, and the work rows it fills. B worlds of n bodies
// each, K boxes; every index must be in range (the bindings check them).
struct FootprintQuery {
    Span<const Vec3> targets;    // (B,) m, the pad's centre at its target
    Span<const Vec3> positions;  // (B n,) m, every body of every world
    Span<const Mat3> rotations;  // (B n,)
    int64_t num_bodies = 0;      // n
    int64_t pad = 0;             // the pad's body index
    Vec3 pad_half = {};          // m
    Span<const int64_t> objects;  // (K,) the boxes' body indices, the same in every world
    Span<const Vec3> halves;     // (K,) m, their half extents
    Span<const int64_t> held;    // (B,) the held box, an index into objects (-1: none)
    // Work rows, overwritten world by world: the parts (the pad, then the held box) and the
    // boxes of the world in hand.
    Span<Vec3> parts_x;     // (2,) m
    Span<Mat3> parts_r;     // (2,)
    Span<Vec3> parts_half;  // (2,) m
    Span<Vec3> boxes_x;     // (K,) m
    Span<Mat3> boxes_r;     // (K,)
};

// For the gripper of every world: the lowest z (m) its centre may take at its target, into
// out (B,). That is where one of its parts (the pad, and the object it holds, at the target)
// would rest on the table or on the top of one of the boxes under its footprint. A box counts
// as under a part if its top is below the part's bottom before the move (the part's bottom at
// the target minus the move's z, m); the held box is ignored.
void lowest_centres(const FootprintQuery& query, Span<double> out);

}  // namespace rg
