// Resting contact over a patch: one impulse and one angular impulse for a face or an edge.
//
// A box standing on an incline needs friction at its base *and* a shift of pressure downhill
// to balance the moment that friction makes about its centre of mass. Point impulses, or one
// impulse at a fixed point, can only reach that balance over many passes and leave the box
// rocking. Here a patch (contacts of one pair with a common normal, see solver.cpp) gets the
// wrench (j, m) at its centroid c that does it in one go:
//
//     unknowns   j (3) and m along the patch's constrained rotations D:
//                a face: tip about t1, t2 and spin about n; an edge (collinear points) with
//                direction e: tip about n x e and spin about n; a single point: none
//     targets    relative velocity at c: -v - e v_n n (the static impulse of impulse.h),
//                relative angular velocity along D: tip -(1 + e) Omega.d, spin -Omega.n
//     matrix     [dv; dOmega] = A [j; m],  A = sum over movable bodies of
//                [[1/M + r*^T W r*, r*^T W], [W r*, W]],  W = I(t)^-1, r = c - X
//
// It is accepted only if physically admissible: j.n > 0; and, for the patch's total over the
// step so far (the impulse F its pairs already transmitted plus j, the earlier part taken as
// acting at c): |F_t| <= mu F_n (Coulomb cone), |m.n| <= mu F_n rho (torsional friction; rho:
// the points' mean distance from c), and the centre of pressure c + n x m_t / F_n lies within
// the patch. If friction cannot hold, the sliding wrench is tried: j = j_n (n - mu T)
// (impulse.h) with only the tip constraints, and torsional friction applied afterwards
// within its limit. If the centre of pressure would leave the patch the body is tipping over
// an edge, and the caller falls back to a single impulse.
#pragma once

#include <cmath>

#include "solver/contact_set.h"
#include "solver/patch_memo.h"

namespace rg {

// m/s: contacts approaching slower than this are at rest and get no impulse. An exact resolve
// leaves round-off (about 1e-17 m/s) behind; without a floor every later pass would apply a
// round-off impulse and count as work done, so the passes never stopped early (a cube resting
// on the table used all 10 contact passes). Gravity alone brings 0.04 m/s per step of 1/240 s,
// so nothing below the floor can build up; 1e-9 m/s is 1 nm of drift in 1 s.
constexpr double REST_SPEED = 1e-9;

// m: contact points this close at the start of the step count as touching. Far below the
// overlap slop (overlap.h) and the 0.1 mm a body should rest within, far above the round-off
// of a separation (~1e-16 m): a body resting on its support stays the bit-exact fixed point
// it was.
constexpr double CLOSED_GAP = 1e-6;

// m: how far apart a contact point may be at the start of the step and still keep approaching
// until it closes the gap within the step (speculative contact, patch.cpp and solver.cpp):
// what gravity closes in one step, |g| dt^2. An impulse at e = 0 stops a body up to that far
// short of its support, where it would otherwise hang (GBF's contact stage judges predicted
// poses). Larger gaps, left by fast impacts, close under gravity in later steps: closing them
// at once in a pile drove bodies deeper into each other (the linearised gap of a fast, turning
// body is least exact). A point of a patch pivoting about its closest point falls faster
// than g and gets a longer reach (lever_reach in patch.cpp).
inline double closing_reach(const BodyModel& model, double dt) {
    const Vec3 g = model.gravity;
    return dt * dt * std::sqrt(g.x * g.x + g.y * g.y + g.z * g.z);
}

// May a point apart by `gap` (m) close it within the step, given its reach (m)?
inline bool closable(double gap, double reach) {
    return gap > CLOSED_GAP && gap <= reach;
}

enum PatchOutcome { APPLIED, AT_REST, UNRESOLVED };

struct PatchResult {
    PatchOutcome outcome;
    Vec3 impulse;  // the linear impulse applied to a, N s
    Vec3 moment;   // the angular impulse applied to a besides impulse at the patch's centroid
                   // (its part about n without torsional friction), N m s
    bool sliding;  // friction at its Coulomb limit (the sliding wrench with mu > 0)
};

// Which bodies of a pair take impulses: false treats one as infinite mass (kinematic, static,
// or frozen by shock propagation).
struct Movable {
    bool a, b;
};

// Apply the patch wrench of the header to the pair (a, b) for the patch whose contacts have
// group == seed. prior: the impulse the patch's pairs already transmitted to a this step
// (N s); the static wrench must keep prior + j inside the friction cone. Outcomes: APPLIED;
// AT_REST when the patch is at rest (its points' relative speeds below REST_SPEED):
// nothing to do; or UNRESOLVED (nothing applied) for a single point, a body tipping over an
// edge, or a patch that holding would pull (j_n <= 0: a tumbling box whose edge strikes with
// one end while the other lifts), which the caller treats with a single impulse on the
// approaching points (none approaching: nothing to do).
// lessen: the wrench may press less than nothing (j_n < 0) where the step's total through the
// patch, prior + j, still presses (impulses accumulated over the step, clamped as a whole):
// a pure moment that stops a body tipping on its support, which friction's reaction passed
// on by shock propagation gives it (solver.h), needs j_n = 0 and got none otherwise.
// key: where the patch's frame, matrix and factors are kept between passes (patch_memo.h).
PatchResult resolve_patch(const BodyStates& bodies, const BodyModel& model, int a, int b,
                          Movable movable, const ContactSet& set, int64_t seed, int64_t count,
                          double e, double mu, Vec3 prior, double dt, bool lessen,
                          PatchKey key = {});

// (V_a + w_a x r_a) - (V_b + w_b x r_b).
Vec3 relative_point_velocity(const BodyStates& bodies, int a, int b, Vec3 ra, Vec3 rb);

// The wrench (j at lever r, plus angular impulse m) on a and its opposite on b (movable
// bodies only): V += j/M, L += r x j + m, omega = I(t)^-1 L.
void apply_pair(const BodyStates& bodies, const BodyModel& model, int a, int b, Movable movable,
                Vec3 j, Vec3 m, Vec3 ra, Vec3 rb);

// apply_pair of (j, m) with torsional friction added to m: the angular impulse t n on a (and
// -t n on b) that stops their relative spin about n once (j, m) has acted, |t| <= limit
// (N m s), in the same update of each body.
void apply_with_spin_friction(const BodyStates& bodies, const BodyModel& model, int a, int b,
                              Movable movable, Vec3 j, Vec3 m, Vec3 ra, Vec3 rb, Vec3 n,
                              double limit);

}  // namespace rg
