// Spheres and capsules: a core (a point, a segment) plus a radius (narrow_phase.h).
#include <algorithm>
#include <cmath>

#include "collision/narrow_phase.h"

namespace rg {

namespace {

// Golden-section steps that refine a minimum of phi along a capsule's core; each keeps
// 0.618 of the bracket, so 48 of them leave 1e-10 of it.
constexpr int CORE_SEARCH_ITERATIONS = 48;
// An interior minimum of phi along a capsule's core is a contact only if it is deeper than
// the ends of its bracket by this much, m: a capsule lying on a face has its two ends only.
constexpr double CORE_MINIMUM_TOLERANCE = 1e-9;
// Cap on the samples of a capsule's core against a mesh (normally one per grid cell of the
// part of the core near the mesh's grid).
constexpr int CORE_MAX_SAMPLES = 256;

// World position of the point at parameter t in [-1, 1] along geom g's core (a sphere's
// centre; a capsule's axis from -half_length to +half_length).
Vec3 core_point(const Geometry& geo, int g, const Pose& body, double t) {
    const Vec3 p = geo.geom_position[g];
    const Mat3& gr = geo.geom_rotation[g];
    const double s = geo.geom_type[g] == CAPSULE ? t * geo.geom_size[g].y : 0.0;
    return to_world(body.x, body.r,
                    {p.x + s * gr.m[0][2], p.y + s * gr.m[1][2], p.z + s * gr.m[2][2]});
}

// Parameters (s, t) in [0, 1] of the closest points p1 + s (q1 - p1), p2 + t (q2 - p2) of
// two segments (Ericson, Real-Time Collision Detection, 5.1.9).
void closest_on_segments(Vec3 p1, Vec3 q1, Vec3 p2, Vec3 q2, double& s, double& t) {
    const Vec3 d1 = sub(q1, p1), d2 = sub(q2, p2), r = sub(p1, p2);
    const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    s = t = 0.0;
    if (a == 0.0 && e == 0.0) {
        return;
    }
    if (a == 0.0) {
        t = std::min(std::max(f / e, 0.0), 1.0);
        return;
    }
    const double c = dot(d1, r);
    if (e == 0.0) {
        s = std::min(std::max(-c / a, 0.0), 1.0);
        return;
    }
    const double b = dot(d1, d2);
    const double denom = a * e - b * b;
    s = denom > 0.0 ? std::min(std::max((b * f - c * e) / denom, 0.0), 1.0) : 0.0;
    t = (b * s + f) / e;
    if (t < 0.0) {
        t = 0.0;
        s = std::min(std::max(-c / a, 0.0), 1.0);
    } else if (t > 1.0) {
        t = 1.0;
        s = std::min(std::max((b - c) / a, 0.0), 1.0);
    }
}

// The point at parameter t of sphere/capsule geom gc's core in the phi of geom gf: writes a
// contact at index if it is one. Returns the contacts written (0 or 1); phi there and gf's
// outward normal (world) in `at`.
int core_contact(const Geometry& geo, int gc, const Pose& pc, int gf, const Pose& pf, double t,
                 double sign, double margin, const ContactBuffer& out, int64_t index,
                 Distance& at) {
    const double radius = geo.geom_size[gc].x;
    const Vec3 c = core_point(geo, gc, pc, t);
    at = world_point_in_geom(geo, gf, pf, c, radius + margin);
    const double depth = radius - at.phi;
    if (depth <= -margin) {
        return 0;
    }
    const Vec3 n = at.normal;
    out.emit(index, {c.x - radius * n.x, c.y - radius * n.y, c.z - radius * n.z},
             scale(sign, n), depth);
    return 1;
}

int core_contact(const Geometry& geo, int gc, const Pose& pc, int gf, const Pose& pf, double t,
                 double sign, double margin, const ContactBuffer& out, int64_t index) {
    Distance unused;
    return core_contact(geo, gc, pc, gf, pf, t, sign, margin, out, index, unused);
}

// A core's ends (t = -1, t = 1) in the frame of geom gf.
struct CoreEnds {
    Vec3 a, b;
};

CoreEnds core_in_geom_frame(const Geometry& geo, int gc, const Pose& pc, int gf, const Pose& pf) {
    const Vec3 gp = geo.geom_position[gf];
    const Mat3& gr = geo.geom_rotation[gf];
    const Vec3 a = to_local(gp, gr, to_local(pf.x, pf.r, core_point(geo, gc, pc, -1.0)));
    const Vec3 b = to_local(gp, gr, to_local(pf.x, pf.r, core_point(geo, gc, pc, 1.0)));
    return {a, b};
}

// phi of geom gf at the point of parameter t in [-1, 1] of a core with these ends, m.
double core_phi(const Geometry& geo, int gf, const CoreEnds& ends, double t, double reach) {
    const double s = 0.5 * (t + 1.0);
    const Vec3 a = ends.a, b = ends.b;
    return geom_distance_within(
               geo, gf, {a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), a.z + s * (b.z - a.z)},
               reach)
        .phi;
}

// Golden-section search for the t in [lo, hi] where phi of geom gf along a core is least:
// the global minimum where phi is convex along the core (a box's), a local one otherwise.
void core_minimum(const Geometry& geo, int gf, const CoreEnds& ends, double reach, double lo,
                  double hi, double& t, double& phi) {
    const double ratio = 0.6180339887498949;
    double c = hi - ratio * (hi - lo);
    double d = lo + ratio * (hi - lo);
    double fc = core_phi(geo, gf, ends, c, reach);
    double fd = core_phi(geo, gf, ends, d, reach);
    for (int k = 0; k < CORE_SEARCH_ITERATIONS; ++k) {
        if (fc <= fd) {
            hi = d;
            d = c;
            fd = fc;
            c = hi - ratio * (hi - lo);
            fc = core_phi(geo, gf, ends, c, reach);
        } else {
            lo = c;
            c = d;
            fc = fd;
            d = lo + ratio * (hi - lo);
            fd = core_phi(geo, gf, ends, d, reach);
        }
    }
    if (fc <= fd) {
        t = c;
        phi = fc;
    } else {
        t = d;
        phi = fd;
    }
}

// The parameters [t0, t1] of the part of a core within reach (m) of mesh geom gf's grid box
// (slab clipping); t0 > t1 when there is none.
void core_range_near_grid(const Geometry& geo, int gf, const CoreEnds& ends, double reach,
                          double& t0, double& t1) {
    const int m = geo.geom_grid[gf];
    const double h = geo.grid_spacing[m];
    double s0 = 0.0, s1 = 1.0;
    for (int c = 0; c < 3; ++c) {
        const double p = ends.a[c], q = ends.b[c];
        const double lo = geo.grid_origin[m][c] - reach;
        const double hi = geo.grid_origin[m][c] + (geo.grid_shape[m][c] - 1) * h + reach;
        if (p == q) {
            if (p < lo || p > hi) {
                t0 = 1.0;
                t1 = -1.0;
                return;
            }
            continue;
        }
        const double e0 = (lo - p) / (q - p), e1 = (hi - p) / (q - p);
        s0 = std::max(s0, std::min(e0, e1));
        s1 = std::min(s1, std::max(e0, e1));
    }
    t0 = 2.0 * s0 - 1.0;
    t1 = 2.0 * s1 - 1.0;
}

// A capsule's core against a mesh: local minima of phi sampled at most a grid cell apart
// along the part of the core near the grid, each refined by golden-section search; the
// deepest CAPSULE_CORE_SAMPLES - 2 are kept after the `found` end contacts at index.
int collide_core_with_mesh(const Geometry& geo, int gc, const Pose& pc, int gf, const Pose& pf,
                           double sign, double margin, const ContactBuffer& out, int64_t index,
                           int found) {
    const double reach = geo.geom_size[gc].x + margin;
    const CoreEnds ends = core_in_geom_frame(geo, gc, pc, gf, pf);
    double t0, t1;
    core_range_near_grid(geo, gf, ends, reach, t0, t1);
    if (t0 >= t1) {
        return found;
    }
    const double length = (t1 - t0) * geo.geom_size[gc].y;
    const int count = std::min(
        std::max(static_cast<int>(std::ceil(length / geo.grid_spacing[geo.geom_grid[gf]])), 2),
        CORE_MAX_SAMPLES);
    const double step = (t1 - t0) / count;
    int interior = 0;
    double before = core_phi(geo, gf, ends, t0, reach);
    double here = core_phi(geo, gf, ends, t0 + step, reach);
    for (int k = 1; k < count; ++k) {
        const double after = core_phi(geo, gf, ends, t0 + (k + 1) * step, reach);
        if (here < before && here <= after && here < reach) {
            double t, phi;
            core_minimum(geo, gf, ends, reach, t0 + (k - 1) * step, t0 + (k + 1) * step, t, phi);
            if (phi < std::min(before, after) - CORE_MINIMUM_TOLERANCE && phi < reach) {
                // keep the deepest CAPSULE_CORE_SAMPLES - 2: replace the shallowest if full
                int64_t slot = index + found + interior;
                if (interior == CAPSULE_CORE_SAMPLES - 2) {
                    slot = -1;
                    const int64_t end = index + found + interior;
                    if (end <= out.capacity()) {
                        slot = index + found;
                        for (int64_t j = index + found + 1; j < end; ++j) {
                            if (out.depth[j] < out.depth[slot]) {
                                slot = j;
                            }
                        }
                        if (out.depth[slot] >= geo.geom_size[gc].x - phi) {
                            slot = -1;
                        }
                    }
                } else {
                    interior += 1;
                }
                if (slot >= 0) {
                    core_contact(geo, gc, pc, gf, pf, t, sign, margin, out, slot);
                }
            }
        }
        before = here;
        here = after;
    }
    return found + interior;
}

// The part [t0, t1] of a core over the face of box geom gf (half extents `half`) nearest to
// its point at t, the core's least phi: the face along the axis on which that point lies
// furthest outside the box, the core clipped to the slabs of the two others. A capsule lying
// across a face narrower than itself touches it along a segment, not at a point: the clipped
// segment's ends (within margin) are its contacts, as box-box clipping gives a face's
// corners. One point at the minimum (its place along a flat minimum is arbitrary) let a
// plank lying across two round bars rock and creep on it (0.5 mm in 5 s); a slightly tilted
// face has its minimum at one edge and the other edge within the margin. False when the
// point is not outside the box or the clipped part is empty (then t0 >= t1).
bool core_over_face(Vec3 half, const CoreEnds& ends, double t, double& t0, double& t1) {
    const Vec3 a = ends.a, d = sub(ends.b, ends.a);
    const double s = 0.5 * (t + 1.0);
    const Vec3 p = {a.x + s * d.x, a.y + s * d.y, a.z + s * d.z};
    int face = 0;
    for (int c = 1; c < 3; ++c) {
        face = std::fabs(p[c]) - half[c] > std::fabs(p[face]) - half[face] ? c : face;
    }
    if (!(std::fabs(p[face]) > half[face])) {
        return false;  // the core's deepest point inside the box: no face to clip against
    }
    double s0 = 0.0, s1 = 1.0;
    for (int c = 0; c < 3; ++c) {
        if (c == face) {
            continue;
        }
        if (d[c] == 0.0) {
            if (std::fabs(a[c]) > half[c]) {
                return false;  // parallel to the slab, outside it
            }
            continue;
        }
        const double e0 = (-half[c] - a[c]) / d[c], e1 = (half[c] - a[c]) / d[c];
        s0 = std::max(s0, std::min(e0, e1));
        s1 = std::min(s1, std::max(e0, e1));
    }
    t0 = 2.0 * s0 - 1.0;
    t1 = 2.0 * s1 - 1.0;
    return t1 > t0;
}

}  // namespace

