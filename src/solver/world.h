// Batch: every buffer the step reads and writes for a batch of B worlds of one scene, and
// StepContext, one world's step: its rows that the stages work on.
//
// Buffers are allocated when the batch is made and reused by every step. The pair buffers
// (and the shock-propagation graph, sized by them) have a capacity per world that grows
// between steps when a broad phase finds more pairs than fit (step.cpp): a world's step
// that overflows is abandoned before anything is applied and run again after the growth.
// Python sees the state, the model and the attachments as numpy arrays over these buffers
// (bindings), never the scratch.
#pragma once

#include <cstdint>
#include <vector>

#include "base/body.h"
#include "collision/broad_phase.h"
#include "solver/contact_set.h"
#include "collision/geometry.h"
#include "solver/joint_rows.h"
#include "solver/patch_memo.h"
#include "solver/settings.h"
#include "solver/sharing.h"
#include "solver/stages.h"
#include "solver/timers.h"

namespace rg {

// Floats of a body's state compared by sleeping: position 3, orientation 4, velocity 3,
// angular momentum 3, angular velocity 3, rotation 9.
constexpr int SNAPSHOT = 25;

// The tables below list a per-world struct's rows once (base/span.h): the struct holds a Span
// of each, Batch an Array of B worlds' rows, which world.cpp allocates, views and grows from
// the same table. n: bodies, p: the pair capacity, per world.

// Shock propagation's work rows. The graph's nodes are the bodies of the stage's pairs
// (graph_nodes): with sleeping, the bodies of the awake pairs, so an asleep body costs the
// stage nothing. Rows "per node" are indexed by node; a node's body is nodes[node].
#define RG_GRAPH_ROWS(X)                                                                    \
    X(int64_t, nodes, n, 0)                /* the bodies of the pairs, in index order */    \
    X(int64_t, node_of, n, -1)             /* each body's node, -1 outside the stage */     \
    X(uint8_t, touching, p, 0)             /* the pair touches at the predicted poses */    \
    X(int64_t, edge_from, 2 * p, 0)        /* support edges, lower body to upper */         \
    X(int64_t, edge_to, 2 * p, 0)                                                           \
    X(int64_t, edge_start, n + 1, 0)       /* CSR form of the edges, per node */            \
    X(int64_t, targets, 2 * p, 0)          /* nodes */                                      \
    X(int64_t, component, n, 0)            /* per node: strongly connected components */   \
    X(int64_t, component_level, n, 0)                                                       \
    X(int64_t, by_component, n, 0)                                                          \
    X(int64_t, index, n, 0)                /* Tarjan's bookkeeping */                       \
    X(int64_t, low, n, 0)                                                                   \
    X(uint8_t, on_stack, n, 0)                                                              \
    X(int64_t, stack, n, 0)                                                                 \
    X(int64_t, calls, n, 0)                                                                 \
    X(int64_t, next_edge, n, 0)                                                             \
    X(int64_t, level, n, 0)                /* per node: its level, 0 static and kinematic */ \
    X(int64_t, by_level, n, 0)             /* the nodes by level */                         \
    X(int64_t, counts, n + 2, 0)           /* counting sorts */                             \
    X(int64_t, body_pair_start, n + 1, 0)  /* each node's touching pairs, CSR */            \
    X(int64_t, body_pairs, 2 * p, 0)                                                        \
    X(int64_t, level_pair_start, n + 2, 0) /* the touching pairs inside each level, CSR */  \
    X(int64_t, level_pairs, p, 0)                                                           \
    X(int64_t, clock, 1, 0)                /* shock.cpp's count of resolves and changes */  \
    X(int64_t, changed_at, n, -1)          /* per body: clock when its velocity changed */  \
    X(int64_t, quiet_since, n, -1)         /* per body: clock of its last resolve against */ \
                                           /* its supports if it applied nothing, else -1 */ \
    X(int64_t, pair_quiet_since, p, -1)    /* the same per pair inside a level */

struct Graph {
    RG_GRAPH_ROWS(RG_SPAN_FIELD)
};

// Sleeping's bookkeeping (sleep.h), kept from step to step. An island is named by its root,
// the least index of its dynamic bodies; per-island rows are kept at the root's index.
// Per body (n), allocated once:
#define RG_REST_BODY_ROWS(X)                                                                 \
    X(int64_t, island, n, -1)         /* each dynamic body's island, -1 for the others */    \
    X(int64_t, previous_island, n, -1) /* the same in the last step; -1: forgotten */        \
    X(int64_t, bodies, n, 0)          /* per island: its bodies */                           \
    X(int64_t, pairs, n, 0)           /* per island: the listed pairs of its bodies */       \
    X(int64_t, previous_bodies, n, 0) /* the same two in the last step */                    \
    X(int64_t, previous_pairs, n, 0)                                                         \
    X(uint8_t, resting, n, 0)         /* per island: is it a fixed point (exactly asleep) */ \
    X(uint8_t, slow, n, 0)            /* per island: stopped by sleep_speed */               \
    X(double, slow_time, n, 0.0)      /* s each body has moved slower than sleep_speed */    \
    X(double, snapshot, n * SNAPSHOT, 0.0) /* each body's state at the last step's start */  \
    X(uint8_t, stale, n, 0)           /* the snapshot is no fixed point's: never unchanged */ \
    X(uint8_t, kept, n, 0)            /* the broad phase carries pairs among these (mark_kept) */ \
    X(uint8_t, intact, n, 0)          /* per island of the last step: all its bodies kept */
// Per pair (P), kept through a growth of the pair buffers:
#define RG_REST_PAIR_ROWS(X)                                                                 \
    X(int64_t, previous_keys, p, 0)   /* the last step's listed pairs as a n + b, in order */ \
    X(Vec3, previous_impulse, p, Vec3{}) /* N s, their impulses */
// One per world:
#define RG_REST_COUNTS(X)                                                                    \
    X(int64_t, awake_pairs, 1, 0)     /* how many of the step's listed pairs (the first) are awake */ \
    X(int64_t, previous_count, 1, 0)  /* how many pairs the last step listed */              \
    X(int64_t, previous_awake, 1, 0)  /* how many of them (the first) were awake */          \
    X(int64_t, at_rest, 1, 0)         /* 1: every dynamic body slept through the last step */ \
    X(double, previous_dt, 1, 0.0)    /* s, the last step's dt; 0: none since forgotten */

struct Rest {
    Span<uint8_t> asleep;  // (n,) skipped by the current step (Batch::asleep)
    RG_REST_BODY_ROWS(RG_SPAN_FIELD)
    RG_REST_PAIR_ROWS(RG_SPAN_FIELD)
    RG_REST_COUNTS(RG_POINTER_FIELD)
};

// Contacts found once per step (contacts.h): per listed pair (p), a pool of rows (q), and
// per body (n) its pose predicted for them.
#define RG_CACHE_PAIR_ROWS(X)                                                                \
    X(int64_t, first, p, -1)      /* pair k's first row, -1: detected in every pass instead */ \
    X(int64_t, count, p, 0)                                                                  \
    X(Vec3, centre_a, p, Vec3{})  /* m, the pair's bodies' predicted centres at detection */ \
    X(Vec3, centre_b, p, Vec3{})                                                             \
    X(Vec3, shift_a, p, Vec3{})   /* m, their predicted displacements then */                \
    X(Vec3, shift_b, p, Vec3{})                                                              \
    X(Vec3, turn_a, p, Vec3{})    /* rad, their predicted turns then */                      \
    X(Vec3, turn_b, p, Vec3{})                                                              \
    X(PatchMemo, memo, p, PatchMemo{}) /* the contact stage's patch of the pair (patch_memo.h) */
#define RG_CACHE_POOL_ROWS(X)                                                                \
    X(Vec3, point, q, Vec3{})     /* m, world, as found */                                   \
    X(Vec3, normal, q, Vec3{})    /* from b to a */                                          \
    X(double, depth, q, 0.0)      /* m, as found */                                          \
    X(Vec3, arm_a, q, Vec3{})     /* (point - centre_a) x normal, m */                       \
    X(Vec3, arm_b, q, Vec3{})     /* (point - centre_b) x normal, m */
#define RG_CACHE_BODY_ROWS(X)                                                                \
    X(Pose, pose, n, Pose{})      /* predicted pose at the latest detection of every pair, */ \
                                  /* where posed[i] == *detections */                        \
    X(int64_t, posed, n, -1)                                                                 \
    X(Vec3, turn, n, Vec3{})      /* rad, a symmetric body's predicted turn (predicted_motion), */ \
    X(Quat, turn_from, n, Quat{}) /* found from this orientation, */                         \
    X(Vec3, turn_momentum, n, Vec3{}) /* this angular momentum, */                           \
    X(double, turn_dt, n, 0.0)    /* this dt */                                              \
    X(int64_t, turned_at, n, -1)  /* and in the step of this count of detections */
#define RG_CACHE_COUNTS(X)                                                                   \
    X(int64_t, used, 1, 0)        /* rows in use */                                          \
    X(int64_t, needed, 1, 0)      /* rows this step asked for (grown to between steps) */    \
    X(int64_t, detected, 1, 0)    /* 1 once the step's contacts are found */                 \
    X(int64_t, detections, 1, 0)  /* such detections so far */

struct ContactCache {
    RG_CACHE_PAIR_ROWS(RG_SPAN_FIELD)
    RG_CACHE_POOL_ROWS(RG_SPAN_FIELD)
    RG_CACHE_BODY_ROWS(RG_SPAN_FIELD)
    RG_CACHE_COUNTS(RG_POINTER_FIELD)
};

// The step's own rows (step.cpp, solver.h, overlap.h), n bodies.
#define RG_STEP_ROWS(X)                                                                       \
    X(Vec3, start, 3 * n, Vec3{})   /* velocity, angular momentum and angular velocity when */ \
                                    /* the impulse stages began (restored to rerun them) */    \
    X(int64_t, pairs_of, n, 0)      /* in how many listed pairs each body is */               \
    X(Vec3, overlap_shift, n, Vec3{}) /* m, overlap.h's position corrections */               \
    X(Vec3, reaction, 2 * n, Vec3{}) /* N s, N m s: shock propagation's reactions held back */ \
                                     /* (solver.h), linear then angular, 0 between rounds */

// One world's step: its rows of every buffer, the step's dt and the stages it runs (Box2D's
// b2StepContext). Batch::world makes one for each world a call steps.
struct StepContext {
    const Geometry* geo;
    const Settings* settings;
    const StageSwitches* stages;  // stage_rules of the settings, the scene's gravity and joints
    double dt = 0.0;              // s, the step's
    double gravity = 0.0;         // |g|, m/s^2
    Vec3 up = {0.0, 0.0, 1.0};    // unit vector against gravity
    BodyStates bodies;
    BodyModel model;
    Attachments attached;
    PairLists lists;
    int64_t* pair_count;     // may exceed the capacity: the buffers are too small
    Span<Vec3> pair_impulse;  // (P,) N s, each pair's impulse on its body a in the current step
    RG_STEP_ROWS(RG_SPAN_FIELD)
    ContactCache contacts;   // the step's contacts, found once
    Span<const double> body_reach;  // (n,) m, the largest distance of a body's point from its
                                    //      centre (bounded bodies; 0 for planes)
    ContactSet scratch;      // one pair's contacts (C, the pair contact capacity)
    ContactSet wide;         // one body's contacts with all its frozen supports
    Graph graph;
    Rest rest;
    JointRows joints;        // joints.h
    StageTimers timers;      // the world's time per stage, filled by step_world

