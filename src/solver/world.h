// StepContext: every buffer the step reads and writes for a batch of B worlds of one scene,
// and WorldStep, the rows of one world that the stages work on.
//
// Buffers are allocated when the context is made and reused by every step. The pair buffers
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
#include "solver/sharing.h"
#include "solver/timers.h"

namespace rg {

// What SolverConfig decides, as the stages take it.
struct Settings {
    int collision_passes = 5;  // 0: phase off
    int contact_passes = 10;   // 0: phase off
    int shock_sweeps = 2;      // 0: phase off
    int rotation_order = 2;    // 1, 2 or 3 (integrate.h)
    bool sweep = false;        // broad phase by sort and sweep (else brute force)
    bool broad_phase = true;   // whether pairs are listed at all
    bool sleep = true;         // sleep.h
    double sleep_speed = 0.0;  // sleep.h: m/s under which a slow island is stopped; 0: exact only
    bool detect_every_pass = false;  // contacts.h: the narrow phase in every pass
    bool keep_energy = true;   // integrate.h: rotation update put back on the body's energy
    double overlap_correction = 1.0;  // overlap.h: fraction of excess overlap removed per step
    bool contact_patches = true;  // solver.h: patch wrenches between movable bodies, and a body
                                  //   held by immovable ones against all of them at once
    bool patch_reactions = true;  // solver.h: shock impulses booked to pairs by the lever rule,
                                  //   friction's reaction passed to dynamic supports
    double gravity = 0.0;      // |g|, m/s^2
    Vec3 up = {0.0, 0.0, 1.0};  // unit vector against gravity
};

// Shock propagation's work rows (n bodies, P pair capacity).
struct Graph {
    // The graph's nodes are the bodies of the stage's pairs (graph_nodes): with sleeping, the
    // bodies of the awake pairs, so an asleep body costs the stage nothing. Rows marked
    // "per node" are indexed by node; a node's body is nodes[node].
    Span<int64_t> nodes;            // (n,) the bodies of the pairs, in index order
    Span<int64_t> node_of;          // (n,) each body's node, -1 outside the stage
    Span<uint8_t> touching;         // (P,) the pair touches at the predicted poses
    Span<int64_t> edge_from;        // (2P,) support edges, lower body to upper
    Span<int64_t> edge_to;          // (2P,)
    Span<int64_t> edge_start;       // (n + 1,) CSR form of the edges, per node
    Span<int64_t> targets;          // (2P,) nodes
    Span<int64_t> component;        // (n,) per node: Tarjan's strongly connected components
    Span<int64_t> component_level;  // (n,)
    Span<int64_t> by_component;     // (n,)
    Span<int64_t> index;            // (n,) Tarjan's bookkeeping
    Span<int64_t> low;              // (n,)
    Span<uint8_t> on_stack;         // (n,)
    Span<int64_t> stack;            // (n,)
    Span<int64_t> calls;            // (n,)
    Span<int64_t> next_edge;        // (n,)
    Span<int64_t> level;            // (n,) per node: its level, 0 for static and kinematic
    Span<int64_t> by_level;         // (n,) the nodes by level
    Span<int64_t> counts;           // (n + 2,) counting sorts
    Span<int64_t> body_pair_start;  // (n + 1,) each node's touching pairs, CSR
    Span<int64_t> body_pairs;       // (2P,)
    Span<int64_t> level_pair_start; // (n + 2,) the touching pairs inside each level, CSR
    Span<int64_t> level_pairs;      // (P,)
};

// Sleeping's bookkeeping (sleep.h), kept from step to step. An island is named by its root,
// the least index of its dynamic bodies; per-island rows are kept at the root's index.
struct Rest {
    Span<uint8_t> asleep;             // (n,) skipped by the current step
    int64_t* awake_pairs;             // how many of the step's listed pairs (the first) are awake
    Span<int64_t> island;             // (n,) each dynamic body's island, -1 for the others
    Span<int64_t> previous_island;    // (n,) the same in the last step; -1: forgotten
    Span<int64_t> bodies;             // (n,) per island: its bodies
    Span<int64_t> pairs;              // (n,) per island: the listed pairs of its bodies
    Span<int64_t> previous_bodies;    // (n,) the same two in the last step
    Span<int64_t> previous_pairs;     // (n,)
    Span<uint8_t> resting;            // (n,) per island: is it a fixed point (exactly asleep)
    Span<uint8_t> slow;               // (n,) per island: stopped by sleep_speed
    Span<double> slow_time;           // (n,) s each body has moved slower than sleep_speed
    Span<double> snapshot;            // (n * SNAPSHOT,) each body's state at the last step's start
    Span<int64_t> previous_keys;      // (P,) the last step's listed pairs as a n + b, in order
    Span<Vec3> previous_impulse;      // (P,) N s, their impulses
    int64_t* previous_count;          // how many pairs the last step listed
    int64_t* previous_awake;          // how many of them (the first) were awake
    int64_t* at_rest;                 // 1: every dynamic body slept through the last step
    Span<uint8_t> kept;               // (n,) the broad phase carries pairs among these from the
                                      //      last step's list (mark_kept, sleep.h)
    Span<uint8_t> intact;             // (n,) per island of the last step: all its bodies kept
    double* previous_dt;              // s, the last step's dt; 0: none since forgotten
};

// Contacts found once per step (contacts.h): per listed pair (P,), a pool of rows (Q,), and
// per body (n,) its pose predicted for them.
struct ContactCache {
    Span<int64_t> first;       // (P,) pair k's first row, -1: detected in every pass instead
    Span<int64_t> count;       // (P,)
    Span<Vec3> centre_a;       // (P,) m, the pair's bodies' predicted centres at its detection
    Span<Vec3> centre_b;       // (P,)
    Span<Vec3> shift_a;        // (P,) m, their predicted displacements then
    Span<Vec3> shift_b;        // (P,)
    Span<Vec3> turn_a;         // (P,) rad, their predicted turns then
    Span<Vec3> turn_b;         // (P,)
    Span<Vec3> point;          // (Q,) m, world, as found
    Span<Vec3> normal;         // (Q,) from b to a
    Span<double> depth;        // (Q,) m, as found
    Span<Vec3> arm_a;          // (Q,) (point - centre_a) x normal, m
    Span<Vec3> arm_b;          // (Q,) (point - centre_b) x normal, m
    int64_t* used;             // rows in use
    int64_t* needed;           // rows this step asked for (the pool grows to it between steps)
    int64_t* detected;         // 1 once the step's contacts are found (reset by the broad phase)
    Span<Pose> pose;           // (n,) each body's predicted pose at the latest detection of
                               //      every pair, where posed[i] == *detections
    Span<int64_t> posed;       // (n,)
    int64_t* detections;       // such detections so far
};

// Floats of a body's state compared by sleeping: position 3, orientation 4, velocity 3,
// angular momentum 3, angular velocity 3, rotation 9.
constexpr int SNAPSHOT = 25;

// One world's rows of every buffer: what a step of that world reads and writes.
struct WorldStep {
    const Geometry* geo;
    const Settings* settings;
    BodyStates bodies;
    BodyModel model;
    Attachments attached;
    PairLists lists;
    int64_t* pair_count;     // may exceed the capacity: the buffers are too small
    Span<Vec3> pair_impulse;  // (P,) N s, each pair's impulse on its body a in the current step
    Span<Vec3> start;        // (3 n,) velocity, angular momentum and angular velocity when
                             //        the step's impulse stages began (restored to rerun them)
    ContactCache contacts;   // the step's contacts, found once
    Span<const double> body_reach;  // (n,) m, the largest distance of a body's point from its
                                    //      centre (bounded bodies; 0 for planes)
    ContactSet scratch;      // one pair's contacts (C, the pair contact capacity)
    ContactSet wide;         // one body's contacts with all its frozen supports
    Span<int64_t> pairs_of;  // (n,) in how many listed pairs each body is
    Span<Vec3> overlap_shift;  // (n,) m, overlap.h's position corrections
    Span<Vec3> reaction;     // (2 n,) N s, N m s: shock propagation's reactions held back
                             //        (solver.h), linear then angular, zero between rounds
    Graph graph;
    Rest rest;
    StageTimers timers;      // the world's time per stage, filled by step_world

