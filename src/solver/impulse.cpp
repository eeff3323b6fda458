// Point impulses (impulse.h: Guendelman, Bridson & Fedkiw 2003).
#include "solver/impulse.h"

#include <algorithm>
#include <cmath>

namespace rg {

namespace {

// Below this share of its scale a matrix's determinant, or n^T K n, is round-off: K is
// singular (a jointed pair's, impulse.h).
constexpr double SINGULAR_K = 1e-12;

// k^-1 b for a symmetric positive definite k (adjugate / determinant).
Vec3 solve3(const Mat3& k, Vec3 b) {
    const double a00 = k.m[0][0], a01 = k.m[0][1], a02 = k.m[0][2];
    const double a11 = k.m[1][1], a12 = k.m[1][2], a22 = k.m[2][2];
    const double c00 = a11 * a22 - a12 * a12;
    const double c01 = a02 * a12 - a01 * a22;
    const double c02 = a01 * a12 - a02 * a11;
    const double c11 = a00 * a22 - a02 * a02;
    const double c12 = a01 * a02 - a00 * a12;
    const double c22 = a00 * a11 - a01 * a01;
    const double det = a00 * c00 + a01 * c01 + a02 * c02;
    return {(c00 * b.x + c01 * b.y + c02 * b.z) / det, (c01 * b.x + c11 * b.y + c12 * b.z) / det,
            (c02 * b.x + c12 * b.y + c22 * b.z) / det};
}

// n^T k d.
double quadratic(const Mat3& k, Vec3 n, Vec3 d) {
    return n.x * (k.m[0][0] * d.x + k.m[0][1] * d.y + k.m[0][2] * d.z) +
           n.y * (k.m[1][0] * d.x + k.m[1][1] * d.y + k.m[1][2] * d.z) +
           n.z * (k.m[2][0] * d.x + k.m[2][1] * d.y + k.m[2][2] * d.z);
}

// The frictionless impulse -(1 + e) v_n / (n^T K n) n.
Vec3 frictionless_impulse(const Mat3& k, Vec3 n, double vn, double e) {
    const double jn = -(1.0 + e) * vn / quadratic(k, n, n);
    return scale(jn, n);
}

// The impulse of Newton's restitution with Coulomb friction, before the energy
// check of contact_impulse.
Vec3 friction_impulse(const Mat3& k, Vec3 v, Vec3 n, double vn, double e, double mu) {
    // static friction: the impulse that leaves -e v_n n
    const Vec3 j = solve3(k, {-v.x - e * vn * n.x, -v.y - e * vn * n.y, -v.z - e * vn * n.z});
    const double jn = j.x * n.x + j.y * n.y + j.z * n.z;
    Vec3 t = {j.x - jn * n.x, j.y - jn * n.y, j.z - jn * n.z};
    const double jt = std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z);
    if (jt <= mu * jn) {
        return j;
    }
    // sliding: friction opposes the tangential velocity (or, if there is none, the static
    // impulse's tangential part shows the direction it would slide; if that is zero too, the
    // static impulse failed by pulling (j_n < 0) and friction has nothing to act on)
    Vec3 u = {v.x - vn * n.x, v.y - vn * n.y, v.z - vn * n.z};
    const double largest = std::max(std::max(std::fabs(u.x), std::fabs(u.y)), std::fabs(u.z));
    if (largest > 0.0) {  // normalise u / largest first: |u|^2 may underflow
        u = {u.x / largest, u.y / largest, u.z / largest};
        const double ut = std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
        t = {u.x / ut, u.y / ut, u.z / ut};
    } else if (jt > 0.0) {
        t = {-t.x / jt, -t.y / jt, -t.z / jt};
    } else {
        t = {0.0, 0.0, 0.0};
    }
    const Vec3 d = {n.x - mu * t.x, n.y - mu * t.y, n.z - mu * t.z};
    const double denom = quadratic(k, n, d);
    if (denom <= 0.0) {
        return j;
    }
    const double jn_sliding = -(1.0 + e) * vn / denom;
    return scale(jn_sliding, d);
}

}  // namespace

void add_point_mass_matrix(double inverse_mass, const Mat3& inverse_inertia, Vec3 r, Mat3& k) {
    // r x e_x = (0, rz, -ry), r x e_y = (-rz, 0, rx), r x e_z = (ry, -rx, 0)
    const Vec3 arms[3] = {{0.0, r.z, -r.y}, {-r.z, 0.0, r.x}, {r.y, -r.x, 0.0}};
    for (int c = 0; c < 3; ++c) {
        const Vec3 t = cross(rotate(inverse_inertia, arms[c]), r);
        k.m[0][c] += t.x;
        k.m[1][c] += t.y;
        k.m[2][c] += t.z;
        k.m[c][c] += inverse_mass;
    }
}

Vec3 contact_impulse(const Mat3& k, Vec3 v, Vec3 n, double e, double mu) {
    const double vn = v.x * n.x + v.y * n.y + v.z * n.z;
    if (mu == 0.0) {
        return frictionless_impulse(k, n, vn, e);
    }
    const Vec3 j = friction_impulse(k, v, n, vn, e, mu);
    // the pair's kinetic energy changes by j.v + j.K j / 2: where friction would make that
    // positive (an eccentric impact, K coupling normal and tangent) the frictionless impulse,
    // which only loses energy for e <= 1, is used instead
    const Vec3 kj = {k.m[0][0] * j.x + k.m[0][1] * j.y + k.m[0][2] * j.z,
                     k.m[1][0] * j.x + k.m[1][1] * j.y + k.m[1][2] * j.z,
                     k.m[2][0] * j.x + k.m[2][1] * j.y + k.m[2][2] * j.z};
    if (dot(j, v) + 0.5 * dot(j, kj) > 0.0) {
        return frictionless_impulse(k, n, vn, e);
    }
    return j;
}

Vec3 jointed_contact_impulse(const Mat3& k, Vec3 v, Vec3 n, double e, double mu) {
    const double trace = k.m[0][0] + k.m[1][1] + k.m[2][2];
    const double a00 = k.m[0][0], a01 = k.m[0][1], a02 = k.m[0][2];
    const double a11 = k.m[1][1], a12 = k.m[1][2], a22 = k.m[2][2];
    const double det = a00 * (a11 * a22 - a12 * a12) + a01 * (a02 * a12 - a01 * a22) +
                       a02 * (a01 * a12 - a02 * a11);
    if (det > SINGULAR_K * trace * trace * trace / 27.0) {
        return contact_impulse(k, v, n, e, mu);
    }
    if (!(quadratic(k, n, n) > SINGULAR_K * trace)) {
        return {0.0, 0.0, 0.0};
    }
    return frictionless_impulse(k, n, v.x * n.x + v.y * n.y + v.z * n.z, e);
}

}  // namespace rg