    int num_bodies() const { return static_cast<int>(bodies.position.size); }
    int64_t pair_capacity() const { return lists.pair_a.size; }
};

// Room for one body's contacts with its frozen supports in shock propagation, in pair
// capacities (a box on up to 4 boxes combines them all; beyond that supports are resolved
// one by one).
constexpr int SUPPORT_CONTACTS = 4;

// The batched buffers behind a ContactSet: B worlds of c contacts.
struct ContactSetBuffers {
    RG_CONTACT_SET_ROWS(RG_ARRAY_FIELD)
    int64_t contacts = 0;

    void allocate(int num_worlds, int64_t num_contacts);
    ContactSet rows(int w);
};

// The batched buffers behind a ContactCache: B worlds of n bodies, P pairs and Q rows.
// World w may use the first limit[w] <= Q of its rows: a limit grows only with what its own
// world's steps needed, so whether a step overflows (and is run again, which wakes the
// world: contacts.h) is the same alone and beside any other worlds in a batch.
struct ContactCacheBuffers {
    RG_CACHE_PAIR_ROWS(RG_ARRAY_FIELD)
    RG_CACHE_POOL_ROWS(RG_ARRAY_FIELD)
    RG_CACHE_BODY_ROWS(RG_ARRAY_FIELD)
    RG_CACHE_COUNTS(RG_ARRAY_FIELD)
    Array<int64_t> limit;
    int64_t bodies = 0, pairs = 0, rows = 0;

