// Allocation of the step context and its per-world rows (world.h).
#include "solver/world.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "solver/sleep.h"

namespace rg {

namespace {

// Rows [w count, (w + 1) count) of a batched buffer.
template <class T>
Span<T> world_rows(Array<T>& a, int w, int64_t count) {
    return a.rows(w * count, count);
}

// The same, read-only.
template <class T>
Span<const T> read_rows(Array<T>& a, int w, int64_t count) {
    const Span<T> rows = world_rows(a, w, count);
    return {rows.data, rows.size};
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

// An entry of a table (base/span.h) allocated for `worlds` worlds, filled; the names its rows
// read (n, p, c, q) are in scope where it expands.
#define RG_ALLOCATE(type, name, count, fill) name.assign(worlds * (count), fill);
// An entry viewed as world w's rows, into `out`.
#define RG_VIEW(type, name, count, fill) out.name = name.rows(w * (count), count);
#define RG_POINT(type, name, count, fill) out.name = &name[w];
// An entry of pair rows regrown from row_pairs to p rows per world, each world's first rows
// kept.
#define RG_KEEP_ROWS(type, name, count, fill) resize_rows(name, worlds, row_pairs, p);

void ContactSetBuffers::allocate(int worlds, int64_t c) {
    contacts = c;
    RG_CONTACT_SET_ROWS(RG_ALLOCATE)
}

ContactSet ContactSetBuffers::rows(int w) {
    const int64_t c = contacts;
    ContactSet out;
    RG_CONTACT_SET_ROWS(RG_VIEW)
    return out;
}

void ContactCacheBuffers::allocate_bodies(int worlds, int64_t n) {
    bodies = n;
    RG_CACHE_BODY_ROWS(RG_ALLOCATE)
    detections.assign(worlds, 0);
}

void ContactCacheBuffers::allocate_pairs(int worlds, int64_t p) {
    pairs = p;
    RG_CACHE_PAIR_ROWS(RG_ALLOCATE)
    used.assign(worlds, 0);
    needed.assign(worlds, 0);
    detected.assign(worlds, 0);  // the pairs' rows are gone: find them again
}

void ContactCacheBuffers::allocate_rows(int num_worlds, int64_t num_rows) {
    allocate_storage(num_worlds, num_rows);
    limit.assign(num_worlds, num_rows);
}

void ContactCacheBuffers::allocate_storage(int worlds, int64_t q) {
    rows = q;
    RG_CACHE_POOL_ROWS(RG_ALLOCATE)
    detected.assign(worlds, 0);
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

// World w's rows; of the pool, the first limit[w] of its Q.
ContactCache ContactCacheBuffers::view(int w) {
    const int64_t n = bodies, p = pairs;
    ContactCache out;
    RG_CACHE_PAIR_ROWS(RG_VIEW)
    RG_CACHE_BODY_ROWS(RG_VIEW)
    RG_CACHE_COUNTS(RG_POINT)
#define RG_POOL_VIEW(type, name, count, fill) out.name = name.rows(w * this->rows, limit[w]);
    RG_CACHE_POOL_ROWS(RG_POOL_VIEW)
#undef RG_POOL_VIEW
    return out;
}

void PairListBuffers::allocate_bodies(int worlds, int64_t n) {
    row_bodies = n;
    RG_PAIR_LIST_BODY_ROWS(RG_ALLOCATE)
    for (int64_t w = 0; w < worlds; ++w) {
        for (int64_t i = 0; i < n; ++i) {
            order[w * n + i] = i;
        }
    }
}

void PairListBuffers::allocate_pairs(int worlds, int64_t p) {
    if (row_pairs == 0) {
        RG_PAIR_LIST_PAIR_ROWS(RG_ALLOCATE)
    } else {
        // every world keeps its last step's pairs, from which the next step carries its asleep
        // ones (sleep.h): a world whose pairs overflowed abandoned its step before its
        // sleeping bookkeeping changed, or woke (a relist), so no world is forgotten
        RG_PAIR_LIST_PAIR_ROWS(RG_KEEP_ROWS)
    }
    row_pairs = p;
}

PairLists PairListBuffers::rows(int w) {
    const int64_t n = row_bodies, p = row_pairs;
    PairLists out;
    RG_PAIR_LIST_BODY_ROWS(RG_VIEW)
    RG_PAIR_LIST_PAIR_ROWS(RG_VIEW)
    return out;
}

void StepBuffers::allocate(int worlds, int64_t n) {
    row_bodies = n;
    RG_STEP_ROWS(RG_ALLOCATE)
}

void StepBuffers::view(int w, StepContext& out) {
    const int64_t n = row_bodies;
    RG_STEP_ROWS(RG_VIEW)
}

void GraphBuffers::allocate(int worlds, int64_t n, int64_t p) {
    bodies = n;
    pairs = p;
    RG_GRAPH_ROWS(RG_ALLOCATE)
}

Graph GraphBuffers::rows(int w) {
    const int64_t n = bodies, p = pairs;
    Graph out;
    RG_GRAPH_ROWS(RG_VIEW)
    return out;
}

void RestBuffers::allocate_bodies(int worlds, int64_t n) {
    row_bodies = n;
    RG_REST_BODY_ROWS(RG_ALLOCATE)
    RG_REST_COUNTS(RG_ALLOCATE)
}

void RestBuffers::allocate_pairs(int worlds, int64_t p) {
    if (row_pairs == 0) {
        RG_REST_PAIR_ROWS(RG_ALLOCATE)
    } else {
        RG_REST_PAIR_ROWS(RG_KEEP_ROWS)
    }
    row_pairs = p;
}

Rest RestBuffers::rows(int w, Span<uint8_t> asleep) {
    const int64_t n = row_bodies, p = row_pairs;
    Rest out;
    out.asleep = asleep;
    RG_REST_BODY_ROWS(RG_VIEW)
    RG_REST_PAIR_ROWS(RG_VIEW)
    RG_REST_COUNTS(RG_POINT)
    return out;
}

void JointBuffers::allocate(int worlds, int64_t n) {
    row_bodies = n;
    const int64_t j = size(), r = MAX_JOINT_ROWS * j;
    RG_JOINT_WORLD_ROWS(RG_ALLOCATE)
    RG_JOINT_SOLVE_ROWS(RG_ALLOCATE)
}

JointRows JointBuffers::view(int w) {
    const int64_t n = row_bodies, j = size(), r = MAX_JOINT_ROWS * j;
    JointRows out;
#define RG_SHARED_VIEW(type, name, count, fill) out.name = {name.data(), name.size()};
    RG_JOINT_MODEL_ROWS(RG_SHARED_VIEW)
#undef RG_SHARED_VIEW
    RG_JOINT_WORLD_ROWS(RG_VIEW)
    RG_JOINT_SOLVE_ROWS(RG_VIEW)
    return out;
}

Batch::Batch(int num_worlds, Geometry geometry, std::vector<int32_t> body_motion,
             Vec3 world_gravity, Settings settings, int64_t pair_contacts)
    : gravity(world_gravity),
      num_worlds_(num_worlds),
      num_bodies_(static_cast<int>(body_motion.size())),
      geometry_(std::move(geometry)),
      settings_(settings) {
    const int64_t b = num_worlds_, n = num_bodies_;
    const Vec3 g = world_gravity;
    gravity_length_ = std::sqrt(g.x * g.x + g.y * g.y + g.z * g.z);
    up_ = gravity_length_ > 0.0 ? Vec3{-g.x / gravity_length_, -g.y / gravity_length_,
                                       -g.z / gravity_length_}
                                : Vec3{0.0, 0.0, 1.0};
    stages_ = stage_rules(settings_, gravity_length_ > 0.0, false);
    for (Array<Vec3>* rows : {&position, &velocity, &angular_momentum, &angular_velocity, &force,
                              &torque, &inverse_moments, &attach_offset_position}) {
        rows->assign(b * n, {0.0, 0.0, 0.0});
    }
    orientation.assign(b * n, {1.0, 0.0, 0.0, 0.0});
    attach_offset_orientation.assign(b * n, {1.0, 0.0, 0.0, 0.0});
    rotation.assign(b * n, {});
    inverse_inertia.assign(b * n, {});
    motion.assign(body_motion.data(), n);
    articulated.assign(n, 0);  // none until set_joints
    inverse_mass.assign(b * n, 0.0);
    friction.assign(b * n, 0.0);
    restitution.assign(b * n, 0.0);
    attach_parent.assign(b * n, -1);
    pair_count.assign(b, 0);
    asleep.assign(b * n, 0);
    lists.allocate_bodies(num_worlds_, n);
    step_.allocate(num_worlds_, n);
    scratch_.allocate(num_worlds_, pair_contacts);
    wide_.allocate(num_worlds_, SUPPORT_CONTACTS * pair_contacts);
    body_reach_.assign(n, 0.0);
    for (int i = 0; i < num_bodies_; ++i) {
        if (geometry_.body_unbounded[i] == 0) {
            const Vec3 c = geometry_.body_bound_center[i], e = geometry_.body_bound_half[i];
            body_reach_[i] = length({std::fabs(c.x) + e.x, std::fabs(c.y) + e.y, std::fabs(c.z) + e.z});
        }
    }
    stage_seconds.assign(b * STAGE_COUNT, 0.0);
    stage_calls.assign(b * STAGE_COUNT, 0);
    stage_resolves.assign(b * STAGE_COUNT, 0);
    rest_.allocate_bodies(num_worlds_, n);
    contacts_.allocate_bodies(num_worlds_, n);
    joints.allocate(num_worlds_, n);  // none until set_joints
    allocate_pairs(std::max<int64_t>(8, 2 * n));
    contacts_.allocate_rows(num_worlds_, 8 * pair_capacity_);
}

void Batch::allocate_pairs(int64_t capacity) {
    const int64_t b = num_worlds_;
    if (pair_capacity_ == 0) {
        pair_impulse.assign(b * capacity, {0.0, 0.0, 0.0});
    } else {
        resize_rows(pair_impulse, num_worlds_, pair_capacity_, capacity);  // as the pairs'
    }
    lists.allocate_pairs(num_worlds_, capacity);
    rest_.allocate_pairs(num_worlds_, capacity);
    graph_.allocate(num_worlds_, num_bodies_, capacity);
    contacts_.allocate_pairs(num_worlds_, capacity);
    pair_capacity_ = capacity;
}

void Batch::fit_contact_rows() { contacts_.fit_rows(num_worlds_); }

void Batch::grow_pairs(int64_t needed) {
    if (needed > pair_capacity_) {
        allocate_pairs(2 * needed);
    }
}

void Batch::set_joints(Array<int32_t> kind, Array<int32_t> body_a, Array<int32_t> body_b,
                       Array<Vec3> anchor_a, Array<Vec3> anchor_b, Array<Vec3> axis_a,
                       Array<Vec3> axis_b, Array<Quat> reference) {
    JointBuffers& m = joints;
    m.kind = std::move(kind);
    m.body_a = std::move(body_a);
    m.body_b = std::move(body_b);
    m.anchor_a = std::move(anchor_a);
    m.anchor_b = std::move(anchor_b);
    m.axis_a = std::move(axis_a);
    m.axis_b = std::move(axis_b);
    m.reference = std::move(reference);
    const int64_t j = m.size();
    // the broad phase's key of each joined pair: a the body of higher motion class, ties the
    // lower index (broad_phase.h)
    std::vector<int64_t> keys;
    for (int64_t k = 0; k < j; ++k) {
        int32_t p = m.body_a[k], q = m.body_b[k];
        if (q < 0) {
            continue;  // the world frame is no body of the broad phase
        }
        if (motion[q] > motion[p] || (motion[q] == motion[p] && q < p)) {
            std::swap(p, q);
        }
        keys.push_back(static_cast<int64_t>(p) * num_bodies_ + q);
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    m.joined_keys.assign(keys.data(), static_cast<int64_t>(keys.size()));
    // components: bodies joined through joints (union-find over the dynamic bodies), each
    // named by its least joint; the joints listed by component, in index order within each
    std::vector<int64_t> root(num_bodies_);
    for (int i = 0; i < num_bodies_; ++i) {
        root[i] = i;
    }
    const auto find = [&](int64_t i) {
        while (root[i] != i) {
            i = root[i] = root[root[i]];
        }
        return i;
    };
    for (int64_t k = 0; k < j; ++k) {
        const int32_t q = m.body_b[k];
        if (q >= 0 && motion[q] == DYNAMIC) {
            const int64_t ra = find(m.body_a[k]), rb = find(q);
            root[std::max(ra, rb)] = std::min(ra, rb);
        }
    }
    std::vector<int64_t> first_joint(num_bodies_, -1);  // per root: its component's least joint
    for (int64_t k = 0; k < j; ++k) {
        const int64_t r = find(m.body_a[k]);
        if (first_joint[r] < 0) {
            first_joint[r] = k;
        }
    }
    std::vector<int32_t> order;
    std::vector<int64_t> starts;
    for (int64_t k = 0; k < j; ++k) {
        const int64_t r = find(m.body_a[k]);
        if (first_joint[r] != k) {
            continue;  // listed with its component's least joint
        }
        starts.push_back(static_cast<int64_t>(order.size()));
        for (int64_t other = k; other < j; ++other) {
            if (find(m.body_a[other]) == r) {
                order.push_back(static_cast<int32_t>(other));
            }
        }
    }
    starts.push_back(static_cast<int64_t>(order.size()));
    m.order.assign(order.data(), static_cast<int64_t>(order.size()));
    m.component_start.assign(starts.data(), static_cast<int64_t>(starts.size()));
    // articulated: body_a of its joints, each to an immovable body (then no joint's body_a
    // is joined to it: body_a is dynamic)
    std::vector<uint8_t> leaf(num_bodies_, 0);
    for (int64_t k = 0; k < j; ++k) {
        leaf[m.body_a[k]] = 1;
    }
    for (int64_t k = 0; k < j; ++k) {
        const int32_t q = m.body_b[k];
        if (q >= 0 && motion[q] == DYNAMIC) {
            leaf[m.body_a[k]] = 0;
            leaf[q] = 0;
        }
    }
    articulated.assign(leaf.data(), num_bodies_);
    const bool any = std::find(leaf.begin(), leaf.end(), 1) != leaf.end();
    mobility.assign(any ? static_cast<int64_t>(num_worlds_) * num_bodies_ : 0, Mobility{});
    m.allocate(num_worlds_, num_bodies_);
    stages_ = stage_rules(settings_, gravity_length_ > 0.0, j > 0);
    forget(0, num_worlds_);
}

void Batch::forget(int first, int last) {
    for (int64_t k = static_cast<int64_t>(first) * num_bodies_;
         k < static_cast<int64_t>(last) * num_bodies_; ++k) {
        rest_.previous_island[k] = -1;
    }
    for (int w = first; w < last; ++w) {
        rest_.at_rest[w] = 0;
        rest_.previous_dt[w] = 0.0;
    }
}

StepContext Batch::world(int w) {
    const int64_t n = num_bodies_, p = pair_capacity_;
    StepContext s;
    s.geo = &geometry_;
    s.settings = &settings_;
    s.stages = &stages_;
    s.gravity = gravity_length_;
    s.up = up_;
    BodyStates& bodies = s.bodies;
    bodies.position = world_rows(position, w, n);
    bodies.orientation = world_rows(orientation, w, n);
    bodies.velocity = world_rows(velocity, w, n);
    bodies.angular_momentum = world_rows(angular_momentum, w, n);
    bodies.angular_velocity = world_rows(angular_velocity, w, n);
    bodies.rotation = world_rows(rotation, w, n);
    bodies.force = world_rows(force, w, n);
    bodies.torque = world_rows(torque, w, n);
    bodies.inverse_inertia = world_rows(inverse_inertia, w, n);
    bodies.mobility = mobility.size() > 0 ? world_rows(mobility, w, n) : Span<Mobility>{};
    BodyModel& model = s.model;
    model.motion = {motion.data(), n};
    model.inverse_mass = read_rows(inverse_mass, w, n);
    model.inverse_moments = read_rows(inverse_moments, w, n);
    model.friction = read_rows(friction, w, n);
    model.restitution = read_rows(restitution, w, n);
    model.articulated = {articulated.data(), n};
    model.gravity = gravity;
    s.attached.parent = world_rows(attach_parent, w, n);
    s.attached.offset_position = world_rows(attach_offset_position, w, n);
    s.attached.offset_orientation = world_rows(attach_offset_orientation, w, n);
    s.lists = lists.rows(w);
    s.pair_count = &pair_count[w];
    s.pair_impulse = world_rows(pair_impulse, w, p);
    step_.view(w, s);
    s.contacts = contacts_.view(w);
    s.body_reach = {body_reach_.data(), n};
    s.scratch = scratch_.rows(w);
    s.wide = wide_.rows(w);
    s.graph = graph_.rows(w);
    s.rest = rest_.rows(w, world_rows(asleep, w, n));
    s.joints = joints.view(w);
    s.timers.seconds = world_rows(stage_seconds, w, STAGE_COUNT);
    s.timers.calls = world_rows(stage_calls, w, STAGE_COUNT);
    s.timers.resolves = world_rows(stage_resolves, w, STAGE_COUNT);
    s.timers.timed = timed;
    return s;
}

}  // namespace rg
