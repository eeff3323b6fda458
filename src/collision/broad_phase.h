// Broad phase: which pairs of bodies might touch, from bounding boxes.
//
// Every bounded body has a box in its own frame (Geometry::body_bound_*), grown on every side
// by how far the body can move in the step. Bounded bodies are paired by the world-aligned
// boxes holding those boxes, by brute force (all pairs, O(n^2)) or by sort and sweep along x
// (O(n log n) plus the overlaps), and a pair whose world-aligned boxes overlap is kept only if
// the turned boxes themselves overlap (separating axes): a turned box's world-aligned box is
// up to sqrt(3) times as wide, and every pair listed is narrow-phased in every contact pass
// (the settled 1000-body pile of the report: 5,336 pairs by world-aligned boxes, 3,478 by
// turned ones). Unbounded bodies (planes) are tested against every bounded body's world-
// aligned box. Both methods return the same pairs in the same order: sorted by (a, b), with
// a the body of higher motion class (dynamic > kinematic > static; ties: the lower index), so
// contact normals point from the ground or gripper towards what they touch. Pairs in which
// neither body is dynamic are skipped: nothing could respond.
#pragma once

#include "base/body.h"
#include "collision/geometry.h"

namespace rg {

struct Aabb {
    Vec3 lo, hi;
};

// One world's broad-phase buffers (n bodies, p pair capacity), as a table (base/span.h).
#define RG_PAIR_LIST_BODY_ROWS(X)                                                             \
    X(Aabb, bounds, n, Aabb{})  /* scratch */                                                 \
    X(int64_t, order, n, 0)     /* body indices, kept between calls (sort and sweep starts */ \
                                /* from the last order: nearly sorted, O(n) to re-sort); */   \
                                /* brute force's scratch (a world never changes method) */    \
    X(double, reach, n, 0.0)    /* m, how far each body's box was grown */
#define RG_PAIR_LIST_PAIR_ROWS(X)                                                             \
    X(int32_t, pair_a, p, 0)    /* out */                                                     \
    X(int32_t, pair_b, p, 0)    /* out */                                                     \
    X(int64_t, keys, p, 0)      /* sorting scratch */                                         \
    X(int64_t, spare, p, 0)     /* sorting scratch */

struct PairLists {
    RG_PAIR_LIST_BODY_ROWS(RG_SPAN_FIELD)
    RG_PAIR_LIST_PAIR_ROWS(RG_SPAN_FIELD)
};

// How far (m) any point of body i can move in dt: |V| dt + |omega| dt (its reach from the
// centre of mass) + |a| dt^2 for an acceleration bound |a| (gravity), plus margin.
double swept_margin(const Geometry& geo, int i, Vec3 velocity, Vec3 angular_velocity,
                    double margin, double dt, double acceleration);

// Pairs known without testing: where kept[i] and kept[j] (both bodies exactly as when the
// last list was made, with the same dt, sleep.h), the pair is listed iff the last list had it,
// so those pairs are taken from that list and never tested. A kept body's box and reach are
// left as that list made them. Empty spans: every pair is tested, every box made.
struct Carried {
    Span<const uint8_t> kept;  // (n,) or empty
    Span<const int64_t> keys;  // the last list's pairs with a kept body, as a n + b in (a, b) order
};

// Candidate pairs of one world for poses anywhere within the next dt; returns how many.
// Every box is grown by swept_margin (dt = 0: the current poses only), or by reach[i] (m)
// where that is larger, and reach is raised to the growth used (zero it for the margins
// alone). sweep: sort and sweep, else brute force. The count may exceed the pair capacity:
// then only that many were written and the caller must grow the buffers.
int64_t find_world_pairs(const Geometry& geo, Span<const int32_t> motion,
                         const BodyStates& bodies, double margin, double dt,
                         double acceleration, bool sweep, const PairLists& lists,
                         Carried carried = {});

}  // namespace rg