    void allocate_bodies(int num_worlds, int64_t num_bodies);
    void allocate_pairs(int num_worlds, int64_t num_pairs);
    // Q = num_rows rows per world, every world's limit Q.
    void allocate_rows(int num_worlds, int64_t num_rows);
    // Each world whose last step needed more rows than its limit gets twice that need as its
    // limit; Q grows to the largest limit (the rows are found again in every step).
    void fit_rows(int num_worlds);
    // Q = num_rows rows per world, the limits left as they are.
    void allocate_storage(int num_worlds, int64_t num_rows);
    ContactCache view(int w);
};

// The batched buffers behind a PairLists (broad_phase.h): B worlds of n bodies and P pairs.
// pair_a and pair_b hold what the last step listed (read by queries); each world keeps its
// first rows when P grows. order starts as 0..n-1 in every world.
struct PairListBuffers {
    RG_PAIR_LIST_BODY_ROWS(RG_ARRAY_FIELD)
    RG_PAIR_LIST_PAIR_ROWS(RG_ARRAY_FIELD)
    int64_t row_bodies = 0, row_pairs = 0;  // n, P

    void allocate_bodies(int num_worlds, int64_t num_bodies);
    void allocate_pairs(int num_worlds, int64_t num_pairs);
    PairLists rows(int w);
};

// The batched buffers behind the step's own rows (RG_STEP_ROWS): B worlds of n bodies.
struct StepBuffers {
    RG_STEP_ROWS(RG_ARRAY_FIELD)
    int64_t row_bodies = 0;  // n

