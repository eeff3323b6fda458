// Which bodies sleep through a step, exactly (sleep.h).
#include "sleep.h"

#include <cmath>

namespace rg {

namespace {

// Body i's state in SNAPSHOT order: position, orientation (w, x, y, z), velocity, angular
// momentum, angular velocity, rotation (row-major). Written field by field: one straight
// copy, which the compiler turns into a few vector moves.
void read_state(const BodyStates& bodies, int i, Span<double> out) {
    const Vec3 p = bodies.position[i], v = bodies.velocity[i];
    const Vec3 l = bodies.angular_momentum[i], omega = bodies.angular_velocity[i];
    const Quat q = bodies.orientation[i];
    const Mat3& r = bodies.rotation[i];
    const double values[SNAPSHOT] = {p.x, p.y, p.z, q.w, q.x, q.y, q.z, v.x, v.y, v.z,
                                     l.x, l.y, l.z, omega.x, omega.y, omega.z,
                                     r.m[0][0], r.m[0][1], r.m[0][2], r.m[1][0], r.m[1][1],
                                     r.m[1][2], r.m[2][0], r.m[2][1], r.m[2][2]};
    for (int k = 0; k < SNAPSHOT; ++k) {
        out[k] = values[k];
    }
}

// Is body i's state bit for bit its snapshot? For doubles that are not NaN, equal with the
// same sign bit means the same bits (the sign of a zero counts); a NaN is never unchanged.
// Every entry is compared (no early exit): a branch per entry costs more than the compares.
bool unchanged(const BodyStates& bodies, int i, Span<const double> snapshot) {
    double now[SNAPSHOT];
    read_state(bodies, i, {now, SNAPSHOT});
    bool same = true;
    for (int k = 0; k < SNAPSHOT; ++k) {
        same &= now[k] == snapshot[k] && std::signbit(now[k]) == std::signbit(snapshot[k]);
    }
    return same;
}

// Body i is listed with body j.
void note_partner(Span<int64_t> partner, Span<const int32_t> motion, int i, int j) {
    partner[i] = partner[i] == NONE && motion[j] != DYNAMIC ? j : SEVERAL;
}

Span<const double> snapshot_of(const Rest& rest, int i) {
    const Span<double> row = rest.snapshot.sub(static_cast<int64_t>(i) * SNAPSHOT, SNAPSHOT);
    return {row.data, row.size};
}

}  // namespace

void mark_asleep(WorldStep& w, int64_t count) {
    const BodyStates& s = w.bodies;
    const Span<const int32_t> motion = w.model.motion;
    const Rest& rest = w.rest;
    const int n = w.num_bodies();
    for (int i = 0; i < n; ++i) {
        rest.partner[i] = NONE;
    }
    for (int64_t k = 0; k < count; ++k) {
        note_partner(rest.partner, motion, w.lists.pair_a[k], w.lists.pair_b[k]);
        note_partner(rest.partner, motion, w.lists.pair_b[k], w.lists.pair_a[k]);
    }
    for (int i = 0; i < n; ++i) {
        const int64_t p = rest.partner[i];
        rest.asleep[i] = 0;
        if (motion[i] != DYNAMIC || p < 0 || p != rest.previous_partner[i] ||
            w.attached.parent[i] >= 0) {
            continue;
        }
        const Vec3 f = s.force[i], t = s.torque[i];
        const bool pushed = f.x != 0.0 || t.x != 0.0 || f.y != 0.0 || t.y != 0.0 || f.z != 0.0 ||
                            t.z != 0.0;
        rest.asleep[i] = !pushed && unchanged(s, i, snapshot_of(rest, i)) &&
                         unchanged(s, static_cast<int>(p), snapshot_of(rest, static_cast<int>(p)));
    }
    for (int i = 0; i < n; ++i) {
        if (!rest.asleep[i]) {  // an asleep body's snapshot is its state: just compared
            read_state(s, i, rest.snapshot.sub(static_cast<int64_t>(i) * SNAPSHOT, SNAPSHOT));
        }
        rest.previous_partner[i] = rest.partner[i];
    }
    const int64_t awake = move_asleep_last(w, count);
    for (int64_t k = awake; k < count; ++k) {
        const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
        w.pair_impulse[k] = rest.asleep[a] ? rest.impulse[a] : scale(-1.0, rest.impulse[b]);
    }
    *rest.awake_pairs = awake;
}

int64_t move_asleep_last(WorldStep& w, int64_t count) {
    const int64_t n = w.num_bodies();
    const Span<int64_t> spare = w.lists.keys;
    int64_t awake = 0, sleeping = 0;
    for (int64_t k = 0; k < count; ++k) {
        const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
        if (w.rest.asleep[a] || w.rest.asleep[b]) {
            spare[sleeping++] = a * n + b;
        } else {
            w.lists.pair_a[awake] = a;
            w.lists.pair_b[awake] = b;
            awake += 1;
        }
    }
    for (int64_t k = 0; k < sleeping; ++k) {
        w.lists.pair_a[awake + k] = static_cast<int32_t>(spare[k] / n);
        w.lists.pair_b[awake + k] = static_cast<int32_t>(spare[k] % n);
    }
    return awake;
}

void keep_rest_impulses(WorldStep& w) {
    const Rest& rest = w.rest;
    for (int64_t k = 0; k < *w.pair_count; ++k) {
        const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
        if (rest.partner[a] == b) {
            rest.impulse[a] = w.pair_impulse[k];
        }
        if (rest.partner[b] == a) {
            rest.impulse[b] = scale(-1.0, w.pair_impulse[k]);
        }
    }
}

void wake_world(WorldStep& w, int64_t count) {
    for (int i = 0; i < w.num_bodies(); ++i) {
        w.rest.asleep[i] = 0;
        w.rest.previous_partner[i] = SEVERAL;
    }
    *w.rest.awake_pairs = count;
}

}  // namespace rg
