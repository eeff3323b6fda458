// Detection once per step and the linearised separations (contacts.h).
#include "solver/contacts.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "solver/continuous.h"
#include "solver/integrate.h"

namespace rg {

namespace {

// Are a and b the same bits (unlike ==, which takes -0 for 0)?
template <typename T>
bool same_bits(const T& a, const T& b) {
    return std::memcmp(&a, &b, sizeof(T)) == 0;
}

// A pair is detected again once its bodies may have moved this far (m) since: beyond it a
// point outside the margin at detection could be within GRAPH_MARGIN now.
constexpr double REDETECT_DRIFT = SPECULATIVE_MARGIN - GRAPH_MARGIN;

// |x| + |y| + |z| >= the length of v, without a square root: the drift test runs for every
// pair in every pass.
double bound(Vec3 v) { return std::fabs(v.x) + std::fabs(v.y) + std::fabs(v.z); }

// Contacts whose normals agree this closely (cosine) share one normal: a face's points.
constexpr double SHARED_NORMAL = 1.0 - 1e-9;

// Dynamic body i's orientation after dt free of torque (integrate.h's turned): with
// Settings::exact_symmetric a symmetric body's exact motion, which its rotation update takes
// (a fast top predicted by omega dt was struck on the floor where its tip was not), else the
// turn by omega dt.
Quat predicted_orientation(const StepContext& w, int i, double dt) {
    if (!w.settings->exact_symmetric) {
        return rotate_by_angular_velocity(w.bodies.orientation[i], w.bodies.angular_velocity[i],
                                          dt);
    }
    return turned(w.bodies.orientation[i], w.bodies.rotation[i], w.bodies.angular_momentum[i],
                  w.bodies.angular_velocity[i], w.model.inverse_moments[i], dt);
}

// Body i's predicted displacement over dt (m) and turn (rad): what predict_pose applies (a
// symmetric body's turn: the rotation vector of its exact motion's). A symmetric body's turn
// costs an arctangent, a sine and a cosine, and every pass asks it again for each of the
// body's pairs, mostly unchanged: it is kept with what it was found from (the orientation,
// L and dt, in the step of the current detection, whose model it read) and reused, bit for
// bit, while they are the same (a fifth of a pile of 100's step).
Travel predicted_motion(const StepContext& w, int i, double dt, Vec3 lookahead) {
    const int32_t motion = w.model.motion[i];
    if (motion == STATIC) {
        return {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    }
    const Vec3 v = w.bodies.velocity[i];
    const Vec3 la = motion == DYNAMIC ? lookahead : Vec3{0.0, 0.0, 0.0};
    const Vec3 shift = {la.x + dt * v.x, la.y + dt * v.y, la.z + dt * v.z};
    if (motion == DYNAMIC && w.settings->exact_symmetric &&
        symmetry_axis(w.model.inverse_moments[i]) >= 0) {
        const ContactCache& c = w.contacts;
        const Quat q = w.bodies.orientation[i];
        const Vec3 l = w.bodies.angular_momentum[i];
        if (c.turned_at[i] != *c.detections || !same_bits(c.turn_from[i], q) ||
            !same_bits(c.turn_momentum[i], l) || !same_bits(c.turn_dt[i], dt)) {
            c.turn[i] = turn_between(q, predicted_orientation(w, i, dt));
            c.turn_from[i] = q;
            c.turn_momentum[i] = l;
            c.turn_dt[i] = dt;
            c.turned_at[i] = *c.detections;
        }
        return {shift, c.turn[i]};
    }
    return {shift, scale(dt, w.bodies.angular_velocity[i])};
}

// Body i's pose after dt at its current velocity; dynamic bodies also move by lookahead (m):
// the collision stage passes dt^2 g, so that a collision that gravity brings about within
// this step is seen (and bounced) there.
Pose predict_pose(const StepContext& w, int i, double dt, Vec3 lookahead) {
    Vec3 x = w.bodies.position[i];
    Quat q = w.bodies.orientation[i];
    const int32_t motion = w.model.motion[i];
    if (motion == DYNAMIC) {
        x = add(x, lookahead);
    }
    if (motion != STATIC) {
        const Vec3 v = w.bodies.velocity[i];
        x = {x.x + dt * v.x, x.y + dt * v.y, x.z + dt * v.z};
        q = motion == DYNAMIC ? predicted_orientation(w, i, dt)
                              : rotate_by_angular_velocity(q, w.bodies.angular_velocity[i], dt);
    }
    return {x, rotation_from_quaternion(q)};
}

// Body i's pose predicted for detect_contacts, found once for all its pairs: a body is in
// several, and its pose costs a turn by its angular velocity (a sine and a cosine) and the
// rotation matrix of the result.
const Pose& detection_pose(StepContext& w, int i, double dt, Vec3 lookahead) {
    const ContactCache& c = w.contacts;
    if (c.posed[i] != *c.detections) {
        c.pose[i] = predict_pose(w, i, dt, lookahead);
        c.posed[i] = *c.detections;
    }
    return c.pose[i];
}

// Detect pair k, its bodies predicted at poses pa and pb, into the pool's free rows; false
// when they do not fit (the pair is then detected in every pass for the rest of the step,
// which is run again: pool_overflowed).
bool detect_pair(StepContext& w, int64_t k, const Pose& pa, const Pose& pb, double dt, Vec3 lookahead) {
    ContactCache& c = w.contacts;
    const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
    const int64_t first = *c.used;
    const Travel ma = predicted_motion(w, a, dt, lookahead), mb = predicted_motion(w, b, dt, lookahead);
    Vec3 centre_a, centre_b;
    const int64_t found = collide_swept(w, a, b, pa, pb, ma, mb, SPECULATIVE_MARGIN,
                                        {c.point, c.normal, c.depth}, first, centre_a, centre_b);
    *c.needed += found;
    if (first + found > c.depth.size) {
        c.first[k] = -1;
        return false;
    }
    *c.used = first + found;
    c.first[k] = first;
    c.count[k] = found;
    c.memo[k].members = 0;  // new contacts: a new patch
    c.centre_a[k] = centre_a;
    c.centre_b[k] = centre_b;
    c.shift_a[k] = ma.shift;
    c.turn_a[k] = ma.turn;
    c.shift_b[k] = mb.shift;
    c.turn_b[k] = mb.turn;
    for (int64_t r = first; r < first + found; ++r) {
        c.arm_a[r] = cross(sub(c.point[r], centre_a), c.normal[r]);
        c.arm_b[r] = cross(sub(c.point[r], centre_b), c.normal[r]);
    }
    return true;
}

// The narrow phase at the current prediction straight into set (Settings::detect_every_pass,
// or a pair the pool could not hold in a step that will be run again), contacts deeper than
// `threshold`.
int64_t collide_now(StepContext& w, const Gather& g, double dt, Vec3 lookahead, const ContactSet& set,
                    int64_t at) {
    const int a = w.lists.pair_a[g.k], b = w.lists.pair_b[g.k];
    const Pose pa = predict_pose(w, a, dt, lookahead), pb = predict_pose(w, b, dt, lookahead);
    Vec3 centre_a, centre_b;
    const int64_t found = collide_swept(w, a, b, pa, pb, predicted_motion(w, a, dt, lookahead),
                                        predicted_motion(w, b, dt, lookahead), -g.threshold,
                                        set.buffer(), at, centre_a, centre_b);
    const bool is_a = g.body == a;
    const double sign = is_a ? 1.0 : -1.0;
    for (int64_t i = at; i < std::min(at + found, set.depth.size); ++i) {
        set.normal[i] = scale(sign, set.normal[i]);
        set.partner[i] = is_a ? b : a;
        set.source[i] = g.k;
        set.orient[i] = sign;
        set.centre_a[i] = is_a ? centre_a : centre_b;
        set.centre_b[i] = is_a ? centre_b : centre_a;
        set.row[i] = -1;
    }
    return found;
}

}  // namespace

void detect_contacts(StepContext& w, int64_t pairs, double dt, Vec3 lookahead) {
    *w.contacts.used = 0;
    *w.contacts.needed = 0;
    *w.contacts.detections += 1;
    for (int64_t k = 0; k < pairs; ++k) {
        if (w.settings->detect_every_pass) {
            w.contacts.first[k] = -1;
        } else {
            const Pose& pa = detection_pose(w, w.lists.pair_a[k], dt, lookahead);
            const Pose& pb = detection_pose(w, w.lists.pair_b[k], dt, lookahead);
            detect_pair(w, k, pa, pb, dt, lookahead);
        }
    }
    *w.contacts.detected = 1;
}

// The part of the bodies' change of predicted displacement since detection that the drift
// test counts (m): all of it, except along the normal of a pair with an articulated body whose
// contacts all share that normal (a finger's pad on a cube's face). A finger's motor pushes it
// F dt / m along its slide into the cube it presses (~15 mm a step), and the contact stage
// takes the push back: moving the contacts rigidly with the bodies along their normal keeps
// their points on the faces and changes their depths exactly, so the pair is not found again
// (and swept, continuous.h) at the pushed poses, and again once the push is undone.
double along_normal_exempt(const StepContext& w, int64_t k, int a, int b, Vec3 da, Vec3 db) {
    const ContactCache& c = w.contacts;
    const int64_t first = c.first[k];
    if ((!w.model.articulated[a] && !w.model.articulated[b]) || c.count[k] == 0) {
        return bound(da) + bound(db);
    }
    const Vec3 n = c.normal[first];
    for (int64_t r = first + 1; r < first + c.count[k]; ++r) {
        if (dot(c.normal[r], n) < SHARED_NORMAL) {
            return bound(da) + bound(db);
        }
    }
    return bound(sub(da, scale(dot(da, n), n))) + bound(sub(db, scale(dot(db, n), n)));
}

int64_t gather_pair(StepContext& w, const Gather& g, double dt, Vec3 lookahead,
                    const ContactSet& set, int64_t at) {
    ContactCache& c = w.contacts;
    const int a = w.lists.pair_a[g.k], b = w.lists.pair_b[g.k];
    if (c.first[g.k] < 0) {
        return collide_now(w, g, dt, lookahead, set, at);
    }
    const Travel ma = predicted_motion(w, a, dt, lookahead), mb = predicted_motion(w, b, dt, lookahead);
    Vec3 da = sub(ma.shift, c.shift_a[g.k]), ta = sub(ma.turn, c.turn_a[g.k]);
    Vec3 db = sub(mb.shift, c.shift_b[g.k]), tb = sub(mb.turn, c.turn_b[g.k]);
    const double drift = along_normal_exempt(w, g.k, a, b, da, db) + bound(ta) * w.body_reach[a] +
                         bound(tb) * w.body_reach[b];
    if (drift > REDETECT_DRIFT) {
        const Pose pa = predict_pose(w, a, dt, lookahead), pb = predict_pose(w, b, dt, lookahead);
        if (!detect_pair(w, g.k, pa, pb, dt, lookahead)) {
            return collide_now(w, g, dt, lookahead, set, at);
        }
        da = ta = db = tb = {0.0, 0.0, 0.0};
    }
    const bool is_a = g.body == a;
    const double sign = is_a ? 1.0 : -1.0;
    const Vec3 centre_body = is_a ? c.centre_a[g.k] : c.centre_b[g.k];
    const Vec3 centre_other = is_a ? c.centre_b[g.k] : c.centre_a[g.k];
    int64_t written = 0;
    const int64_t first = c.first[g.k];
    for (int64_t r = first; r < first + c.count[g.k]; ++r) {
        const Vec3 n = c.normal[r];
        const double depth =
            c.depth[r] - (dot(da, n) + dot(ta, c.arm_a[r]) - dot(db, n) - dot(tb, c.arm_b[r]));
        if (!(depth > g.threshold)) {
            continue;
        }
        const int64_t i = at + written++;
        if (i < set.depth.size) {
            set.point[i] = c.point[r];
            set.normal[i] = scale(sign, n);
            set.depth[i] = depth;
            set.partner[i] = is_a ? b : a;
            set.source[i] = g.k;
            set.orient[i] = sign;
            set.centre_a[i] = centre_body;
            set.centre_b[i] = centre_other;
            set.row[i] = r - first;
        }
    }
    return written;
}

int64_t contact_rows_needed(const StepContext& w) { return *w.contacts.needed; }

bool pool_overflowed(const StepContext& w) {
    return *w.contacts.detected && *w.contacts.needed > *w.contacts.used;
}

}  // namespace rg
