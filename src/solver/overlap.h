// Removing overlap after the position update: a projection of positions that adds no energy.
//
// GBF's step has no position correction: impulses stop the approach at the predicted poses, but
// overlap made where the passes have not converged (bodies landing on a pile), by the position
// update's rotation (a rod pivoting on its end sinks on an arc), or given as an initial state
// (a box placed inside the ground) stays for ever. So does overlap that no velocity sees: the
// corner of a box turning at ~10 rad/s sweeps into a neighbour and, at the predicted pose, is
// already moving out again (v_n > 0 at a contact 1 mm deep), so no impulse acts on it, as GBF's
// contact rule says. After the position update each awake pair's contacts (contacts.h: found
// once per step, their separations carried to the final velocities, which are what the position
// update moved the bodies by) that overlap by more than OVERLAP_SLOP are pushed apart by a
// fraction of the excess (all of it by default: a smaller fraction, as in Baumgarte
// stabilisation, left such sweeps 0.9-1.1 mm deep in the 1000-body pile, where removing it all
// leaves 0.7-0.8 mm at worst and ~0.3 mm typically, with every other report figure the same or
// smaller), Gauss-Seidel over the contacts with their depths updated as bodies move, a few
// iterations. Only positions move, by translations split by inverse mass: orientations are
// untouched, and a resting contact (overlap far below the slop) is left exactly as it is
// (stacks stay bitwise at rest, sleeping stays exact). A lift against gravity adds potential
// energy; with Settings::overlap_energy a lifted body that only static bodies touch pays from
// its kinetic energy whatever the step would have gained (overlap.cpp's pay_for_lifts);
// otherwise velocities are untouched.
#pragma once

#include "solver/world.h"

namespace rg {

// m: overlap allowed to stay; below it contacts are left alone.
constexpr double OVERLAP_SLOP = 1e-4;

// Push apart the first `pairs` listed pairs' contacts that overlap by more than OVERLAP_SLOP,
// each by `fraction` (in (0, 1]) of the excess per step (Settings::overlap_correction).
void correct_overlap(StepContext& w, int64_t pairs, double dt, double fraction);

}  // namespace rg
