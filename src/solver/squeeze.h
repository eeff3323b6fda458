// A body squeezed between articulated partners (a cube between a gripper's two fingers): its
// contact patches with them resolved at once, in the contact stage.
//
// Each finger of a parallel gripper is pressed by its motor with up to F dt a solver step
// (joint velocity stage), and the cube between the fingers has to stop both. Pair by pair,
// stopping one finger moves the cube into the other, and the impulses bounce between the two
// faces, each pass taking out only part of what is left: never at rest within the contact
// stage's 10 passes, which every step then ran in full (the gripper's env steps at a fifth of
// the suction pad's). Resolved together the squeeze is exact in one pass.
//
// The static impulses j_i at the patches' centroids c_i (partner i's contacts with body a)
// make every centroid's relative velocity zero:
//
//     sum_k K_ik j_k = -v_i,   K_ik = K_a(c_i, c_k) + [i == k] K_i(c_i)
//
// K_a(x, y) = 1/M_a - [x - X_a]x W_a [y - X_a]x, the velocity change of body a at x per unit
// impulse at y (W_a = I(t)^-1), and K_i the partner's point matrix with its joints
// (mobility.h: a finger moves only along its slide). Two fingers pressing from opposite faces
// fix the body's relative motion but its spin about their common normal u, so where every
// normal is along u one more unknown, an angular impulse s u shared equally by the patches,
// stops that spin too (a cube held off its centre of mass as the hand accelerates: without
// it the cube pivots between the pads); with normals along several axes the centroids fix
// the spin and torsional friction follows (each patch within mu j_n rho). The solution
// is the Coulomb one where every patch presses (j_i . n_i > 0) and every pair's impulse over
// the step (what it transmitted before, plus j_i) lies in its friction cone, and the shared
// spin impulse within each patch's torsional limit. Otherwise (a frictionless cube, a grip
// too weak to hold, a cube left behind by a jerk of the hand, a finger pulling away) the
// caller resolves the pairs one at a time as any others, whose patch wrenches also keep a
// sliding cube from tipping between the pads.
#pragma once

#include "base/body.h"

namespace rg {

// The most patches resolved together: four fingers' faces (a 13 x 13 system).
constexpr int MAX_SQUEEZE_PATCHES = 4;

// One contact patch of the squeezed body a with an articulated partner.
struct SqueezePatch {
    int partner;
    Vec3 lever_a;   // m: the patch's centroid from a's predicted centre
    Vec3 lever_b;   // m: the centroid from the partner's predicted centre
    Vec3 normal;    // the patch's mean normal, towards a
    Vec3 prior;     // N s: what the patch's pairs transmitted to a earlier in the step
    double mu;      // the pair's Coulomb coefficient
    double radius;  // m: the patch points' mean distance from the centroid (torsion's lever)
    Vec3 impulse;   // N s on a (its opposite on the partner): the solution
    Vec3 spin;      // N m s on a about the normal (its opposite on the partner): the solution
};

// Solve the header's system for a's `count` patches (2 <= count <= MAX_SQUEEZE_PATCHES), each
// at relative velocity `velocity[i]` (m/s, a minus partner at the centroid), into their
// `impulse` and `spin`. True when the solution presses at every patch, keeps every pair's
// impulse over the step in its friction cone and the spin within torsion's limit; false
// (impulses undefined) when it does not or the system is singular.
bool solve_squeeze(const BodyStates& bodies, const BodyModel& model, int a,
                   SqueezePatch* patches, const Vec3* velocity, int count);

}  // namespace rg
