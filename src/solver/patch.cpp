// The patch wrench (patch.h).
#include "solver/patch.h"

#include <algorithm>
#include <cmath>

namespace rg {

namespace {

enum PatchKind { POINT, EDGE, FACE };

// A patch is an edge when its smaller in-plane spread is below this fraction of its larger.
constexpr double COLLINEAR = 1e-6;
// Pivots below this fraction of the largest diagonal entry mean an unsolvable system.
constexpr double SINGULAR = 1e-12;

using Matrix6 = double[6][6];

// Two unit vectors completing n to a right-handed orthonormal frame (t1, t2, n).
void tangent_basis(Vec3 n, Vec3& t1, Vec3& t2) {
    const Vec3 a = std::fabs(n.x) < 0.57735 ? Vec3{1.0, 0.0, 0.0} : Vec3{0.0, 1.0, 0.0};
    t1 = cross(a, n);
    const double norm = std::sqrt(t1.x * t1.x + t1.y * t1.y + t1.z * t1.z);
    t1 = {t1.x / norm, t1.y / norm, t1.z / norm};
    t2 = cross(n, t1);
}

// big += [[1/M + r*^T W r*, r*^T W], [W r*, W]] for one body, lever r, W = I(t)^-1.
void add_body_wrench_matrix(double inverse_mass, const Mat3& inverse_inertia, Vec3 r,
                            Matrix6& big) {
    const auto& w = inverse_inertia.m;
    double wr[3][3];  // W r*
    for (int i = 0; i < 3; ++i) {
        // (W r*) e_j = W (r x e_j): r x e_x = (0, rz, -ry), r x e_y = (-rz, 0, rx), r x e_z = (ry, -rx, 0)
        wr[i][0] = w[i][1] * r.z - w[i][2] * r.y;
        wr[i][1] = -w[i][0] * r.z + w[i][2] * r.x;
        wr[i][2] = w[i][0] * r.y - w[i][1] * r.x;
    }
    for (int j = 0; j < 3; ++j) {
        // r*^T x = -r x x = x x r, applied to the columns of W r* and of W
        const Vec3 c = cross({wr[0][j], wr[1][j], wr[2][j]}, r);
        big[0][j] += c.x;
        big[1][j] += c.y;
        big[2][j] += c.z;
        const Vec3 d = cross({w[0][j], w[1][j], w[2][j]}, r);
        big[0][3 + j] += d.x;
        big[1][3 + j] += d.y;
        big[2][3 + j] += d.z;
        for (int i = 0; i < 3; ++i) {
            big[3 + i][j] += wr[i][j];
            big[3 + i][3 + j] += w[i][j];
        }
        big[j][j] += inverse_mass;
    }
}

// Solve m[:size, :size] x = rhs[:size] by Gaussian elimination with partial pivoting (m and
// rhs are overwritten); false for a (near-)singular matrix.
bool solve_dense(Matrix6& m, double* rhs, int size, double* out) {
    double largest = 0.0;
    for (int i = 0; i < size; ++i) {
        largest = std::max(largest, std::fabs(m[i][i]));
    }
    if (largest == 0.0) {
        return false;
    }
    for (int col = 0; col < size; ++col) {
        int pivot = col;
        for (int row = col + 1; row < size; ++row) {
            if (std::fabs(m[row][col]) > std::fabs(m[pivot][col])) {
                pivot = row;
            }
        }
        if (std::fabs(m[pivot][col]) <= SINGULAR * largest) {
            return false;
        }
        if (pivot != col) {
            for (int k = 0; k < size; ++k) {
                std::swap(m[col][k], m[pivot][k]);
            }
            std::swap(rhs[col], rhs[pivot]);
        }
        for (int row = col + 1; row < size; ++row) {
            const double f = m[row][col] / m[col][col];
            for (int k = col; k < size; ++k) {
                m[row][k] -= f * m[col][k];
            }
            rhs[row] -= f * rhs[col];
        }
    }
    for (int row = size - 1; row >= 0; --row) {
        double acc = rhs[row];
        for (int k = row + 1; k < size; ++k) {
            acc -= m[row][k] * out[k];
        }
        out[row] = acc / m[row][row];
    }
    return true;
}

// True when the centre of pressure c + d lies within the patch (its support along d reaches
// |d|; exact for the segments and rectangles of box faces and edges up to a slight leniency
// near the corners of a rectangle).
bool centre_of_pressure_inside(const ContactSet& set, int64_t seed, int64_t count, Vec3 c, Vec3 d) {
    const double len = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (len == 0.0) {
        return true;
    }
    double reach = 0.0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            const Vec3 p = set.point[i];
            reach = std::max(reach, ((p.x - c.x) * d.x + (p.y - c.y) * d.y + (p.z - c.z) * d.z) / len);
        }
    }
    return len <= reach;
}

