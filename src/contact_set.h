// The work rows of the impulse stages: predicted poses and the contacts being resolved.
#pragma once

#include "body.h"
#include "narrow_phase.h"

namespace rg {

// Poses predicted for the end of the step (n,), and contacts (C,) with their bookkeeping:
// the contacts of one pair, or of one body with all its frozen supports (shock propagation).
struct ContactSet {
    Span<Vec3> position;      // (n,) predicted centres: contacts' lever arms start here
    Span<Quat> orientation;   // (n,)
    Span<Mat3> rotation;      // (n,)
    Span<Vec3> point;         // (C,) m, world
    Span<Vec3> normal;        // (C,) towards the body being resolved
    Span<double> depth;       // (C,) m from the narrow phase, then the approach speed v_n, m/s
    Span<int64_t> group;      // (C,) the patch: its seed contact, -1 unassigned
    Span<int64_t> partner;    // (C,) the body on the other side
    Span<int64_t> source;     // (C,) the listed pair it came from
    Span<double> orient;      // (C,) +1 if the resolved body is the pair's a, -1 if its b

    ContactBuffer buffer() const { return {point, normal, depth}; }
};

}  // namespace rg
