// The step's stages in order (step.h).
#include "solver/step.h"

#include <algorithm>
#include <vector>

#include "solver/contacts.h"
#include "solver/integrate.h"
#include "solver/joints.h"
#include "solver/overlap.h"
#include "solver/sleep.h"
#include "solver/solver.h"
#include "base/thread_pool.h"

namespace rg {

namespace {

// Times a step's impulse stages may run again with the pairs of the bodies' grown reach.
constexpr int MAX_RELISTS = 4;

// How a stage leaves the step: go on to the next stage, skip the rest of the step (nothing
// to do), or give the step up (a buffer was too small: run it again whole once grown).
enum Flow { NEXT, SKIP, GIVE_UP };

// Whether a stage switched on has work in this step: the impulse stages need awake pairs,
// overlap correction contacts found in the step.
bool has_work(const StepContext& w, Stage stage) {
    switch (stage) {
        case COLLISION_STAGE:
        case CONTACT_STAGE:
        case SHOCK_STAGE:
            return *w.rest.awake_pairs > 0;
        case OVERLAP_STAGE:
            return *w.contacts.detected != 0;
        default:
            return true;
    }
}

// Run `stage` (its body: Flow body(StepContext&)) if the step's rules switch it on and it has
// work, counted and timed as one run (timers.h). A run given up for room is timed but not
// counted: the count is the same whatever the buffers' sizes, which depend on the batch.
template <class Body>
Flow run(StepContext& w, Stage stage, Body&& body) {
    if (!(*w.stages)[stage] || !has_work(w, stage)) {
        return NEXT;
    }
    const StageTimer timer(w.timers, stage);
    const Flow flow = body(w);
    if (flow == GIVE_UP) {
        timer.uncount();
    }
    return flow;
}

// The world's pairs for its current poses and velocities, boxes grown by at least the
// reach recorded so far; returns how many. acceleration: m/s^2 the bodies may gain (gravity).
// carried: pairs among the bodies of rest.kept taken from the last step's list (sleep.h):
// from its asleep pairs, in (a, b) order, which hold every pair of a kept dynamic body (it
// slept) and no pair of two static or kinematic ones (never listed).
int64_t list_pairs(StepContext& w, double acceleration, bool carried) {
    const int64_t asleep = *w.rest.previous_awake;
    const Carried known = {{w.rest.kept.data, w.rest.kept.size},
                           {w.rest.previous_keys.data + asleep, *w.rest.previous_count - asleep}};
    const int64_t count =
        find_world_pairs(*w.geo, w.model.motion, w.bodies, 0.0, w.dt, acceleration,
                         w.settings->sweep, w.lists, carried ? known : Carried{});
    if (w.joints.joined_keys.size == 0 || count > w.pair_capacity()) {
        return count;
    }
    return drop_joined_pairs(w.joints, w.lists, count, w.num_bodies());  // joints.h
}

// Whether the joint stages run (stages.h: the scene has joints and joint_passes > 0).
bool joints_on(const StepContext& w) { return (*w.stages)[JOINT_VELOCITY_STAGE]; }

// Copy every body's velocity, angular momentum and angular velocity into w.start (keep), or
// back from it.
void keep_velocities(StepContext& w, bool keep) {
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

// The bodies kept since the last step (rest.kept, sleep.h), or none without sleeping: their
// inverse inertia is as when it was computed.
Span<const uint8_t> kept_bodies(const StepContext& w) {
    return w.settings->sleep ? Span<const uint8_t>{w.rest.kept.data, w.rest.kept.size}
                             : Span<const uint8_t>{};
}

// The bodies asleep in this step (rest.asleep), or none without sleeping.
Span<const uint8_t> asleep_bodies(const StepContext& w) {
    return w.settings->sleep ? Span<const uint8_t>{w.rest.asleep.data, w.rest.asleep.size}
                             : Span<const uint8_t>{};
}

// True when some body, at its current velocity, moves further in dt than its box was grown.
// Called before the position update, which moves a body by its current velocities: no
// acceleration term (the broad phase's bounds the velocity update's gravity). An asleep body
// keeps the velocities it started the step with, which its box was grown for.
bool outgrown(const StepContext& w) {
    const bool sleeping = w.settings->sleep;
    for (int i = 0; i < w.num_bodies(); ++i) {
        if (w.geo->body_unbounded[i] == 0 && !(sleeping && w.rest.asleep[i]) &&
            swept_margin(*w.geo, i, w.bodies.velocity[i], w.bodies.angular_velocity[i], 0.0, w.dt,
                         0.0) > w.lists.reach[i]) {
            return true;
        }
    }
    return false;
}

// The step's listed pairs are `count`: give the step up if they do not fit, else make them
// the impulse stages' (impulses cleared, contacts to be found, every pair awake until the
// islands are found).
Flow take_pairs(StepContext& w, int64_t count) {
    *w.pair_count = count;
    if (count > w.pair_capacity()) {
        return GIVE_UP;  // run again once the buffers have grown
    }
    for (int64_t k = 0; k < count; ++k) {
        w.pair_impulse[k] = {0.0, 0.0, 0.0};  // Coulomb's limit applies to the step's total
    }
    *w.contacts.detected = 0;
    *w.rest.awake_pairs = count;
    if (joints_on(w)) {
        form_joint_mobility(w, count);  // joints.h: the paired articulated bodies' response
    }
    return NEXT;
}

// The step's contacts, found by the first impulse stage that needs them (contacts.h), at
// the poses it predicts: the collision stage's (old velocities, dt^2 g ahead) or the joint
// velocity, contact and shock stages' (new velocities), which are the same poses until an
// impulse or a force acts. Found once per step (take_pairs clears the flag).
void find_contacts(StepContext& w, Vec3 lookahead) {
    if (!*w.contacts.detected) {
        detect_contacts(w, *w.rest.awake_pairs, w.dt, lookahead);
    }
}

// -- the stages, in step order (stages.h) ------------------------------------------------------

// With sleeping: a world still at rest skips its step (sleep.h); else the bodies unchanged
// since the last step are marked, whose pairs among each other the broad phase carries.
Flow check_rest(StepContext& w) {
    if (still_at_rest(w, w.dt)) {
        return SKIP;
    }
    mark_kept(w, w.dt);
    return NEXT;
}

// Held bodies at their place, I^-1 for the step's orientations, and every box's reach
// cleared but a kept body's (sleep.h: it is as when they were computed).
Flow prepare(StepContext& w) {
    const bool sleep = w.settings->sleep;
    place_attached(w.bodies, w.attached);
    refresh_inverse_inertia(w.bodies, w.model, kept_bodies(w));
    for (int i = 0; i < w.num_bodies(); ++i) {
        if (!(sleep && w.rest.kept[i])) {
            w.lists.reach[i] = 0.0;
        }
    }
    return NEXT;
}

// Every pair whose boxes may meet within the step, velocities and gravity included.
Flow broad_phase(StepContext& w) { return take_pairs(w, list_pairs(w, w.gravity, w.settings->sleep)); }

// Which islands sleep (sleep.h); may stop slow islands, before the velocities are kept.
Flow sleep_islands(StepContext& w) {
    mark_asleep(w, *w.pair_count, w.dt);
    return NEXT;
}

Flow collide(StepContext& w) {
    find_contacts(w, collision_lookahead(w.model, w.dt));
    resolve_world_contacts(w, *w.rest.awake_pairs, w.dt, COLLISION, w.settings->collision_passes);
    return NEXT;
}

Flow velocity_update(StepContext& w) {
    update_velocities(w.bodies, w.model, w.dt, asleep_bodies(w));
    return NEXT;
}

// The contacts are found before the joints act, at the poses the velocity update predicts:
// a finger's motor then pushes the finger into what it presses, which the contact stage
// takes back (contacts.cpp, along_normal_exempt: found at the pushed poses, such a pair was
// swept and found again in every step).
Flow joint_velocity(StepContext& w) {
    if (*w.rest.awake_pairs > 0) {
        find_contacts(w, {0.0, 0.0, 0.0});
    }
    solve_joint_velocities(w, w.dt);
    return NEXT;
}

Flow contact(StepContext& w) {
    find_contacts(w, {0.0, 0.0, 0.0});
    resolve_world_contacts(w, *w.rest.awake_pairs, w.dt, CONTACT, w.settings->contact_passes);
    return NEXT;
}

Flow propagate_shock(StepContext& w) {
    find_contacts(w, {0.0, 0.0, 0.0});
    propagate_world_shock(w, *w.rest.awake_pairs, w.dt);
    return NEXT;
}

Flow joint_position(StepContext& w) {
    stabilize_joint_positions(w, w.dt);
    return NEXT;
}

// The collision, velocity update, joint velocity, contact, shock and joint position stages
// over the awake pairs (and joints), from the
// velocities kept in w.start. Where their contacts overflowed the pool, the velocities are
// put back (the impulse stages change nothing else of the bodies), the world woken (its
// sleeping bookkeeping has taken this step in: sleep.h; waking changes no bit) and the step
// given up, to run again whole once the pool has grown (contacts.h).
Flow impulse_stages(StepContext& w) {
    keep_velocities(w, true);
    run(w, COLLISION_STAGE, collide);
    run(w, VELOCITY_STAGE, velocity_update);
    run(w, JOINT_VELOCITY_STAGE, joint_velocity);
    run(w, CONTACT_STAGE, contact);
    run(w, SHOCK_STAGE, propagate_shock);
    run(w, JOINT_POSITION_STAGE, joint_position);
    if (!pool_overflowed(w)) {
        return NEXT;
    }
    keep_velocities(w, false);
    wake_world(w, *w.pair_count);
    return GIVE_UP;
}

// The broad phase lists the pairs that can touch if every body keeps its speed through the
// step (swept_margin), but the impulse stages may speed a body up: a resting box struck by
// another. Before the position update, a body whose new velocity reaches past its box grows
// its box; if that lists more pairs, the velocities are put back as they were when the
// impulse stages began and the stages run again with every pair (up to MAX_RELISTS times),
// so a body is not moved into a neighbour whose pair was never listed. Nothing sleeps then.
// The impulse stages run again count as runs of their own.
Flow relist(StepContext& w) {
    for (int relist = 0; relist < MAX_RELISTS && outgrown(w); ++relist) {
        const int64_t listed = *w.pair_count;
        const int64_t more = list_pairs(w, 0.0, false);  // the final velocities
        if (more == listed) {  // boxes only grow: the same count is the same pairs, in the
            if (w.settings->sleep) {  // order the impulses were recorded in
                move_asleep_last(w, listed);
            }
            return NEXT;
        }
        keep_velocities(w, false);
        wake_world(w, more);
        if (take_pairs(w, more) == GIVE_UP || impulse_stages(w) == GIVE_UP) {
            return GIVE_UP;
        }
    }
    return NEXT;
}

Flow correct_overlaps(StepContext& w) {
    correct_overlap(w, *w.rest.awake_pairs, w.dt, w.settings->overlap_correction);
    return NEXT;
}

// The position update with the final velocities; forces and torques are spent. The asleep
// pairs' bodies are asleep or not dynamic: the position update reads no count of theirs. A
// jointed body counts as acted on (joints.h).
Flow position_update(StepContext& w) {
    const Settings& c = *w.settings;
    count_acting_pairs_of_bodies(w, *w.rest.awake_pairs);
    if (joints_on(w)) {
        count_joints_of_bodies(w);
    }
    update_positions(w.bodies, w.model, w.dt, c.rotation_order, c.keep_energy, c.exact_symmetric,
                     {w.pairs_of.data, w.pairs_of.size}, asleep_bodies(w));
    for (int i = 0; i < w.num_bodies(); ++i) {
        w.bodies.force[i] = {0.0, 0.0, 0.0};
        w.bodies.torque[i] = {0.0, 0.0, 0.0};
    }
    return NEXT;
}

// The joints' velocities projected at the new poses, with I^-1 at the new orientations
// (joints.h): the step ends with velocities the joints allow.
Flow joint_projection(StepContext& w) {
    refresh_inverse_inertia(w.bodies, w.model, kept_bodies(w));
    project_joint_velocities(w, w.dt);
    return NEXT;
}

// What the next step's sleeping compares with (sleep.h).
Flow record_rest(StepContext& w) {
    keep_pair_impulses(w);
    forget_moved(w);
    return NEXT;
}

}  // namespace

// Each step runs the stages of stages.h in order, each when the rules switch it on and it has
// work (run), counted and timed in the world's timers. A step that has to give up (a buffer
// too small) has applied nothing that its run again would not redo.
int64_t step_world(StepContext& w, int64_t steps, double dt) {
    w.dt = dt;
    for (int64_t done = 0; done < steps; ++done) {
        if (run(w, SLEEP_CHECK_STAGE, check_rest) == SKIP) {
            continue;  // at rest: the step would change nothing
        }
        run(w, PREPARE_STAGE, prepare);
        if (run(w, BROAD_STAGE, broad_phase) == GIVE_UP) {
            return done;
        }
        run(w, SLEEP_ISLANDS_STAGE, sleep_islands);
        if (impulse_stages(w) == GIVE_UP || run(w, RELIST_STAGE, relist) == GIVE_UP) {
            return done;
        }
        run(w, OVERLAP_STAGE, correct_overlaps);
        run(w, POSITION_STAGE, position_update);
        run(w, JOINT_PROJECTION_STAGE, joint_projection);
        run(w, SLEEP_RECORD_STAGE, record_rest);
    }
    place_attached(w.bodies, w.attached);  // held bodies where the last step left their holders
    return steps;
}

void advance(Batch& batch, int64_t steps, double dt) {
    const int num_worlds = batch.num_worlds();
    std::vector<int64_t> done(num_worlds, 0);
    ThreadPool& pool = ThreadPool::instance();
    const bool choice = num_worlds > 1 && pool.size() > 1;  // sharing.h
    const bool shared = choice && batch.sharing.share();
    const double start = choice ? clock_seconds() : 0.0;
    while (true) {
        const int ranges = shared ? std::min(num_worlds, pool.size()) : 1;
        pool.run(ranges, [&](int range) {
            const int first = static_cast<int>(static_cast<int64_t>(num_worlds) * range / ranges);
            const int last = static_cast<int>(static_cast<int64_t>(num_worlds) * (range + 1) / ranges);
            for (int w = first; w < last; ++w) {
                if (done[w] < steps) {
                    StepContext rows = batch.world(w);
                    done[w] += step_world(rows, steps - done[w], dt);
                }
            }
        });
        batch.fit_contact_rows();  // the contact pool may grow for the next steps
        if (std::all_of(done.begin(), done.end(), [&](int64_t d) { return d == steps; })) {
            if (choice) {
                batch.sharing.record(shared, clock_seconds() - start, num_worlds * steps);
            }
            return;
        }
        int64_t needed = 0;
        for (int w = 0; w < num_worlds; ++w) {
            needed = std::max(needed, batch.pair_count[w]);
        }
        batch.grow_pairs(needed);  // an overflowed step was abandoned: it runs again whole
    }
}

}  // namespace rg