// Is the centre of pressure c + n x m_t / j_n (m_t: the tip moment) within the patch?
bool pressure_inside(const ContactSet& set, int64_t seed, int64_t count, Vec3 c, Vec3 n, Vec3 m,
                     double jn) {
    return centre_of_pressure_inside(set, seed, count, c, cross(n, {m.x / jn, m.y / jn, m.z / jn}));
}

// Kind of the patch, its direction (for an edge) and the mean distance of its points from c.
PatchKind patch_shape(const ContactSet& set, int64_t seed, int64_t count, Vec3 c, Vec3 t1, Vec3 t2,
                      Vec3& direction, double& radius) {
    double sxx = 0.0, sxy = 0.0, syy = 0.0;
    radius = 0.0;
    int m = 0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            const Vec3 p = set.point[i];
            const Vec3 q = {p.x - c.x, p.y - c.y, p.z - c.z};
            const double u = q.x * t1.x + q.y * t1.y + q.z * t1.z;
            const double v = q.x * t2.x + q.y * t2.y + q.z * t2.z;
            sxx += u * u;
            sxy += u * v;
            syy += v * v;
            radius += std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
            m += 1;
        }
    }
    radius /= m;
    direction = {0.0, 0.0, 0.0};
    // eigenvalues of the in-plane spread [[sxx, sxy], [sxy, syy]]
    const double mean = 0.5 * (sxx + syy);
    const double split = sxx - syy;
    const double half_gap = std::sqrt(0.25 * (split * split) + sxy * sxy);
    const double big = mean + half_gap, small = mean - half_gap;
    if (big <= 0.0 || radius == 0.0) {
        return POINT;
    }
    if (small > COLLINEAR * big) {
        return FACE;
    }
    const double angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
    const double ca = std::cos(angle), sa = std::sin(angle);
    direction = {ca * t1.x + sa * t2.x, ca * t1.y + sa * t2.y, ca * t1.z + sa * t2.z};
    return EDGE;
}

// out[:3+k, :3+k] = [[A_vv, A_vm D], [D^T A_mv, D^T A_mm D]] for the rows d[:k] of D.
void reduced_system(const Matrix6& big, const Vec3* d, int k, Matrix6& out) {
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            out[i][j] = big[i][j];
        }
        for (int c = 0; c < k; ++c) {
            out[i][3 + c] = big[i][3] * d[c].x + big[i][4] * d[c].y + big[i][5] * d[c].z;
            out[3 + c][i] = d[c].x * big[3][i] + d[c].y * big[4][i] + d[c].z * big[5][i];
        }
    }
    for (int r = 0; r < k; ++r) {
        for (int c = 0; c < k; ++c) {
            double acc = 0.0;
            for (int i = 0; i < 3; ++i) {
                for (int j = 0; j < 3; ++j) {
                    acc += d[r][i] * big[3 + i][3 + j] * d[c][j];
                }
            }
            out[3 + r][3 + c] = acc;
        }
    }
}