    int num_bodies() const { return static_cast<int>(bodies.position.size); }
    int64_t pair_capacity() const { return lists.pair_a.size; }
};

// Room for one body's contacts with its frozen supports in shock propagation, in pair
// capacities (a box on up to 4 boxes combines them all; beyond that supports are resolved
// one by one).
constexpr int SUPPORT_CONTACTS = 4;

// The batched buffers behind a ContactSet: B worlds of C contacts.
struct ContactSetBuffers {
    Array<Vec3> point, normal, centre_a, centre_b;
    Array<double> depth, gap, orient;
    Array<int64_t> group, partner, source;
    int64_t contacts = 0;

    void allocate(int num_worlds, int64_t num_contacts);
    ContactSet rows(int w);
};

// The batched buffers behind a ContactCache: B worlds of n bodies, P pairs and Q rows.
// World w may use the first limit[w] <= Q of its rows: a limit grows only with what its own
// world's steps needed, so whether a step overflows (and is run again, which wakes the
// world: contacts.h) is the same alone and beside any other worlds in a batch.
struct ContactCacheBuffers {
    Array<int64_t> first, count;
    Array<Vec3> centre_a, centre_b, shift_a, shift_b, turn_a, turn_b;
    Array<Vec3> point, normal, arm_a, arm_b;
    Array<double> depth;
    Array<int64_t> used, needed, detected, limit;
    Array<Pose> pose;
    Array<int64_t> posed, detections;
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

// The batched buffers behind a Graph: B worlds of n bodies and P pairs.
struct GraphBuffers {
    Array<uint8_t> touching, on_stack;
    Array<int64_t> nodes, node_of, edge_from, edge_to, edge_start, targets, component,
        component_level, by_component, index, low, stack, calls, next_edge, level, by_level,
        counts, body_pair_start, body_pairs, level_pair_start, level_pairs;
    int64_t bodies = 0, pairs = 0;