    void allocate(int num_worlds, int64_t num_bodies);
    // World w's rows, into the step context.
    void view(int w, StepContext& out);
};

// The batched buffers behind a Graph: B worlds of n bodies and P pairs, allocated afresh
// when P grows (scratch).
struct GraphBuffers {
    RG_GRAPH_ROWS(RG_ARRAY_FIELD)
    int64_t bodies = 0, pairs = 0;

    void allocate(int num_worlds, int64_t num_bodies, int64_t num_pairs);
    Graph rows(int w);
};

// The batched buffers behind a Rest (all but asleep, which is Batch's): B worlds of n bodies
// and P pairs. The per-pair rows keep each world's first rows when P grows.
struct RestBuffers {
    RG_REST_BODY_ROWS(RG_ARRAY_FIELD)
    RG_REST_PAIR_ROWS(RG_ARRAY_FIELD)
    RG_REST_COUNTS(RG_ARRAY_FIELD)
    int64_t row_bodies = 0, row_pairs = 0;  // n, P

    void allocate_bodies(int num_worlds, int64_t num_bodies);
    void allocate_pairs(int num_worlds, int64_t num_pairs);
    // World w's rows, asleep its rows of Batch::asleep.
    Rest rows(int w, Span<uint8_t> asleep);
};

// The batched buffers behind a JointRows: the model of J joints, shared by the worlds, and B
// worlds' rows of J joints and of their solve (n bodies).
struct JointBuffers {
    RG_JOINT_MODEL_ROWS(RG_ARRAY_FIELD)
    RG_JOINT_WORLD_ROWS(RG_ARRAY_FIELD)
    RG_JOINT_SOLVE_ROWS(RG_ARRAY_FIELD)
    int64_t row_bodies = 0;  // n

