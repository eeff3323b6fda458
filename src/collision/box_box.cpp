// Box against box in closed form: separating axes, then face clipping or edge-edge.
//
// Sampled signed distances are ambiguous for boxes stacked face to face: a corner of the upper
// box lies exactly on a vertical edge of the lower one, where the nearest face is a side face,
// so the sampled normal points sideways. The separating-axis test has no such tie: of the 15
// axes (3 face normals of each box, 9 edge-edge cross products) the one of least overlap is
// the contact normal. For a face axis, the most anti-parallel face of the other box is clipped
// against the reference face's side planes (Sutherland-Hodgman), giving up to 8 points below
// the reference face; for an edge axis, the closest points of the two edges give one contact.
// Face axes win near-ties (FACE_PREFERENCE_*), so resting stacks get stable face contacts.
#include <algorithm>
#include <cmath>
#include <limits>

#include "collision/narrow_phase.h"

namespace rg {

namespace {

// An edge axis is chosen only if its overlap is smaller than the best face axis's by more
// than 5% + 1 micrometre (and B's faces must beat A's likewise): near-ties go to the stable
// face.
constexpr double FACE_PREFERENCE_RELATIVE = 0.05;
constexpr double FACE_PREFERENCE_ABSOLUTE = 1e-6;
// Edge pairs with |e_a x e_b| below this are parallel: their axis is left to the face axes.
constexpr double EDGE_PARALLEL = 1e-9;

// A clipped face: 4 corners, each of the 4 planes adding at most one vertex to a convex
// polygon; room for twice that, should round-off make a polygon look non-convex.
constexpr int POLYGON_CAPACITY = 16;
struct Polygon {
    Vec3 v[POLYGON_CAPACITY];
    int count = 0;

