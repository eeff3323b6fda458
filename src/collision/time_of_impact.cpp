// Conservative advancement over the bodies' separation (time_of_impact.h).
#include "collision/time_of_impact.h"

#include <algorithm>
#include <cmath>

namespace rg {

namespace {

// Advances before time_of_impact gives up and returns the t reached (still before any
// impact: every advance is conservative). Face against face or vertex takes 1-3; a corner
// meeting a corner closes the gap by at least 1 - 1/sqrt(3) an advance.
constexpr int MAX_ADVANCES = 64;
// The advance stops once the separation is within this fraction of target above it.
constexpr double TARGET_TOLERANCE = 0.25;

bool is_core(const Geometry& geo, int g) {
    return geo.geom_type[g] == SPHERE || geo.geom_type[g] == CAPSULE;
}

// The least phi (m) of geom gs's surface samples (body at pose ps) in geom gf (body at pose
// pf), vertices only against a plane; at least `reach` where none is nearer.
double samples_in_field(const Geometry& geo, int gs, const Pose& ps, int gf, const Pose& pf,
                        double reach) {
    const int begin = geo.sample_start[gs];
    const int end = geo.geom_type[gf] == PLANE ? begin + geo.sample_vertex_count[gs]
                                               : geo.sample_start[gs + 1];
    double least = reach;
    for (int k = begin; k < end; ++k) {
        const Vec3 p = to_world(ps.x, ps.r, geo.sample_points[k]);
        least = std::min(least, world_point_in_geom(geo, gf, pf, p, reach).phi);
    }
    return least;
}

// The deepest of the contacts a narrow-phase call found in out (m of separation: -depth), or
// reach when it found none.
double deepest(const ContactBuffer& out, int found, double reach) {
    double least = reach;
    for (int k = 0; k < std::min<int64_t>(found, out.capacity()); ++k) {
        least = std::min(least, -out.depth[k]);
    }
    return least;
}

}  // namespace

Pose sweep_pose(const Sweep& s, double t) {
    const Vec3 x = {s.x.x + t * s.shift.x, s.x.y + t * s.shift.y, s.x.z + t * s.shift.z};
    return {x, rotation_from_quaternion(rotate_by_angular_velocity(s.q, s.turn, t))};
}

double body_separation(const Geometry& geo, int a, int b, const Pose& pa, const Pose& pb,
                       double reach) {
    Vec3 point[CAPSULE_CORE_SAMPLES], normal[CAPSULE_CORE_SAMPLES];
    double depth[CAPSULE_CORE_SAMPLES];
    const ContactBuffer out = {{point, CAPSULE_CORE_SAMPLES}, {normal, CAPSULE_CORE_SAMPLES},
                               {depth, CAPSULE_CORE_SAMPLES}};
    double least = reach;
    for (int ga = geo.body_geom_start[a]; ga < geo.body_geom_start[a + 1]; ++ga) {
        for (int gb = geo.body_geom_start[b]; gb < geo.body_geom_start[b + 1]; ++gb) {
            double gap;
            if (is_core(geo, ga) && is_core(geo, gb)) {
                gap = deepest(out, collide_cores(geo, ga, pa, gb, pb, reach, out, 0), reach);
            } else if (is_core(geo, ga)) {
                gap = deepest(out, collide_core_with_field(geo, ga, pa, gb, pb, 1.0, reach, out, 0),
                              reach);
            } else if (is_core(geo, gb)) {
                gap = deepest(out, collide_core_with_field(geo, gb, pb, ga, pa, 1.0, reach, out, 0),
                              reach);
            } else if (geo.geom_type[ga] == BOX && geo.geom_type[gb] == BOX) {
                gap = box_separation(geom_pose(geo, ga, pa), geo.geom_size[ga],
                                     geom_pose(geo, gb, pb), geo.geom_size[gb]);
            } else {
                gap = std::min(samples_in_field(geo, ga, pa, gb, pb, reach),
                               samples_in_field(geo, gb, pb, ga, pa, reach));
            }
            least = std::min(least, gap);
        }
    }
    return least;
}

double time_of_impact(const Geometry& geo, int a, int b, const Sweep& sa, const Sweep& sb,
                      double target) {
    const double rate = length(sub(sa.shift, sb.shift)) + length(sa.turn) * sa.reach +
                        length(sb.turn) * sb.reach;  // m per unit of t, at most
    double t = 0.0;
    for (int advance = 0; advance < MAX_ADVANCES; ++advance) {
        const double ahead = rate * (1.0 - t);  // the most the gap can still close
        const double gap =
            body_separation(geo, a, b, sweep_pose(sa, t), sweep_pose(sb, t), ahead + 2.0 * target);
        if (gap <= target * (1.0 + TARGET_TOLERANCE)) {
            return t;
        }
        if (gap - target >= ahead) {
            return NO_IMPACT;
        }
        t += (gap - target) / rate;
    }
    return t;
}

}  // namespace rg
