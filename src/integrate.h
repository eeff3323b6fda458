// Time integration of free motion (course notes slides 10-16; Buss, JCP 164, 2000).
//
// Linear motion is symplectic Euler: V += dt (g + F/M), X += dt V_new. Angular: L += dt tau,
// then q is advanced by the exact rotation of slide 13 with an effective angular velocity
// omega_bar:
//     order 1: omega_bar = omega
//     order 2: omega_bar = omega + h/2 alpha                            (Buss's second order)
//     order 3: omega_bar = omega + h/2 alpha + h^2/6 omega'' + h^2/12 alpha x omega
//              (Buss's third order), alpha = I^-1 (L x omega + tau).
// A step is cut into sub-steps of at most a quarter turn (|omega| h <= pi/2, slide 14).
#pragma once

#include "body.h"

namespace rg {

// R(q) for every body and omega = I(t)^-1 L for the dynamic ones (after q or L were set).
void refresh_rotation_and_angular_velocity(const BodyStates& bodies, const BodyModel& model);

// V += dt (g + F/M), L += dt tau, omega = I(t)^-1 L, for the dynamic bodies.
void update_velocities(const BodyStates& bodies, const BodyModel& model, double dt);

// X += dt V; advance q by the rotation of the step; refresh R and omega. Dynamic bodies rotate
// in sub-steps of at most a quarter turn, each re-evaluating omega from L at the current
// orientation; kinematic bodies turn at their set angular velocity (exact).
void update_positions(const BodyStates& bodies, const BodyModel& model, double dt, int order);

// Put every attached body at its offset from its parent, moving with the parent's velocity
// and not turning.
void place_attached(const BodyStates& bodies, const Attachments& attached);

}  // namespace rg
