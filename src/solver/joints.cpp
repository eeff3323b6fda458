// The joint stages: velocity solve and position pre-stabilisation (joints.h).
#include "solver/joints.h"

#include <algorithm>
#include <cmath>

#include "solver/mobility.h"
#include "solver/solver.h"

namespace rg {

namespace {

constexpr double PI = 3.14159265358979323846;
// Pivots below this share of the system's largest diagonal entry are rows the bodies cannot
// move (an axis of zero inverse moment, a row repeating another): they get no impulse.
constexpr double SINGULAR = 1e-12;
// Halvings of a pre-stabilisation Newton step that does not lower the predicted error.
constexpr int NEWTON_HALVINGS = 4;

// A row's role in the velocity solve: an equality, or the free coordinate's condition.
enum Role : int32_t { EQUALITY = -1, MOTOR = 0, LOWER = 1, UPPER = 2 };

// A body (or the world frame) as a joint's rows see it: pose and velocity.
struct Frame {
    Vec3 x;
    Quat q;
    Mat3 r;
    Vec3 v, w;
};

using Row = JointRow;

// One joint's rows: its equality rows, and its free coordinate's row apart.
struct Rows {
    Row row[MAX_JOINT_ROWS];
    int count = 0;
    Row axial;
    bool has_axial = false;
    double coordinate = 0.0;  // rad or m

