// The step's stages in order (step.h).
#include "solver/step.h"

#include <algorithm>
#include <vector>

#include "solver/contacts.h"
#include "solver/integrate.h"
#include "solver/overlap.h"
#include "solver/sleep.h"
#include "solver/solver.h"
#include "base/thread_pool.h"

namespace rg {

namespace {

// Times a step's impulse stages may run again with the pairs of the bodies' grown reach.
constexpr int MAX_RELISTS = 4;

// The world's pairs for its current poses and velocities, boxes grown by at least the
// reach recorded so far; returns how many. acceleration: m/s^2 the bodies may gain (gravity).
// carried: pairs among the bodies of rest.kept taken from the last step's list (sleep.h):
// from its asleep pairs, in (a, b) order, which hold every pair of a kept dynamic body (it
// slept) and no pair of two static or kinematic ones (never listed).
int64_t list_pairs(WorldStep& w, double dt, double acceleration, bool carried) {
    const int64_t asleep = *w.rest.previous_awake;
    const Carried known = {{w.rest.kept.data, w.rest.kept.size},
                           {w.rest.previous_keys.data + asleep, *w.rest.previous_count - asleep}};
    return find_world_pairs(*w.geo, w.model.motion, w.bodies, 0.0, dt, acceleration,
                            w.settings->sweep, w.lists, carried ? known : Carried{});
}

// Copy every body's velocity, angular momentum and angular velocity into w.start (keep), or
// back from it.
void keep_velocities(WorldStep& w, bool keep) {
    const int64_t n = w.num_bodies();
    const BodyStates& s = w.bodies;
    for (int64_t i = 0; i < n; ++i) {
        if (keep) {
            w.start[i] = s.velocity[i];
            w.start[n + i] = s.angular_momentum[i];
            w.start[2 * n + i] = s.angular_velocity[i];
        } else {
            s.velocity[i] = w.start[i];
            s.angular_momentum[i] = w.start[n + i];
            s.angular_velocity[i] = w.start[2 * n + i];
        }
    }
}

// The bodies asleep in this step (rest.asleep), or none without sleeping.
Span<const uint8_t> asleep_bodies(const WorldStep& w) {
    return w.settings->sleep ? Span<const uint8_t>{w.rest.asleep.data, w.rest.asleep.size}
                             : Span<const uint8_t>{};
}

// True when some body, at its current velocity, moves further in dt than its box was grown.
// Called before the position update, which moves a body by its current velocities: no
// acceleration term (the broad phase's bounds the velocity update's gravity). An asleep body
// keeps the velocities it started the step with, which its box was grown for.
bool outgrown(const WorldStep& w, double dt) {
    const bool sleeping = w.settings->sleep;
    for (int i = 0; i < w.num_bodies(); ++i) {
        if (w.geo->body_unbounded[i] == 0 && !(sleeping && w.rest.asleep[i]) &&
            swept_margin(*w.geo, i, w.bodies.velocity[i], w.bodies.angular_velocity[i], 0.0, dt,
                         0.0) > w.lists.reach[i]) {
            return true;
        }
    }
    return false;
}

void clear_impulses(WorldStep& w, int64_t count) {
    for (int64_t k = 0; k < count; ++k) {
        w.pair_impulse[k] = {0.0, 0.0, 0.0};  // Coulomb's limit applies to the step's total
    }
}

// The step's contacts, found by the first impulse stage that needs them (contacts.h), at
// the poses it predicts: the collision stage's (old velocities, dt^2 g ahead) or the contact
// and shock stages' (new velocities), which are the same poses until an impulse or a force
// acts. Found once per step (the broad phase clears the flag).
void find_contacts(WorldStep& w, int64_t count, double dt, Vec3 lookahead) {
    if (!*w.contacts.detected) {
        detect_contacts(w, count, dt, lookahead);
    }
}

// The collision, velocity update, contact and shock stages over the first `count` listed
// pairs (the awake ones, with sleeping), each counted and timed (timers.h) from `since` on;
// returns where the next stage starts. A stage with nothing to do (no pair, or switched off)
// is not run.
double impulse_stages(WorldStep& w, double dt, int64_t count, double since) {
    const Settings& c = *w.settings;
    if (c.collision_passes > 0 && count > 0) {
        find_contacts(w, count, dt, collision_lookahead(w.model, dt));
        resolve_world_contacts(w, count, dt, COLLISION, c.collision_passes);
        since = lap(w.timers, COLLISION_STAGE, since);
    }
    update_velocities(w.bodies, w.model, dt, asleep_bodies(w));
    since = lap(w.timers, VELOCITY_STAGE, since);
    if (c.contact_passes > 0 && count > 0) {
        find_contacts(w, count, dt, {0.0, 0.0, 0.0});
        resolve_world_contacts(w, count, dt, CONTACT, c.contact_passes);
        since = lap(w.timers, CONTACT_STAGE, since);
    }
    if (c.shock_sweeps > 0 && c.gravity > 0.0 && count > 0) {
        find_contacts(w, count, dt, {0.0, 0.0, 0.0});
        propagate_world_shock(w, count, dt);
        since = lap(w.timers, SHOCK_STAGE, since);
    }
    return since;
}

// After impulse stages whose contacts overflowed the pool: put the velocities back as the
// stages found them (the impulse stages change nothing else of the bodies) and wake the
// world, whose sleeping bookkeeping has taken this step in (sleep.h: waking changes no bit).
// The step is then run again whole, once the pool has grown.
bool abandoned_for_rows(WorldStep& w) {
    if (!pool_overflowed(w)) {
        return false;
    }
    keep_velocities(w, false);
    wake_world(w, *w.pair_count);
    return true;
}

}  // namespace

// The broad phase lists the pairs that can touch if every body keeps its speed through the
// step (swept_margin), but the impulse stages may speed a body up: a resting box struck by
// another. Before the position update, a body whose new velocity reaches past its box grows
// its box; if that lists more pairs, the velocities are put back as they were when the
// impulse stages began and the stages run again with every pair (up to MAX_RELISTS times),
// so a body is not moved into a neighbour whose pair was never listed. Nothing sleeps then.
// Each stage counts its runs in the world's timers and, when timed, its time (timers.h): a
// relisting's time is the broad phase's (not counted as a run: the broad phase runs once per
// step), the stages run again count as runs of their own.
int64_t step_world(WorldStep& w, int64_t steps, double dt) {
    const Settings& c = *w.settings;
    const int64_t capacity = w.pair_capacity();
    double since = start_timing(w.timers);
    for (int64_t done = 0; done < steps; ++done) {
        if (c.sleep && still_at_rest(w, dt)) {  // nothing to do (sleep.h); not a stage's run
            since = lap(w.timers, BROAD_STAGE, since, 0);
            continue;
        }
        // 0. broad phase: every pair whose boxes may meet within this step (velocities
        //    included); held bodies are put at their place first. Counted as a run only when
        //    it lists pairs (SolverConfig.phases)
        //    A kept body (sleep.h) keeps its inverse inertia, box and reach: it is as when
        //    they were computed
        place_attached(w.bodies, w.attached);
        if (c.sleep) {
            mark_kept(w, dt);
        }
        const Span<const uint8_t> kept =
            c.sleep ? Span<const uint8_t>{w.rest.kept.data, w.rest.kept.size} : Span<const uint8_t>{};
        refresh_inverse_inertia(w.bodies, w.model, kept);
        for (int i = 0; i < w.num_bodies(); ++i) {
            if (!(c.sleep && w.rest.kept[i])) {
                w.lists.reach[i] = 0.0;
            }
        }
        const int64_t count = c.broad_phase ? list_pairs(w, dt, c.gravity, c.sleep) : 0;
        *w.pair_count = count;
        if (count > capacity) {
            lap(w.timers, BROAD_STAGE, since, 0);  // run again once the buffers have grown
            return done;
        }
        clear_impulses(w, count);
        *w.contacts.detected = 0;
        *w.rest.awake_pairs = count;
        if (c.sleep) {
            mark_asleep(w, count, dt);  // may stop slow islands: before the velocities are kept
        }
        keep_velocities(w, true);
        since = lap(w.timers, BROAD_STAGE, since, c.broad_phase ? 1 : 0);
        // 1-4. collision, velocity update, contact, shock propagation
        since = impulse_stages(w, dt, *w.rest.awake_pairs, since);
        if (abandoned_for_rows(w)) {
            return done;
        }
        // 5. position update with the final velocities
        if (c.broad_phase) {
            for (int relist = 0; relist < MAX_RELISTS && outgrown(w, dt); ++relist) {
                since = lap(w.timers, POSITION_STAGE, since, 0);
                const int64_t listed = *w.pair_count;
                const int64_t more = list_pairs(w, dt, 0.0, false);  // the final velocities
                if (more == listed) {  // boxes only grow: the same count is the same pairs
                    if (c.sleep) {     // in the order the impulses were recorded in
                        move_asleep_last(w, listed);
                    }
                    since = lap(w.timers, BROAD_STAGE, since, 0);
                    break;
                }
                *w.pair_count = more;
                keep_velocities(w, false);
                wake_world(w, more);
                if (more > capacity) {
                    lap(w.timers, BROAD_STAGE, since, 0);
                    return done;
                }
                clear_impulses(w, more);
                *w.contacts.detected = 0;
                since = lap(w.timers, BROAD_STAGE, since, 0);
                since = impulse_stages(w, dt, more, since);
                if (abandoned_for_rows(w)) {
                    return done;
                }
            }
        }
        if (c.sleep) {
            keep_pair_impulses(w);
        }
        if (c.overlap_correction > 0.0 && *w.contacts.detected) {
            correct_overlap(w, *w.rest.awake_pairs, dt, c.overlap_correction);
        }
        // the asleep pairs' bodies are asleep or not dynamic: the position update reads no
        // count of theirs
        count_acting_pairs_of_bodies(w, *w.rest.awake_pairs);
        update_positions(w.bodies, w.model, dt, c.rotation_order, c.keep_energy,
                         {w.pairs_of.data, w.pairs_of.size},
                         asleep_bodies(w));
        for (int i = 0; i < w.num_bodies(); ++i) {
            w.bodies.force[i] = {0.0, 0.0, 0.0};
            w.bodies.torque[i] = {0.0, 0.0, 0.0};
        }
        if (c.sleep) {
            forget_moved(w);
        }
        since = lap(w.timers, POSITION_STAGE, since);
    }
    place_attached(w.bodies, w.attached);
    lap(w.timers, POSITION_STAGE, since, 0);
    return steps;
}

void advance(StepContext& context, int64_t steps, double dt) {
    const int num_worlds = context.num_worlds();
    std::vector<int64_t> done(num_worlds, 0);
    ThreadPool& pool = ThreadPool::instance();
    const bool choice = num_worlds > 1 && pool.size() > 1;  // sharing.h
    const bool shared = choice && context.sharing.share();
    const double start = choice ? clock_seconds() : 0.0;
    while (true) {
        const int ranges = shared ? std::min(num_worlds, pool.size()) : 1;
        pool.run(ranges, [&](int range) {
            const int first = static_cast<int>(static_cast<int64_t>(num_worlds) * range / ranges);
            const int last = static_cast<int>(static_cast<int64_t>(num_worlds) * (range + 1) / ranges);
            for (int w = first; w < last; ++w) {
                if (done[w] < steps) {
                    WorldStep rows = context.world(w);
                    done[w] += step_world(rows, steps - done[w], dt);
                }
            }
        });
        context.fit_contact_rows();  // the contact pool may grow for the next steps
        if (std::all_of(done.begin(), done.end(), [&](int64_t d) { return d == steps; })) {
            if (choice) {
                context.sharing.record(shared, clock_seconds() - start, num_worlds * steps);
            }
            return;
        }
        int64_t needed = 0;
        for (int w = 0; w < num_worlds; ++w) {
            needed = std::max(needed, context.pair_count[w]);
        }
        context.grow_pairs(needed);  // an overflowed step was abandoned: it runs again whole
    }
}

}  // namespace rg
