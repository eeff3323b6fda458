// Narrow phase: the contacts between two bodies at given poses.
//
// Every contact has a point (world, m), a unit normal pointing from body B to body A (the
// direction that separates A from B) and a depth (m, > 0 when they overlap). For each pair of
// geoms (one of A's, one of B's):
//
// * sphere/capsule against sphere/capsule: closest points of their cores (a point, a
//   segment) in closed form, exact (narrow_cores.cpp);
// * sphere/capsule against box/mesh/plane: the core's points in the other geom's phi, exact
//   for boxes and planes, to the grid's accuracy for meshes (exact outside the grid, where a
//   core of large radius may lie). A capsule's core contributes its two ends (so a capsule
//   lying on a face has two contacts) and the interior minima of phi along it, for edges it
//   crosses: against a plane none (phi is linear along the core), against a box the one
//   minimum of its convex phi, found by golden-section search, against a mesh the local
//   minima of phi sampled at most a grid cell apart, each refined by golden-section search
//   (the deepest CAPSULE_CORE_SAMPLES - 2 of them) (narrow_cores.cpp);
// * box against box: separating axes and face clipping in closed form (box_box.cpp), since
//   sampled distances give sideways normals for boxes stacked face to face;
// * box/mesh against mesh/plane, mesh against box: A's surface samples in B's phi and B's in
//   A's (GBF 2003), corners first, edge samples only where they can add a contact.
//
// The contact point is the deepest point of one body inside the other: a sample, or a core
// point moved by its radius against the normal. The deepest contact of the pair comes first.
#pragma once

#include "collision/geometry.h"

namespace rg {

// The most contacts a capsule's core makes with one box or mesh geom: its 2 ends and up to 3
// interior minima of phi along it.
constexpr int CAPSULE_CORE_SAMPLES = 5;

// Where contacts are written: rows [index, capacity) of three parallel buffers.
struct ContactBuffer {
    Span<Vec3> point;
    Span<Vec3> normal;
    Span<double> depth;

    int64_t capacity() const { return depth.size; }

    // Write one contact at index if it fits (callers count what did not, and grow).
    void emit(int64_t index, Vec3 p, Vec3 n, double d) const {
        if (index < capacity()) {
            point[index] = p;
            normal[index] = n;
            depth[index] = d;
        }
    }
};

// A pose: position (m) and rotation.
struct Pose {
    Vec3 x;
    Mat3 r;
};

// All contacts of body a (pose pa) with body b (pose pb) deeper than -margin (m), written
// to out from row start, deepest first. Returns how many were found: more than fit means
// the buffer was too small (the caller grows it).
int collide_bodies(const Geometry& geo, int a, int b, const Pose& pa, const Pose& pb,
                   double margin, const ContactBuffer& out, int64_t start);

// The world pose of geom g of a body at pose body.
Pose geom_pose(const Geometry& geo, int g, const Pose& body);

// phi of geom g (of the body at pose body) at world point w, and its outward normal in world
// coordinates; reach: phi is needed only below it (geom_distance_within).
Distance world_point_in_geom(const Geometry& geo, int g, const Pose& body, Vec3 w,
                             double reach);

// Sphere/capsule geom ga against sphere/capsule geom gb; contacts found (0 or 1).
int collide_cores(const Geometry& geo, int ga, const Pose& pa, int gb, const Pose& pb,
                  double margin, const ContactBuffer& out, int64_t index);

// Core of sphere/capsule geom gc (of the body at pose pc) in the phi of geom gf (of the body
// at pose pf). sign = +1 when gc belongs to body A (normals are gf's outward normals), -1
// when it belongs to B. Returns the number of contacts found.
int collide_core_with_field(const Geometry& geo, int gc, const Pose& pc, int gf,
                            const Pose& pf, double sign, double margin,
                            const ContactBuffer& out, int64_t index);

// Box A (centre, rotation, half extents) against box B in closed form; normals from B to A.
int collide_boxes(const Pose& a, Vec3 half_a, const Pose& b, Vec3 half_b, double margin,
                  const ContactBuffer& out, int64_t index);

// The largest separation of box A from box B over the 15 separating axes (m; < 0: they
// overlap, by at least its magnitude along every axis). A gap along any axis is a lower bound
// on the boxes' distance, so this never exceeds it (time_of_impact.h relies on that).
double box_separation(const Pose& a, Vec3 half_a, const Pose& b, Vec3 half_b);

// The 8 corners of a box in units of its half extents, in sample order (x slowest), and its
// 12 edges as corner pairs, in sample order (the surface samples of geometry.py).
extern const Vec3 BOX_CORNERS[8];
extern const int BOX_EDGES[12][2];

}  // namespace rg