    void add(Vec3 la, Vec3 aa, Vec3 lb, Vec3 ab, double error) {
        row[count++] = {la, aa, lb, ab, error};
    }
};

Vec3 negate(Vec3 a) { return {-a.x, -a.y, -a.z}; }

Quat conjugate(Quat q) { return {q.w, -q.x, -q.y, -q.z}; }

// Two unit vectors across unit u, with u a right-handed frame.
void across(Vec3 u, Vec3& t1, Vec3& t2) {
    const Vec3 seed = std::fabs(u.x) < 0.57735 ? Vec3{1.0, 0.0, 0.0}
                      : std::fabs(u.y) < 0.57735 ? Vec3{0.0, 1.0, 0.0}
                                                 : Vec3{0.0, 0.0, 1.0};
    t1 = cross(u, seed);
    t1 = scale(1.0 / length(t1), t1);
    t2 = cross(u, t1);
}

// Body i (or the world frame) at its current pose, or predicted dt ahead (X + dt V, q turned
// by omega dt: the poses the position update reaches, to the rotation update's order).
Frame frame_of(const StepContext& w, int i, double ahead) {
    Frame f;
    if (i == WORLD_BODY) {
        f = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0, 0.0}, {}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
        f.r = rotation_from_quaternion(f.q);
        return f;
    }
    const BodyStates& s = w.bodies;
    f.v = s.velocity[i];
    f.w = s.angular_velocity[i];
    f.x = add(s.position[i], scale(ahead, f.v));
    f.q = ahead > 0.0 ? rotate_by_angular_velocity(s.orientation[i], f.w, ahead) : s.orientation[i];
    f.r = ahead > 0.0 ? rotation_from_quaternion(f.q) : s.rotation[i];
    return f;
}

// Rotation vector of unit quaternion q (rad), taken the short way.
Vec3 rotation_vector(Quat q) {
    if (q.w < 0.0) {
        q = {-q.w, -q.x, -q.y, -q.z};
    }
    const Vec3 v = {q.x, q.y, q.z};
    const double s = length(v);
    if (s == 0.0) {
        return v;
    }
    return scale(2.0 * std::atan2(s, q.w) / s, v);
}

// Joint j's rows at frames a and b (joints.h lists them).
void build_rows(const JointRows& joints, int64_t j, const Frame& a, const Frame& b, Rows& rows) {
    rows.count = 0;
    rows.has_axial = false;
    rows.coordinate = 0.0;
    const int32_t kind = joints.kind[j];
    const Vec3 pa = to_world(a.x, a.r, joints.anchor_a[j]);
    const Vec3 pb = to_world(b.x, b.r, joints.anchor_b[j]);
    const Vec3 ra = sub(pa, a.x), rb = sub(pb, b.x);
    const Vec3 d = sub(pa, pb);
    // a's orientation relative to where coordinate 0 puts it (world frame)
    const Quat relative = multiply(a.q, conjugate(multiply(b.q, joints.reference[j])));
    if (kind == REVOLUTE || kind == FIXED) {
        const Vec3 axes[3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
        for (const Vec3& e : axes) {
            rows.add(e, cross(ra, e), negate(e), negate(cross(rb, e)), dot(d, e));
        }
    }
    if (kind == PRISMATIC) {
        // t fixed in b: d(t.d)/dt = t.(v_a + w_a x r_a - v_b - w_b x r_b) + (w_b x t).d
        const Vec3 u = rotate(b.r, joints.axis_b[j]);
        const Vec3 arm_b = sub(pa, b.x);
        Vec3 t1, t2;
        across(u, t1, t2);
        for (const Vec3& t : {t1, t2}) {
            rows.add(t, cross(ra, t), negate(t), negate(cross(arm_b, t)), dot(d, t));
        }
        rows.axial = {u, cross(ra, u), negate(u), negate(cross(arm_b, u)), 0.0};
        rows.has_axial = true;
        rows.coordinate = dot(d, u);
    }
    if (kind == PRISMATIC || kind == FIXED) {
        const Vec3 error = rotation_vector(relative);
        const Vec3 axes[3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
        for (const Vec3& e : axes) {
            rows.add({0.0, 0.0, 0.0}, e, {0.0, 0.0, 0.0}, negate(e), dot(error, e));
        }
    }
    if (kind == REVOLUTE) {
        // a small turn delta about t (across b's axis n_b) makes n_b x n_a = delta t
        const Vec3 na = rotate(a.r, joints.axis_a[j]), nb = rotate(b.r, joints.axis_b[j]);
        const Vec3 misaligned = cross(nb, na);
        Vec3 t1, t2;
        across(nb, t1, t2);
        for (const Vec3& t : {t1, t2}) {
            rows.add({0.0, 0.0, 0.0}, t, {0.0, 0.0, 0.0}, negate(t), dot(misaligned, t));
        }
        rows.axial = {{0.0, 0.0, 0.0}, nb, {0.0, 0.0, 0.0}, negate(nb), 0.0};
        rows.has_axial = true;
        const Quat q = relative.w < 0.0 ? Quat{-relative.w, -relative.x, -relative.y, -relative.z}
                                        : relative;
        double angle = 2.0 * std::atan2(q.x * nb.x + q.y * nb.y + q.z * nb.z, q.w);
        if (angle > PI) {
            angle -= 2.0 * PI;
        }
        rows.coordinate = angle;
    }
}

// Row's rate (m/s or rad/s) at joint j's bodies' current velocities.
double rate(const StepContext& w, const JointRows& joints, const Row& row, int64_t j) {
    const Frame a = frame_of(w, joints.body_a[j], 0.0);
    const Frame b = frame_of(w, joints.body_b[j], 0.0);
    return dot(row.la, a.v) + dot(row.aa, a.w) + dot(row.lb, b.v) + dot(row.ab, b.w);
}

// Does body i take joint impulses (a dynamic body, not the world frame)?
bool takes_impulses(const StepContext& w, int i) {
    return i != WORLD_BODY && w.model.motion[i] == DYNAMIC;
}

// joints.turn_a, turn_b of the system's columns [0, count): each row's angular parts turned
// by its bodies' I(t)^-1, the part of M^-1 J_q^T that every coupling with column q needs,
// formed once a solve instead of once an entry.
void turn_columns(const StepContext& w, const JointRows& joints, int64_t count) {
    const Vec3 none = {0.0, 0.0, 0.0};
    for (int64_t q = 0; q < count; ++q) {
        const int64_t j = joints.row_joint[q];
        const int a = joints.body_a[j], b = joints.body_b[j];
        joints.turn_a[q] = takes_impulses(w, a)
                               ? rotate(w.bodies.inverse_inertia[a], joints.rows[q].aa) : none;
        joints.turn_b[q] = takes_impulses(w, b)
                               ? rotate(w.bodies.inverse_inertia[b], joints.rows[q].ab) : none;
    }
}

// J_p M^-1 J_q^T for row p of joint jp and column q of the system (joints.rows[q], turned by
// turn_columns): nonzero where they share a movable body.
double coupling(const StepContext& w, const JointRows& joints, const Row& p, int64_t jp,
                int64_t q) {
    const int64_t jq = joints.row_joint[q];
    const Row& row = joints.rows[q];
    const int pa = joints.body_a[jp], pb = joints.body_b[jp];
    const int qa = joints.body_a[jq], qb = joints.body_b[jq];
    double sum = 0.0;
    const auto term = [&](int body, Vec3 pl, Vec3 pang, Vec3 ql, Vec3 turned) {
        if (!takes_impulses(w, body)) {
            return;
        }
        sum += w.model.inverse_mass[body] * dot(pl, ql) + dot(pang, turned);
    };
    if (pa == qa) term(pa, p.la, p.aa, row.la, joints.turn_a[q]);
    if (pa == qb) term(pa, p.la, p.aa, row.lb, joints.turn_b[q]);
    if (pb == qa) term(pb, p.lb, p.ab, row.la, joints.turn_a[q]);
    if (pb == qb) term(pb, p.lb, p.ab, row.lb, joints.turn_b[q]);
    return sum;
}

// Apply impulse lambda along row of joint j to its bodies' state (V, L, omega = I^-1 L) and
// to the joint's reported impulse.
void apply_row(StepContext& w, const JointRows& joints, const Row& row, int64_t j, double lambda) {
    const BodyStates& s = w.bodies;
    const int bodies[2] = {joints.body_a[j], joints.body_b[j]};
    const Vec3 linear[2] = {row.la, row.lb}, angular[2] = {row.aa, row.ab};
    for (int k = 0; k < 2; ++k) {
        const int i = bodies[k];
        if (i == WORLD_BODY || w.model.motion[i] != DYNAMIC) {
            continue;
        }
        s.velocity[i] = add(s.velocity[i], scale(lambda * w.model.inverse_mass[i], linear[k]));
        s.angular_momentum[i] = add(s.angular_momentum[i], scale(lambda, angular[k]));
        s.angular_velocity[i] = rotate(s.inverse_inertia[i], s.angular_momentum[i]);
    }
    joints.impulse[j] = add(joints.impulse[j], scale(lambda, row.la));
    joints.angular_impulse[j] = add(joints.angular_impulse[j], scale(lambda, row.aa));
}

// Is joint j's island asleep in this step (sleep.h)? Its bodies are one island, so body b is
// then asleep too or takes no impulse.
bool asleep(const StepContext& w, int64_t j) {
    return w.settings->sleep && w.rest.asleep[w.joints.body_a[j]];
}

// lambda over the rows [0, count) of joints.rows (the impulses' directions) for the system
// A_pq = measured_p M^-1 rows_q^T (the rate of measured row p that an impulse along row q
// makes: measured is rows itself, or the same rows at the predicted poses for a Newton step
// there) with right-hand side joints.rhs; with skip_held, the rows joints.held get none.
// Gaussian elimination with partial pivoting over the whole system (joints.h says why); a
// row whose pivot is below SINGULAR of the largest diagonal entry gets no impulse.
void solve_system(StepContext& w, Span<const Row> measured, int64_t count, bool skip_held) {
    const JointRows& joints = w.joints;
    const int64_t width = count + 1;
    const Span<double> m = joints.matrix;
    turn_columns(w, joints, count);
    double largest = 0.0;
    for (int64_t p = 0; p < count; ++p) {
        for (int64_t q = 0; q < count; ++q) {
            const bool out = skip_held && (joints.held[p] || joints.held[q]);
            m[p * width + q] = out ? (p == q ? 1.0 : 0.0)
                                   : coupling(w, joints, measured[p], joints.row_joint[p], q);
        }
        m[p * width + count] = skip_held && joints.held[p] ? 0.0 : joints.rhs[p];
        largest = std::max(largest, std::fabs(m[p * width + p]));
        joints.lambda[p] = 0.0;
    }
    const double floor = SINGULAR * largest;
    int64_t rank = 0;
    for (int64_t c = 0; c < count && rank < count; ++c) {
        int64_t pivot = rank;
        for (int64_t p = rank + 1; p < count; ++p) {
            if (std::fabs(m[p * width + c]) > std::fabs(m[pivot * width + c])) {
                pivot = p;
            }
        }
        if (!(std::fabs(m[pivot * width + c]) > floor)) {
            continue;  // the bodies cannot move along this row given the ones before
        }
        for (int64_t q = 0; q < width; ++q) {
            std::swap(m[rank * width + q], m[pivot * width + q]);
        }
        const double diagonal = m[rank * width + c];
        for (int64_t p = 0; p < count; ++p) {
            const double f = m[p * width + c];
            if (p != rank && f != 0.0) {
                const double ratio = f / diagonal;
                for (int64_t q = c; q < width; ++q) {
                    m[p * width + q] -= ratio * m[rank * width + q];
                }
            }
        }
        joints.column_of[rank] = static_cast<int32_t>(c);
        rank += 1;
    }
    for (int64_t p = 0; p < rank; ++p) {
        const int64_t c = joints.column_of[p];
        joints.lambda[c] = m[p * width + count] / m[p * width + c];
    }
}

// Joint j's coordinate condition for the velocity solve at its current coordinate s and
// rate: a limit the joint would pass within the step (its rate wanted at least (lower -
// s) / dt, at most (upper - s) / dt), else the motor, else none (-2).
int32_t axial_role(const JointRows& joints, int64_t j, double s, double speed, double dt) {
    if (speed < (joints.lower[j] - s) / dt) {
        return LOWER;
    }
    if (speed > (joints.upper[j] - s) / dt) {
        return UPPER;
    }
    return joints.max_motor[j] > 0.0 ? MOTOR : -2;
}

// The velocity solve of the joints order[first, last) (one component, awake): their
// equality rows at rate 0 and, with `coordinates`, each one's coordinate condition
// (axial_role); see solve_joint_velocities.
void solve_velocity_rows(StepContext& w, double dt, bool coordinates, int64_t first,
                         int64_t last) {
    const JointRows& joints = w.joints;
    int64_t count = 0;
    for (int64_t k = first; k < last; ++k) {
        const int64_t j = joints.order[k];
        const Frame a = frame_of(w, joints.body_a[j], 0.0);
        const Frame b = frame_of(w, joints.body_b[j], 0.0);
        Rows rows;
        build_rows(joints, j, a, b, rows);
        for (int p = 0; p < rows.count; ++p) {
            joints.rows[count] = rows.row[p];
            joints.row_joint[count] = static_cast<int32_t>(j);
            joints.row_role[count] = EQUALITY;
            joints.target[count] = 0.0;
            count += 1;
        }
        if (coordinates && rows.has_axial) {
            const double speed = rate(w, joints, rows.axial, j);
            const int32_t role = axial_role(joints, j, rows.coordinate, speed, dt);
            if (role >= 0) {
                joints.rows[count] = rows.axial;
                joints.row_joint[count] = static_cast<int32_t>(j);
                joints.row_role[count] = role;
                joints.target[count] = role == MOTOR   ? joints.motor_speed[j]
                                       : role == LOWER ? (joints.lower[j] - rows.coordinate) / dt
                                                       : (joints.upper[j] - rows.coordinate) / dt;
                count += 1;
            }
        }
    }
    // Every row at its wanted rate at once; a coordinate row whose impulse would leave its
    // bounds (a motor past max_motor dt, a limit pulling) is held at the bound and the rest
    // solved again, up to joint_passes times (an active set that only shrinks; the last
    // pass clamps what is left).
    for (int64_t p = 0; p < count; ++p) {
        joints.held[p] = 0;
    }
    for (int pass = 0; pass < w.settings->joint_passes; ++pass) {
        for (int64_t p = 0; p < count; ++p) {
            joints.rhs[p] = joints.target[p] - rate(w, joints, joints.rows[p], joints.row_joint[p]);
        }
        solve_system(w, {joints.rows.data, count}, count, true);
        const bool last = pass + 1 == w.settings->joint_passes;
        bool newly_held = false;
        for (int64_t p = 0; p < count; ++p) {
            const int32_t role = joints.row_role[p];
            if (role == EQUALITY || joints.held[p]) {
                continue;
            }
            const int64_t j = joints.row_joint[p];
            const double bound = role == MOTOR ? joints.max_motor[j] * dt : INFINITY;
            const double low = role == MOTOR ? -bound : role == LOWER ? 0.0 : -INFINITY;
            const double high = role == MOTOR ? bound : role == UPPER ? 0.0 : INFINITY;
            const double clamped = std::min(std::max(joints.lambda[p], low), high);
            if (clamped != joints.lambda[p]) {
                joints.held[p] = 1;
                joints.lambda[p] = clamped;
                newly_held = true;
                apply_row(w, joints, joints.rows[p], j, clamped);
                joints.accumulated[3 * j + (role == MOTOR ? 0 : 1)] += clamped;
            }
        }
        if (newly_held && !last) {
            continue;
        }
        for (int64_t p = 0; p < count; ++p) {
            if (!joints.held[p]) {
                const int64_t j = joints.row_joint[p];
                apply_row(w, joints, joints.rows[p], j, joints.lambda[p]);
                if (joints.row_role[p] != EQUALITY) {
                    joints.accumulated[3 * j + (joints.row_role[p] == MOTOR ? 0 : 1)] +=
                        joints.lambda[p];
                }
            }
        }
        break;
    }
}

// The rows of joint j at its predicted poses (errors there), with the free coordinate's row
// added where the predicted coordinate is past a limit (to be brought back to it).
void predicted_rows(const JointRows& joints, int64_t j, const Frame& a, const Frame& b,
                    Rows& rows) {
    build_rows(joints, j, a, b, rows);
    if (rows.has_axial) {
        const double s = rows.coordinate;
        const double bound = s < joints.lower[j] ? joints.lower[j]
                             : s > joints.upper[j] ? joints.upper[j]
                                                   : s;
        if (bound != s) {
            rows.row[rows.count] = rows.axial;
            rows.row[rows.count].error = s - bound;
            rows.count += 1;
        }
    }
}

// The rows of the joints order[first, last) at the predicted poses: into joints.along with
// their errors (targets -error / dt), and with `current` their impulse directions at the
// current poses into joints.rows; returns how many.
int64_t predicted_system(StepContext& w, double dt, bool current, int64_t first, int64_t last) {
    const JointRows& joints = w.joints;
    int64_t count = 0;
    for (int64_t k = first; k < last; ++k) {
        const int64_t j = joints.order[k];
        Rows predicted, now;
        predicted_rows(joints, j, frame_of(w, joints.body_a[j], dt),
                       frame_of(w, joints.body_b[j], dt), predicted);
        if (current) {
            build_rows(joints, j, frame_of(w, joints.body_a[j], 0.0),
                       frame_of(w, joints.body_b[j], 0.0), now);
        }
        for (int p = 0; p < predicted.count; ++p) {
            if (current) {
                joints.rows[count] = p < now.count ? now.row[p] : now.axial;
                joints.row_joint[count] = static_cast<int32_t>(j);
            }
            joints.along[count] = predicted.row[p];
            joints.target[count] = -predicted.row[p].error / dt;
            count += 1;
        }
    }
    return count;
}

// The largest |error| (m, rad) of the first count predicted rows (predicted_system).
double largest_error(const JointRows& joints, int64_t count, double dt) {
    double error = 0.0;
    for (int64_t p = 0; p < count; ++p) {
        error = std::max(error, std::fabs(joints.target[p] * dt));
    }
    return error;
}

// Copy the bodies of the joints order[first, last) (their velocity, angular momentum and
// angular velocity) into joints.saved (keep), or back from it.
void keep_joint_velocities(StepContext& w, bool keep, int64_t first, int64_t last) {
    const JointRows& joints = w.joints;
    const BodyStates& s = w.bodies;
    for (int64_t k = first; k < last; ++k) {
        const int64_t j = joints.order[k];
        const int bodies[2] = {joints.body_a[j], joints.body_b[j]};
        for (const int i : bodies) {
            if (i == WORLD_BODY || w.model.motion[i] != DYNAMIC) {
                continue;
            }
            Vec3* saved = &joints.saved[3 * static_cast<int64_t>(i)];
            if (keep) {
                saved[0] = s.velocity[i];
                saved[1] = s.angular_momentum[i];
                saved[2] = s.angular_velocity[i];
            } else {
                s.velocity[i] = saved[0];
                s.angular_momentum[i] = saved[1];
                s.angular_velocity[i] = saved[2];
            }
        }
    }
}

// Pre-stabilisation of the joints order[first, last): one component, awake (see below).
void stabilize_component(StepContext& w, double dt, int64_t first, int64_t last) {
    const JointRows& joints = w.joints;
    for (int pass = 0; pass < w.settings->joint_passes; ++pass) {
        const int64_t count = predicted_system(w, dt, true, first, last);
        const double error = largest_error(joints, count, dt);
        if (!(error > POSITION_TOLERANCE)) {
            break;
        }
        for (int64_t p = 0; p < count; ++p) {
            joints.rhs[p] = joints.target[p];
        }
        solve_system(w, {joints.along.data, count}, count, false);
        // a Newton step that does not lower the error is halved (backtracking), up to
        // NEWTON_HALVINGS times; then the error is left to the next step
        keep_joint_velocities(w, true, first, last);
        double fraction = 1.0;
        bool lowered = false;
        for (int halving = 0; halving <= NEWTON_HALVINGS && !lowered; ++halving) {
            for (int64_t p = 0; p < count; ++p) {
                apply_row(w, joints, joints.rows[p], joints.row_joint[p],
                          fraction * joints.lambda[p]);
            }
            const int64_t rows = predicted_system(w, dt, false, first, last);
            lowered = largest_error(joints, rows, dt) < error;
            if (!lowered) {
                keep_joint_velocities(w, false, first, last);
                fraction *= 0.5;
            }
        }
        if (!lowered) {
            break;
        }
    }
}

// Call fn(first, last) for each component of joints (rows [first, last) of joints.order)
// whose bodies are awake, in component order.
template <class Fn>
void for_awake_components(const StepContext& w, Fn&& fn) {
    const JointRows& joints = w.joints;
    for (int64_t c = 0; c + 1 < joints.component_start.size; ++c) {
        const int64_t first = joints.component_start[c], last = joints.component_start[c + 1];
        if (!asleep(w, joints.order[first])) {
            fn(first, last);
        }
    }
}

}  // namespace

void count_joints_of_bodies(StepContext& w) {
    const JointRows& joints = w.joints;
    for (int64_t j = 0; j < joints.size(); ++j) {
        w.pairs_of[joints.body_a[j]] += 1;
        const int b = joints.body_b[j];
        if (b != WORLD_BODY && w.model.motion[b] == DYNAMIC) {
            w.pairs_of[b] += 1;
        }
    }
}

int64_t drop_joined_pairs(const JointRows& joints, const PairLists& lists, int64_t count,
                          int64_t num_bodies) {
    const Span<const int64_t> keys = joints.joined_keys;
    int64_t kept = 0, at = 0;
    for (int64_t k = 0; k < count; ++k) {
        const int a = lists.pair_a[k], b = lists.pair_b[k];
        const int64_t key = static_cast<int64_t>(a) * num_bodies + b;
        while (at < keys.size && keys[at] < key) {
            at += 1;
        }
        if (at < keys.size && keys[at] == key) {
            continue;
        }
        lists.pair_a[kept] = a;
        lists.pair_b[kept] = b;
        kept += 1;
    }
    return kept;
}

void solve_joint_velocities(StepContext& w, double dt) {
    const JointRows& joints = w.joints;
    for (int64_t j = 0; j < joints.size(); ++j) {
        if (asleep(w, j)) {
            continue;  // it reports the last step's impulses, as stepping it would (sleep.h)
        }
        joints.impulse[j] = {0.0, 0.0, 0.0};
        joints.angular_impulse[j] = {0.0, 0.0, 0.0};
        for (int c = 0; c < 3; ++c) {
            joints.accumulated[3 * j + c] = 0.0;
        }
    }
    for_awake_components(w, [&](int64_t first, int64_t last) {
        solve_velocity_rows(w, dt, true, first, last);
    });
}

void project_joint_velocities(StepContext& w, double dt) {
    for_awake_components(w, [&](int64_t first, int64_t last) {
        solve_velocity_rows(w, dt, false, first, last);
    });
}

// Pre-stabilisation: Newton steps on the predicted poses over each awake component of joints
// at once, until every row's predicted error is below POSITION_TOLERANCE or joint_passes steps. The
// impulses act along the rows at the current poses: SHAKE's projection (Ryckaert, Ciccotti &
// Berendsen 1977), which with the velocity solve at the step's start makes RATTLE (Andersen
// 1983), symplectic: a pendulum's energy oscillates by O(dt^2) and does not drift. Impulses
// along the rows at the predicted poses instead (plain Newton there) bend the velocity by
// the step's turn every step: a pendulum released at 90 degrees lost a quarter of its energy
// in 12 s at dt = 1/240. The system is J(current) M^-1 J(current)^T, symmetric, so each step
// is a contraction while the bodies turn little in a step.
void stabilize_joint_positions(StepContext& w, double dt) {
    for_awake_components(w, [&](int64_t first, int64_t last) {
        stabilize_component(w, dt, first, last);
    });
}

void form_joint_mobility(StepContext& w, int64_t pairs) {
    const JointRows& joints = w.joints;
    count_pairs_of_bodies(w, pairs);
    for (int64_t c = 0; c + 1 < joints.component_start.size; ++c) {
        const int64_t first = joints.component_start[c], last = joints.component_start[c + 1];
        const int body = joints.body_a[joints.order[first]];
        if (!w.model.articulated[body] || w.pairs_of[body] == 0) {
            continue;
        }
        int count = 0;  // the component's joints all hold `body` (its a) to immovable bodies
        for (int64_t k = first; k < last; ++k) {
            const int64_t j = joints.order[k];
            Rows rows;
            build_rows(joints, j, frame_of(w, body, 0.0), frame_of(w, joints.body_b[j], 0.0),
                       rows);
            for (int p = 0; p < rows.count; ++p) {
                joints.rows[count++] = rows.row[p];
            }
        }
        form_mobility(w.model.inverse_mass[body], w.bodies.inverse_inertia[body],
                      joints.rows.data, count, w.bodies.mobility[body]);
    }
}

double joint_coordinate(const StepContext& w, int64_t j) {
    const Frame a = frame_of(w, w.joints.body_a[j], 0.0);
    const Frame b = frame_of(w, w.joints.body_b[j], 0.0);
    Rows rows;
    build_rows(w.joints, j, a, b, rows);
    return rows.coordinate;
}

}  // namespace rg
