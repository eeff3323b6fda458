// The work rows of the impulse stages: the contacts being resolved.
#pragma once

#include "base/body.h"
#include "collision/narrow_phase.h"

namespace rg {

// Contacts (C,) being resolved with their bookkeeping: the contacts of one pair, or of one
// body with all its frozen supports (shock propagation), at the poses predicted for the end of
// the step.
struct ContactSet {
    Span<Vec3> point;         // (C,) m, world
    Span<Vec3> normal;        // (C,) towards the body being resolved
    Span<double> depth;       // (C,) m from the narrow phase, then the approach speed v_n, m/s
    Span<double> gap;         // (C,) m, the separation at the start of the step that depth and
                              //      v_n imply: -(depth + dt v_n) (negative: overlapping)
    Span<int64_t> group;      // (C,) the patch: its seed contact, -1 unassigned
    Span<int64_t> partner;    // (C,) the body on the other side
    Span<int64_t> source;     // (C,) the listed pair it came from
    Span<double> orient;      // (C,) +1 if the resolved body is the pair's a, -1 if its b
    Span<Vec3> centre_a;      // (C,) predicted centre of the resolved body: levers start here
    Span<Vec3> centre_b;      // (C,) predicted centre of the partner

    ContactBuffer buffer() const { return {point, normal, depth}; }
};

}  // namespace rg