// The (1 + k) square system for j = j_n s and m = sum mu_c d_c: the normal row n^T dv and
// the rows d_r^T dOmega; columns j_n (through s), then mu_c (through d_c).
void sliding_system(const Matrix6& big, const Vec3* d, int k, Vec3 s, Vec3 n, Matrix6& out) {
    for (int row = 0; row < 1 + k; ++row) {
        for (int col = 0; col < 1 + k; ++col) {
            double acc = 0.0;
            for (int i = 0; i < 3; ++i) {
                const double left = row == 0 ? n[i] : d[row - 1][i];
                const int li = row == 0 ? i : 3 + i;
                for (int j = 0; j < 3; ++j) {
                    const double right = col == 0 ? s[j] : d[col - 1][j];
                    const int lj = col == 0 ? j : 3 + j;
                    acc += left * big[li][lj] * right;
                }
            }
            out[row][col] = acc;
        }
    }
}

// m = sum over c < k of sol[first + c] d_c (the solved coefficients of the rotations).
Vec3 moment(const Vec3* d, const double* sol, int first, int k) {
    Vec3 m = {0.0, 0.0, 0.0};
    for (int c = 0; c < k; ++c) {
        m = {m.x + sol[first + c] * d[c].x, m.y + sol[first + c] * d[c].y,
             m.z + sol[first + c] * d[c].z};
    }
    return m;
}

// sign (j at lever r, plus angular impulse m) on body i: V += j/M, L += r x j + m.
void apply_wrench(const BodyStates& bodies, const BodyModel& model, int i, double sign, Vec3 j,
                  Vec3 m, Vec3 r) {
    const double inv = model.inverse_mass[i];
    const Vec3 l = cross(r, j);
    Vec3& v = bodies.velocity[i];
    v = {v.x + sign * j.x * inv, v.y + sign * j.y * inv, v.z + sign * j.z * inv};
    Vec3& momentum = bodies.angular_momentum[i];
    momentum = {momentum.x + sign * (l.x + m.x), momentum.y + sign * (l.y + m.y),
                momentum.z + sign * (l.z + m.z)};
    bodies.angular_velocity[i] =
        rotate(bodies.inverse_inertia[i], momentum);
}

// What the wrench should leave behind along n: the relative normal velocity at c (m/s) and
// the relative angular velocity along each tip axis d[k] (rad/s). Restitution alone asks for
// -e times today's (every point's approach scaled alike). A point still apart at the start of
// the step may instead keep approaching at up to gap / dt, which
// closes its gap within the step (speculative contact, closable in patch.h): a face resting on
// one edge, its other edge hovering, then tips down onto its support rather than being held
// tilted. Each point's
// target is t_i = max(v_n,i, min(-e v_n,i, -gap_i / dt)): never faster than closing, never
// pulling a point that closes on its own. The targets are fitted by the affine field a rigid
// motion gives over the patch, v_n(c + u t1 + v t2) = a + v Omega.t1 - u Omega.t2 (a face;
// an edge along `edge`: a - s Omega.(n x edge)), by least squares; exact for a flat face over
// a flat support, whose gaps are affine in the same way.
// The pair as the patch's impulses see it: which bodies move and where their levers start.
struct PairLevers {
    const BodyStates& bodies;
    const BodyModel& model;
    int a, b;
    Movable movable;
    Vec3 centre_a, centre_b;
};

// n . (relative velocity change at q per unit impulse n at p): GBF's K_qp, along n.
double normal_coupling(const PairLevers& pair, Vec3 n, Vec3 q, Vec3 p) {
    double k = 0.0;
    if (pair.movable.a) {
        const Vec3 rp = sub(p, pair.centre_a), rq = sub(q, pair.centre_a);
        k += pair.model.inverse_mass[pair.a] +
             dot(rotate(pair.bodies.inverse_inertia[pair.a], cross(rp, n)), cross(rq, n));
    }
    if (pair.movable.b) {
        const Vec3 rp = sub(p, pair.centre_b), rq = sub(q, pair.centre_b);
        k += pair.model.inverse_mass[pair.b] +
             dot(rotate(pair.bodies.inverse_inertia[pair.b], cross(rp, n)), cross(rq, n));
    }
    return k;
}

