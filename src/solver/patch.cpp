// The patch wrench (patch.h).
#include "solver/patch.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>

#include "base/dense.h"
#include "solver/mobility.h"

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

// Body i's change of angular velocity for j at lever r plus the angular impulse m, and its
// spin compliance about n (n . I^-1 n), through its joints where it is articulated
// (mobility.h).
void spin_response(const BodyStates& bodies, const BodyModel& model, int i, Vec3 r, Vec3 j,
                   Vec3 m, Vec3 n, Vec3& dw, double& compliance) {
    const Mat3& wi = bodies.inverse_inertia[i];
    if (!model.articulated[i]) {
        dw = rotate(wi, add(cross(r, j), m));
        compliance = dot(rotate(wi, n), n);
        return;
    }
    Vec3 dv, turn;
    articulated_response(bodies, model, i, j, add(cross(r, j), m), dv, dw);
    articulated_response(bodies, model, i, {0.0, 0.0, 0.0}, n, dv, turn);
    compliance = dot(turn, n);
}

// add_body_wrench_matrix for body i, through its joints where it is articulated (mobility.h).
void add_wrench_matrix(const BodyStates& bodies, const BodyModel& model, int i, Vec3 r,
                       Matrix6& big) {
    if (model.articulated[i]) {
        add_articulated_wrench_matrix(bodies, model, i, r, big);
    } else {
        add_body_wrench_matrix(model.inverse_mass[i], bodies.inverse_inertia[i], r, big);
    }
}

// True when the centre of pressure c + d lies within the patch (its support along d reaches
// |d|; exact for the segments and rectangles of box faces and edges up to a slight leniency
// near the corners of a rectangle).
bool centre_of_pressure_inside(const ContactSet& set, int64_t seed, int64_t count, Vec3 c, Vec3 d) {
    const double len = length(d);
    if (len == 0.0) {
        return true;
    }
    double reach = 0.0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            const Vec3 p = set.point[i];
            reach = std::max(reach, dot(sub(p, c), d) / len);
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
            const Vec3 q = sub(set.point[i], c);
            const double u = dot(q, t1), v = dot(q, t2);
            sxx += u * u;
            sxy += u * v;
            syy += v * v;
            radius += length(q);
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
    direction = add(scale(ca, t1), scale(sa, t2));
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

// sign (j at lever r, plus angular impulse m) on body i: V += j/M, L += r x j + m (of the
// part that its joints let through, for an articulated body: mobility.h).
void apply_wrench(const BodyStates& bodies, const BodyModel& model, int i, double sign, Vec3 j,
                  Vec3 m, Vec3 r) {
    const double inv = model.inverse_mass[i];
    const Vec3 l = cross(r, j);
    if (model.articulated[i]) {  // what its joints let through (mobility.h)
        Vec3 linear = scale(sign, j), angular = scale(sign, add(l, m));
        admit(bodies, model, i, linear, angular);
        bodies.velocity[i] = add(bodies.velocity[i], scale(inv, linear));
        bodies.angular_momentum[i] = add(bodies.angular_momentum[i], angular);
        bodies.angular_velocity[i] = rotate(bodies.inverse_inertia[i], bodies.angular_momentum[i]);
        return;
    }
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
    const int bodies[2] = {pair.a, pair.b};
    const bool movable[2] = {pair.movable.a, pair.movable.b};
    const Vec3 centres[2] = {pair.centre_a, pair.centre_b};
    bool articulated = false;
    for (int s = 0; s < 2; ++s) {
        if (movable[s] && pair.model.articulated[bodies[s]]) {  // mobility.h
            articulated = true;
        }
    }
    if (articulated) {
        for (int s = 0; s < 2; ++s) {
            if (movable[s]) {
                const Vec3 rp = sub(p, centres[s]), rq = sub(q, centres[s]);
                Vec3 dv = scale(pair.model.inverse_mass[bodies[s]], n);
                Vec3 dw = rotate(pair.bodies.inverse_inertia[bodies[s]], cross(rp, n));
                if (pair.model.articulated[bodies[s]]) {
                    articulated_response(pair.bodies, pair.model, bodies[s], n, cross(rp, n),
                                         dv, dw);
                }
                k += dot(n, add(dv, cross(dw, rq)));
            }
        }
        return k;
    }
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
        rhs[1 + k] = target.tip[k] - dot(w, d[k]);
    }
    if (!solve_dense(system, rhs, 1 + tips, sol, SINGULAR)) {
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
        Vec3 dw;
        double turn;
        spin_response(bodies, model, a, ra, j, m, n, dw, turn);
        spin = add(spin, dw);
        compliance += turn;
    }
    if (movable.b) {
        Vec3 dw;
        double turn;
        spin_response(bodies, model, b, rb, j, m, n, dw, turn);
        spin = add(spin, dw);
        compliance += turn;
    }
    if (compliance > 0.0) {
        const double t = std::min(std::max(-dot(spin, n) / compliance, -limit), limit);
        m = add(m, scale(t, n));
    }
    apply_pair(bodies, model, a, b, movable, j, m, ra, rb);
}

