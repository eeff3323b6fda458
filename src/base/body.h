// One world's bodies as the stages see them: rows of the batched state and model (world.h).
//
// State is held per body at the centre of mass in the principal frame: position X (m),
// orientation q (unit quaternion, principal frame to world), velocity V (m/s), angular
// momentum L about the centre of mass (world frame, kg m^2/s), and the derived angular
// velocity omega = I(t)^-1 L (rad/s; set directly for kinematic bodies) and rotation R(q),
// refreshed whenever q or L change. Force (N) and torque (N m) act during the next step.
#pragma once

#include <cstdint>

#include "base/math.h"
#include "base/span.h"

namespace rg {

enum Motion : int32_t { STATIC = 0, KINEMATIC = 1, DYNAMIC = 2 };

// The part of a wrench on a jointed body that moves it (solver/mobility.h): the wrench
// (linear N s, angular N m s about the centre of mass) as a 6-vector f goes to g f, what its
// joints do not take.
struct Mobility {
    double g[6][6];  // g[row][column]
};

struct BodyStates {
    Span<Vec3> position;
    Span<Quat> orientation;
    Span<Vec3> velocity;
    Span<Vec3> angular_momentum;
    Span<Vec3> angular_velocity;
    Span<Mat3> rotation;
    Span<Vec3> force;
    Span<Vec3> torque;
    // I(t)^-1 of every body (0 for static and kinematic ones), formed with the broad phase:
    // orientations do not change until the position update, so the impulse stages apply it
    // as one matrix product per use
    Span<Mat3> inverse_inertia;
    // each articulated body's Mobility at the step's poses (BodyModel::articulated; empty
    // where the scene has none), formed with I(t)^-1
    Span<Mobility> mobility;
};

// What stays fixed while stepping. Per-body parameters may differ between worlds (domain
// randomisation); motion classes and gravity are shared.
struct BodyModel {
    Span<const int32_t> motion;           // Motion
    Span<const double> inverse_mass;      // 1/kg, 0 for static and kinematic bodies
    Span<const Vec3> inverse_moments;     // principal 1/kg m^2, 0 on degenerate axes
    Span<const double> friction;          // a pair uses sqrt(mu_a mu_b)
    Span<const double> restitution;       // a pair uses max(e_a, e_b)
    Span<const uint8_t> articulated;      // 1: a contact moves the body as its joints let it
                                          // (solver/mobility.h), shared by the worlds
    Vec3 gravity;                         // m/s^2
};

// Bodies held rigidly by another (World.attach): parent -1 for a free body; the pose
// relative to the parent (position in the parent's frame, m; relative quaternion).
struct Attachments {
    Span<int32_t> parent;
    Span<Vec3> offset_position;
    Span<Quat> offset_orientation;
};

}  // namespace rg
