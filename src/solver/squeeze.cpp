#include "solver/squeeze.h"

#include <cmath>

#include "base/dense.h"
#include "solver/mobility.h"

namespace rg {
namespace {

// 3 rows a patch, and the spin about a common axis.
constexpr int MAX_ROWS = 3 * MAX_SQUEEZE_PATCHES + 1;

// A pivot at or below this fraction of the largest diagonal entry of the system is singular:
// the patches do not fix a's motion (two fingers on one face), the impulses are not
// determined.
constexpr double SINGULAR_PIVOT = 1e-12;

// Patches whose normals are parallel or opposite within this cosine share a spin axis.
constexpr double PARALLEL_COS = 0.95;

// Velocity change at lever x of free body a per unit impulse at lever y (the header's K_a).
Mat3 cross_point_matrix(double inverse_mass, const Mat3& inverse_inertia, Vec3 x, Vec3 y) {
    // column c: e_c / M + (W (y x e_c)) x x, with y x e_x = (0, y.z, -y.y) and so on
    const Vec3 arms[3] = {{0.0, y.z, -y.y}, {-y.z, 0.0, y.x}, {y.y, -y.x, 0.0}};
    Mat3 k = {};
    for (int c = 0; c < 3; ++c) {
        const Vec3 t = cross(rotate(inverse_inertia, arms[c]), x);
        k.m[0][c] = t.x;
        k.m[1][c] = t.y;
        k.m[2][c] = t.z;
        k.m[c][c] += inverse_mass;
    }
    return k;
}

// Does the step's total through a patch, prior + j, lie in the friction cone, with j pressing?
bool admissible(const SqueezePatch& p) {
    if (!(dot(p.impulse, p.normal) > 0.0)) {
        return false;
    }
    const Vec3 total = add(p.prior, p.impulse);
    const double tn = dot(total, p.normal);
    const Vec3 tangential = sub(total, scale(tn, p.normal));
    return length(tangential) <= p.mu * tn;
}

// The static system: the impulses j_i (3 rows each) that stop every centroid, and, where all
// normals share the axis u = n_0 (a parallel gripper), the spin impulse s about u that stops
// a's spin relative to partner 0, shared equally as s / count u by the patches.
int static_system(const BodyStates& bodies, const BodyModel& model, int a,
                  const SqueezePatch* patches, const Vec3* velocity, int count, bool spin,
                  double k[MAX_ROWS][MAX_ROWS], double* rhs) {
    const int n = 3 * count + (spin ? 1 : 0);
    const Mat3& wa = bodies.inverse_inertia[a];
    const Vec3 u = patches[0].normal;
    const double share = 1.0 / count;
    for (int i = 0; i < count; ++i) {
        const SqueezePatch& p = patches[i];
        for (int c = 0; c < count; ++c) {
            const Mat3 block = cross_point_matrix(model.inverse_mass[a], wa, p.lever_a,
                                                  patches[c].lever_a);
            for (int r = 0; r < 3; ++r) {
                for (int q = 0; q < 3; ++q) {
                    k[3 * i + r][3 * c + q] = block.m[r][q];
                }
            }
        }
        // the partner takes -j_i and -s / count u at its lever: its response adds to the
        // relative velocity (and, for partner 0, to the relative spin) with a plus sign
        double big[6][6] = {};
        add_articulated_wrench_matrix(bodies, model, p.partner, p.lever_b, big);
        for (int r = 0; r < 3; ++r) {
            for (int q = 0; q < 3; ++q) {
                k[3 * i + r][3 * i + q] += big[r][q];
            }
        }
        rhs[3 * i] = -velocity[i].x;
        rhs[3 * i + 1] = -velocity[i].y;
        rhs[3 * i + 2] = -velocity[i].z;
        if (!spin) {
            continue;
        }
        const int s = 3 * count;
        const Vec3 turn_a = cross(rotate(wa, u), p.lever_a);  // a's velocity at c_i per unit s
        const Vec3 turn_b = {big[0][3] * u.x + big[0][4] * u.y + big[0][5] * u.z,
                             big[1][3] * u.x + big[1][4] * u.y + big[1][5] * u.z,
                             big[2][3] * u.x + big[2][4] * u.y + big[2][5] * u.z};
        k[3 * i][s] = turn_a.x + share * turn_b.x;
        k[3 * i + 1][s] = turn_a.y + share * turn_b.y;
        k[3 * i + 2][s] = turn_a.z + share * turn_b.z;
        // a's spin about u per unit j_i: u . W (r_i x e_q); partner 0's per unit j_0 and s
        for (int q = 0; q < 3; ++q) {
            Vec3 e = {0.0, 0.0, 0.0};
            set_component(e, q, 1.0);
            k[s][3 * i + q] = dot(u, rotate(wa, cross(p.lever_a, e)));
            if (i == 0) {
                k[s][q] += big[3][q] * u.x + big[4][q] * u.y + big[5][q] * u.z;
            }
        }
        if (i == 0) {
            const Vec3 wu = rotate(wa, u);
            const double uc[3] = {u.x, u.y, u.z};
            double partner = 0.0;  // u . (partner 0's spin per unit angular impulse about u)
            for (int r = 0; r < 3; ++r) {
                for (int q = 0; q < 3; ++q) {
                    partner += uc[r] * big[3 + r][3 + q] * uc[q];
                }
            }
            k[s][s] = dot(u, wu) + share * partner;
            const Vec3 relative = sub(bodies.angular_velocity[a],
                                      bodies.angular_velocity[p.partner]);
            rhs[s] = -dot(relative, u);
        }
    }
    return n;
}

}  // namespace

bool solve_squeeze(const BodyStates& bodies, const BodyModel& model, int a,
                   SqueezePatch* patches, const Vec3* velocity, int count) {
    double k[MAX_ROWS][MAX_ROWS] = {};
    double rhs[MAX_ROWS];
    double x[MAX_ROWS];
    bool spin = true;
    for (int i = 1; i < count; ++i) {
        spin = spin && std::fabs(dot(patches[i].normal, patches[0].normal)) >= PARALLEL_COS;
    }
    const int n = static_system(bodies, model, a, patches, velocity, count, spin, k, rhs);
    if (!solve_dense(k, rhs, n, x, SINGULAR_PIVOT)) {
        return false;
    }
    const Vec3 torque = spin ? scale(x[3 * count] / count, patches[0].normal)
                             : Vec3{0.0, 0.0, 0.0};
    for (int i = 0; i < count; ++i) {
        SqueezePatch& p = patches[i];
        p.impulse = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
        p.spin = torque;
        // torsional friction: the spin impulse within mu j_n rho at each patch
        if (!admissible(p) || length(torque) > p.mu * dot(p.impulse, p.normal) * p.radius) {
            return false;
        }
    }
    return true;
}

}  // namespace rg
