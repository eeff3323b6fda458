// Winding numbers and signed distances of points to a closed mesh (mesh_distance.h).
#include "mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "thread_pool.h"

namespace rg {

namespace {

constexpr double FOUR_PI = 4.0 * 3.14159265358979323846;

// A triangle whose corner angle at its first vertex has |sin| below this is treated as a
// segment by point_triangle_distance_squared (its plane is not well defined).
constexpr double DEGENERATE_SINE = 1e-12;

// Signed solid angle (sr, in (-2 pi, 2 pi]) that triangle (a, b, c) subtends at the origin.
//
// a, b, c are the vertices relative to the viewpoint, m. Van Oosterom & Strackee (1983):
// tan(omega / 2) = a . (b x c) / (|a||b||c| + (a . b)|c| + (a . c)|b| + (b . c)|a|).
// Positive when the viewpoint sees the triangle's back (the inside of an outward mesh).
double solid_angle(Vec3 a, Vec3 b, Vec3 c) {
    const double la = length(a);
    const double lb = length(b);
    const double lc = length(c);
    const double triple = dot(a, cross(b, c));
    const double denominator = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    return 2.0 * std::atan2(triple, denominator);
}

// Squared distance (m^2) from point p to the segment [a, b] (a == b allowed).
double point_segment_distance_squared(Vec3 p, Vec3 a, Vec3 b) {
    const Vec3 ab = sub(b, a);
    const Vec3 ap = sub(p, a);
    const double length2 = dot(ab, ab);
    double t = 0.0;
    if (length2 > 0.0) {
        t = std::min(std::max(dot(ap, ab) / length2, 0.0), 1.0);
    }
    const Vec3 d = sub(ap, scale(t, ab));
    return dot(d, d);
}

// Squared distance (m^2) from p to a zero-area triangle: the nearest of its three edges.
double degenerate_distance_squared(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
    return std::min(std::min(point_segment_distance_squared(p, a, b),
                             point_segment_distance_squared(p, b, c)),
                    point_segment_distance_squared(p, c, a));
}

// Squared distance (m^2) from point p to the closest point of triangle (a, b, c), m.
//
// Ericson, Real-Time Collision Detection (2005) 5.1.5: find the Voronoi region of p (a
// vertex, an edge or the face) from dot products, then project onto that feature.
double point_triangle_distance_squared(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
    const Vec3 ab = sub(b, a);
    const Vec3 ac = sub(c, a);
    const Vec3 n = cross(ab, ac);
    const double area2 = dot(n, n);
    const double ab2 = dot(ab, ab);
    const double ac2 = dot(ac, ac);
    if (area2 <= DEGENERATE_SINE * DEGENERATE_SINE * ab2 * ac2) {
        return degenerate_distance_squared(p, a, b, c);
    }

    const Vec3 ap = sub(p, a);
    const double d1 = dot(ab, ap);
    const double d2 = dot(ac, ap);
    // Each branch sets the closest point q = a + v ab + w ac.
    double v = 0.0;
    double w = 0.0;
    const Vec3 bp = sub(p, b);
    const double d3 = dot(ab, bp);
    const double d4 = dot(ac, bp);
    const Vec3 cp = sub(p, c);
    const double d5 = dot(ab, cp);
    const double d6 = dot(ac, cp);
    const double vc = d1 * d4 - d3 * d2;
    const double vb = d5 * d2 - d1 * d6;
    const double va = d3 * d6 - d5 * d4;
    if (d1 <= 0.0 && d2 <= 0.0) {  // vertex a
    } else if (d3 >= 0.0 && d4 <= d3) {  // vertex b
        v = 1.0;
    } else if (d6 >= 0.0 && d5 <= d6) {  // vertex c
        w = 1.0;
    } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {  // edge ab
        v = d1 / (d1 - d3);
    } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {  // edge ac
        w = d2 / (d2 - d6);
    } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {  // edge bc
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        v = 1.0 - w;
    } else {  // face
        v = vb / (va + vb + vc);
        w = vc / (va + vb + vc);
    }
    const Vec3 d = sub(sub(ap, scale(v, ab)), scale(w, ac));
    return dot(d, d);
}

// Winding number of point p (m) with respect to the mesh: sum of solid angles / 4 pi.
double point_winding_number(Vec3 p, Span<const Vec3> vertices, Span<const Index3> triangles) {
    double omega = 0.0;
    for (int64_t t = 0; t < triangles.size; ++t) {
        const Index3 tri = triangles[t];
        omega += solid_angle(sub(vertices[tri[0]], p), sub(vertices[tri[1]], p),
                             sub(vertices[tri[2]], p));
    }
    return omega / FOUR_PI;
}

// Distance (m) from point p (m) to the nearest triangle of the mesh.
double point_mesh_distance(Vec3 p, Span<const Vec3> vertices, Span<const Index3> triangles) {
    double best = std::numeric_limits<double>::infinity();
    for (int64_t t = 0; t < triangles.size; ++t) {
        const Index3 tri = triangles[t];
        best = std::min(best, point_triangle_distance_squared(p, vertices[tri[0]],
                                                              vertices[tri[1]], vertices[tri[2]]));
    }
    return std::sqrt(best);
}

// f(i) for every point i in [0, count): one contiguous range of points per thread of the pool.
template <class F>
void for_each_point(int64_t count, const F& f) {
    ThreadPool& pool = ThreadPool::instance();
    const int jobs = static_cast<int>(std::min<int64_t>(pool.size(), count));
    pool.run(jobs, [&](int job) {
        const int64_t first = count * job / jobs;
        const int64_t last = count * (job + 1) / jobs;
        for (int64_t i = first; i < last; ++i) {
            f(i);
        }
    });
}

}  // namespace

void winding_number(Span<const Vec3> points, Span<const Vec3> vertices,
                    Span<const Index3> triangles, Span<double> out) {
    for_each_point(points.size, [&](int64_t i) {
        out[i] = point_winding_number(points[i], vertices, triangles);
    });
}

void signed_distance(Span<const Vec3> points, Span<const Vec3> vertices,
                     Span<const Index3> triangles, Span<double> out) {
    for_each_point(points.size, [&](int64_t i) {
        const Vec3 p = points[i];
        const double distance = point_mesh_distance(p, vertices, triangles);
        const bool inside = point_winding_number(p, vertices, triangles) > 0.5;
        out[i] = inside ? -distance : distance;
    });
}

}  // namespace rg
