// Allocation of the step context and its per-world rows (world.h).
#include "solver/world.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "solver/sleep.h"

namespace rg {

namespace {

// Rows [w count, (w + 1) count) of a batched buffer.
template <class T>
Span<T> world_rows(Array<T>& a, int w, int64_t count) {
    return a.rows(w * count, count);
}

// A batched buffer's rows copied into a buffer of another row count per world.
template <class T>
void resize_rows(Array<T>& a, int num_worlds, int64_t old_count, int64_t new_count) {
    Array<T> grown(num_worlds * new_count, T());
    const int64_t kept = std::min(old_count, new_count);
    for (int w = 0; w < num_worlds; ++w) {
        for (int64_t k = 0; k < kept; ++k) {
            grown[w * new_count + k] = a[w * old_count + k];
        }
    }
    a = std::move(grown);
}

}  // namespace

void ContactSetBuffers::allocate(int num_worlds, int64_t num_contacts) {
    contacts = num_contacts;
    const int64_t rows = num_worlds * num_contacts;
    for (Array<Vec3>* vectors : {&point, &normal, &centre_a, &centre_b}) {
        vectors->assign(rows, {0.0, 0.0, 0.0});
    }
    depth.assign(rows, 0.0);
    gap.assign(rows, 0.0);
    orient.assign(rows, 0.0);
    group.assign(rows, 0);
    partner.assign(rows, 0);
    source.assign(rows, 0);
}

ContactSet ContactSetBuffers::rows(int w) {
    return {world_rows(point, w, contacts),    world_rows(normal, w, contacts),
            world_rows(depth, w, contacts),    world_rows(gap, w, contacts),
            world_rows(group, w, contacts),
            world_rows(partner, w, contacts),  world_rows(source, w, contacts),
            world_rows(orient, w, contacts),   world_rows(centre_a, w, contacts),
            world_rows(centre_b, w, contacts)};
}

void ContactCacheBuffers::allocate_bodies(int num_worlds, int64_t num_bodies) {
    bodies = num_bodies;
    pose.assign(num_worlds * num_bodies, {});
    posed.assign(num_worlds * num_bodies, -1);
    detections.assign(num_worlds, 0);
}

void ContactCacheBuffers::allocate_pairs(int num_worlds, int64_t num_pairs) {
    pairs = num_pairs;
    first.assign(num_worlds * num_pairs, -1);
    count.assign(num_worlds * num_pairs, 0);
    for (Array<Vec3>* per_pair : {&centre_a, &centre_b, &shift_a, &shift_b, &turn_a, &turn_b}) {
        per_pair->assign(num_worlds * num_pairs, {0.0, 0.0, 0.0});
    }
    used.assign(num_worlds, 0);
    needed.assign(num_worlds, 0);
    detected.assign(num_worlds, 0);  // the pairs' rows are gone: find them again
}

void ContactCacheBuffers::allocate_rows(int num_worlds, int64_t num_rows) {
    allocate_storage(num_worlds, num_rows);
    limit.assign(num_worlds, num_rows);
}

void ContactCacheBuffers::allocate_storage(int num_worlds, int64_t num_rows) {
    rows = num_rows;
    for (Array<Vec3>* per_row : {&point, &normal, &arm_a, &arm_b}) {
        per_row->assign(num_worlds * num_rows, {0.0, 0.0, 0.0});
    }
    depth.assign(num_worlds * num_rows, 0.0);
    detected.assign(num_worlds, 0);
}

void ContactCacheBuffers::fit_rows(int num_worlds) {
    int64_t largest = rows;
    for (int w = 0; w < num_worlds; ++w) {
        if (needed[w] > limit[w]) {
            limit[w] = 2 * needed[w];
            largest = std::max(largest, limit[w]);
        }
    }
    if (largest > rows) {
        allocate_storage(num_worlds, largest);
    }
}

ContactCache ContactCacheBuffers::view(int w) {
    return {world_rows(first, w, pairs),    world_rows(count, w, pairs),
            world_rows(centre_a, w, pairs), world_rows(centre_b, w, pairs),
            world_rows(shift_a, w, pairs),  world_rows(shift_b, w, pairs),
            world_rows(turn_a, w, pairs),   world_rows(turn_b, w, pairs),
            point.rows(w * rows, limit[w]), normal.rows(w * rows, limit[w]),
            depth.rows(w * rows, limit[w]), arm_a.rows(w * rows, limit[w]),
            arm_b.rows(w * rows, limit[w]), &used[w],
            &needed[w],                     &detected[w],
            world_rows(pose, w, bodies),    world_rows(posed, w, bodies),
            &detections[w]};
}

void GraphBuffers::allocate(int num_worlds, int64_t num_bodies, int64_t num_pairs) {
    bodies = num_bodies;
    pairs = num_pairs;
    const int64_t b = num_worlds;
    touching.assign(b * num_pairs, 0);
    for (Array<int64_t>* edges : {&edge_from, &edge_to, &targets, &body_pairs}) {
        edges->assign(b * 2 * num_pairs, 0);
    }
    for (Array<int64_t>* per_body : {&nodes, &component, &component_level, &by_component, &index,
                                     &low, &stack, &calls, &next_edge, &level, &by_level}) {
        per_body->assign(b * num_bodies, 0);
    }
    node_of.assign(b * num_bodies, -1);
    on_stack.assign(b * num_bodies, 0);
    edge_start.assign(b * (num_bodies + 1), 0);
    body_pair_start.assign(b * (num_bodies + 1), 0);
    counts.assign(b * (num_bodies + 2), 0);
    level_pair_start.assign(b * (num_bodies + 2), 0);
    level_pairs.assign(b * num_pairs, 0);
}

Graph GraphBuffers::rows(int w) {
    const int64_t n = bodies, e = 2 * pairs;
    return {world_rows(nodes, w, n),             world_rows(node_of, w, n),
            world_rows(touching, w, pairs),      world_rows(edge_from, w, e),
            world_rows(edge_to, w, e),           world_rows(edge_start, w, n + 1),
            world_rows(targets, w, e),           world_rows(component, w, n),
            world_rows(component_level, w, n),   world_rows(by_component, w, n),
            world_rows(index, w, n),             world_rows(low, w, n),
            world_rows(on_stack, w, n),          world_rows(stack, w, n),
            world_rows(calls, w, n),             world_rows(next_edge, w, n),
            world_rows(level, w, n),             world_rows(by_level, w, n),
            world_rows(counts, w, n + 2),        world_rows(body_pair_start, w, n + 1),
            world_rows(body_pairs, w, e),        world_rows(level_pair_start, w, n + 2),
            world_rows(level_pairs, w, pairs)};
}

StepContext::StepContext(int num_worlds, Geometry geometry, std::vector<int32_t> body_motion,
                         Vec3 world_gravity, Settings settings, int64_t pair_contacts)
    : gravity(world_gravity),
      num_worlds_(num_worlds),
      num_bodies_(static_cast<int>(body_motion.size())),
      geometry_(std::move(geometry)),
      settings_(settings) {
    const int64_t b = num_worlds_, n = num_bodies_;
    for (Array<Vec3>* rows : {&position, &velocity, &angular_momentum, &angular_velocity, &force,
                              &torque, &inverse_moments, &attach_offset_position}) {
        rows->assign(b * n, {0.0, 0.0, 0.0});
    }
    orientation.assign(b * n, {1.0, 0.0, 0.0, 0.0});
    attach_offset_orientation.assign(b * n, {1.0, 0.0, 0.0, 0.0});
    rotation.assign(b * n, {});
    inverse_inertia.assign(b * n, {});
    motion.assign(body_motion.data(), n);
    inverse_mass.assign(b * n, 0.0);
    friction.assign(b * n, 0.0);
    restitution.assign(b * n, 0.0);
    attach_parent.assign(b * n, -1);
    pair_count.assign(b, 0);
    asleep.assign(b * n, 0);
    bounds_.assign(b * n, {});
    order_.assign(b * n, 0);
    for (int64_t w = 0; w < b; ++w) {
        for (int64_t i = 0; i < n; ++i) {
            order_[w * n + i] = i;
        }
    }
    reach_.assign(b * n, 0.0);
    start_.assign(b * 3 * n, {0.0, 0.0, 0.0});
    scratch_.allocate(num_worlds_, pair_contacts);
    wide_.allocate(num_worlds_, SUPPORT_CONTACTS * pair_contacts);
    body_reach_.assign(n, 0.0);
    for (int i = 0; i < num_bodies_; ++i) {
        if (geometry_.body_unbounded[i] == 0) {
            const Vec3 c = geometry_.body_bound_center[i], e = geometry_.body_bound_half[i];
            body_reach_[i] = length({std::fabs(c.x) + e.x, std::fabs(c.y) + e.y, std::fabs(c.z) + e.z});
        }
    }
    pairs_of_.assign(b * n, 0);
    overlap_shift_.assign(b * n, {0.0, 0.0, 0.0});
    reaction_.assign(2 * b * n, {0.0, 0.0, 0.0});
    awake_pairs_.assign(b, 0);
    stage_seconds.assign(b * STAGE_COUNT, 0.0);
    stage_calls.assign(b * STAGE_COUNT, 0);
    island_.assign(b * n, -1);
    previous_island_.assign(b * n, -1);
    island_bodies_.assign(b * n, 0);
    island_pairs_.assign(b * n, 0);
    previous_bodies_.assign(b * n, 0);
    previous_pairs_.assign(b * n, 0);
    resting_.assign(b * n, 0);
    slow_.assign(b * n, 0);
    slow_time_.assign(b * n, 0.0);
    snapshot_.assign(b * n * SNAPSHOT, 0.0);
    previous_count_.assign(b, 0);
    previous_awake_.assign(b, 0);
    at_rest_.assign(b, 0);
    kept_.assign(b * n, 0);
    intact_.assign(b * n, 0);
    previous_dt_.assign(b, 0.0);
    contacts_.allocate_bodies(num_worlds_, n);
    allocate_pairs(std::max<int64_t>(8, 2 * n));
    contacts_.allocate_rows(num_worlds_, 8 * pair_capacity_);
}

void StepContext::allocate_pairs(int64_t capacity) {
    const int64_t b = num_worlds_;
    if (pair_capacity_ == 0) {
        pair_a.assign(b * capacity, 0);
        pair_b.assign(b * capacity, 0);
        pair_impulse.assign(b * capacity, {0.0, 0.0, 0.0});
        previous_keys_.assign(b * capacity, 0);
        previous_impulse_.assign(b * capacity, {0.0, 0.0, 0.0});
    } else {
        // every world keeps its last step's pairs, from which the next step carries its asleep
        // ones (sleep.h): a world whose pairs overflowed abandoned its step before its
        // sleeping bookkeeping changed, or woke (a relist), so no world is forgotten
        resize_rows(pair_a, num_worlds_, pair_capacity_, capacity);
        resize_rows(pair_b, num_worlds_, pair_capacity_, capacity);
        resize_rows(pair_impulse, num_worlds_, pair_capacity_, capacity);
        resize_rows(previous_keys_, num_worlds_, pair_capacity_, capacity);
        resize_rows(previous_impulse_, num_worlds_, pair_capacity_, capacity);
    }
    keys_.assign(b * capacity, 0);
    spare_.assign(b * capacity, 0);
    graph_.allocate(num_worlds_, num_bodies_, capacity);
    contacts_.allocate_pairs(num_worlds_, capacity);
    pair_capacity_ = capacity;
}

void StepContext::fit_contact_rows() { contacts_.fit_rows(num_worlds_); }

void StepContext::grow_pairs(int64_t needed) {
    if (needed > pair_capacity_) {
        allocate_pairs(2 * needed);
    }
}

void StepContext::forget(int first, int last) {
    for (int64_t k = static_cast<int64_t>(first) * num_bodies_;
         k < static_cast<int64_t>(last) * num_bodies_; ++k) {
        previous_island_[k] = -1;
    }
    for (int w = first; w < last; ++w) {
        at_rest_[w] = 0;
        previous_dt_[w] = 0.0;
    }
}

WorldStep StepContext::world(int w) {
    const int64_t n = num_bodies_, p = pair_capacity_;
    WorldStep s;
    s.geo = &geometry_;
    s.settings = &settings_;
    s.bodies = {world_rows(position, w, n),         world_rows(orientation, w, n),
                world_rows(velocity, w, n),         world_rows(angular_momentum, w, n),
                world_rows(angular_velocity, w, n), world_rows(rotation, w, n),
                world_rows(force, w, n),            world_rows(torque, w, n),
                world_rows(inverse_inertia, w, n)};
    const Span<const int32_t> motion_rows = {motion.data(), n};
    const Span<double> mass = world_rows(inverse_mass, w, n);
    const Span<Vec3> moments = world_rows(inverse_moments, w, n);
    const Span<double> mu = world_rows(friction, w, n);
    const Span<double> e = world_rows(restitution, w, n);
    s.model = {motion_rows, {mass.data, n}, {moments.data, n}, {mu.data, n}, {e.data, n}, gravity};
    s.attached = {world_rows(attach_parent, w, n), world_rows(attach_offset_position, w, n),
                  world_rows(attach_offset_orientation, w, n)};
    s.lists = {world_rows(bounds_, w, n), world_rows(order_, w, n), world_rows(pair_a, w, p),
               world_rows(pair_b, w, p),  world_rows(keys_, w, p),  world_rows(spare_, w, p),
               world_rows(reach_, w, n)};
    s.pair_count = &pair_count[w];
    s.pair_impulse = world_rows(pair_impulse, w, p);
    s.start = world_rows(start_, w, 3 * n);
    s.contacts = contacts_.view(w);
    s.body_reach = {body_reach_.data(), n};
    s.scratch = scratch_.rows(w);
    s.wide = wide_.rows(w);
    s.pairs_of = world_rows(pairs_of_, w, n);
    s.overlap_shift = world_rows(overlap_shift_, w, n);
    s.reaction = world_rows(reaction_, w, 2 * n);
    s.graph = graph_.rows(w);
    s.rest = {world_rows(asleep, w, n),           &awake_pairs_[w],
              world_rows(island_, w, n),          world_rows(previous_island_, w, n),
              world_rows(island_bodies_, w, n),   world_rows(island_pairs_, w, n),
              world_rows(previous_bodies_, w, n), world_rows(previous_pairs_, w, n),
              world_rows(resting_, w, n),         world_rows(slow_, w, n),
              world_rows(slow_time_, w, n),       world_rows(snapshot_, w, n * SNAPSHOT),
              world_rows(previous_keys_, w, p),   world_rows(previous_impulse_, w, p),
              &previous_count_[w],                &previous_awake_[w],
              &at_rest_[w],                       world_rows(kept_, w, n),
              world_rows(intact_, w, n),          &previous_dt_[w]};
    s.timers = {world_rows(stage_seconds, w, STAGE_COUNT), world_rows(stage_calls, w, STAGE_COUNT),
                timed};
    return s;
}

}  // namespace rg
