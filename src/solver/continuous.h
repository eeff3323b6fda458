// Continuous collision: the contacts of a pair that moves far in a step, found at its time of
// impact rather than at the end of the step.
//
// The impulse stages judge contacts at the poses predicted for the end of the step
// (contacts.h). A pair whose bodies move further relative to each other in a step than
// FAST_FRACTION of the thinner one's half thickness can meet and part again between two
// predictions (a 2 cm cube at 50 m/s moves 21 cm a step at dt = 1/240 and jumps a 1 cm wall),
// or end a step with the moving body's centre past the other's mid-plane, where the nearest
// way out is forwards (box_box.cpp's least overlap: a falling plate then sinks through a table
// top). For such a pair (Settings::continuous) the bodies are swept from their current poses
// to the predicted ones (time_of_impact.h); where they come within SWEEP_TARGET of each other
// at fraction t < 1 of the step, the narrow phase runs at the poses of time t, and each
// contact's depth is carried on to the end of the step by the rest of the motion, moving the
// contact rigidly with both bodies as contacts.h carries depths through the passes:
//
//     depth = depth_t - (1 - t) [D_a . n + Theta_a . (r_a x n) - D_b . n - Theta_b . (r_b x n)]
//
// (D, Theta: each body's predicted displacement and turn; r: the contact's levers from the
// centres at time t, which are the pair's centres for the passes). The contact stage then
// sees a contact that overlaps at the predicted poses and stops the approach there, as for
// any contact; what the start-of-step gap (gap = -(depth + dt v_n), solver.cpp) comes to is
// the separation at the start of the step, so speculative closing treats it as what it is.
// A pair that does not meet within the step, or moves less, is found at the predicted poses
// as before: nothing changes for slow scenes, bit for bit.
//
// Thickness: a box's least half extent, a sphere's or capsule's radius, a mesh's least half
// extent of its bounding box in its body frame (an overestimate for a thin mesh lying
// diagonally in it); a plane has none (nothing passes a half-space), and a body of several
// geoms has its thinnest geom's. Box2D v3 calls a body fast above half its least extent,
// and sweeps it against the static world; here the pair's relative motion is compared with
// the thinner body, so that a slow box pushed through a thin moving plate is swept too.
#pragma once

#include "collision/narrow_phase.h"
#include "solver/world.h"

namespace rg {

// A pair is swept when its relative motion in a step exceeds this fraction of the thinner
// body's half thickness.
constexpr double FAST_FRACTION = 0.5;

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
int collide_swept(const WorldStep& w, int a, int b, const Pose& pa, const Pose& pb,
                  const Travel& ma, const Travel& mb, double margin, const ContactBuffer& out,
                  int64_t start, Vec3& centre_a, Vec3& centre_b);

}  // namespace rg
