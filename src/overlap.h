// Removing overlap after the position update: a projection of positions that adds no energy.
//
// GBF's step has no position correction: impulses stop the approach at the predicted poses,
// but overlap made where the passes have not converged (bodies landing on a pile), by the
// position update's rotation (a rod pivoting on its end sinks on an arc), or given as an
// initial state (a box placed inside the ground) stays for ever. After the position update
// each awake pair's contacts (contacts.h: found once per step, their separations carried to
// the final velocities, which are what the position update moved the bodies by) that overlap
// by more than OVERLAP_SLOP are pushed apart by a fraction of the excess, Gauss-Seidel over
// the contacts with their depths updated as bodies move, a few iterations. Only positions
// move, by translations split by inverse mass: velocities, orientations and so every body's
// kinetic energy and angular momentum are untouched, and a resting contact (overlap far
// below the slop) is left exactly as it is (stacks stay bitwise at rest, sleeping stays
// exact).
#pragma once

#include "world.h"

namespace rg {

// m: overlap allowed to stay; below it contacts are left alone.
constexpr double OVERLAP_SLOP = 1e-4;

// Push apart the first `pairs` listed pairs' contacts that overlap by more than OVERLAP_SLOP,
// each by `fraction` (in (0, 1]) of the excess per step (Settings::overlap_correction).
void correct_overlap(WorldStep& w, int64_t pairs, double dt, double fraction);

}  // namespace rg