// Each point's reach (closable, patch.h). A patch held at its closest point p pivots about it:
// falling at g, the impulse that stops p changes the normal velocity at q by K_qp / K_pp of
// p's, so q falls at (1 - K_qp / K_pp) g. The far end of a thin rod tipping about the other
// falls at 1.5 g and, with gravity's reach alone, would hang 1 to 1.5 |g| dt^2 above its
// support for good. Points nearer the pivot than the centre of mass keep gravity's reach.
struct LeverReach {
    double base;  // closing_reach, m
    Vec3 pivot;
    double k_pivot;
};

LeverReach lever_reach(const PairLevers& pair, const ContactSet& set, int64_t seed, int64_t count,
                       Vec3 n, double dt) {
    int64_t closest = seed;
    bool apart = false;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            closest = set.gap[i] < set.gap[closest] ? i : closest;
            apart = apart || set.gap[i] > CLOSED_GAP;
        }
    }
    const Vec3 p = set.point[closest];
    const double reach = closing_reach(pair.model, dt);
    if (!apart || -set.depth[closest] > reach / dt + REST_SPEED) {
        // every point touches (none asks its reach: point_closable), or the pivot strikes:
        // no body held at rest by it
        return {reach, p, 0.0};
    }
    return {reach, p, normal_coupling(pair, n, p, p)};
}

double point_reach(const PairLevers& pair, const LeverReach& lever, Vec3 n, Vec3 q) {
    if (lever.k_pivot <= 0.0) {
        return lever.base;
    }
    const double faster = 1.0 - normal_coupling(pair, n, q, lever.pivot) / lever.k_pivot;
    return lever.base * std::max(1.0, faster);
}

// May contact i close its gap within the step (closable with its point_reach)? A point
// that touches already (most of a resting patch's) closes nothing, whatever its reach: the
// reach, a coupling through both bodies' inertia, is only worked out for one that is apart.
bool point_closable(const PairLevers& pair, const LeverReach& lever, const ContactSet& set,
                    int64_t i, Vec3 n) {
    const double gap = set.gap[i];
    return gap > CLOSED_GAP && closable(gap, point_reach(pair, lever, n, set.point[i]));
}

// Contact i's target normal velocity t_i (normal_targets below).
double point_target(const PairLevers& pair, const LeverReach& lever, const ContactSet& set,
                    int64_t i, Vec3 n, double e, double dt) {
    const double v = set.depth[i];
    const double target = -e * v;
    return point_closable(pair, lever, set, i, n) ? std::max(v, std::min(target, -set.gap[i] / dt))
                                                  : target;
}

struct Targets {
    double normal;
    double tip[2];
};

Targets normal_targets(const PairLevers& pair, const LeverReach& lever, const ContactSet& set,
                       int64_t seed, int64_t count, Vec3 c, Vec3 n, Vec3 t1, Vec3 t2, Vec3 edge,
                       int tips, const Vec3* d, double vn, Vec3 w, double e, double dt) {
    Targets out = {-e * vn, {-e * dot(w, d[0]), tips > 1 ? -e * dot(w, d[1]) : 0.0}};
    bool closing = false;
    for (int64_t i = seed; i < count; ++i) {
        closing = closing || (set.group[i] == seed && point_closable(pair, lever, set, i, n));
    }
    if (!closing) {
        return out;
    }
    double mean = 0.0, suu = 0.0, suv = 0.0, svv = 0.0, sut = 0.0, svt = 0.0;
    int m = 0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] != seed) {
            continue;
        }
        const double target = point_target(pair, lever, set, i, n, e, dt);
        const Vec3 q = sub(set.point[i], c);
        const double u = tips > 1 ? dot(q, t1) : dot(q, edge), v = tips > 1 ? dot(q, t2) : 0.0;
        mean += target;
        suu += u * u;
        suv += u * v;
        svv += v * v;
        sut += u * target;
        svt += v * target;
        m += 1;
    }
    // c is the points' centroid, so the coordinates are centred: a is the mean target
    const double a = mean / m;
    double slope_u, slope_v = 0.0;
    if (tips > 1) {
        const double det = suu * svv - suv * suv;
        slope_u = (sut * svv - svt * suv) / det;
        slope_v = (svt * suu - sut * suv) / det;
    } else {
        slope_u = sut / suu;
    }
    // a fit that would let some point approach faster than its target allows (points whose
    // gaps are not affine: a face clipped against a smaller one, a curved support) keeps
    // restitution's targets: it could drive that point into its partner
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] != seed) {
            continue;
        }
        const Vec3 q = sub(set.point[i], c);
        const double fitted = a + slope_u * (tips > 1 ? dot(q, t1) : dot(q, edge)) +
                              slope_v * (tips > 1 ? dot(q, t2) : 0.0);
        if (fitted < point_target(pair, lever, set, i, n, e, dt) - REST_SPEED) {
            return out;
        }
    }
    out.normal = a;
    if (tips > 1) {
        out.tip[0] = slope_v;   // Omega.t1
        out.tip[1] = -slope_u;  // Omega.t2
    } else {
        out.tip[0] = -slope_u;  // Omega.(n x edge)
    }
    return out;
}