    void add(Vec3 p) {
        if (count < POLYGON_CAPACITY) {
            v[count++] = p;
        }
    }
};

// How much better (m) an axis must be than one with this separation to replace it.
double preference(double separation) {
    if (separation == -std::numeric_limits<double>::infinity()) {
        return 0.0;
    }
    return FACE_PREFERENCE_RELATIVE * std::fabs(separation) + FACE_PREFERENCE_ABSOLUTE;
}

// Half-width of a box (rotation r, half extents h) along unit axis u.
double box_extent_along(const Mat3& r, Vec3 h, Vec3 u) {
    return h.x * std::fabs(r.m[0][0] * u.x + r.m[1][0] * u.y + r.m[2][0] * u.z) +
           h.y * std::fabs(r.m[0][1] * u.x + r.m[1][1] * u.y + r.m[2][1] * u.z) +
           h.z * std::fabs(r.m[0][2] * u.x + r.m[1][2] * u.y + r.m[2][2] * u.z);
}

// Separation of the two boxes along unit axis u (> 0: a gap along u), d = a.x - b.x.
double axis_separation(Vec3 d, const Mat3& ra, Vec3 ha, const Mat3& rb, Vec3 hb, Vec3 u) {
    return std::fabs(dot(d, u)) - box_extent_along(ra, ha, u) - box_extent_along(rb, hb, u);
}

// The edge-edge axis of A's edge direction i and B's j (unit), or false where the edges are
// parallel (that axis is then one of the face axes).
bool edge_axis(const Mat3& ra, const Mat3& rb, int i, int j, Vec3& u) {
    u = {ra.m[1][i] * rb.m[2][j] - ra.m[2][i] * rb.m[1][j],
         ra.m[2][i] * rb.m[0][j] - ra.m[0][i] * rb.m[2][j],
         ra.m[0][i] * rb.m[1][j] - ra.m[1][i] * rb.m[0][j]};
    const double len = std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
    if (len < EDGE_PARALLEL) {
        return false;
    }
    u = {u.x / len, u.y / len, u.z / len};
    return true;
}

// The part of polygon `in` with n.p <= offset (Sutherland-Hodgman, one plane).
void clip_polygon(const Polygon& in, Vec3 n, double offset, Polygon& out) {
    out.count = 0;
    for (int k = 0; k < in.count; ++k) {
        const int j = (k + 1) % in.count;
        const Vec3 pk = in.v[k], pj = in.v[j];
        const double dk = n.x * pk.x + n.y * pk.y + n.z * pk.z - offset;
        const double dj = n.x * pj.x + n.y * pj.y + n.z * pj.z - offset;
        if (dk <= 0.0) {
            out.add(pk);
        }
        if ((dk < 0.0 && 0.0 < dj) || (dj < 0.0 && 0.0 < dk)) {
            const double t = dk / (dk - dj);
            out.add({pk.x + t * (pj.x - pk.x), pk.y + t * (pj.y - pk.y), pk.z + t * (pj.z - pk.z)});
        }
    }
}

// Clip the incident box's face against face `axis` of the reference box, whose outward
// normal (towards the incident box) is n. Contact points are incident-face points below the
// reference face; their normals are sign n (sign = +1 when the incident box is A).
int face_contact(const Pose& ref, Vec3 half_ref, const Pose& inc, Vec3 half_inc, int axis,
                 Vec3 n, double margin, double sign, const ContactBuffer& out, int64_t index) {
    const Mat3& ri = inc.r;
    const Mat3& rr = ref.r;
    // incident face: the face of the incident box most anti-parallel to n
    double best = std::numeric_limits<double>::infinity();
    int face_axis = 0;
    double face_sign = 1.0;
    for (int c = 0; c < 3; ++c) {
        const double d = ri.m[0][c] * n.x + ri.m[1][c] * n.y + ri.m[2][c] * n.z;
        if (d < best) {
            best = d;
            face_axis = c;
            face_sign = 1.0;
        }
        if (-d < best) {
            best = -d;
            face_axis = c;
            face_sign = -1.0;
        }
    }
    const int u = (face_axis + 1) % 3, v = (face_axis + 2) % 3;
    const double corner_u[4] = {1.0, -1.0, -1.0, 1.0};
    const double corner_v[4] = {1.0, 1.0, -1.0, -1.0};
    Polygon polygons[2];
    Polygon* src = &polygons[0];
    Polygon* dst = &polygons[1];
    for (int k = 0; k < 4; ++k) {
        Vec3 p;
        for (int c = 0; c < 3; ++c) {
            set_component(p, c,
                          inc.x[c] + ri.m[c][face_axis] * face_sign * half_inc[face_axis] +
                              ri.m[c][u] * corner_u[k] * half_inc[u] +
                              ri.m[c][v] * corner_v[k] * half_inc[v]);
        }
        src->v[k] = p;
    }
    src->count = 4;
    // clip against the 4 side planes of the reference face
    const int ru = (axis + 1) % 3, rv = (axis + 2) % 3;
    for (int side = 0; side < 4; ++side) {
        const int c = side < 2 ? ru : rv;
        const double s = side % 2 == 0 ? 1.0 : -1.0;
        const Vec3 plane = {s * rr.m[0][c], s * rr.m[1][c], s * rr.m[2][c]};
        const double offset = plane.x * ref.x.x + plane.y * ref.x.y + plane.z * ref.x.z + half_ref[c];
        clip_polygon(*src, plane, offset, *dst);
        Polygon* kept = dst;
        dst = src;
        src = kept;
        if (src->count == 0) {
            return 0;
        }
    }
    // keep the points below the reference face
    const double face_offset = n.x * ref.x.x + n.y * ref.x.y + n.z * ref.x.z + half_ref[axis];
    int found = 0;
    for (int k = 0; k < src->count; ++k) {
        const Vec3 p = src->v[k];
        const double depth = face_offset - (n.x * p.x + n.y * p.y + n.z * p.z);
        if (depth > -margin) {
            out.emit(index + found, p, scale(sign, n), depth);
            found += 1;
        }
    }
    return found;
}

// One contact for an edge-edge axis n (from B to A): the point of A's edge (along its axis
// i) closest to B's edge (along axis j), the two edges being the ones facing each other.
int edge_contact(const Pose& a, Vec3 ha, const Pose& b, Vec3 hb, int i, int j, Vec3 n,
                 double separation, const ContactBuffer& out, int64_t index) {
    const Mat3& ra = a.r;
    const Mat3& rb = b.r;
    // A's edge: the one whose corner is furthest along -n; B's: furthest along +n
    Vec3 pa = a.x, pb = b.x;
    for (int c = 0; c < 3; ++c) {
        if (c != i) {
            const double s =
                ra.m[0][c] * n.x + ra.m[1][c] * n.y + ra.m[2][c] * n.z > 0.0 ? -ha[c] : ha[c];
            pa = {pa.x + s * ra.m[0][c], pa.y + s * ra.m[1][c], pa.z + s * ra.m[2][c]};
        }
        if (c != j) {
            const double s =
                rb.m[0][c] * n.x + rb.m[1][c] * n.y + rb.m[2][c] * n.z > 0.0 ? hb[c] : -hb[c];
            pb = {pb.x + s * rb.m[0][c], pb.y + s * rb.m[1][c], pb.z + s * rb.m[2][c]};
        }
    }
    // closest points of the lines pa + s ua and pb + t ub, clamped to the edges
    const Vec3 ua = ra.column(i), ub = rb.column(j);
    const Vec3 w = sub(pa, pb);
    const double bb = dot(ua, ub), d = dot(ua, w), e = dot(ub, w);
    const double denom = 1.0 - bb * bb;
    double s = denom > 1e-12 ? (bb * e - d) / denom : 0.0;
    s = std::min(std::max(s, -ha[i]), ha[i]);
    out.emit(index, {pa.x + s * ua.x, pa.y + s * ua.y, pa.z + s * ua.z}, n, -separation);
    return 1;
}

}  // namespace

int collide_boxes(const Pose& a, Vec3 ha, const Pose& b, Vec3 hb, double margin,
                  const ContactBuffer& out, int64_t index) {
    const Mat3& ra = a.r;
    const Mat3& rb = b.r;
    const Vec3 d = sub(a.x, b.x);
    double best_sep = -std::numeric_limits<double>::infinity();
    int best_axis = -1;
    Vec3 best = {0.0, 0.0, 0.0};
    // face axes: 0-2 of A, 3-5 of B
    for (int k = 0; k < 6; ++k) {
        const Vec3 u = (k < 3 ? ra : rb).column(k % 3);
        const double dist = dot(d, u);
        const double sep = axis_separation(d, ra, ha, rb, hb, u);
        if (sep > margin) {
            return 0;
        }
        const double bias = k >= 3 ? preference(best_sep) : 0.0;
        if (sep > best_sep + bias) {
            const double s = dist >= 0.0 ? 1.0 : -1.0;
            best_sep = sep;
            best_axis = k;
            best = scale(s, u);
        }
    }
    const double face_sep = best_sep;
    // edge-edge axes
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            Vec3 u;
            if (!edge_axis(ra, rb, i, j, u)) {
                continue;
            }
            const double dist = dot(d, u);
            const double sep = axis_separation(d, ra, ha, rb, hb, u);
            if (sep > margin) {
                return 0;
            }
            if (sep > best_sep && sep > face_sep + preference(face_sep)) {
                const double s = dist >= 0.0 ? 1.0 : -1.0;
                best_sep = sep;
                best_axis = 6 + 3 * i + j;
                best = scale(s, u);
            }
        }
    }
    if (best_axis >= 6) {
        return edge_contact(a, ha, b, hb, (best_axis - 6) / 3, (best_axis - 6) % 3, best,
                            best_sep, out, index);
    }
    if (best_axis < 3) {
        // reference face on A; the normal (B to A) is -axis from A's view: the axis points B->A
        return face_contact(a, ha, b, hb, best_axis, scale(-1.0, best), margin, -1.0, out, index);
    }
    return face_contact(b, hb, a, ha, best_axis - 3, best, margin, 1.0, out, index);
}

double box_separation(const Pose& a, Vec3 ha, const Pose& b, Vec3 hb) {
    const Vec3 d = sub(a.x, b.x);
    double best = -std::numeric_limits<double>::infinity();
    for (int k = 0; k < 6; ++k) {
        best = std::max(best, axis_separation(d, a.r, ha, b.r, hb, (k < 3 ? a.r : b.r).column(k % 3)));
    }
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            Vec3 u;
            if (edge_axis(a.r, b.r, i, j, u)) {
                best = std::max(best, axis_separation(d, a.r, ha, b.r, hb, u));
            }
        }
    }
    return best;
}

}  // namespace rg
