// Continuous collision: the contacts of a pair that moves far in a step, found where its
// bodies meet rather than at the end of the step.
//
// The impulse stages judge contacts at the poses predicted for the end of the step
// (contacts.h). Where a pair's relative motion in a step exceeds the thinner body's half
// thickness, the prediction can carry one body past the other's mid-plane, or past it
// altogether: a 2 cm cube at 50 m/s moves 21 cm a step at dt = 1/240 and jumps a 1 cm wall,
// and a plate falling onto a table top is found with its centre past the top's mid-plane,
// where the nearest way out is downwards (box_box.cpp's least overlap), and sinks through.
// For such a pair (Settings::continuous) the bodies are swept from their current poses to
// the predicted ones (time_of_impact.h). Where they come within SWEEP_TARGET of each other at
// fraction t < 1 of the step, the narrow phase runs at the poses of time t and each contact's
// depth is carried on to the end of the step by the rest of the motion, moving the contact
// rigidly with both bodies as contacts.h carries depths through the passes:
//
//     depth = depth_t - (1 - t) [D_a . n + Theta_a . (r_a x n) - D_b . n - Theta_b . (r_b x n)]
//
// (D, Theta: each body's predicted displacement and turn; r: the contact's levers from the
// centres at time t, which are the pair's centres for the passes). The contact stage then
// sees a contact that overlaps at the prediction, with the normal of the face the bodies
// meet at, and a start-of-step gap (gap = -(depth + dt v_n), solver.cpp) that is the real
// one. Those contacts are used only where one is carried deeper than the thinner half
// thickness: short of that the prediction passes no mid-plane, and its own contacts are
// better (the features that touch at the end of the step, not only those that touched
// first: a pile's tumbling bodies). A pair that moves less, does not meet within the step or
// is not carried that deep is found at the predicted poses as before, bit for bit (a
// falling pile of 1000 steps the same bits with continuous collision on or off).
//
// GBF's contact stage stops an approach at e = 0 without closing gaps larger than gravity
// closes in a step (patch.h, closable), so a body caught this way stops where it began the
// step, up to a step's travel short of what it meets, and gravity closes the rest over the
// next steps; with e > 0 the collision stage bounces it from there at its full speed.
//
// Thickness: a box's least half extent, a sphere's or capsule's radius, a mesh's least half
// extent of its bounding box in its body frame (an overestimate for a thin mesh lying
// diagonally in it), and a body of several geoms has its thinnest geom's. A plane's pairs are
// never swept: nothing passes a half-space and its normal never flips. Box2D v3 sweeps a body fast against its own least extent, and
// against the static world only; here the pair's relative motion is compared with the
// thinner body of the two, so that a slow box pushed at a thin moving plate is swept too.
// The rest of the step's turn is linearised, so a body turning by radians a step can still
// be missed. Nothing is allocated; the result is a function of the pair's state alone.
#pragma once

#include "collision/narrow_phase.h"
#include "solver/world.h"

namespace rg {

// m: the sweep stops this far short of contact, within the speculative margin (contacts.h),
// so the narrow phase at time t finds the contact.
constexpr double SWEEP_TARGET = 1e-3;

// A body's predicted motion over the step: displacement (m) and turn (rad).
struct Travel {
    Vec3 shift, turn;
};

// The contacts of pair (a, b) deeper than -margin at the end of the step (bodies predicted at
// pa, pb after motions ma, mb), into out from row start, as collide_bodies writes them;
// centre_a and centre_b get the centres their levers are taken from (pa.x and pb.x, or the
// centres at the time of impact). Returns how many were found (more than fit: out is too small).
int collide_swept(const StepContext& w, int a, int b, const Pose& pa, const Pose& pb,
                  const Travel& ma, const Travel& mb, double margin, const ContactBuffer& out,
                  int64_t start, Vec3& centre_a, Vec3& centre_b);

}  // namespace rg
