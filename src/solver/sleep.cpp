// Which bodies sleep through a step, exactly (sleep.h).
#include "solver/sleep.h"

#include <algorithm>
#include <cstring>

namespace rg {

namespace {

// Calls visit(field) for body i's state in SNAPSHOT order: position, orientation (w, x, y,
// z), velocity, angular momentum, angular velocity, rotation (row-major). Each field is a
// plain struct of doubles, taken as its bytes.
template <class Visit>
void visit_state(const BodyStates& bodies, int i, Visit&& visit) {
    static_assert(sizeof(Vec3) == 3 * sizeof(double) && sizeof(Quat) == 4 * sizeof(double) &&
                  sizeof(Mat3) == 9 * sizeof(double));
    static_assert(3 + 4 + 3 + 3 + 3 + 9 == SNAPSHOT);
    visit(bodies.position[i]);
    visit(bodies.orientation[i]);
    visit(bodies.velocity[i]);
    visit(bodies.angular_momentum[i]);
    visit(bodies.angular_velocity[i]);
    visit(bodies.rotation[i]);
}

void read_state(const BodyStates& bodies, int i, Span<double> out) {
    RG_CHECK(out.size == SNAPSHOT);
    int64_t at = 0;
    visit_state(bodies, i, [&](const auto& field) {
        std::memcpy(out.data + at, &field, sizeof field);
        at += sizeof field / sizeof(double);
    });
}

// Is body i's state bit for bit its snapshot (the sign of a zero counts)? A NaN is never
// unchanged. Every entry is compared (no early exit): a branch per entry costs more than the
// compares, and the bits' differences OR-ed together, and the NaN test made on the bits
// too, are a few vector operations. Each field is compared where it stands: this
// comparison is what an asleep body costs a step.
bool unchanged(const BodyStates& bodies, int i, Span<const double> snapshot) {
    constexpr uint64_t MAGNITUDE = 0x7fffffffffffffffu, INFINITE = 0x7ff0000000000000u;
    RG_CHECK(snapshot.size == SNAPSHOT);
    uint64_t differ = 0;
    bool nan = false;
    int64_t at = 0;
    visit_state(bodies, i, [&](const auto& field) {
        constexpr int64_t count = sizeof field / sizeof(double);
        const char* bytes = reinterpret_cast<const char*>(&field);
        for (int64_t k = 0; k < count; ++k) {
            uint64_t now, was;
            std::memcpy(&now, bytes + k * sizeof(double), sizeof now);
            std::memcpy(&was, snapshot.data + at + k, sizeof was);
            differ |= now ^ was;
            nan |= (now & MAGNITUDE) > INFINITE;
        }
        at += count;
    });
    return differ == 0 && !nan;
}

// Does a force or torque act on body i in this step? (-0.0 counts as none, as for the sum.)
bool pushed(const BodyStates& bodies, int i) {
    const Vec3 f = bodies.force[i], t = bodies.torque[i];
    return f.x != 0.0 || t.x != 0.0 || f.y != 0.0 || t.y != 0.0 || f.z != 0.0 || t.z != 0.0;
}

// Each dynamic body's time below Settings::sleep_speed (|V| + |omega| reach, the fastest any
// of its points can move) after a step of dt s, counted from zero again in an island that
// was disturbed (rest.slow clear).
void count_slow_time(StepContext& w, double dt) {
    const BodyStates& s = w.bodies;
    const Rest& rest = w.rest;
    const double sleep_speed = w.settings->sleep_speed;
    for (int i = 0; i < w.num_bodies(); ++i) {
        if (w.model.motion[i] == DYNAMIC) {
            const double speed =
                length(s.velocity[i]) + length(s.angular_velocity[i]) * w.body_reach[i];
            rest.slow_time[i] =
                rest.slow[rest.island[i]] && speed < sleep_speed ? rest.slow_time[i] + dt : 0.0;
        }
    }
}

// Is body i as it was at the start of the last step: its snapshot a fixed point's (not
// stale) and its state that snapshot bit for bit?
bool same_as_last_start(const StepContext& w, int i) {
    const Span<double> row = w.rest.snapshot.sub(static_cast<int64_t>(i) * SNAPSHOT, SNAPSHOT);
    return !w.rest.stale[i] && unchanged(w.bodies, i, {row.data, row.size});
}

// The root of body i's island in the union-find forest rest.island, halving the path.
int64_t root_of(Span<int64_t> parent, int64_t i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

// rest.island: each dynamic body's island, named by its least body index (-1 for static and
// kinematic bodies); rest.bodies and rest.pairs counted per island. The names do not depend
// on the order of the unions, so an island of the last step whose bodies are all kept
// (rest.intact) starts joined under its name: its pairs among themselves are the last step's,
// which joined them then, and only pairs with a body not kept are joined again.
void find_islands(StepContext& w, int64_t count) {
    const Rest& rest = w.rest;
    const Span<const int32_t> motion = w.model.motion;
    const int n = w.num_bodies();
    for (int i = 0; i < n; ++i) {
        rest.intact[i] = 1;
    }
    for (int i = 0; i < n; ++i) {
        if (motion[i] == DYNAMIC && !rest.kept[i] && rest.previous_island[i] >= 0) {
            rest.intact[rest.previous_island[i]] = 0;
        }
    }
    const auto joined = [&](int i) { return rest.kept[i] && rest.intact[rest.previous_island[i]]; };
    for (int i = 0; i < n; ++i) {
        rest.island[i] = motion[i] != DYNAMIC ? -1 : joined(i) ? rest.previous_island[i] : i;
        rest.bodies[i] = 0;
        rest.pairs[i] = 0;
    }
    for (int64_t k = 0; k < count; ++k) {  // a is dynamic (broad_phase.h)
        const int b = w.lists.pair_b[k];
        if (motion[b] == DYNAMIC && !(joined(w.lists.pair_a[k]) && joined(b))) {
            const int64_t ra = root_of(rest.island, w.lists.pair_a[k]);
            const int64_t rb = root_of(rest.island, b);
            rest.island[std::max(ra, rb)] = std::min(ra, rb);
        }
    }
    const JointRows& joints = w.joints;  // a joint of two dynamic bodies joins them for good
    for (int64_t j = 0; j < joints.size(); ++j) {
        const int b = joints.body_b[j];
        if (b >= 0 && motion[b] == DYNAMIC) {
            const int64_t ra = root_of(rest.island, joints.body_a[j]);
            const int64_t rb = root_of(rest.island, b);
            rest.island[std::max(ra, rb)] = std::min(ra, rb);
        }
    }
    for (int i = 0; i < n; ++i) {
        if (motion[i] == DYNAMIC) {
            rest.island[i] = root_of(rest.island, i);
            rest.bodies[rest.island[i]] += 1;
        }
    }
    // pairs are listed by a, so runs of them share an island: counted in a register, the
    // counts do not wait on each other's stores
    int64_t island = -1, run = 0;
    for (int64_t k = 0; k < count; ++k) {
        const int64_t r = rest.island[w.lists.pair_a[k]];
        if (r != island) {
            if (run > 0) {
                rest.pairs[island] += run;
            }
            island = r;
            run = 0;
        }
        run += 1;
    }
    if (run > 0) {
        rest.pairs[island] += run;
    }
}

// The impulses the asleep pairs [awake, count) transmitted in the last step. The last step's
// list is two runs sorted by key (a n + b), its awake pairs and its asleep ones
// (move_asleep_last keeps each in order), and an asleep island's pairs were all listed then;
// the asleep pairs are sorted by key too, so one walk through each run finds them all.
void carry_impulses(StepContext& w, int64_t awake, int64_t count) {
    const Rest& rest = w.rest;
    const int64_t n = w.num_bodies();
    int64_t at[2] = {0, *rest.previous_awake};
    const int64_t end[2] = {*rest.previous_awake, *rest.previous_count};
    for (int64_t k = awake; k < count; ++k) {
        const int64_t key = static_cast<int64_t>(w.lists.pair_a[k]) * n + w.lists.pair_b[k];
        if (at[1] < end[1] && rest.previous_keys[at[1]] == key) {
            // most asleep pairs were asleep in the last step too: next in its asleep run
            w.pair_impulse[k] = rest.previous_impulse[at[1]++];
            continue;
        }
        Vec3 impulse = {0.0, 0.0, 0.0};  // not found: not reached, an island with a new pair is awake
        for (int r = 0; r < 2; ++r) {
            while (at[r] < end[r] && rest.previous_keys[at[r]] < key) {
                at[r] += 1;
            }
            if (at[r] < end[r] && rest.previous_keys[at[r]] == key) {
                impulse = rest.previous_impulse[at[r]];
                break;
            }
        }
        w.pair_impulse[k] = impulse;
    }
}

// With Settings::sleep_speed: each dynamic body's time below it counted (count_slow_time);
// an undisturbed island whose every body has been that slow for SLEEP_TIME is stopped, its
// velocities zeroed, and sleeps (rest.slow stays set only for those, and for the exact fixed
// points of rest.resting).
void stop_slow_islands(StepContext& w, double dt) {
    const BodyStates& s = w.bodies;
    const Span<const int32_t> motion = w.model.motion;
    const Rest& rest = w.rest;
    const int n = w.num_bodies();
    count_slow_time(w, dt);
    for (int i = 0; i < n; ++i) {
        if (motion[i] == DYNAMIC && rest.slow_time[i] < SLEEP_TIME) {
            rest.slow[rest.island[i]] = 0;
        }
    }
    for (int i = 0; i < n; ++i) {
        const int64_t r = rest.island[i];
        if (motion[i] != DYNAMIC) {
            continue;
        }
        if (rest.resting[r]) {
            rest.slow[r] = 1;
        } else if (rest.slow[r]) {
            s.velocity[i] = {0.0, 0.0, 0.0};
            s.angular_momentum[i] = {0.0, 0.0, 0.0};
            s.angular_velocity[i] = {0.0, 0.0, 0.0};
        }
    }
}

}  // namespace

void mark_kept(StepContext& w, double dt) {
    const Span<const int32_t> motion = w.model.motion;
    const Rest& rest = w.rest;
    const bool same_dt = *rest.previous_dt == dt;
    for (int i = 0; i < w.num_bodies(); ++i) {
        const bool candidate =
            same_dt && (motion[i] != DYNAMIC ||
                        (rest.asleep[i] && rest.previous_island[i] >= 0 && rest.resting[rest.island[i]]));
        rest.kept[i] = candidate && same_as_last_start(w, i);
    }
}

void mark_asleep(StepContext& w, int64_t count, double dt) {
    const BodyStates& s = w.bodies;
    const Span<const int32_t> motion = w.model.motion;
    const Rest& rest = w.rest;
    const int n = w.num_bodies();
    const double sleep_speed = w.settings->sleep_speed;
    const bool same_dt = *rest.previous_dt == dt;  // another dt is another step: none rests
    find_islands(w, count);
    // rest.slow: not disturbed (the same bodies and as many pairs as in the last step, no
    // force, no attachment, its static and kinematic partners unchanged); rest.resting: and
    // every body unchanged too, at the same dt (rest.kept: known unchanged)
    for (int i = 0; i < n; ++i) {
        rest.slow[i] = motion[i] == DYNAMIC && rest.island[i] == i &&
                       rest.bodies[i] == rest.previous_bodies[i] &&
                       rest.pairs[i] == rest.previous_pairs[i];
        rest.resting[i] = rest.slow[i] && same_dt;
    }
    for (int i = 0; i < n; ++i) {
        if (motion[i] != DYNAMIC) {
            continue;
        }
        const int64_t r = rest.island[i];
        if (rest.previous_island[i] != r || w.attached.parent[i] >= 0 || pushed(s, i)) {
            rest.slow[r] = 0;
        }
        if (rest.resting[r] && !rest.kept[i] && !same_as_last_start(w, i)) {
            rest.resting[r] = 0;
        }
    }
    // an island touching a static or kinematic body that changed is disturbed; most steps
    // none changed (each one kept is unchanged), and the pairs need no walk
    bool partner_changed = false;
    for (int i = 0; i < n; ++i) {
        partner_changed =
            partner_changed || (motion[i] != DYNAMIC && !rest.kept[i] && !same_as_last_start(w, i));
    }
    for (int64_t k = 0; partner_changed && k < count; ++k) {
        const int b = w.lists.pair_b[k];
        const int64_t r = rest.island[w.lists.pair_a[k]];
        if (rest.slow[r] && motion[b] != DYNAMIC && !rest.kept[b] && !same_as_last_start(w, b)) {
            rest.slow[r] = 0;
        }
    }
    // so is an island jointed to one that changed (a joint held by a moving kinematic body)
    for (int64_t j = 0; partner_changed && j < w.joints.size(); ++j) {
        const int b = w.joints.body_b[j];
        const int64_t r = rest.island[w.joints.body_a[j]];
        if (b >= 0 && rest.slow[r] && motion[b] != DYNAMIC && !rest.kept[b] &&
            !same_as_last_start(w, b)) {
            rest.slow[r] = 0;
        }
    }
    for (int i = 0; i < n; ++i) {
        if (motion[i] == DYNAMIC) {
            rest.resting[rest.island[i]] &= rest.slow[rest.island[i]];
        }
    }
    if (sleep_speed > 0.0) {
        stop_slow_islands(w, dt);
    } else {
        for (int i = 0; i < n; ++i) {
            rest.slow[i] = rest.resting[i];
        }
    }
    bool all_asleep = true;
    for (int i = 0; i < n; ++i) {
        rest.asleep[i] = motion[i] == DYNAMIC && rest.slow[rest.island[i]];
        all_asleep &= motion[i] != DYNAMIC || rest.asleep[i];
        if (motion[i] != DYNAMIC || !rest.resting[rest.island[i]]) {
            // a fixed point's snapshot is its state, just compared; a stopped body's is new
            const Span<double> row = rest.snapshot.sub(static_cast<int64_t>(i) * SNAPSHOT, SNAPSHOT);
            read_state(s, i, row);
            // this step is not the next one's: a force that holds a body still makes no fixed
            // point once it stops, nor does a holder once the body is let go (even by a write
            // to the attachments). A stale snapshot is never unchanged, so the island wakes
            rest.stale[i] = pushed(s, i) || w.attached.parent[i] >= 0;
        }
        rest.previous_island[i] = rest.island[i];
        rest.previous_bodies[i] = rest.bodies[i];
        rest.previous_pairs[i] = rest.pairs[i];
    }
    const int64_t awake = move_asleep_last(w, count);
    carry_impulses(w, awake, count);
    *rest.awake_pairs = awake;
    *rest.at_rest = all_asleep;
    *rest.previous_dt = dt;
}

bool still_at_rest(StepContext& w, double dt) {
    const Rest& rest = w.rest;
    if (!*rest.at_rest || *rest.previous_dt != dt) {
        return false;
    }
    bool same = true;
    for (int i = 0; i < w.num_bodies(); ++i) {
        same &= same_as_last_start(w, i) && !pushed(w.bodies, i);
    }
    if (same && w.settings->sleep_speed > 0.0) {
        count_slow_time(w, dt);  // every island undisturbed: rest.slow is still set for each
    }
    return same;
}

int64_t move_asleep_last(StepContext& w, int64_t count) {
    // the asleep pairs wait in the spare keys as a << 32 | b: decoded by a shift and a mask,
    // not by two 64-bit divisions a pair (most of this partition's time)
    const Span<int64_t> spare = w.lists.keys;
    int64_t awake = 0, sleeping = 0;
    for (int64_t k = 0; k < count; ++k) {
        const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
        if (w.rest.asleep[a] || w.rest.asleep[b]) {
            spare[sleeping++] = static_cast<int64_t>(static_cast<uint64_t>(a) << 32 | static_cast<uint32_t>(b));
        } else {
            w.lists.pair_a[awake] = a;
            w.lists.pair_b[awake] = b;
            awake += 1;
        }
    }
    for (int64_t k = 0; k < sleeping; ++k) {
        const uint64_t packed = static_cast<uint64_t>(spare[k]);
        w.lists.pair_a[awake + k] = static_cast<int32_t>(packed >> 32);
        w.lists.pair_b[awake + k] = static_cast<int32_t>(packed & 0xffffffffu);
    }
    return awake;
}

void keep_pair_impulses(StepContext& w) {
    const Rest& rest = w.rest;
    const int64_t n = w.num_bodies();
    for (int64_t k = 0; k < *w.pair_count; ++k) {
        rest.previous_keys[k] = static_cast<int64_t>(w.lists.pair_a[k]) * n + w.lists.pair_b[k];
        rest.previous_impulse[k] = w.pair_impulse[k];
    }
    *rest.previous_count = *w.pair_count;
    *rest.previous_awake = *rest.awake_pairs;
}

void forget_moved(StepContext& w) {
    const Rest& rest = w.rest;
    for (int i = 0; i < w.num_bodies(); ++i) {
        if (w.model.motion[i] == DYNAMIC && !rest.asleep[i] && !same_as_last_start(w, i)) {
            rest.stale[i] = 1;
        }
    }
}

void wake_world(StepContext& w, int64_t count) {
    for (int i = 0; i < w.num_bodies(); ++i) {
        w.rest.asleep[i] = 0;
        w.rest.previous_island[i] = -1;
    }
    *w.rest.awake_pairs = count;
    *w.rest.at_rest = 0;
}

}  // namespace rg
