// Time of impact of two moving bodies, by conservative advancement over their separation.
//
// Each body moves over a step as its prediction does (contacts.h): its centre along a
// straight shift, its orientation turned at a constant rate, both scaled by the fraction t of
// the step in [0, 1]. No point of body i moves further than |shift_i| + |turn_i| reach_i
// while t goes from 0 to 1 (reach_i: the distance of its furthest point from its centre), so
// the bodies' separation falls at most at the sum of the two rates: advancing t by the
// separation over that rate cannot carry them into each other (Mirtich 1996; Box2D v3's
// b2TimeOfImpact finds the same time by root-finding on separating axes). The separation:
//
// * core against core (spheres, capsules): the exact distance of the cores less the radii;
// * a core against a box, mesh or plane: the least phi along the core less its radius, as
//   the narrow phase finds it (exact for boxes and planes, the grid's for meshes);
// * box against box: the largest gap over the 15 separating axes, a lower bound on the
//   distance (never overshoots; a corner meeting a corner takes a few more advances);
// * otherwise: the least phi of either geom's surface samples in the other (vertices only
//   against a plane): exact where a vertex meets a face, a sample spacing long where edges
//   cross, which can carry the bodies that far into each other at the time found.
//
// Nothing is allocated; the result is a function of the arguments alone.
#pragma once

#include "base/math.h"
#include "collision/geometry.h"
#include "collision/narrow_phase.h"

namespace rg {

// One body's motion over a step: pose(t) = (x + t shift, q turned by t turn).
struct Sweep {
    Vec3 x;
    Quat q;
    Vec3 shift;    // m
    Vec3 turn;     // rad, world frame
    double reach;  // m, its furthest point from its centre (0 for a plane)
};

// The body's pose at fraction t of its sweep.
Pose sweep_pose(const Sweep& s, double t);

// The separation of body a at pose pa from body b at pose pb (m; < 0 overlapping), as listed
// above; values at or beyond `reach` (m) are only known to be that large.
double body_separation(const Geometry& geo, int a, int b, const Pose& pa, const Pose& pb,
                       double reach);

// t > 1 from time_of_impact: the bodies come no closer than `target` within the sweep.
constexpr double NO_IMPACT = 2.0;

// The first t in [0, 1] at which body a (sweep sa) and body b (sweep sb) are within `target`
// (m) of each other (0 when they start so), or NO_IMPACT.
double time_of_impact(const Geometry& geo, int a, int b, const Sweep& sa, const Sweep& sb,
                      double target);

}  // namespace rg
