// Winding numbers and signed distances of points to a closed mesh (mesh_distance.h).
#include "collision/mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/thread_pool.h"

namespace rg {

namespace {

constexpr double FOUR_PI = 4.0 * 3.14159265358979323846;

// A triangle whose corner angle at its first vertex has |sin| below this is treated as a
// segment by closest_on_triangle (its plane is not well defined).
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

// The point of segment [a, b] nearest to p (a == b allowed).
Vec3 closest_on_segment(Vec3 p, Vec3 a, Vec3 b) {
    const Vec3 ab = sub(b, a);
    const double length2 = dot(ab, ab);
    double t = 0.0;
    if (length2 > 0.0) {
        t = std::min(std::max(dot(sub(p, a), ab) / length2, 0.0), 1.0);
    }
    return add(a, scale(t, ab));
}

double distance2(Vec3 p, Vec3 q) {
    const Vec3 d = sub(p, q);
    return dot(d, d);
}

}  // namespace

// Ericson, Real-Time Collision Detection (2005) 5.1.5: find the Voronoi region of p (a
// vertex, an edge or the face) from dot products, then project onto that feature. A
// zero-area triangle's nearest point is its nearest edge's.
Vec3 closest_on_triangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
    const Vec3 ab = sub(b, a);
    const Vec3 ac = sub(c, a);
    const Vec3 n = cross(ab, ac);
    const double area2 = dot(n, n);
    if (area2 <= DEGENERATE_SINE * DEGENERATE_SINE * dot(ab, ab) * dot(ac, ac)) {
        Vec3 best = closest_on_segment(p, a, b);
        for (const Vec3 q : {closest_on_segment(p, b, c), closest_on_segment(p, c, a)}) {
            if (distance2(p, q) < distance2(p, best)) {
                best = q;
            }
        }
        return best;
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
    return add(add(a, scale(v, ab)), scale(w, ac));
}

namespace {

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
        best = std::min(best, distance2(p, closest_on_triangle(p, vertices[tri[0]],
                                                               vertices[tri[1]], vertices[tri[2]])));
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
