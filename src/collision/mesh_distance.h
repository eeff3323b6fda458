// Closed triangle meshes: generalised winding number and signed distance of points.
//
// A mesh is `vertices` (V,) positions in metres and `triangles` (T,) vertex indices, wound
// counter-clockwise seen from outside (outward normals), as rigid_gym.shapes.Mesh stores
// them. Points are (P,) in the same frame. Both functions share the points out over the
// process's worker pool (thread_pool.h) and loop over every triangle for each point, so they
// cost O(P T): meant for the small meshes of a manipulation scene and for offline work such
// as mass properties (the distance grids of rigid_gym/geometry.py, rigid_gym/inertia.py).
// Each point's result is computed by one thread alone, so it does not depend on the split.
//
// Every index in `triangles` must lie in [0, V) (the bindings check it); Mesh validates the
// mesh itself (closed, consistently wound, positive volume).
#pragma once

#include "collision/geometry.h"
#include "base/math.h"
#include "base/span.h"

namespace rg {

// The point of triangle (a, b, c) nearest to p.
Vec3 closest_on_triangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c);

// Generalised winding number of each point: the signed solid angles of all triangles / 4 pi,
// into out (P,). 1 inside a closed outward mesh, 0 outside, 1/2 on the surface (up to
// rounding). Right for nonconvex meshes too (Jacobson et al. 2013).
void winding_number(Span<const Vec3> points, Span<const Vec3> vertices,
                    Span<const Index3> triangles, Span<double> out);

// Signed distance of each point to the mesh surface, m, into out (P,). Magnitude: exact
// distance to the nearest triangle. Sign: negative where the winding number exceeds 1/2
// (inside), positive elsewhere.
void signed_distance(Span<const Vec3> points, Span<const Vec3> vertices,
                     Span<const Index3> triangles, Span<double> out);

}  // namespace rg