int collide_cores(const Geometry& geo, int ga, const Pose& pa, int gb, const Pose& pb,
                  double margin, const ContactBuffer& out, int64_t index) {
    const Vec3 a0 = core_point(geo, ga, pa, -1.0), a1 = core_point(geo, ga, pa, 1.0);
    const Vec3 b0 = core_point(geo, gb, pb, -1.0), b1 = core_point(geo, gb, pb, 1.0);
    double s, t;
    closest_on_segments(a0, a1, b0, b1, s, t);
    const Vec3 qa = {a0.x + s * (a1.x - a0.x), a0.y + s * (a1.y - a0.y), a0.z + s * (a1.z - a0.z)};
    const Vec3 qb = {b0.x + t * (b1.x - b0.x), b0.y + t * (b1.y - b0.y), b0.z + t * (b1.z - b0.z)};
    const Vec3 d = sub(qa, qb);
    const double dist = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    const double radius_a = geo.geom_size[ga].x, radius_b = geo.geom_size[gb].x;
    const double depth = radius_a + radius_b - dist;
    if (depth <= -margin) {
        return 0;
    }
    const Vec3 n = dist > 0.0 ? Vec3{d.x / dist, d.y / dist, d.z / dist} : Vec3{0.0, 0.0, 1.0};
    out.emit(index, {qa.x - radius_a * n.x, qa.y - radius_a * n.y, qa.z - radius_a * n.z}, n,
             depth);
    return 1;
}

