// The articulated response of a jointed body to contact impulses (mobility.h).
#include "solver/mobility.h"

namespace rg {

namespace {

// A row whose part independent of the rows before is below this share of its M^-1 norm is
// dependent on them: it adds nothing (round-off is ~1e-16 of it).
constexpr double DEPENDENT = 1e-12;

// x^T M^-1 y for 6-vectors [linear; angular].
double inner(double inverse_mass, const Mat3& inverse_inertia, const double* x, const double* y) {
    const Vec3 wy = rotate(inverse_inertia, {y[3], y[4], y[5]});
    return inverse_mass * (x[0] * y[0] + x[1] * y[1] + x[2] * y[2]) + x[3] * wy.x + x[4] * wy.y +
           x[5] * wy.z;
}

// g f for the 6-vector f = [j; l], back into j and l.
void apply_mobility(const Mobility& m, Vec3& j, Vec3& l) {
    const double f[6] = {j.x, j.y, j.z, l.x, l.y, l.z};
    double out[6];
    for (int r = 0; r < 6; ++r) {
        double acc = 0.0;
        for (int c = 0; c < 6; ++c) {
            acc += m.g[r][c] * f[c];
        }
        out[r] = acc;
    }
    j = {out[0], out[1], out[2]};
    l = {out[3], out[4], out[5]};
}

}  // namespace

void form_mobility(double inverse_mass, const Mat3& inverse_inertia, const JointRow* rows,
                   int count, Mobility& out) {
    double basis[6][6], norm[6];
    int size = 0;
    for (int r = 0; r < count && size < 6; ++r) {
        double x[6] = {rows[r].la.x, rows[r].la.y, rows[r].la.z,
                       rows[r].aa.x, rows[r].aa.y, rows[r].aa.z};
        const double original = inner(inverse_mass, inverse_inertia, x, x);
        for (int k = 0; k < size; ++k) {  // modified Gram-Schmidt
            const double c = inner(inverse_mass, inverse_inertia, basis[k], x) / norm[k];
            for (int e = 0; e < 6; ++e) {
                x[e] -= c * basis[k][e];
            }
        }
        const double left = inner(inverse_mass, inverse_inertia, x, x);
        if (left > DEPENDENT * original) {
            for (int e = 0; e < 6; ++e) {
                basis[size][e] = x[e];
            }
            norm[size] = left;
            size += 1;
        }
    }
    // g = 1 - sum_k q_k (M^-1 q_k)^T / (q_k^T M^-1 q_k) over the orthogonal rows q_k; a body
    // held in all six directions (a fixed joint) gets exactly 0, not round-off, which a
    // contact's K would take for a direction it can move in
    for (int r = 0; r < 6; ++r) {
        for (int c = 0; c < 6; ++c) {
            out.g[r][c] = r == c && size < 6 ? 1.0 : 0.0;
        }
    }
    if (size == 6) {
        return;
    }
    for (int k = 0; k < size; ++k) {
        const double* q = basis[k];
        const Vec3 wq = rotate(inverse_inertia, {q[3], q[4], q[5]});
        const double mq[6] = {inverse_mass * q[0], inverse_mass * q[1], inverse_mass * q[2],
                              wq.x, wq.y, wq.z};
        for (int r = 0; r < 6; ++r) {
            for (int c = 0; c < 6; ++c) {
                out.g[r][c] -= q[r] * mq[c] / norm[k];
            }
        }
    }
}

void admit(const BodyStates& bodies, const BodyModel& model, int i, Vec3& j, Vec3& l) {
    if (model.articulated[i]) {
        apply_mobility(bodies.mobility[i], j, l);
    }
}

void articulated_response(const BodyStates& bodies, const BodyModel& model, int i, Vec3 j,
                          Vec3 l, Vec3& dv, Vec3& dw) {
    apply_mobility(bodies.mobility[i], j, l);
    dv = scale(model.inverse_mass[i], j);
    dw = rotate(bodies.inverse_inertia[i], l);
}

void add_articulated_point_matrix(const BodyStates& bodies, const BodyModel& model, int i,
                                  Vec3 r, Mat3& k) {
    const Vec3 axes[3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
    for (int c = 0; c < 3; ++c) {
        Vec3 dv, dw;
        articulated_response(bodies, model, i, axes[c], cross(r, axes[c]), dv, dw);
        const Vec3 at = add(dv, cross(dw, r));
        k.m[0][c] += at.x;
        k.m[1][c] += at.y;
        k.m[2][c] += at.z;
    }
}

void add_articulated_wrench_matrix(const BodyStates& bodies, const BodyModel& model, int i,
                                   Vec3 r, double big[6][6]) {
    const Vec3 axes[3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
    const Vec3 none = {0.0, 0.0, 0.0};
    for (int c = 0; c < 6; ++c) {
        const Vec3 j = c < 3 ? axes[c] : none;
        const Vec3 m = c < 3 ? none : axes[c - 3];
        Vec3 dv, dw;
        articulated_response(bodies, model, i, j, add(cross(r, j), m), dv, dw);
        const Vec3 at = add(dv, cross(dw, r));
        const double column[6] = {at.x, at.y, at.z, dw.x, dw.y, dw.z};
        for (int row = 0; row < 6; ++row) {
            big[row][c] += column[row];
        }
    }
}

}  // namespace rg
