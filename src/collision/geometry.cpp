// Signed distances of the geom types (geometry.h).
#include "collision/geometry.h"

#include "collision/mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rg {

Distance sphere_distance(double radius, Vec3 p) {
    const double d = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    if (d == 0.0) {
        return {-radius, {0.0, 0.0, 1.0}};
    }
    return {d - radius, {p.x / d, p.y / d, p.z / d}};
}

Distance capsule_distance(double radius, double half_length, Vec3 p) {
    const double dz = p.z - std::min(std::max(p.z, -half_length), half_length);
    if (p.x == 0.0 && p.y == 0.0 && dz == 0.0) {
        return {-radius, {1.0, 0.0, 0.0}};  // on the axis: any radial direction is a gradient
    }
    return sphere_distance(radius, {p.x, p.y, dz});
}

Distance box_distance(Vec3 half, Vec3 p) {
    const double qx = std::fabs(p.x) - half.x;
    const double qy = std::fabs(p.y) - half.y;
    const double qz = std::fabs(p.z) - half.z;
    const double sx = p.x >= 0.0 ? 1.0 : -1.0;
    const double sy = p.y >= 0.0 ? 1.0 : -1.0;
    const double sz = p.z >= 0.0 ? 1.0 : -1.0;
    const double ox = std::max(qx, 0.0), oy = std::max(qy, 0.0), oz = std::max(qz, 0.0);
    const double outside = std::sqrt(ox * ox + oy * oy + oz * oz);
    if (outside > 0.0) {
        return {outside, {sx * ox / outside, sy * oy / outside, sz * oz / outside}};
    }
    // inside: the nearest face is the one with the largest (least negative) q
    if (qx >= qy && qx >= qz) {
        return {qx, {sx, 0.0, 0.0}};
    }
    if (qy >= qz) {
        return {qy, {0.0, sy, 0.0}};
    }
    return {qz, {0.0, 0.0, sz}};
}

