// The narrow phase's dispatch over geom pairs, and surface samples in a signed distance
// (narrow_phase.h).
#include "collision/narrow_phase.h"

#include <utility>

namespace rg {

const Vec3 BOX_CORNERS[8] = {{-1, -1, -1}, {-1, -1, 1}, {-1, 1, -1}, {-1, 1, 1},
                             {1, -1, -1},  {1, -1, 1},  {1, 1, -1},  {1, 1, 1}};
const int BOX_EDGES[12][2] = {{0, 1}, {0, 2}, {0, 4}, {1, 3}, {1, 5}, {2, 3},
                              {2, 6}, {3, 7}, {4, 5}, {4, 6}, {5, 7}, {6, 7}};

Pose geom_pose(const Geometry& geo, int g, const Pose& body) {
    const Mat3& gr = geo.geom_rotation[g];
    Pose pose;
    pose.x = to_world(body.x, body.r, geo.geom_position[g]);
    for (int c = 0; c < 3; ++c) {
        const Vec3 axis = rotate(body.r, gr.column(c));
        pose.r.m[0][c] = axis.x;
        pose.r.m[1][c] = axis.y;
        pose.r.m[2][c] = axis.z;
    }
    return pose;
}

Distance world_point_in_geom(const Geometry& geo, int g, const Pose& body, Vec3 w,
                             double reach) {
    const Vec3 in_body = to_local(body.x, body.r, w);
    const Mat3& gr = geo.geom_rotation[g];
    const Vec3 in_geom = to_local(geo.geom_position[g], gr, in_body);
    Distance d = geom_distance_within(geo, g, in_geom, reach);
    d.normal = rotate(body.r, rotate(gr, d.normal));
    return d;
}

namespace {

bool is_core(const Geometry& geo, int g) {
    return geo.geom_type[g] == SPHERE || geo.geom_type[g] == CAPSULE;
}

// Surface sample k (of a geom of the body at pose ps) in the phi of geom gf (of the body at
// pose pf); 1 if it is a contact (written at index), else 0.
int sample_in_field(const Geometry& geo, int k, const Pose& ps, int gf, const Pose& pf,
                    double sign, double margin, const ContactBuffer& out, int64_t index) {
    const Vec3 w = to_world(ps.x, ps.r, geo.sample_points[k]);
    const Distance d = world_point_in_geom(geo, gf, pf, w, margin);
    if (-d.phi <= -margin) {
        return 0;
    }
    out.emit(index, w, scale(sign, d.normal), -d.phi);
    return 1;
}

// Surface samples of box or mesh geom gs (of the body at pose ps) in the phi of geom gf (of
// the body at pose pf); sign as in collide_core_with_field. Returns the contacts found.
//
// The corners/vertices (the first sample_vertex_count samples) are always tested. Against a
// plane nothing else can be deepest (a polyhedron's deepest point in a half-space is a
// vertex). A box's edge samples are tested only on edges with neither corner inside: that is
// exactly the edge-edge crossing the corners miss, and it keeps a resting face to 4 contacts.
// A mesh's edge samples are always tested (its target may be nonconvex).
int collide_samples_with_field(const Geometry& geo, int gs, const Pose& ps, int gf,
                               const Pose& pf, double sign, double margin,
                               const ContactBuffer& out, int64_t index) {
    const int begin = geo.sample_start[gs], end = geo.sample_start[gs + 1];
    const int vertices = geo.sample_vertex_count[gs];
    int found = 0;
    uint32_t corner_inside = 0;
    for (int k = begin; k < begin + vertices; ++k) {
        const int hit = sample_in_field(geo, k, ps, gf, pf, sign, margin, out, index + found);
        found += hit;
        if (hit && k - begin < 32) {
            corner_inside |= 1u << (k - begin);
        }
    }
    if (geo.geom_type[gf] == PLANE) {
        return found;
    }
    if (geo.geom_type[gs] != BOX) {
        for (int k = begin + vertices; k < end; ++k) {
            found += sample_in_field(geo, k, ps, gf, pf, sign, margin, out, index + found);
        }
        return found;
    }
    const int per_edge = (end - begin - vertices) / 12;
    for (int e = 0; e < 12; ++e) {
        if (((corner_inside >> BOX_EDGES[e][0]) & 1u) || ((corner_inside >> BOX_EDGES[e][1]) & 1u)) {
            continue;
        }
        const int first = begin + vertices + e * per_edge;
        for (int k = first; k < first + per_edge; ++k) {
            found += sample_in_field(geo, k, ps, gf, pf, sign, margin, out, index + found);
        }
    }
    return found;
}

// Swap the deepest contact of rows [begin, end) into row begin.
void move_deepest_first(const ContactBuffer& out, int64_t begin, int64_t end) {
    int64_t deepest = begin;
    for (int64_t k = begin + 1; k < end; ++k) {
        if (out.depth[k] > out.depth[deepest]) {
            deepest = k;
        }
    }
    if (deepest != begin) {
        std::swap(out.point[begin], out.point[deepest]);
        std::swap(out.normal[begin], out.normal[deepest]);
        std::swap(out.depth[begin], out.depth[deepest]);
    }
}

}  // namespace

int collide_bodies(const Geometry& geo, int a, int b, const Pose& pa, const Pose& pb,
                   double margin, const ContactBuffer& out, int64_t start) {
    int found = 0;
    for (int ga = geo.body_geom_start[a]; ga < geo.body_geom_start[a + 1]; ++ga) {
        for (int gb = geo.body_geom_start[b]; gb < geo.body_geom_start[b + 1]; ++gb) {
            const int64_t index = start + found;
            if (is_core(geo, ga) && is_core(geo, gb)) {
                found += collide_cores(geo, ga, pa, gb, pb, margin, out, index);
            } else if (is_core(geo, ga)) {
                found += collide_core_with_field(geo, ga, pa, gb, pb, 1.0, margin, out, index);
            } else if (is_core(geo, gb)) {
                found += collide_core_with_field(geo, gb, pb, ga, pa, -1.0, margin, out, index);
            } else if (geo.geom_type[ga] == BOX && geo.geom_type[gb] == BOX) {
                found += collide_boxes(geom_pose(geo, ga, pa), geo.geom_size[ga],
                                       geom_pose(geo, gb, pb), geo.geom_size[gb], margin, out,
                                       index);
            } else {
                found += collide_samples_with_field(geo, ga, pa, gb, pb, 1.0, margin, out, index);
                found += collide_samples_with_field(geo, gb, pb, ga, pa, -1.0, margin, out,
                                                    start + found);
            }
        }
    }
    if (found > 0 && start + found <= out.capacity()) {
        move_deepest_first(out, start, start + found);
    }
    return found;
}

}  // namespace rg