namespace {

// The largest of |x|, |y|, |z|.
double max_abs(Vec3 a) { return std::max(std::max(std::fabs(a.x), std::fabs(a.y)), std::fabs(a.z)); }

// The patch seen from its centre: its geometry (patch_memo.h) and the pair's relative
// motion there.
struct PatchFrame : PatchGeometry {
    Vec3 v, w;         // relative velocity at c (m/s) and relative angular velocity (rad/s)
    double vn;         // v . n
};

// The geometry of the patch whose contacts have group == seed; false for a single point
// (fewer than two contacts, or all at one place).
bool patch_geometry(const ContactSet& set, int64_t seed, int64_t count, PatchGeometry& f) {
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
        return false;
    }
    f.c = {c.x / m, c.y / m, c.z / m};
    const double norm = length(n);
    f.n = {n.x / norm, n.y / norm, n.z / norm};
    tangent_basis(f.n, f.t1, f.t2);
    const PatchKind kind = patch_shape(set, seed, count, f.c, f.t1, f.t2, f.edge, f.rho);
    if (kind == POINT) {
        return false;
    }
    if (kind == FACE) {
        f.tips = 2;
        f.d[0] = f.t1;
        f.d[1] = f.t2;
    } else {
        f.tips = 1;
        f.d[0] = cross(f.n, f.edge);
    }
    f.d[f.tips] = f.n;
    f.ra = sub(f.c, set.centre_a[seed]);
    f.rb = sub(f.c, set.centre_b[seed]);
    return true;
}

// The frame of the patch whose contacts have group == seed, its geometry from key's memo
// where that holds these contacts (else found, and kept there); false for a single point.
bool patch_frame(const BodyStates& bodies, int a, int b, const ContactSet& set, int64_t seed,
                 int64_t count, const PatchKey& key, PatchFrame& f) {
    PatchMemo* memo = key.memo;
    if (memo != nullptr && memo->members == key.members && memo->movable == key.movable) {
        if (memo->point) {
            return false;
        }
        static_cast<PatchGeometry&>(f) = memo->geometry;
    } else {
        const bool patch = patch_geometry(set, seed, count, f);
        if (memo != nullptr) {
            memo->members = key.members;
            memo->movable = key.movable;
            memo->point = !patch;
            memo->geometry = f;
            memo->system.has_matrix = false;
            memo->system.has_factors = false;
        }
        if (!patch) {
            return false;
        }
    }
    f.v = relative_point_velocity(bodies, a, b, f.ra, f.rb);
    f.vn = dot(f.v, f.n);
    f.w = sub(bodies.angular_velocity[a], bodies.angular_velocity[b]);
    return true;
}