    // The per-world rows of the model's joints: every limit open, every motor off.
    void allocate(int num_worlds, int64_t num_bodies);
    JointRows view(int w);
    int64_t size() const { return kind.size(); }
};

// The batch: every buffer the step reads and writes for B worlds of one scene.
class Batch {
public:
    // B worlds of n bodies (motion (n,)), their geometry, gravity (m/s^2), the solver's
    // settings and the contact capacity of one pair (max_pair_contacts in geometry.py).
    Batch(int num_worlds, Geometry geometry, std::vector<int32_t> motion, Vec3 gravity,
          Settings settings, int64_t pair_contacts);

    int num_worlds() const { return num_worlds_; }
    int num_bodies() const { return num_bodies_; }
    int64_t pair_capacity() const { return pair_capacity_; }
    const Geometry& geometry() const { return geometry_; }
    const Settings& settings() const { return settings_; }
    const StageSwitches& stages() const { return stages_; }

    // The rows of world w.
    StepContext world(int w);

    // Make room for at least `needed` pairs per world, keeping the pairs listed so far.
    void grow_pairs(int64_t needed);

    // Let each world's contact pool hold what its last step needed (ContactCacheBuffers).
    void fit_contact_rows();

    // The scene's J joints (joint_rows.h: kinds, bodies, anchors, axes and references),
    // every world's limits open and motors off (set through `joints`' per-world rows); made
    // once, before stepping. Switches the joint stages on (stages.h) where J > 0, and marks
    // the articulated bodies (solver/mobility.h): those whose every joint holds them to a
    // static or kinematic body or the world frame, and no joint to them.
    void set_joints(Array<int32_t> kind, Array<int32_t> body_a, Array<int32_t> body_b,
                    Array<Vec3> anchor_a, Array<Vec3> anchor_b, Array<Vec3> axis_a,
                    Array<Vec3> axis_b, Array<Quat> reference);

    // No body of worlds [first, last) sleeps in their next step: what changed cannot be seen
    // in their state (masses, materials, attachments, a reset).
    void forget(int first, int last);

    // Batched state (B, n), model and attachments: numpy arrays in the bindings.
    Array<Vec3> position, velocity, angular_momentum, angular_velocity, force, torque;
    Array<Quat> orientation;
    Array<Mat3> rotation;
    Array<Mat3> inverse_inertia;  // derived in the step (body.h), not seen by Python
    Array<Mobility> mobility;     // (B, n) where a body is articulated, else empty: the same
    Array<int32_t> motion;  // (n,)
    Array<uint8_t> articulated;  // (n,) BodyModel::articulated, set by set_joints
    Array<double> inverse_mass, friction, restitution;
    Array<Vec3> inverse_moments;
    Vec3 gravity;
    Array<int32_t> attach_parent;
    Array<Vec3> attach_offset_position;
    Array<Quat> attach_offset_orientation;
    // What the last step listed, per world: read by queries.
    Array<int64_t> pair_count;      // (B,)
    PairListBuffers lists;          // pair_a, pair_b (B, P)
    Array<Vec3> pair_impulse;       // (B, P)
    Array<uint8_t> asleep;          // (B, n)
    // Time per stage of every step so far (timers.h), per world: read by World.profile().
    Array<double> stage_seconds;    // (B, STAGE_COUNT) s
    Array<int64_t> stage_calls;     // (B, STAGE_COUNT)
    Array<int64_t> stage_resolves;  // (B, STAGE_COUNT)
    // Joints (joint_rows.h): the model, and per world limits, motors, the last step's impulses.
    JointBuffers joints;
    bool timed = false;             // read the clock in every stage (timers.h)
    BatchSharing sharing;           // step on the calling thread or the pool (sharing.h)

private:
    void allocate_pairs(int64_t capacity);

    int num_worlds_, num_bodies_;
    int64_t pair_capacity_ = 0;
    Geometry geometry_;
    Settings settings_;
    StageSwitches stages_;
    double gravity_length_;
    Vec3 up_;
    StepBuffers step_;
    // impulse stages
    ContactCacheBuffers contacts_;
    Array<double> body_reach_;  // (n,) shared by the worlds
    ContactSetBuffers scratch_, wide_;
    GraphBuffers graph_;
    RestBuffers rest_;  // sleeping
};

}  // namespace rg
