// Contacts at the time of impact, carried on to the end of the step (continuous.h).
#include "solver/continuous.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "collision/time_of_impact.h"

namespace rg {

namespace {

// Body i's half thickness (m; infinite for a plane, whose pairs are never swept): its
// thinnest geom's (continuous.h).
double half_thickness(const Geometry& geo, int i) {
    double least = std::numeric_limits<double>::infinity();
    for (int g = geo.body_geom_start[i]; g < geo.body_geom_start[i + 1]; ++g) {
        const Vec3 h = geo.geom_size[g];
        switch (geo.geom_type[g]) {
            case SPHERE:
            case CAPSULE:
                least = std::min(least, h.x);
                break;
            case BOX:
                least = std::min({least, h.x, h.y, h.z});
                break;
            case MESH: {
                const Vec3 bound = geo.body_bound_half[i];
                least = std::min({least, bound.x, bound.y, bound.z});
                break;
            }
            default:  // PLANE
                break;
        }
    }
    return least;
}

Sweep body_sweep(const StepContext& w, int i, const Travel& m) {
    return {w.bodies.position[i], w.bodies.orientation[i], m.shift, m.turn, w.body_reach[i]};
}

// Swap the deepest of rows [begin, end) into row begin (collide_bodies' order).
void deepest_first(const ContactBuffer& out, int64_t begin, int64_t end) {
    int64_t deepest = begin;
    for (int64_t r = begin + 1; r < end; ++r) {
        if (out.depth[r] > out.depth[deepest]) {
            deepest = r;
        }
    }
    std::swap(out.point[begin], out.point[deepest]);
    std::swap(out.normal[begin], out.normal[deepest]);
    std::swap(out.depth[begin], out.depth[deepest]);
}

}  // namespace

int collide_swept(const StepContext& w, int a, int b, const Pose& pa, const Pose& pb,
                  const Travel& ma, const Travel& mb, double margin, const ContactBuffer& out,
                  int64_t start, Vec3& centre_a, Vec3& centre_b) {
    centre_a = pa.x;
    centre_b = pb.x;
    // a half-space's normal never flips and nothing passes it: a plane's pairs as predicted
    if (!w.settings->continuous || w.geo->body_unbounded[a] || w.geo->body_unbounded[b]) {
        return collide_bodies(*w.geo, a, b, pa, pb, margin, out, start);
    }
    const double relative = length(sub(ma.shift, mb.shift)) + length(ma.turn) * w.body_reach[a] +
                            length(mb.turn) * w.body_reach[b];
    const double thin = std::min(half_thickness(*w.geo, a), half_thickness(*w.geo, b));
    if (!(relative > thin)) {  // no prediction carried past a mid-plane (continuous.h)
        return collide_bodies(*w.geo, a, b, pa, pb, margin, out, start);
    }
    // apart by gap, the step closes them by at most relative - gap: the prediction's depth.
    // Their centres' distance less their reaches bounds the gap from below, for nothing
    const double apart = length(sub(w.bodies.position[a], w.bodies.position[b])) -
                         w.body_reach[a] - w.body_reach[b];
    if (apart > 0.0 && relative - apart <= thin) {
        return collide_bodies(*w.geo, a, b, pa, pb, margin, out, start);
    }
    const Sweep sa = body_sweep(w, a, ma), sb = body_sweep(w, b, mb);
    const double gap = body_separation(*w.geo, a, b, sweep_pose(sa, 0.0), sweep_pose(sb, 0.0),
                                       relative);
    if (gap > 0.0 && relative - gap <= thin) {
        return collide_bodies(*w.geo, a, b, pa, pb, margin, out, start);
    }
    const double t = time_of_impact(*w.geo, a, b, sa, sb, SWEEP_TARGET);
    // apart at t, the rest of the step closes them by at most (1 - t) relative: where that
    // is no deeper than thin, the prediction is trusted without looking at time t
    if (t >= 1.0 || (t > 0.0 && (1.0 - t) * relative <= thin)) {
        return collide_bodies(*w.geo, a, b, pa, pb, margin, out, start);
    }
    const Pose ta = sweep_pose(sa, t), tb = sweep_pose(sb, t);
    centre_a = ta.x;
    centre_b = tb.x;
    const int found = collide_bodies(*w.geo, a, b, ta, tb, margin, out, start);
    if (start + found > out.capacity()) {
        return found;  // the caller grows the buffer and asks again
    }
    // carry each depth on to the end of the step; keep those still deeper than -margin
    const double rest = 1.0 - t;
    const Vec3 relative_shift = sub(ma.shift, mb.shift);
    int kept = 0;
    double deepest = -margin;
    for (int64_t r = start; r < start + found; ++r) {
        const Vec3 n = out.normal[r], p = out.point[r];
        const double closing = dot(relative_shift, n) + dot(ma.turn, cross(sub(p, ta.x), n)) -
                               dot(mb.turn, cross(sub(p, tb.x), n));
        const double depth = out.depth[r] - rest * closing;
        deepest = std::max(deepest, depth);
        if (depth > -margin) {
            out.point[start + kept] = p;
            out.normal[start + kept] = n;
            out.depth[start + kept] = depth;
            kept += 1;
        }
    }
    if (deepest <= thin) {  // the prediction is not carried past a mid-plane: trust it
        centre_a = pa.x;
        centre_b = pb.x;
        return collide_bodies(*w.geo, a, b, pa, pb, margin, out, start);
    }
    if (kept > 1) {
        deepest_first(out, start, start + kept);
    }
    return kept;
}

}  // namespace rg
