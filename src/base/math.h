// Small fixed-size vectors, quaternions and rotations, and the few operations the solver
// needs on them.
//
// Every operation spells out its arithmetic in one fixed order: results must be bit-for-bit
// repeatable (no -ffast-math, no FMA contraction: see CMakeLists.txt), so the order of each
// sum is part of the contract. Quaternions are (w, x, y, z); a rotation matrix's columns are
// the rotated body axes. The types are laid out like the numpy rows
// they are read from: Vec3 as float64 (3,), Quat as (4,), Mat3 as (3, 3) in C order.
#pragma once

#include <cmath>

namespace rg {

struct Vec3 {
    double x, y, z;

    // Component k (0, 1, 2): for the loops over axes that the box tests are written as.
    double operator[](int k) const { return k == 0 ? x : (k == 1 ? y : z); }
};

struct Quat {
    double w, x, y, z;
};

struct Mat3 {
    double m[3][3];  // m[row][column]

    double operator()(int row, int column) const { return m[row][column]; }
    Vec3 column(int c) const { return {m[0][c], m[1][c], m[2][c]}; }
};

static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must match a float64 (3,) row");
static_assert(sizeof(Quat) == 4 * sizeof(double), "Quat must match a float64 (4,) row");
static_assert(sizeof(Mat3) == 9 * sizeof(double), "Mat3 must match a float64 (3, 3) block");

inline void set_component(Vec3& v, int k, double value) {
    if (k == 0) {
        v.x = value;
    } else if (k == 1) {
        v.y = value;
    } else {
        v.z = value;
    }
}

inline Vec3 add(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 scale(double s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double length(Vec3 a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

inline Vec3 cross(Vec3 a, Vec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// R v.
inline Vec3 rotate(const Mat3& r, Vec3 v) {
    return {r.m[0][0] * v.x + r.m[0][1] * v.y + r.m[0][2] * v.z,
            r.m[1][0] * v.x + r.m[1][1] * v.y + r.m[1][2] * v.z,
            r.m[2][0] * v.x + r.m[2][1] * v.y + r.m[2][2] * v.z};
}

// R^T v.
inline Vec3 rotate_inverse(const Mat3& r, Vec3 v) {
    return {r.m[0][0] * v.x + r.m[1][0] * v.y + r.m[2][0] * v.z,
            r.m[0][1] * v.x + r.m[1][1] * v.y + r.m[2][1] * v.z,
            r.m[0][2] * v.x + r.m[1][2] * v.y + r.m[2][2] * v.z};
}

// x + R p: a point of a frame at pose (x, R) in its parent's frame.
inline Vec3 to_world(Vec3 x, const Mat3& r, Vec3 p) {
    return {x.x + r.m[0][0] * p.x + r.m[0][1] * p.y + r.m[0][2] * p.z,
            x.y + r.m[1][0] * p.x + r.m[1][1] * p.y + r.m[1][2] * p.z,
            x.z + r.m[2][0] * p.x + r.m[2][1] * p.y + r.m[2][2] * p.z};
}

// R^T (p - x): a point of the parent frame in the frame at pose (x, R).
inline Vec3 to_local(Vec3 x, const Mat3& r, Vec3 p) {
    return rotate_inverse(r, sub(p, x));
}

// The rotation matrix of unit quaternion q.
inline Mat3 rotation_from_quaternion(Quat q) {
    const double w = q.w, x = q.x, y = q.y, z = q.z;
    Mat3 r;
    r.m[0][0] = 1.0 - 2.0 * (y * y + z * z);
    r.m[0][1] = 2.0 * (x * y - w * z);
    r.m[0][2] = 2.0 * (x * z + w * y);
    r.m[1][0] = 2.0 * (x * y + w * z);
    r.m[1][1] = 1.0 - 2.0 * (x * x + z * z);
    r.m[1][2] = 2.0 * (y * z - w * x);
    r.m[2][0] = 2.0 * (x * z - w * y);
    r.m[2][1] = 2.0 * (y * z + w * x);
    r.m[2][2] = 1.0 - 2.0 * (x * x + y * y);
    return r;
}

inline Quat normalize(Quat q) {
    const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    return {q.w / n, q.x / n, q.y / n, q.z / n};
}

// a b (Hamilton product).
inline Quat multiply(Quat a, Quat b) {
    return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
            a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
            a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
            a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

// (cos|h w/2|, sin|h w/2| w/|w|) q, renormalised: exact for an angular velocity w
// (rad/s, world frame) that is constant over h (s).
inline Quat rotate_by_angular_velocity(Quat q, Vec3 w, double h) {
    const double speed = std::sqrt(w.x * w.x + w.y * w.y + w.z * w.z);
    if (speed == 0.0) {
        return q;
    }
    const double half_angle = 0.5 * h * speed;
    const double c = std::cos(half_angle);
    const double s = std::sin(half_angle) / speed;
    const Quat d = {c, s * w.x, s * w.y, s * w.z};
    return normalize(multiply(d, q));
}

// I(t)^-1 = R diag(inverse_moments) R^T, formed once where it is applied often.
inline Mat3 inverse_inertia(const Mat3& r, Vec3 inverse_moments) {
    Mat3 w;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            w.m[i][j] = r.m[i][0] * inverse_moments.x * r.m[j][0] +
                        r.m[i][1] * inverse_moments.y * r.m[j][1] +
                        r.m[i][2] * inverse_moments.z * r.m[j][2];
        }
    }
    return w;
}

// I(t)^-1 v = R diag(inverse_moments) R^T v; inverse_moments 1/kg m^2, 0 on a
// degenerate axis.
inline Vec3 apply_inverse_inertia(const Mat3& r, Vec3 inverse_moments, Vec3 v) {
    const Vec3 b = rotate_inverse(r, v);
    return rotate(r, {b.x * inverse_moments.x, b.y * inverse_moments.y, b.z * inverse_moments.z});
}

}  // namespace rg