int collide_core_with_field(const Geometry& geo, int gc, const Pose& pc, int gf,
                            const Pose& pf, double sign, double margin,
                            const ContactBuffer& out, int64_t index) {
    if (geo.geom_type[gc] != CAPSULE) {
        return core_contact(geo, gc, pc, gf, pf, 0.0, sign, margin, out, index);
    }
    Distance lo, hi;
    int found = core_contact(geo, gc, pc, gf, pf, -1.0, sign, margin, out, index, lo);
    found += core_contact(geo, gc, pc, gf, pf, 1.0, sign, margin, out, index + found, hi);
    if (geo.geom_type[gf] == PLANE) {
        return found;
    }
    if (geo.geom_type[gf] != BOX) {
        return collide_core_with_mesh(geo, gc, pc, gf, pf, sign, margin, out, index, found);
    }
    // A box's phi is convex, so along the core it falls below both ends' values only if it
    // falls inwards from each end; the gradient at an end (a subgradient where phi has a
    // ridge) bounds that slope from below: where it does not fall, an end is least.
    const double reach = geo.geom_size[gc].x + margin;
    const Vec3 axis = rotate(pc.r, geo.geom_rotation[gc].column(2));  // the core, t = -1 to 1
    if (dot(lo.normal, axis) >= 0.0 || dot(hi.normal, axis) <= 0.0) {
        return found;
    }
    double t, phi;
    const CoreEnds ends = core_in_geom_frame(geo, gc, pc, gf, pf);
    core_minimum(geo, gf, ends, reach, -1.0, 1.0, t, phi);
    if (!(phi < std::min(lo.phi, hi.phi) - CORE_MINIMUM_TOLERANCE && phi < reach)) {
        return found;
    }
    // the clipped segment, stretched to the minimum where that lies beyond the face's edge
    // (the core crosses the edge: the minimum is the deepest point there): its ends inside
    // the core (its own ends are written already), or the minimum alone
    double t0 = t, t1 = t;
    const bool over = core_over_face(geo.geom_size[gf], ends, t, t0, t1);
    t0 = std::min(t0, t);
    t1 = std::max(t1, t);
    if (!over || (t0 <= -1.0 && t1 >= 1.0) || t1 - t0 <= CORE_MINIMUM_TOLERANCE) {
        return found + core_contact(geo, gc, pc, gf, pf, t, sign, margin, out, index + found);
    }
    if (t0 > -1.0) {
        found += core_contact(geo, gc, pc, gf, pf, t0, sign, margin, out, index + found);
    }
    if (t1 < 1.0) {
        found += core_contact(geo, gc, pc, gf, pf, t1, sign, margin, out, index + found);
    }
    return found;
}

}  // namespace rg