// Is the patch at rest: every point's relative speed below REST_SPEED?
bool patch_at_rest(const PatchFrame& f) { return std::max(max_abs(f.v), f.rho * max_abs(f.w)) < REST_SPEED; }

// Does some point approach faster than its target? Not when every point approaches no faster
// (a rod's end closing its gap while the other end rests): solved, the wrench would be
// j_n <= 0, and the fallback impulse would stop the closing point short.
bool short_of_target(const PairLevers& pair, const LeverReach& lever, const ContactSet& set,
                     int64_t seed, int64_t count, const PatchFrame& f, double e, double dt) {
    bool short_of = false;
    for (int64_t i = seed; i < count; ++i) {
        short_of = short_of || (set.group[i] == seed &&
                                set.depth[i] < point_target(pair, lever, set, i, f.n, e, dt) - REST_SPEED);
    }
    return short_of;
}

// The static wrench: j (3) and a moment along every constrained rotation reaching the targets,
// applied if it pushes (j_n > 0; with lessen, if prior + j does) and keeps the step's total
// through the patch (prior + j) inside the friction cone, its spin moment inside mu j_n rho and its centre of pressure
// inside the patch. Returns APPLIED or UNRESOLVED (it would pull), or nothing where it is not
// taken (a singular system, or a wrench that would slide): the sliding wrench is next.
std::optional<PatchResult> static_wrench(const PairLevers& pair, const ContactSet& set, int64_t seed, int64_t count,
                          const PatchFrame& f, PatchSystem& kept, const Targets& target, double mu,
                          Vec3 prior, bool lessen) {
    const Vec3 n = f.n, v = f.v;
    const int size = 3 + f.tips + 1;
    if (!kept.has_factors) {
        reduced_system(kept.matrix, f.d, f.tips + 1, kept.factors);
        kept.solvable = factor_dense(kept.factors, size, kept.pivot, SINGULAR);
        kept.has_factors = true;
    }
    if (!kept.solvable) {
        return std::nullopt;
    }
    double rhs[6], sol[6];
    rhs[0] = -v.x + target.normal * n.x;
    rhs[1] = -v.y + target.normal * n.y;
    rhs[2] = -v.z + target.normal * n.z;
    for (int k = 0; k < f.tips + 1; ++k) {
        const double spin = dot(f.w, f.d[k]);
        rhs[3 + k] = k == f.tips ? -spin : target.tip[k] - spin;
    }
    solve_factored(kept.factors, kept.pivot, size, rhs, sol);
    const Vec3 j = {sol[0], sol[1], sol[2]};
    const Vec3 mo = moment(f.d, sol, 3, f.tips + 1);
    const double mn = dot(mo, n);
    // Coulomb on the step's total through this patch
    const Vec3 total = add(prior, j);
    const double fn = dot(total, n);
    if (!(lessen ? fn > 0.0 : dot(j, n) > 0.0)) {
        return PatchResult{UNRESOLVED, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, false};
    }
    if (length(sub(total, scale(fn, n))) <= mu * fn && std::fabs(mn) <= mu * fn * f.rho &&
        pressure_inside(set, seed, count, f.c, n, sub(mo, scale(mn, n)), fn)) {
        apply_pair(pair.bodies, pair.model, pair.a, pair.b, pair.movable, j, mo, f.ra, f.rb);
        return PatchResult{APPLIED, j, mo, false};
    }
    return std::nullopt;
}