// The sliding wrench for j = j_n s with the tip constraints only: j_n and the tip moment m
// reaching `target` (normal_targets); false for a singular system.
bool solve_sliding(const Matrix6& big, const Vec3* d, int tips, Vec3 s, Vec3 n, const Targets& target,
                   double vn, Vec3 w, double& jn, Vec3& mo) {
    Matrix6 system;
    double rhs[6], sol[6];
    sliding_system(big, d, tips, s, n, system);
    rhs[0] = target.normal - vn;
    for (int k = 0; k < tips; ++k) {
        rhs[1 + k] = target.tip[k] - (w.x * d[k].x + w.y * d[k].y + w.z * d[k].z);
    }
    if (!solve_dense(system, rhs, 1 + tips, sol)) {
        return false;
    }
    jn = sol[0];
    mo = moment(d, sol, 1, tips);
    return true;
}

// The change of relative velocity at the patch centre that the wrench (j, m) makes: the top
// rows of big [j; m].
Vec3 centre_velocity_change(const Matrix6& big, Vec3 j, Vec3 m) {
    const double x[6] = {j.x, j.y, j.z, m.x, m.y, m.z};
    double dv[3] = {0.0, 0.0, 0.0};
    for (int i = 0; i < 3; ++i) {
        for (int k = 0; k < 6; ++k) {
            dv[i] += big[i][k] * x[k];
        }
    }
    return {dv[0], dv[1], dv[2]};
}

}  // namespace

Vec3 relative_point_velocity(const BodyStates& bodies, int a, int b, Vec3 ra, Vec3 rb) {
    const Vec3 pa = cross(bodies.angular_velocity[a], ra);
    const Vec3 pb = cross(bodies.angular_velocity[b], rb);
    const Vec3 va = bodies.velocity[a], vb = bodies.velocity[b];
    return {va.x + pa.x - vb.x - pb.x, va.y + pa.y - vb.y - pb.y, va.z + pa.z - vb.z - pb.z};
}

void apply_pair(const BodyStates& bodies, const BodyModel& model, int a, int b, Movable movable,
                Vec3 j, Vec3 m, Vec3 ra, Vec3 rb) {
    if (movable.a) {
        apply_wrench(bodies, model, a, 1.0, j, m, ra);
    }
    if (movable.b) {
        apply_wrench(bodies, model, b, -1.0, j, m, rb);
    }
}

