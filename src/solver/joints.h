// Joints: revolute, prismatic and fixed, each with limits and a motor, solved as impulses
// inside the step (Weinstein, Teran & Fedkiw 2006, "Dynamic simulation of articulated rigid
// bodies with contact and collision", IEEE TVCG 12(3)).
//
// A joint holds dynamic body a to body b (static, kinematic, dynamic, or the world frame:
// b = WORLD_BODY). Its anchor and axis are fixed in each body's frame (the principal frame,
// origin at the centre of mass); `reference` is a's orientation in b's frame at coordinate 0.
// Its coordinate is a's angle about the axis relative to b (revolute, rad, in (-pi, pi]) or
// a's anchor's travel along b's axis from b's anchor (prismatic, m); a fixed joint has none.
//
// Constraint rows (up to 6 a joint, Jacobian rows (la, aa, lb, ab): the row's rate is
// la.V_a + aa.omega_a + lb.V_b + ab.omega_b):
//   point (revolute, fixed): the anchors coincide, 3 rows along the world axes;
//   line (prismatic): a's anchor on b's axis through b's anchor, 2 rows across the axis;
//   orientation (prismatic, fixed): a's orientation is b's times reference, 3 rows;
//   axis (revolute): a's axis along b's, 2 rows across it;
//   and along the free coordinate, where the joint has one: the motor (rate towards
//   motor_speed, impulse within max_motor dt over the step) and the limits (one-sided).
//
// Two stages, the paper's, and a projection after the position update, each solving the
// rows of each awake component of joints (bodies joined through joints: JointRows::order)
// at once: one dense system (Gaussian elimination with partial pivoting, R <= 6 J rows,
// O(R^3)), so a chain is as exact as one joint, and a component's bits do not depend on
// another's (sleep.h); joint-by-joint passes (Gauss-Seidel) left a 10-link chain's
// velocities off by millimetres a step after 100 passes and it blew up. (Baraff's O(n)
// factorisation of a tree of joints is the way to many joints.)
// * solve_joint_velocities, after the velocity update: every equality row at rate 0, and
//   where a joint would pass a limit within the step, that limit (rate at least (lower -
//   s) / dt, at most (upper - s) / dt), else its motor (rate motor_speed). A coordinate row
//   whose impulse leaves its bounds (the motor beyond max_motor dt, a limit pulling) is held
//   at the bound and the rest solved again (an active set, up to Settings::joint_passes
//   rounds).
// * stabilize_joint_positions (pre-stabilisation), after the contact and shock stages: the
//   impulses after which the poses the position update will reach (X + dt V, q turned by
//   omega dt) satisfy every joint to POSITION_TOLERANCE (and its limits), by Newton steps on
//   those predicted poses (up to joint_passes, each halved while it does not lower the
//   error). Drift is removed in the step that would make it, not fed back as a velocity bias
//   (Baumgarte).
// * project_joint_velocities, after the position update: the equality rows at rate 0 at the
//   new poses, taking out the correction velocity pre-stabilisation left.
// The three make RATTLE (Andersen 1983) of the joints: symplectic, so a pendulum's period
// is second order in dt and its energy oscillates by O(dt) (symplectic Euler's velocity
// update) without drifting.
// Bodies joined by a joint do not collide (drop_joined_pairs), form one island for sleeping
// (sleep.h), and count as acted on in the position update (integrate.h: no energy restore).
#pragma once

#include <cstdint>

#include "collision/broad_phase.h"
#include "solver/world.h"

namespace rg {

enum JointKind : int32_t { REVOLUTE = 0, PRISMATIC = 1, FIXED = 2 };

// body_b of a joint held to the world frame.
constexpr int32_t WORLD_BODY = -1;

// m (point and line rows) or rad (orientation and axis rows): pre-stabilisation stops once
// every joint's predicted error is below this.
constexpr double POSITION_TOLERANCE = 1e-12;

// w.joints: in how many joints each dynamic body is, added to w.pairs_of (solver.h), so that
// the position update treats a jointed body as one that took an impulse.
void count_joints_of_bodies(StepContext& w);

// Remove from the first `count` listed pairs (sorted by key a n + b, broad_phase.h) those of
// two bodies joined by a joint; returns how many remain, in order.
int64_t drop_joined_pairs(const JointRows& joints, const PairLists& lists, int64_t count,
                          int64_t num_bodies);

// The joint velocity stage over the awake joints (see top); clears their reported impulses
// first (an asleep joint reports its last step's, as stepping it would: sleep.h).
void solve_joint_velocities(StepContext& w, double dt);

// The pre-stabilisation stage over the awake joints (see top).
void stabilize_joint_positions(StepContext& w, double dt);

// After the position update, with I(t)^-1 refreshed at the new orientations: the awake
// joints' equality rows brought to rate 0 at the new poses (no motor or limit), RATTLE's
// last projection: the step ends with velocities the joints allow, which the pre-
// stabilisation's correction velocity is not (its kinetic energy, up to 1% of a fast
// 10-link chain's, would show as energy the bodies do not have).
void project_joint_velocities(StepContext& w, double dt);

// The Mobility (mobility.h) of each articulated body in one of the first `pairs` listed pairs,
// at the current poses from its joints' equality rows, with I(t)^-1 as formed for the step:
// when the pairs are listed, before the impulse stages. Only a body in a pair takes contact
// impulses (the one use of G), so a finger touching nothing costs no G; a relisting forms it
// again for every paired body (the same poses and I(t)^-1: the same bits).
void form_joint_mobility(StepContext& w, int64_t pairs);

// Joint j's coordinate at the bodies' current poses: rad (revolute), m (prismatic), 0 (fixed).
double joint_coordinate(const StepContext& w, int64_t j);

}  // namespace rg
