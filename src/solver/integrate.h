// Time integration of free motion (Guendelman, Bridson & Fedkiw 2003; Buss, "Accurate and
// efficient simulation of rigid-body rotations", J. Comput. Phys. 164, 2000).
//
// Linear motion is symplectic Euler: V += dt (g + F/M), X += dt V_new. Angular: L += dt tau,
// then q is advanced by the exact rotation through omega_bar h with an effective angular velocity
// omega_bar:
//     order 1: omega_bar = omega
//     order 2: omega_bar = omega + h/2 alpha                            (Buss's second order)
//     order 3: omega_bar = omega + h/2 alpha + h^2/6 omega'' + h^2/12 alpha x omega
//              (Buss's third order), alpha = I^-1 (L x omega + tau).
// Buss's update starts from the step's (sub-step's) initial state, so for a body that took no
// impulse it is taken from L at the start of each sub-step (L minus the torque's share of the
// step still to come): a constant torque from rest then turns the body exactly at orders 2
// and 3, instead of counting the torque twice (once in L, once in alpha). A body that took an
// impulse was given its velocities by contacts judged at poses predicted with the final
// omega, so its torque stays in L alone (symplectic Euler, as the force in V) and alpha keeps
// only the gyroscopic part L x omega: adding the torque's share again, or taking it away,
// slides a block tipping about its edge by millimetres.
// A step is cut into sub-steps of at most a quarter turn (|omega| h <= pi/2), and into
// at most MAX_ROTATION_SUBSTEPS of them: beyond 64 quarter turns a step (|omega| > 32 pi / dt,
// 24,127 rad/s at dt = 1/240 s) each sub-step turns further, so a step's cost stays bounded
// whatever the speed. The exact rotation is still exact for a constant omega (a
// sphere, a symmetric top about its axis); what grows is the error of the effective angular
// velocity over the longer sub-steps (a tumbling asymmetric body), and L stays exact.
#pragma once

#include "base/body.h"

namespace rg {

constexpr int MAX_ROTATION_SUBSTEPS = 64;

// The body axis (0, 1, 2) about which a body with exactly two equal principal moments is
// symmetric (the third moment differs), or -1 (all three equal, or none).
int symmetry_axis(Vec3 inverse_moments);

// The exact torque-free motion over h (s) of a body symmetric about body axis `axis`, at
// orientation q (rotation r) with world angular momentum l: a turn about l by |l| h / I1
// (world side) and a spin about the symmetry axis by (1/I3 - 1/I1) L3 h (body side), I1 the
// two equal moments, I3 the axis's, L3 = l along the axis (constant). omega = l / I1 +
// (1/I3 - 1/I1) L3 e3 is exactly the sum of the two turns' rates, and the axis e3 only turns
// with the first, so this is the motion for any h: |L| and the energy are kept exactly, where
// Buss's updates, expansions in omega h, are unstable for a fast flat top (I3 near 2 I1) once
// |omega| h > ~0.4 (a top spinning on its tip gained 74% energy in 1 s at |omega| h = 1.25).
Quat symmetric_rotation(Quat q, const Mat3& r, Vec3 l, Vec3 inverse_moments, int axis, double h);

// q advanced over h (s) free of torque, as the contact stages predict a dynamic body's pose:
// symmetric_rotation for a symmetric body (l: its world angular momentum), else the turn by
// omega h (rad/s world; exact for a sphere's constant omega, first order otherwise).
Quat turned(Quat q, const Mat3& r, Vec3 l, Vec3 omega, Vec3 inverse_moments, double h);

// The rotation vector (axis times angle, rad, world frame, angle in [0, pi]) of to from^-1.
Vec3 turn_between(Quat from, Quat to);

// Sub-steps of the rotation update for angular speed |omega| (rad/s) over dt (s).
int rotation_substeps(double speed, double dt);

// R(q) for every body and omega = I(t)^-1 L for the dynamic ones (after q or L were set).
void refresh_rotation_and_angular_velocity(const BodyStates& bodies, const BodyModel& model);

// I(t)^-1 = R diag(1/I) R^T of every body into bodies.inverse_inertia (0 unless dynamic),
// but those of `kept` (empty, or (n,) nonzero where it holds already: an asleep body unchanged
// since its last refresh, sleep.h).
void refresh_inverse_inertia(const BodyStates& bodies, const BodyModel& model,
                             Span<const uint8_t> kept = {});

// V += dt (g + F/M), L += dt tau, omega = I(t)^-1 L, for the dynamic bodies (with
// bodies.inverse_inertia), but those with asleep[i] set (sleep.h; asleep empty without
// sleeping): their step ends with the velocities it started with, and no impulse stage sees
// them in between.
void update_velocities(const BodyStates& bodies, const BodyModel& model, double dt,
                       Span<const uint8_t> asleep = {});

// X += dt V; advance q by the rotation of the step; refresh R and omega. Dynamic bodies rotate
// in sub-steps of at most a quarter turn, each re-evaluating omega from L at the current
// orientation; kinematic bodies turn at their set angular velocity (exact). With keep_energy
// a free dynamic body (in no pair that took an impulse this step: acting[i] == 0, so a pair
// listed because two fast bodies' grown boxes met, but which never touched, leaves it free)
// is then turned, by the smallest body-frame rotation that does it, back onto the rotational
// energy it had (L is kept exactly: it is the stored state), so it keeps both |L| and E to
// round-off whatever dt (SolverConfig.keep_energy). A body that took an impulse is left to
// its contacts: turning it after the impulse stages would move its contact points off the
// poses the impulses were computed for (a tumbling cube's corner dug 28 mm into the ground),
// and its energy is the impulses' to change anyway.
// Bodies with asleep[i] set (sleep.h; asleep empty without sleeping) are left as they are:
// their velocities are the last step's final ones, which moved them nowhere (the step is a
// fixed point for them), so updating them would give the same bits.
// exact_symmetric: a symmetric body (symmetry_axis) with no torque in the update turns by
// symmetric_rotation instead (SolverConfig.exact_symmetric).
void update_positions(const BodyStates& bodies, const BodyModel& model, double dt, int order,
                      bool keep_energy, bool exact_symmetric, Span<const int64_t> acting,
                      Span<const uint8_t> asleep);

// Put every attached body at its offset from its parent, moving with the parent's velocity
// and not turning.
void place_attached(const BodyStates& bodies, const Attachments& attached);

}  // namespace rg
