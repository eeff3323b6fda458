// The collision impulse at one contact point, with restitution and Coulomb friction
// (Guendelman, Bridson & Fedkiw 2003, "Nonconvex rigid bodies with stacking", after Mirtich &
// Canny 1995 and Moore & Wilhelms 1988).
//
// At contact point x with normal n (from body 2 to body 1), r_i = x - X_i and
//     K_i = (1/M_i) 1 + r_i*^T I_i^-1 r_i*        (zero for an infinite mass)
// the relative velocity v = v_1 - v_2 (v_i = V_i + omega_i x r_i), v_n = v.n. Only approaching
// contacts (v_n < 0) get an impulse j, +j on body 1 and -j on body 2:
//     frictionless      j = -(1 + e) v_n / (n^T K n) n
//     static friction   j = K^-1 (-v - e v_n n)   if |j_t| <= mu j_n (the cone)
//     sliding friction  j = j_n (n - mu T), T = v_t / |v_t|,
//                       j_n = -(1 + e) v_n / (n^T K (n - mu T))
// with K = K_1 + K_2. A non-positive sliding denominator (large mu with coupling, a
// Painleve-type case) falls back to the static impulse, which always removes the approach.
// Newton's restitution with Coulomb friction is not energy-consistent: where K couples normal
// and tangent (a corner hitting eccentrically) the combined impulse can add kinetic energy
// (Kane & Levinson's paradox); there the frictionless impulse is used, which at e <= 1 only
// removes energy (Stronge's energetic coefficient would keep friction; it needs the impact
// integrated along its compression and restitution, not one impulse).
// (In the plane of n and T such a denominator implies the static impulse is inside the
// cone, so the sliding branch is not reached there; tests/test_impulse.py.)
#pragma once

#include "base/math.h"

namespace rg {

// k += (1/M) 1 + r*^T I^-1 r*: column c is e_c / M + (I^-1 (r x e_c)) x r; inverse_inertia
// is I(t)^-1 in world axes.
void add_point_mass_matrix(double inverse_mass, const Mat3& inverse_inertia, Vec3 r, Mat3& k);

// Impulse (N s) on body 1 that resolves relative velocity v along normal n with restitution e
// (may be negative in the contact phase: it then only slows the approach) and friction
// coefficient mu, given the summed matrix k. v_n must be < 0.
Vec3 contact_impulse(const Mat3& k, Vec3 v, Vec3 n, double e, double mu);

// contact_impulse where k may be singular: a pair with an articulated body (mobility.h),
// whose contact point moves only along the directions its joints let it (a finger on a
// prismatic joint along the axis, a hinged body across its lever). Of full rank (det k above
// SINGULAR_K of trace(k)^3 / 27, a free body beside the jointed one), it is contact_impulse.
// Else the impulse changes v only within k's range: the normal condition v_n -> -e v_n
// fixes the outcome along a single direction t (k = c t t^T: every impulse with the same t.j
// gives it), so the frictionless impulse, inside every friction cone, is the one; for a
// range of two directions the same frictionless impulse is used (friction across the
// pair's two jointed motions is left out); with n^T k n below SINGULAR_K trace(k) the pair
// cannot move along n and gets none.
Vec3 jointed_contact_impulse(const Mat3& k, Vec3 v, Vec3 n, double e, double mu);

}  // namespace rg