// The sliding (or frictionless) wrench: j = j_n s, s = n - mu T, with the tip constraints
// only. T is the direction the patch slides in once the wrench has acted, taken from the
// frictionless wrench: the tip constraints can turn the sliding round (a block pushed at its
// top rocks its base backwards before they stop the rocking), and friction must oppose the
// sliding that is left, not the one before (then it pointed forwards in the push's first
// step). With lessen it may press less than nothing where prior + j still presses.
PatchResult sliding_wrench(const PairLevers& pair, const ContactSet& set, int64_t seed,
                           int64_t count, const PatchFrame& f, const Matrix6& big,
                           const Targets& target, double mu, Vec3 prior, bool lessen) {
    const Vec3 n = f.n;
    Vec3 u = sub(f.v, scale(f.vn, n));
    double jn;
    Vec3 mo;
    if (mu > 0.0 && solve_sliding(big, f.d, f.tips, n, n, target, f.vn, f.w, jn, mo) && jn > 0.0) {
        const Vec3 after = add(f.v, centre_velocity_change(big, scale(jn, n), mo));
        const Vec3 left = sub(after, scale(dot(after, n), n));
        if (max_abs(left) > REST_SPEED) {
            u = left;
        }
    }
    const double ut = length(u);
    const double friction = ut > 0.0 ? mu : 0.0;
    Vec3 s = n;
    if (friction > 0.0) {
        s = {n.x - friction * u.x / ut, n.y - friction * u.y / ut, n.z - friction * u.z / ut};
    }
    const PatchResult unresolved = {UNRESOLVED, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, false};
    if (!solve_sliding(big, f.d, f.tips, s, n, target, f.vn, f.w, jn, mo)) {
        return unresolved;
    }
    // summed in this order (jn first): the rounding is the step's
    const double fn = jn + prior.x * n.x + prior.y * n.y + prior.z * n.z;
    if (!(lessen ? fn > 0.0 : jn > 0.0) || !pressure_inside(set, seed, count, f.c, n, mo, fn)) {
        return unresolved;
    }
    const Vec3 j = scale(jn, s);
    if (mu > 0.0) {
        apply_with_spin_friction(pair.bodies, pair.model, pair.a, pair.b, pair.movable, j, mo,
                                 f.ra, f.rb, n, mu * jn * f.rho);
    } else {
        apply_pair(pair.bodies, pair.model, pair.a, pair.b, pair.movable, j, mo, f.ra, f.rb);
    }
    return {APPLIED, j, mo, mu > 0.0};
}

}  // namespace

PatchResult resolve_patch(const BodyStates& bodies, const BodyModel& model, int a, int b,
                          Movable movable, const ContactSet& set, int64_t seed, int64_t count,
                          double e, double mu, Vec3 prior, double dt, bool lessen, PatchKey key) {
    const PatchResult at_rest = {AT_REST, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, false};
    PatchFrame f;
    if (!patch_frame(bodies, a, b, set, seed, count, key, f)) {
        return {UNRESOLVED, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, false};
    }
    if (patch_at_rest(f)) {
        return at_rest;  // nothing to do
    }
    const PairLevers pair = {bodies, model, a, b, movable, set.centre_a[seed], set.centre_b[seed]};
    const LeverReach lever = lever_reach(pair, set, seed, count, f.n, dt);
    if (!short_of_target(pair, lever, set, seed, count, f, e, dt)) {
        return at_rest;
    }
    PatchSystem local;  // without a memo: this resolve's own
    PatchSystem& kept = key.memo != nullptr ? key.memo->system : local;
    if (!kept.has_matrix) {
        for (auto& row : kept.matrix) {
            std::fill(std::begin(row), std::end(row), 0.0);
        }
        if (movable.a) {
            add_wrench_matrix(bodies, model, a, f.ra, kept.matrix);
        }
        if (movable.b) {
            add_wrench_matrix(bodies, model, b, f.rb, kept.matrix);
        }
        kept.has_matrix = true;
    }
    const Targets target = normal_targets(pair, lever, set, seed, count, f.c, f.n, f.t1, f.t2,
                                          f.edge, f.tips, f.d, f.vn, f.w, e, dt);
    if (mu > 0.0) {
        if (const auto held = static_wrench(pair, set, seed, count, f, kept, target, mu, prior, lessen)) {
            return *held;
        }
    }
    return sliding_wrench(pair, set, seed, count, f, kept.matrix, target, mu, prior, lessen);
}

}  // namespace rg