void apply_with_spin_friction(const BodyStates& bodies, const BodyModel& model, int a, int b,
                              Movable movable, Vec3 j, Vec3 m, Vec3 ra, Vec3 rb, Vec3 n,
                              double limit) {
    // the relative spin about n once (j, m) has acted: omega_a + W_a (r_a x j + m) minus
    // omega_b - W_b (r_b x j + m), so both act in one update of each body
    Vec3 spin = sub(bodies.angular_velocity[a], bodies.angular_velocity[b]);
    double compliance = 0.0;
    if (movable.a) {
        const Mat3& wa = bodies.inverse_inertia[a];
        spin = add(spin, rotate(wa, add(cross(ra, j), m)));
        compliance += dot(rotate(wa, n), n);
    }
    if (movable.b) {
        const Mat3& wb = bodies.inverse_inertia[b];
        spin = add(spin, rotate(wb, add(cross(rb, j), m)));
        compliance += dot(rotate(wb, n), n);
    }
    if (compliance > 0.0) {
        const double t = std::min(std::max(-dot(spin, n) / compliance, -limit), limit);
        m = add(m, scale(t, n));
    }
    apply_pair(bodies, model, a, b, movable, j, m, ra, rb);
}

PatchResult resolve_patch(const BodyStates& bodies, const BodyModel& model, int a, int b,
                          Movable movable, const ContactSet& set, int64_t seed, int64_t count,
                          double e, double mu, Vec3 prior, double dt, bool lessen) {
    const PatchResult unresolved = {UNRESOLVED, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, false};
    const PatchResult at_rest = {AT_REST, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, false};
    // geometric centroid and mean normal of the patch
    Vec3 c = {0.0, 0.0, 0.0}, n = {0.0, 0.0, 0.0};
    int m = 0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            c = add(c, set.point[i]);
            n = add(n, set.normal[i]);
            m += 1;
        }
    }
    if (m < 2) {
        return unresolved;
    }
    c = {c.x / m, c.y / m, c.z / m};
    const double norm = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    n = {n.x / norm, n.y / norm, n.z / norm};
    Vec3 t1, t2, edge;
    tangent_basis(n, t1, t2);
    double rho;
    const PatchKind kind = patch_shape(set, seed, count, c, t1, t2, edge, rho);
    if (kind == POINT) {
        return unresolved;
    }
    // constrained rotations: tip axes first, spin about n last
    Vec3 d[3];
    int tips;
    if (kind == FACE) {
        tips = 2;
        d[0] = t1;
        d[1] = t2;
    } else {
        tips = 1;
        d[0] = cross(n, edge);
    }
    d[tips] = n;
    // relative velocity at c and relative angular velocity
    const Vec3 ra = sub(c, set.centre_a[seed]), rb = sub(c, set.centre_b[seed]);
    const Vec3 v = relative_point_velocity(bodies, a, b, ra, rb);
    const double vn = v.x * n.x + v.y * n.y + v.z * n.z;
    const Vec3 w = sub(bodies.angular_velocity[a], bodies.angular_velocity[b]);
    const double spin_speed = rho * std::max(std::max(std::fabs(w.x), std::fabs(w.y)), std::fabs(w.z));
    if (std::max(std::max(std::max(std::fabs(v.x), std::fabs(v.y)), std::fabs(v.z)), spin_speed) <
        REST_SPEED) {
        return at_rest;  // nothing to do
    }
    // every point approaching no faster than its target (a rod's end closing its gap while the
    // other end rests): nothing to do. Solved, the wrench would be j_n <= 0, and the fallback
    // impulse would stop the closing point short.
    const PairLevers pair = {bodies, model, a, b, movable, set.centre_a[seed], set.centre_b[seed]};
    const LeverReach lever = lever_reach(pair, set, seed, count, n, dt);
    bool short_of_target = false;
    for (int64_t i = seed; i < count; ++i) {
        short_of_target = short_of_target ||
                          (set.group[i] == seed &&
                           set.depth[i] < point_target(pair, lever, set, i, n, e, dt) - REST_SPEED);
    }
    if (!short_of_target) {
        return at_rest;
    }
    Matrix6 big = {};
    if (movable.a) {
        add_body_wrench_matrix(model.inverse_mass[a], bodies.inverse_inertia[a], ra, big);
    }
    if (movable.b) {
        add_body_wrench_matrix(model.inverse_mass[b], bodies.inverse_inertia[b], rb, big);
    }
    const Targets target =
        normal_targets(pair, lever, set, seed, count, c, n, t1, t2, edge, tips, d, vn, w, e, dt);
    Matrix6 system;
    double rhs[6], sol[6];
    if (mu > 0.0) {
        // static: j (3) and m along every constrained rotation
        reduced_system(big, d, tips + 1, system);
        rhs[0] = -v.x + target.normal * n.x;
        rhs[1] = -v.y + target.normal * n.y;
        rhs[2] = -v.z + target.normal * n.z;
        for (int k = 0; k < tips + 1; ++k) {
            const double spin = w.x * d[k].x + w.y * d[k].y + w.z * d[k].z;
            rhs[3 + k] = k == tips ? -spin : target.tip[k] - spin;
        }
        if (solve_dense(system, rhs, 3 + tips + 1, sol)) {
            const Vec3 j = {sol[0], sol[1], sol[2]};
            const double jn = j.x * n.x + j.y * n.y + j.z * n.z;
            const Vec3 mo = moment(d, sol, 3, tips + 1);
            const double mn = mo.x * n.x + mo.y * n.y + mo.z * n.z;
            // Coulomb on the step's total through this patch
            const Vec3 f = add(prior, j);
            const double fn = f.x * n.x + f.y * n.y + f.z * n.z;
            if (!(lessen ? fn > 0.0 : jn > 0.0)) {
                return unresolved;
            }
            const Vec3 t = {f.x - fn * n.x, f.y - fn * n.y, f.z - fn * n.z};
            if (std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z) <= mu * fn &&
                std::fabs(mn) <= mu * fn * rho &&
                pressure_inside(set, seed, count, c, n,
                                {mo.x - mn * n.x, mo.y - mn * n.y, mo.z - mn * n.z}, fn)) {
                apply_pair(bodies, model, a, b, movable, j, mo, ra, rb);
                return {APPLIED, j, mo, false};
            }
        }
    }
    // sliding (or frictionless): j = j_n s, s = n - mu T, with the tip constraints only. T is
    // the direction the patch slides in once the wrench has acted, taken from the frictionless
    // wrench: the tip constraints can turn the sliding round (a block pushed at its top rocks
    // its base backwards before they stop the rocking), and friction must oppose the sliding
    // that is left, not the one before (then it pointed forwards in the push's first step).
    Vec3 u = {v.x - vn * n.x, v.y - vn * n.y, v.z - vn * n.z};
    double jn;
    Vec3 mo;
    if (mu > 0.0 && solve_sliding(big, d, tips, n, n, target, vn, w, jn, mo) && jn > 0.0) {
        const Vec3 after = add(v, centre_velocity_change(big, scale(jn, n), mo));
        const double an = dot(after, n);
        const Vec3 left = {after.x - an * n.x, after.y - an * n.y, after.z - an * n.z};
        if (std::max(std::max(std::fabs(left.x), std::fabs(left.y)), std::fabs(left.z)) > REST_SPEED) {
            u = left;
        }
    }
    const double ut = std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
    const double friction = ut > 0.0 ? mu : 0.0;
    Vec3 s = n;
    if (friction > 0.0) {
        s = {n.x - friction * u.x / ut, n.y - friction * u.y / ut, n.z - friction * u.z / ut};
    }
    if (!solve_sliding(big, d, tips, s, n, target, vn, w, jn, mo)) {
        return unresolved;
    }
    const double fn = jn + prior.x * n.x + prior.y * n.y + prior.z * n.z;
    if (!(lessen ? fn > 0.0 : jn > 0.0)) {
        return unresolved;
    }
    if (!pressure_inside(set, seed, count, c, n, mo, fn)) {
        return unresolved;
    }
    const Vec3 j = scale(jn, s);
    if (mu > 0.0) {
        apply_with_spin_friction(bodies, model, a, b, movable, j, mo, ra, rb, n, mu * jn * rho);
    } else {
        apply_pair(bodies, model, a, b, movable, j, mo, ra, rb);
    }
    return {APPLIED, j, mo, mu > 0.0};
}

}  // namespace rg