    void allocate(int num_worlds, int64_t num_bodies, int64_t num_pairs);
    Graph rows(int w);
};

class StepContext {
public:
    // B worlds of n bodies (motion (n,)), their geometry, and the contact capacity of one
    // pair (max_pair_contacts in geometry.py).
    StepContext(int num_worlds, Geometry geometry, std::vector<int32_t> motion, Vec3 gravity,
                Settings settings, int64_t pair_contacts);

    int num_worlds() const { return num_worlds_; }
    int num_bodies() const { return num_bodies_; }
    int64_t pair_capacity() const { return pair_capacity_; }
    const Geometry& geometry() const { return geometry_; }
    const Settings& settings() const { return settings_; }

    // The rows of world w.
    WorldStep world(int w);

    // Make room for at least `needed` pairs per world, keeping the pairs listed so far.
    void grow_pairs(int64_t needed);

    // Let each world's contact pool hold what its last step needed (ContactCacheBuffers).
    void fit_contact_rows();

    // No body of worlds [first, last) sleeps in their next step: what changed cannot be seen
    // in their state (masses, materials, attachments, a reset).
    void forget(int first, int last);

    // Batched state (B, n), model and attachments: numpy arrays in the bindings.
    Array<Vec3> position, velocity, angular_momentum, angular_velocity, force, torque;
    Array<Quat> orientation;
    Array<Mat3> rotation;
    Array<Mat3> inverse_inertia;  // derived in the step (body.h), not seen by Python
    Array<int32_t> motion;  // (n,)
    Array<double> inverse_mass, friction, restitution;
    Array<Vec3> inverse_moments;
    Vec3 gravity;
    Array<int32_t> attach_parent;
    Array<Vec3> attach_offset_position;
    Array<Quat> attach_offset_orientation;
    // What the last step listed, per world: read by queries.
    Array<int64_t> pair_count;      // (B,)
    Array<int32_t> pair_a, pair_b;  // (B, P)
    Array<Vec3> pair_impulse;       // (B, P)
    Array<uint8_t> asleep;          // (B, n)
    // Time per stage of every step so far (timers.h), per world: read by World.profile().
    Array<double> stage_seconds;    // (B, STAGE_COUNT) s
    Array<int64_t> stage_calls;     // (B, STAGE_COUNT)
    bool timed = false;             // read the clock in every stage (timers.h)
    BatchSharing sharing;           // step on the calling thread or the pool (sharing.h)

private:
    void allocate_pairs(int64_t capacity);

    int num_worlds_, num_bodies_;
    int64_t pair_capacity_ = 0;
    Geometry geometry_;
    Settings settings_;
    // broad phase, per body (n) and per pair (P)
    Array<Aabb> bounds_;
    Array<int64_t> order_, keys_, spare_;
    Array<double> reach_;
    Array<Vec3> start_;  // (B, 3 n)
    // impulse stages
    ContactCacheBuffers contacts_;
    Array<double> body_reach_;
    ContactSetBuffers scratch_, wide_;
    Array<int64_t> pairs_of_;
    Array<Vec3> overlap_shift_;
    Array<Vec3> reaction_;
    GraphBuffers graph_;
    // sleeping
    Array<int64_t> awake_pairs_, island_, previous_island_, island_bodies_, island_pairs_,
        previous_bodies_, previous_pairs_, previous_keys_, previous_count_, previous_awake_,
        at_rest_;
    Array<uint8_t> resting_, slow_, kept_, intact_;
    Array<double> slow_time_, previous_dt_;
    Array<double> snapshot_;
    Array<Vec3> previous_impulse_;
};

}  // namespace rg
