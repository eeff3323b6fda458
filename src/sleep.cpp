// Which bodies sleep through a step, exactly (sleep.h).
#include "sleep.h"

#include <cmath>

namespace rg {

namespace {

// Float k of body i's state, in SNAPSHOT order.
double body_state(const BodyStates& bodies, int i, int k) {
    if (k < 3) {
        return bodies.position[i][k];
    }
    if (k < 7) {
        const Quat q = bodies.orientation[i];
        const int c = k - 3;
        return c == 0 ? q.w : (c == 1 ? q.x : (c == 2 ? q.y : q.z));
    }
    if (k < 10) {
        return bodies.velocity[i][k - 7];
    }
    if (k < 13) {
        return bodies.angular_momentum[i][k - 10];
    }
    if (k < 16) {
        return bodies.angular_velocity[i][k - 13];
    }
    return bodies.rotation[i].m[(k - 16) / 3][(k - 16) % 3];
}

// Is body i's state bit for bit its snapshot? (The sign of a zero counts; a NaN is never
// unchanged.)
bool unchanged(const BodyStates& bodies, int i, Span<const double> snapshot) {
    for (int k = 0; k < SNAPSHOT; ++k) {
        const double x = body_state(bodies, i, k);
        if (x != snapshot[k] || std::signbit(x) != std::signbit(snapshot[k])) {
            return false;
        }
    }
    return true;
}

// Body i is listed with body j.
void note_partner(Span<int64_t> partner, Span<const int32_t> motion, int i, int j) {
    partner[i] = partner[i] == NONE && motion[j] != DYNAMIC ? j : SEVERAL;
}

Span<const double> snapshot_of(const Rest& rest, int i) {
    return {rest.snapshot.data + static_cast<int64_t>(i) * SNAPSHOT, SNAPSHOT};
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
        for (int k = 0; k < SNAPSHOT; ++k) {
            rest.snapshot[static_cast<int64_t>(i) * SNAPSHOT + k] = body_state(s, i, k);
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
