// The work rows of the impulse stages: the contacts being resolved.
#pragma once

#include "base/body.h"
#include "collision/narrow_phase.h"

namespace rg {

// Contacts (c,) being resolved with their bookkeeping: the contacts of one pair, or of one
// body with all its frozen supports (shock propagation), at the poses predicted for the end of
// the step.
#define RG_CONTACT_SET_ROWS(X)                                                              \
    X(Vec3, point, c, Vec3{})      /* m, world */                                          \
    X(Vec3, normal, c, Vec3{})     /* towards the body being resolved */                   \
    X(double, depth, c, 0.0)       /* m from the narrow phase, then the approach speed v_n, m/s */ \
    X(double, gap, c, 0.0)         /* m, the separation at the start of the step that depth */ \
                                   /* and v_n imply: -(depth + dt v_n) (negative: overlapping) */ \
    X(int64_t, group, c, 0)        /* the patch: its seed contact, -1 unassigned */        \
    X(int64_t, partner, c, 0)      /* the body on the other side */                        \
    X(int64_t, source, c, 0)       /* the listed pair it came from */                      \
    X(double, orient, c, 0.0)      /* +1 if the resolved body is the pair's a, -1 if its b */ \
    X(Vec3, centre_a, c, Vec3{})   /* predicted centre of the resolved body: levers start here */ \
    X(Vec3, centre_b, c, Vec3{})   /* predicted centre of the partner */                   \
    X(int64_t, row, c, -1)         /* its row among its pair's kept contacts (contacts.h), */ \
                                   /* -1 for one found in the pass */

struct ContactSet {
    RG_CONTACT_SET_ROWS(RG_SPAN_FIELD)

    ContactBuffer buffer() const { return {point, normal, depth}; }
};

}  // namespace rg