namespace {

// phi and gradient from grid m's sampled signed distance: its nodes are
// grid_values[offset + (i ny + j) nz + k] at origin + h (i, j, k).
Distance grid_distance(const Geometry& geo, int m, Vec3 p) {
    const Index3 shape = geo.grid_shape[m];
    const int nx = shape[0], ny = shape[1], nz = shape[2];
    const Vec3 o = geo.grid_origin[m];
    const double h = geo.grid_spacing[m];
    // clamp into the grid; outside, add the distance to it and point away from it
    const double cx = std::min(std::max(p.x, o.x), o.x + (nx - 1) * h);
    const double cy = std::min(std::max(p.y, o.y), o.y + (ny - 1) * h);
    const double cz = std::min(std::max(p.z, o.z), o.z + (nz - 1) * h);
    const double ex = p.x - cx, ey = p.y - cy, ez = p.z - cz;
    const double gap = std::sqrt(ex * ex + ey * ey + ez * ez);
    const double fx = (cx - o.x) / h, fy = (cy - o.y) / h, fz = (cz - o.z) / h;
    const int i = std::min(static_cast<int>(fx), nx - 2);
    const int j = std::min(static_cast<int>(fy), ny - 2);
    const int k = std::min(static_cast<int>(fz), nz - 2);
    const double tx = fx - i, ty = fy - j, tz = fz - k;
    const int64_t base = geo.grid_offset[m] + (static_cast<int64_t>(i) * ny + j) * nz + k;
    const int64_t step_y = nz, step_x = static_cast<int64_t>(ny) * nz;
    const Array<double>& v = geo.grid_values;
    const double c000 = v[base];
    const double c001 = v[base + 1];
    const double c010 = v[base + step_y];
    const double c011 = v[base + step_y + 1];
    const double c100 = v[base + step_x];
    const double c101 = v[base + step_x + 1];
    const double c110 = v[base + step_x + step_y];
    const double c111 = v[base + step_x + step_y + 1];
    // trilinear interpolation and its exact gradient
    const double c00 = c000 + (c001 - c000) * tz;
    const double c01 = c010 + (c011 - c010) * tz;
    const double c10 = c100 + (c101 - c100) * tz;
    const double c11 = c110 + (c111 - c110) * tz;
    const double c0 = c00 + (c01 - c00) * ty;
    const double c1 = c10 + (c11 - c10) * ty;
    const double phi = c0 + (c1 - c0) * tx;
    if (gap > 0.0) {
        return {phi + gap, {ex / gap, ey / gap, ez / gap}};
    }
    const double gx = (c1 - c0) / h;
    const double gy = ((c01 - c00) * (1.0 - tx) + (c11 - c10) * tx) / h;
    const double d0 = (c001 - c000) * (1.0 - ty) + (c011 - c010) * ty;
    const double d1 = (c101 - c100) * (1.0 - ty) + (c111 - c110) * ty;
    const double gz = (d0 * (1.0 - tx) + d1 * tx) / h;
    const double norm = std::sqrt(gx * gx + gy * gy + gz * gz);
    if (norm == 0.0) {
        return {phi, {0.0, 0.0, 1.0}};
    }
    return {phi, {gx / norm, gy / norm, gz / norm}};
}

// How far p lies outside the interval [lo, hi]; 0 inside it.
double axis_gap(double p, double lo, double hi) {
    return p < lo ? lo - p : (p > hi ? p - hi : 0.0);
}

// Distance (m) from p (the mesh's frame) to the box of grid m; 0 inside it.
double grid_gap(const Geometry& geo, int m, Vec3 p) {
    const Index3 shape = geo.grid_shape[m];
    const Vec3 o = geo.grid_origin[m];
    const double h = geo.grid_spacing[m];
    const double gx = axis_gap(p.x, o.x, o.x + (shape[0] - 1) * h);
    const double gy = axis_gap(p.y, o.y, o.y + (shape[1] - 1) * h);
    const double gz = axis_gap(p.z, o.z, o.z + (shape[2] - 1) * h);
    return std::sqrt(gx * gx + gy * gy + gz * gz);
}

double distance2(Vec3 p, Vec3 q) {
    const double dx = p.x - q.x, dy = p.y - q.y, dz = p.z - q.z;
    return dx * dx + dy * dy + dz * dz;
}

}  // namespace

Distance mesh_distance(const Geometry& geo, int m, Vec3 p) {
    const Array<Vec3>& v = geo.mesh_vertices;
    double best = std::numeric_limits<double>::infinity();
    Vec3 q = p;
    for (int t = geo.mesh_triangle_start[m]; t < geo.mesh_triangle_start[m + 1]; ++t) {
        const Index3 tri = geo.mesh_triangles[t];
        const Vec3 s = closest_on_triangle(p, v[tri[0]], v[tri[1]], v[tri[2]]);
        const double d2 = distance2(p, s);
        if (d2 < best) {
            best = d2;
            q = s;
        }
    }
    const double d = std::sqrt(best);
    if (d == 0.0) {
        return {0.0, {0.0, 0.0, 1.0}};
    }
    return {d, {(p.x - q.x) / d, (p.y - q.y) / d, (p.z - q.z) / d}};
}

Distance geom_distance(const Geometry& geo, int g, Vec3 p) {
    const Vec3 s = geo.geom_size[g];
    switch (geo.geom_type[g]) {
        case SPHERE:
            return sphere_distance(s.x, p);
        case CAPSULE:
            return capsule_distance(s.x, s.y, p);
        case BOX:
            return box_distance(s, p);
        case PLANE:
            return {p.z, {0.0, 0.0, 1.0}};
        default:
            return grid_distance(geo, geo.geom_grid[g], p);
    }
}

Distance geom_distance_within(const Geometry& geo, int g, Vec3 p, double reach) {
    if (geo.geom_type[g] == MESH) {
        const int m = geo.geom_grid[g];
        const double gap = grid_gap(geo, m, p);
        if (0.0 < gap && gap < reach) {
            return mesh_distance(geo, m, p);
        }
    }
    return geom_distance(geo, g, p);
}

}  // namespace rg
