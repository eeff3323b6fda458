// Compiled collision geometry and the signed distances phi(p) of every geom type (the
// representation of Guendelman, Bridson & Fedkiw 2003).
//
// A geom is one primitive of a body, placed in the body's principal frame; a Compound gives a
// body several. The arrays are built in Python (rigid_gym/geometry.py, compile_geometry) and
// copied here once per World. Distances are evaluated in the geom's own frame; phi < 0
// inside, and the gradient (unit length) is the outward normal.
//
//     SPHERE   size (r, -, -)          exact
//     CAPSULE  size (r, half_length, -) exact, axis z
//     BOX      size (hx, hy, hz)       exact
//     MESH     a signed distance sampled on a grid, trilinear inside the grid; outside it, the
//              distance to the grid box plus the value at the nearest grid point (an upper
//              bound, >= the gap to the box), or, through geom_distance_within where that
//              gap is small enough to matter, the exact distance to the triangles
//     PLANE    the half-space z <= 0   exact
#pragma once

#include <array>
#include <cstdint>

#include "base/math.h"
#include "base/span.h"

namespace rg {

enum GeomType : int32_t { SPHERE = 0, CAPSULE = 1, BOX = 2, MESH = 3, PLANE = 4 };

using Index3 = std::array<int32_t, 3>;

// Collision geometry of n bodies as G geoms, S surface samples and M distance grids.
struct Geometry {
    Array<int32_t> geom_body;       // (G,) the body of each geom
    Array<int32_t> geom_type;       // (G,) GeomType
    Array<Vec3> geom_size;          // (G,) m: sphere (r, 0, 0), capsule (r, half_length, 0),
                                    //      box half extents
    Array<Vec3> geom_position;      // (G,) m, the geom frame in the body frame
    Array<Mat3> geom_rotation;      // (G,)
    Array<int32_t> geom_grid;       // (G,) the mesh's grid, -1 for other types
    Array<int32_t> body_geom_start;  // (n + 1,) body i owns geoms [start[i], start[i + 1])
    Array<int32_t> sample_start;    // (G + 1,) each geom's surface samples
    Array<int32_t> sample_vertex_count;  // (G,) corners or vertices first, this many
    Array<Vec3> sample_points;      // (S,) m, body frame
    Array<Vec3> body_bound_center;  // (n,) m: a box in the body frame holding the body
    Array<Vec3> body_bound_half;    // (n,) m
    Array<int32_t> body_unbounded;  // (n,) 1 for bodies without bounds (planes)
    Array<int32_t> grid_offset;     // (M,) first node of each grid in grid_values
    Array<Index3> grid_shape;       // (M,) nodes per axis
    Array<Vec3> grid_origin;        // (M,) m
    Array<double> grid_spacing;     // (M,) m
    Array<double> grid_values;      // (sum of nodes,) m, sampled phi
    Array<int32_t> mesh_triangle_start;  // (M + 1,) mesh m's triangles
    Array<Index3> mesh_triangles;   // (T,) indices into mesh_vertices
    Array<Vec3> mesh_vertices;      // (V,) m, the mesh's frame

    int num_bodies() const { return static_cast<int>(body_unbounded.size()); }
};

// A signed distance and its unit gradient.
struct Distance {
    double phi;
    Vec3 normal;
};

Distance sphere_distance(double radius, Vec3 p);
Distance capsule_distance(double radius, double half_length, Vec3 p);
Distance box_distance(Vec3 half, Vec3 p);

// phi of geom g at p (the geom's frame).
Distance geom_distance(const Geometry& geo, int g, Vec3 p);

// geom_distance for a caller that needs phi only where phi < reach (m). Inside a mesh's grid,
// and for every other type, it is geom_distance. Outside the grid the grid only bounds phi
// from below (phi >= the gap to the grid box); where that bound is below reach the point may
// be a contact (a sphere or capsule core, whose radius can exceed the grid's padding), so phi
// is computed exactly from the triangles; elsewhere the grid's value (>= reach) is returned
// and can make no contact.
Distance geom_distance_within(const Geometry& geo, int g, Vec3 p, double reach);

// Exact distance from p (mesh m's frame, outside the mesh) to its triangles and the unit
// gradient (p - nearest point) / distance. O(T).
Distance mesh_distance(const Geometry& geo, int m, Vec3 p);

}  // namespace rg
