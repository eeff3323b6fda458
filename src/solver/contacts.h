// Contacts found once per step, and their separations carried through the impulse stages.
//
// The impulse stages judge every contact at the poses predicted for the end of the step
// (solver.h). Running the narrow phase again in every pass at the poses the pass's velocities
// predict costs ~130 narrow phases a step for a 10-box stack. Instead each listed pair's
// contacts are found once, at the predicted poses, within SPECULATIVE_MARGIN (contacts up to
// that far apart are kept, inactive), and a pass updates each contact's separation from the
// bodies' change of predicted displacement since then, moving the contact rigidly with both
// bodies (the linearisation of Box2D v3's relax iterations):
//
//     depth = depth_0 - [dD_a . n + dTheta_a . (r_a x n) - dD_b . n - dTheta_b . (r_b x n)]
//
// with D_i = lookahead_i + dt V_i the predicted displacement of body i's centre, Theta_i =
// dt omega_i its predicted turn, r_i the contact's lever from that centre and n the normal (B
// to A). A contact takes part in a pass while its depth is above the pass's threshold (0 for
// impulses, -GRAPH_MARGIN for shock propagation's supports, more for its graph), as a
// contact the narrow phase found there would. Points, normals and levers stay as found: within the margin the
// bodies' turns move them by less than a margin times the turn. When a pair's bodies have
// moved further than the margin allows since its detection (a collision reversed a body, a
// stack above pushed harder), the pair is detected again at the current prediction before the
// pass uses it, so no contact the narrow phase would find is missed. Motion along the shared
// normal of a pair with an articulated body does not count (contacts.cpp, along_normal_exempt:
// a finger pushed into the cube it presses by its motor, and back by the contact stage). With
// Settings::detect_every_pass the narrow phase runs in every pass instead (the original GBF
// formulation, kept to measure the difference). A pair whose bodies move far relative to each
// other in a step is found where they meet instead, its depths carried on to the end of the
// step (Settings::continuous, continuous.h), wherever the narrow phase runs.
//
// The pool of contact rows has a capacity per world that grows between steps to what the
// world's own last step needed (world.h: not what other worlds of its batch needed). A step
// whose contacts do not all fit in its impulse stages (pool_overflowed) is abandoned before its position update and run again whole once the
// pool has grown (step.cpp), as a step whose pairs overflow their buffers is. The overlap
// correction after them needs no rerun: it asks at the detection's own margin with the final
// velocities, so a pair it must find again at the current prediction gets the same narrow
// phase call whether its rows fit (drift 0 from there) or not (collide_now). So a row the pool
// could not hold never changes a trajectory: a world steps bit for bit the same alone or
// beside a batch's larger worlds, and with sleeping on or off (asleep pairs take no rows).
// The rerun step wakes its world; with Settings::sleep_speed, whose stops change trajectories
// anyway, that restarts its islands' slow time, and an island the abandoned step stopped
// stays stopped: the same alone and in any batch, since the world's own pool decides the
// rerun. The step allocates nothing.
#pragma once

#include "solver/contact_set.h"
#include "solver/world.h"

namespace rg {

// m: contacts this far apart at the predicted poses are found and kept, inactive.
constexpr double SPECULATIVE_MARGIN = 2e-3;

// Contacts closer than this (m) at the predicted poses count as touching in shock
// propagation's patches against a body's frozen supports (a rocking box's lifting corners
// belong to the face it rests on; the patch wrench decides whether the patch holds, j_n > 0);
// its graph orders the pairs within a wider reach (shock.cpp).
constexpr double GRAPH_MARGIN = 1e-4;

// Find every listed pair's contacts at the predicted poses (displacement lookahead + dt V for
// dynamic bodies, dt V for kinematic ones; lookahead in m), within SPECULATIVE_MARGIN.
void detect_contacts(StepContext& w, int64_t pairs, double dt, Vec3 lookahead);

// What gather_pair writes: pair k's contacts whose depth is above `threshold` (m), into set
// from row `at`, as contacts of body `body` (one of the pair's) against the other.
struct Gather {
    int64_t k;
    int body;
    double threshold;
};

// Write pair g.k's current contacts (see Gather) into set from row g's `at`, normals turned
// towards g.body, partner the other body, source k, orient +1 if body is the pair's a, -1 if
// its b, the two bodies' predicted centres. Returns how many there are: more than fit means
// the set is too small and only what fitted was written (the caller resolves the pair alone).
int64_t gather_pair(StepContext& w, const Gather& g, double dt, Vec3 lookahead,
                    const ContactSet& set, int64_t at);

// Contacts found, and their rows, per world: what the pool should hold in the next step.
int64_t contact_rows_needed(const StepContext& w);

// Did some pair's contacts not fit the pool in this step? Its stages then ran with that pair
// found anew in every pass (gather_pair), which rounds differently: the step must be run
// again once the pool has grown.
bool pool_overflowed(const StepContext& w);

}  // namespace rg
