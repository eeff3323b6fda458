// The collision and contact stages, and the per-pair resolve they share with shock
// propagation (solver.h).
#include "solver/solver.h"

#include <algorithm>
#include <cmath>

#include "solver/contacts.h"
#include "solver/impulse.h"
#include "solver/mobility.h"
#include "solver/squeeze.h"

namespace rg {

namespace {

constexpr double CONTACT_RESTITUTION_START = -0.9;
// Supports whose velocity fields differ by less than this (m/s, rad/s) move as one: their
// contacts can share a patch (the seed partner's velocity field is used for all of them).
constexpr double SAME_MOTION = 1e-9;
// Contacts of a pair whose normals agree within this cosine form one patch (one impulse).
constexpr double PATCH_COS = 0.95;
// A patch's spread along a direction below this fraction of its largest is no spread: its
// points lie on a line (an edge), across which pressures are not determined.
constexpr double PRESSURE_SPAN = 1e-6;

// v_a - v_b at contact i's point, each body's lever arm taken from its predicted centre.
Vec3 relative_velocity(const StepContext& w, const ContactSet& set, int a, int b, int64_t i) {
    const Vec3 p = set.point[i];
    return relative_point_velocity(w.bodies, a, b, sub(p, set.centre_a[i]), sub(p, set.centre_b[i]));
}

// Do bodies p and q move as one rigid body, to within SAME_MOTION (same omega and same
// V - omega x X)?
bool same_motion(const BodyStates& s, int64_t p, int64_t q) {
    if (p == q) {
        return true;
    }
    const Vec3 wp = s.angular_velocity[p], wq = s.angular_velocity[q];
    if (std::fabs(wp.x - wq.x) > SAME_MOTION || std::fabs(wp.y - wq.y) > SAME_MOTION ||
        std::fabs(wp.z - wq.z) > SAME_MOTION) {
        return false;
    }
    const Vec3 cp = cross(wp, s.position[p]), cq = cross(wp, s.position[q]);
    const Vec3 vp = s.velocity[p], vq = s.velocity[q];
    return std::fabs(vp.x - cp.x - vq.x + cq.x) <= SAME_MOTION &&
           std::fabs(vp.y - cp.y - vq.y + cq.y) <= SAME_MOTION &&
           std::fabs(vp.z - cp.z - vq.z + cq.z) <= SAME_MOTION;
}

// The approach speed of each of body a's `count` contacts in set, kept in set.depth
// (negative: approaching), the separation at the start of the step that it and the predicted
// depth imply in set.gap, every contact unassigned to a patch; true if one approaches.
bool measure_approach(const StepContext& w, const ContactSet& set, int a, int64_t count,
                      double dt) {
    bool any_approaching = false;
    for (int64_t i = 0; i < count; ++i) {
        const Vec3 v = relative_velocity(w, set, a, static_cast<int>(set.partner[i]), i);
        const double vn = dot(v, set.normal[i]);
        set.gap[i] = -(set.depth[i] + dt * vn);
        set.depth[i] = vn;
        set.group[i] = -1;
        any_approaching = any_approaching || vn < -REST_SPEED;
    }
    return any_approaching;
}

// Put every unassigned contact whose normal is within PATCH_COS of contact seed's, and whose
// partner moves rigidly with the seed's, into the patch seed. Returns how many of them
// approach (v_n < 0, kept in set.depth).
int gather_patch(const BodyStates& s, const ContactSet& set, int64_t seed, int64_t count) {
    const Vec3 seed_normal = set.normal[seed];
    int approaching = 0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] >= 0 || !same_motion(s, set.partner[seed], set.partner[i]) ||
            dot(set.normal[i], seed_normal) < PATCH_COS) {
            continue;
        }
        set.group[i] = seed;
        if (set.depth[i] < -REST_SPEED) {
            approaching += 1;
        }
    }
    return approaching;
}

// Centroid and mean normal of patch seed's approaching contacts, each weighted by its approach
// speed -v_n, and their mean distance from that centroid (m).
void approach_weighted_centre(const ContactSet& set, int64_t seed, int64_t count, Vec3& c,
                              Vec3& n, double& radius) {
    double total = 0.0;
    c = {0.0, 0.0, 0.0};
    n = {0.0, 0.0, 0.0};
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed && set.depth[i] < -REST_SPEED) {
            const double weight = -set.depth[i];
            total += weight;
            c = add(c, scale(weight, set.point[i]));
            n = add(n, scale(weight, set.normal[i]));
        }
    }
    c = {c.x / total, c.y / total, c.z / total};
    // average before normalising: with approach speeds near 1e-160 m/s the weighted sum's
    // square underflows to 0 (a cube at rest under a kinematic pad turned NaN)
    n = {n.x / total, n.y / total, n.z / total};
    const double norm = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    n = {n.x / norm, n.y / norm, n.z / norm};
    radius = 0.0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed && set.depth[i] < -REST_SPEED) {
            const Vec3 d = sub(set.point[i], c);
            radius += -set.depth[i] * std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
        }
    }
    radius /= total;
}

// What the pairs behind patch seed already transmitted to its body this step (their contacts
// are contiguous, so each pair is counted once), N s.
Vec3 prior_impulse(const StepContext& w, const ContactSet& set, int64_t seed, int64_t count) {
    Vec3 p = {0.0, 0.0, 0.0};
    int64_t last = -1;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed && set.source[i] != last) {
            last = set.source[i];
            p = add(p, scale(set.orient[i], w.pair_impulse[last]));
        }
    }
    return p;
}

// Add impulse j (on the patch's body) to the step total of the seed contact's pair.
void record_impulse(const StepContext& w, const ContactSet& set, int64_t seed, Vec3 j) {
    Vec3& total = w.pair_impulse[set.source[seed]];
    total = add(total, scale(set.orient[seed], j));
}

// The geometric centroid of patch seed's points (the point its patch wrench acts at).
Vec3 patch_centroid(const ContactSet& set, int64_t seed, int64_t count) {
    Vec3 c = {0.0, 0.0, 0.0};
    int k = 0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            c = add(c, set.point[i]);
            k += 1;
        }
    }
    return scale(1.0 / k, c);
}

// Normal pressure impulses over a patch's k points: p(x) = j_n / k + beta . (x - centroid).
struct Pressures {
    double jn;  // N s; 0: not determined (the caller books the impulse whole)
    Vec3 beta;  // N s / m, in the patch's plane
    Vec3 centroid;
    Vec3 n;     // the patch's mean normal
    int k;

    double at(Vec3 x) const { return jn / k + dot(beta, sub(x, centroid)); }
};

// The pressures over patch seed's points that make its wrench: j at c plus the angular
// impulse m, along the patch's mean normal n (its part of j). The linear distribution has
// the total j_n and, for beta solved in the patch's plane, m's tip part as its moment about c:
// sum (x_i - c) x p_i n = m - (m . n) n. For an edge only beta along it is determined (the
// part across it is the least-squares choice, 0). Two knife edges get the lever rule. jn = 0
// when j does not press (j_n <= 0) or the patch has one point.
Pressures patch_pressures(const ContactSet& set, int64_t seed, int64_t count, Vec3 c, Vec3 j,
                          Vec3 m) {
    Pressures out = {0.0, {0.0, 0.0, 0.0}, patch_centroid(set, seed, count), {0.0, 0.0, 0.0}, 0};
    Vec3 n = {0.0, 0.0, 0.0};
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            n = add(n, set.normal[i]);
            out.k += 1;
        }
    }
    const double norm = length(n);
    if (out.k < 2 || norm == 0.0) {
        return out;
    }
    n = scale(1.0 / norm, n);
    const double jn = dot(j, n);
    if (!(jn > 0.0)) {
        return out;
    }
    // the moment the pressures' spread must make about the centroid: m's tip part about c,
    // less that of j_n n moved from c to the centroid
    const Vec3 tip = sub(m, scale(dot(m, n), n));
    const Vec3 spread = sub(tip, cross(sub(out.centroid, c), scale(jn, n)));
    const Vec3 target = cross(n, spread);  // S beta = target, S = sum q q^T over the plane
    const Vec3 a = std::fabs(n.x) < 0.57735 ? Vec3{1.0, 0.0, 0.0} : Vec3{0.0, 1.0, 0.0};
    const Vec3 t1 = scale(1.0 / length(cross(a, n)), cross(a, n)), t2 = cross(n, t1);
    double suu = 0.0, suv = 0.0, svv = 0.0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            const Vec3 q = sub(set.point[i], out.centroid);
            const double u = dot(q, t1), v = dot(q, t2);
            suu += u * u;
            suv += u * v;
            svv += v * v;
        }
    }
    // beta by the eigenvectors of S in the plane, leaving out a direction it does not span
    const double mean = 0.5 * (suu + svv), half = 0.5 * (suu - svv);
    const double radius = std::sqrt(half * half + suv * suv);
    const double angle = 0.5 * std::atan2(2.0 * suv, suu - svv);
    const double ca = std::cos(angle), sa = std::sin(angle);
    const Vec3 e[2] = {add(scale(ca, t1), scale(sa, t2)), sub(scale(ca, t2), scale(sa, t1))};
    const double lambda[2] = {mean + radius, mean - radius};
    for (int r = 0; r < 2; ++r) {
        if (lambda[r] > PRESSURE_SPAN * lambda[0]) {
            out.beta = add(out.beta, scale(dot(e[r], target) / lambda[r], e[r]));
        }
    }
    out.jn = jn;
    out.n = n;
    return out;
}

// Does contact i's partner move more at x under the impulse t (t.K t, K its point mass
// matrix, add_point_mass_matrix) than the resolved body does? Then passing t on to it would
// diverge (shock.cpp, REACTION_ROUNDS): the body's impulse was sized against the partner held
// still, and the partner, reversed, would answer it by more than the relative velocity it
// stopped.
bool lighter_at(const StepContext& w, const ContactSet& set, int64_t i, Vec3 x, Vec3 t) {
    const int64_t k = set.source[i];
    const int body = static_cast<int>(set.orient[i] > 0.0 ? w.lists.pair_a[k] : w.lists.pair_b[k]);
    const int partner = static_cast<int>(set.partner[i]);
    Mat3 own{}, other{};
    add_point_mass_matrix(w.model.inverse_mass[body], w.bodies.inverse_inertia[body],
                          sub(x, set.centre_a[i]), own);
    add_point_mass_matrix(w.model.inverse_mass[partner], w.bodies.inverse_inertia[partner],
                          sub(x, set.centre_b[i]), other);
    return dot(t, rotate(other, t)) > dot(t, rotate(own, t));
}

// The reaction across gravity of a sliding patch or a single impulse: the part of `share`
// (an impulse on the resolved body at point x) off the up axis, held back reversed in
// w.reaction for contact i's partner when that is a dynamic body held frozen by shock
// propagation (else it took its share already, or takes none); shock.cpp applies it once
// the levels are done. Applied at once, the supports would move under the bodies still to be
// resolved on them, which then followed them and were left moving when the next round
// stopped the supports (a box on two boxes rose off them). Along gravity the frozen support takes nothing (what keeps a stack
// from sinking: the ground takes it in the end); across it nothing else would: friction, and
// the normal impulse of a support tilted by the friction it took (a block pulled on a
// frictionless floor, the block on it sliding, lost 5e-4 of F T at dt = 1/60 with the
// normal's part off). Returns 1 if applied, else 0.
int react(const StepContext& w, const ContactSet& set, int64_t i, Vec3 x, Vec3 share) {
    const int partner = static_cast<int>(set.partner[i]);
    if (w.model.motion[partner] != DYNAMIC) {
        return 0;
    }
    const Vec3 up = w.up;
    const Vec3 t = sub(share, scale(dot(share, up), up));
    if (lighter_at(w, set, i, x, t)) {
        return 0;
    }
    const int n = w.num_bodies();
    w.reaction[partner] = sub(w.reaction[partner], t);
    w.reaction[n + partner] = sub(w.reaction[n + partner], cross(sub(x, set.centre_b[i]), t));
    return 1;
}

// Add the patch's impulse j (on its body; with the angular impulse m, applied at c) to the
// step totals of its pairs. A patch of several pairs (a body on two frozen supports, shock.cpp)
// with Settings::patch_reactions splits j by the pressures of patch_pressures (its normal
// part point by point, its tangential part in proportion to the pressing points' pressures),
// so each pair's total is the reaction its support gives; otherwise the whole of j goes to
// the seed contact's pair. frozen (shock propagation's sliding patches and single impulses
// against frozen bodies, with patch_reactions): the reaction goes to each dynamic partner too,
// point by point by the same shares (react); *reactions counts them. A single impulse's
// reaction is its exact opposite at its point (a cube tipping over the back edge of a block
// pulled under it, dt = 1/30, added 1% to the momentum without it). A static patch wrench's
// is not passed on: the reactions of a 55-box pyramid's patches then needed 9 rounds of the
// levels in every step to die out, and cut at 4 the pyramid spread at 2.5 mm/s, or
// collapsed; nor is torsional friction's.
void book_impulse(const StepContext& w, const ContactSet& set, int64_t seed, int64_t count, Vec3 c,
                  Vec3 j, Vec3 m, bool frozen, int* reactions) {
    const bool split = w.settings->patch_reactions;
    bool several = false;
    for (int64_t i = seed; i < count && split && !several; ++i) {
        several = set.group[i] == seed && set.source[i] != set.source[seed];
    }
    const Pressures p = several && split ? patch_pressures(set, seed, count, c, j, m)
                                         : Pressures{0.0, {}, {}, {}, 0};
    const bool passed_on = frozen && split && reactions != nullptr;
    if (p.jn == 0.0) {
        record_impulse(w, set, seed, j);
        if (passed_on) {
            *reactions += react(w, set, seed, c, j);
        }
        return;
    }
    // the normal part by the pressures, the tangential part (friction) by the pressing ones:
    // a moment's pressures (large and of both signs where j_n is small) would scale it up
    const Vec3 tangential = sub(j, scale(p.jn, p.n));
    double pressing = 0.0;
    for (int64_t i = seed; i < count; ++i) {
        pressing += set.group[i] == seed ? std::max(p.at(set.point[i]), 0.0) : 0.0;
    }
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            const double pi = p.at(set.point[i]);
            const Vec3 share =
                add(scale(pi, p.n), scale(std::max(pi, 0.0) / pressing, tangential));
            Vec3& total = w.pair_impulse[set.source[i]];
            total = add(total, scale(set.orient[i], share));
            if (passed_on) {
                *reactions += react(w, set, i, set.point[i], share);
            }
        }
    }
}

// The most negative restitution patch seed may take in the contact and shock stages so that
// it still closes the gap it starts the step with (speculative contact, closable in patch.h):
// the patch may keep approaching at gap / dt, gap being its points' least separation at the
// start of the step, against the approach of its fastest point. -1 or below: no point reaches
// its partner within the step. 0 when a point touches or its gap is not closable.
double closing_restitution(const BodyModel& model, const ContactSet& set, int64_t seed,
                           int64_t count, double dt) {
    double gap = INFINITY, fastest = 0.0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            gap = std::min(gap, set.gap[i]);
            fastest = std::max(fastest, -set.depth[i]);
        }
    }
    if (fastest <= REST_SPEED) {
        return 0.0;
    }
    const double reached = -gap / (dt * fastest);
    return reached <= -1.0 || closable(gap, closing_reach(model, dt)) ? reached : 0.0;
}

// COLLISION: the pair's max(e_a, e_b); CONTACT: the ramp value; SHOCK: 0.
double restitution_for(const StepContext& w, int a, int b, ImpulseMode mode, double ramp_e) {
    if (mode == COLLISION) {
        return std::max(w.model.restitution[a], w.model.restitution[b]);
    }
    return mode == CONTACT ? ramp_e : 0.0;
}

// Is the pair (a, b) the only pair of each of its dynamic bodies? (Static and kinematic
// bodies take no impulse, so the pairs they share carry nothing from one to another.)
bool alone(const StepContext& w, int a, int b) {
    return (w.model.motion[a] != DYNAMIC || w.pairs_of[a] == 1) &&
           (w.model.motion[b] != DYNAMIC || w.pairs_of[b] == 1);
}

// How the contact stage resolves the pairs of body a = pair k's a (with
// Settings::contact_patches): HELD, all at once, when a is dynamic, in two or more pairs, all
// with static or kinematic partners; SQUEEZED, its pairs with articulated partners at once
// (squeeze.h), when a is dynamic, not articulated, in two or more pairs with articulated
// partners and in none with another dynamic body; else ONE_BY_ONE. Both need a to be the a of
// all its pairs (w.pairs_of[a]): pairs are listed sorted by (a, b) (broad_phase.h), so they
// follow each other from the first, `start`. A dynamic body is the a of its pairs with static
// and kinematic bodies, and of those with dynamic bodies listed after it.
enum Resolve { ONE_BY_ONE, HELD, SQUEEZED };

struct OwnPairs {
    Resolve resolve;
    int64_t start;  // the body's first pair (HELD, SQUEEZED)
};

// Is body b a partner that squeezes (squeeze.h): dynamic and articulated?
bool squeezes(const BodyModel& model, int b) {
    return model.motion[b] == DYNAMIC && model.articulated[b];
}

OwnPairs own_pairs(const StepContext& w, int64_t k, int64_t pairs) {
    const OwnPairs one_by_one = {ONE_BY_ONE, -1};
    const int a = w.lists.pair_a[k];
    const BodyModel& model = w.model;
    const auto free_partner = [&](int b) {
        return model.motion[b] == DYNAMIC && !model.articulated[b];
    };
    if (!w.settings->contact_patches || model.motion[a] != DYNAMIC || w.pairs_of[a] < 2 ||
        free_partner(w.lists.pair_b[k])) {
        return one_by_one;
    }
    int64_t start = k;
    while (start > 0 && w.lists.pair_a[start - 1] == a) {
        start -= 1;
    }
    const int64_t end = start + w.pairs_of[a];
    if (end > pairs) {
        return one_by_one;
    }
    int squeezing = 0;
    for (int64_t j = start; j < end; ++j) {
        const int b = w.lists.pair_b[j];
        if (w.lists.pair_a[j] != a || free_partner(b)) {
            return one_by_one;
        }
        squeezing += squeezes(model, b);
    }
    if (squeezing == 0) {
        return {HELD, start};
    }
    return squeezing >= 2 && !model.articulated[a] ? OwnPairs{SQUEEZED, start} : one_by_one;
}

// The contact stage's resolve of a held body (own_pairs): all its contacts at once, in
// w.wide, at e = 0, as shock propagation resolves a body against its frozen supports. Pair
// by pair, a plank on two bars was pushed up at one bar by the impulse that stopped it at
// the other, and rocked for good (3e-5 m/s): the two patches' impulses disturb each other.
int resolve_held(StepContext& w, int64_t start, double dt) {
    const int a = w.lists.pair_a[start];
    const ContactSet& wide = w.wide;
    int64_t count = 0;
    int applied = 0;
    for (int64_t k = start; k < start + w.pairs_of[a]; ++k) {
        const int64_t found = gather_pair(w, {k, a, 0.0}, dt, {0.0, 0.0, 0.0}, wide, count);
        if (count + found > wide.depth.size) {
            // no room to combine it: resolve this pair on its own rather than drop it
            applied += resolve_pair(w, k, dt, {0.0, 0.0, 0.0}, CONTACT, 0.0, {true, false});
            continue;
        }
        count += found;
    }
    return applied + resolve_patches(w, a, {true, false}, wide, count, dt, CONTACT, 0.0);
}

// Fill `patch` and its centroid's relative velocity from patch seed of body a's contacts in
// set; false if the patch does not touch (its least gap above CLOSED_GAP: a finger still
// closing, whose approach is for the pair's own resolve to judge).
bool squeeze_patch(const StepContext& w, const ContactSet& set, int a, int64_t seed,
                   int64_t count, SqueezePatch& patch, Vec3& velocity) {
    double least_gap = set.gap[seed];
    Vec3 n = {0.0, 0.0, 0.0};
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            least_gap = std::min(least_gap, set.gap[i]);
            n = add(n, set.normal[i]);
        }
    }
    if (least_gap > CLOSED_GAP) {
        return false;
    }
    const int b = static_cast<int>(set.partner[seed]);
    const Vec3 c = patch_centroid(set, seed, count);
    double radius = 0.0;
    int points = 0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] == seed) {
            radius += length(sub(set.point[i], c));
            points += 1;
        }
    }
    const double mu = std::sqrt(w.model.friction[a] * w.model.friction[b]);
    patch = {b, sub(c, set.centre_a[seed]), sub(c, set.centre_b[seed]), scale(1.0 / length(n), n),
             prior_impulse(w, set, seed, count), mu, radius / points, {0.0, 0.0, 0.0},
             {0.0, 0.0, 0.0}};
    velocity = relative_point_velocity(w.bodies, a, b, patch.lever_a, patch.lever_b);
    return true;
}

// The contact stage's resolve of squeezed body a's pairs with its articulated partners (the
// pairs from `start`; squeeze.h), at e = 0: all their patches at once where each touches and
// the static solution holds (squeeze.h), with torsional friction about each patch's normal
// where a spin is left (mu j_n r, as resolve_patches' single impulse); else pair by pair at
// the pass's ramp_e, as the other pairs of the contact stage.
int resolve_squeeze(StepContext& w, int64_t start, double dt, double ramp_e) {
    const int a = w.lists.pair_a[start];
    const int64_t end = start + w.pairs_of[a];
    const ContactSet& wide = w.wide;
    SqueezePatch patches[MAX_SQUEEZE_PATCHES];
    Vec3 velocity[MAX_SQUEEZE_PATCHES];
    int64_t seeds[MAX_SQUEEZE_PATCHES];
    int n = 0;
    int64_t count = 0;
    bool together = true;
    // contacts up to GRAPH_MARGIN apart at the prediction, as shock propagation's supports:
    // once resolved, a pad's contacts lie at depth 0 there give or take round-off, and a pad
    // with none would send the body back to the pairs' own resolves
    for (int64_t k = start; k < end && together; ++k) {
        if (squeezes(w.model, w.lists.pair_b[k])) {
            const int64_t found =
                gather_pair(w, {k, a, -GRAPH_MARGIN}, dt, {0.0, 0.0, 0.0}, wide, count);
            together = count + found <= wide.depth.size;
            count += found;
        }
    }
    bool moving = false;
    if (together) {
        measure_approach(w, wide, a, count, dt);
        for (int64_t seed = 0; seed < count && together; ++seed) {
            if (wide.group[seed] >= 0) {
                continue;
            }
            gather_patch(w.bodies, wide, seed, count);
            together = n < MAX_SQUEEZE_PATCHES &&
                       squeeze_patch(w, wide, a, seed, count, patches[n], velocity[n]);
            if (together) {
                const Vec3 spin = sub(w.bodies.angular_velocity[a],
                                      w.bodies.angular_velocity[patches[n].partner]);
                moving = moving || length(velocity[n]) > REST_SPEED ||
                         std::fabs(dot(spin, patches[n].normal)) * patches[n].radius > REST_SPEED;
                seeds[n++] = seed;
            }
        }
    }
    if (together && n >= 2 && !moving) {
        return 0;
    }
    const bool solved =
        together && n >= 2 && solve_squeeze(w.bodies, w.model, a, patches, velocity, n);
    if (solved) {
        for (int i = 0; i < n; ++i) {
            const SqueezePatch& p = patches[i];
            apply_pair(w.bodies, w.model, a, p.partner, {true, true}, p.impulse, p.spin,
                       p.lever_a, p.lever_b);
        }
        // torsional friction where the solve left a spin (normals along several axes; after
        // a shared spin impulse there is none left to stop)
        for (int i = 0; i < n; ++i) {
            const SqueezePatch& p = patches[i];
            apply_with_spin_friction(w.bodies, w.model, a, p.partner, {true, true},
                                     {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, p.lever_a, p.lever_b,
                                     p.normal, p.mu * dot(p.impulse, p.normal) * p.radius);
            book_impulse(w, wide, seeds[i], count, add(p.lever_a, wide.centre_a[seeds[i]]),
                         p.impulse, p.spin, false, nullptr);
        }
        return n;
    }
    int applied = 0;
    for (int64_t k = start; k < end; ++k) {
        if (squeezes(w.model, w.lists.pair_b[k])) {
            applied += resolve_pair(w, k, dt, {0.0, 0.0, 0.0}, CONTACT, ramp_e, {true, true});
        }
    }
    return applied;
}

// w.pairs_of over the first `pairs` listed pairs; acting_only: those with an impulse.
void count_pairs(StepContext& w, int64_t pairs, bool acting_only) {
    for (int i = 0; i < w.num_bodies(); ++i) {
        w.pairs_of[i] = 0;
    }
    for (int64_t k = 0; k < pairs; ++k) {
        const Vec3 j = w.pair_impulse[k];
        if (acting_only && j.x == 0.0 && j.y == 0.0 && j.z == 0.0) {
            continue;
        }
        w.pairs_of[w.lists.pair_a[k]] += 1;
        w.pairs_of[w.lists.pair_b[k]] += 1;
    }
}

}  // namespace

void count_pairs_of_bodies(StepContext& w, int64_t pairs) { count_pairs(w, pairs, false); }

void count_acting_pairs_of_bodies(StepContext& w, int64_t pairs) { count_pairs(w, pairs, true); }

Vec3 collision_lookahead(const BodyModel& model, double dt) {
    const Vec3 g = model.gravity;
    return {dt * dt * g.x, dt * dt * g.y, dt * dt * g.z};
}

int resolve_pair(StepContext& w, int64_t k, double dt, Vec3 lookahead, ImpulseMode mode,
                 double ramp_e, Movable movable) {
    const int a = w.lists.pair_a[k];
    const ContactSet& set = w.scratch;
    const int64_t count = gather_pair(w, {k, a, 0.0}, dt, lookahead, set, 0);
    // the contact stage keeps a patch's frame, matrix and factors from pass to pass
    // (patch_memo.h); an articulated body's matrix is its joints' (mobility.h), built anew
    const int b = w.lists.pair_b[k];
    const bool keep = mode == CONTACT && !w.model.articulated[a] && !w.model.articulated[b];
    return resolve_patches(w, a, movable, set, std::min(count, set.depth.size), dt, mode, ramp_e,
                           nullptr, keep ? &w.contacts.memo[k] : nullptr);
}

namespace {

// The key of patch seed's memo: memo with the bits of the patch's rows among its pair's kept
// contacts and of its movable bodies, or no memo where one of its contacts is not a kept row
// (found in the pass).
PatchKey patch_key(const ContactSet& set, int64_t seed, int64_t count, Movable movable,
                   PatchMemo* memo) {
    if (memo == nullptr) {
        return {};
    }
    uint64_t members = 0;
    for (int64_t i = seed; i < count; ++i) {
        if (set.group[i] != seed) {
            continue;
        }
        const int64_t row = set.row[i];
        if (row < 0 || row >= 64) {
            return {};
        }
        members |= uint64_t{1} << row;
    }
    return {memo, members, static_cast<uint8_t>((movable.a ? 1 : 0) | (movable.b ? 2 : 0))};
}

}  // namespace

// The contacts are grouped into patches of similar normal and rigidly co-moving partners (a
// face resting on a face is one patch). Against an immovable partner (static, kinematic, or
// frozen by shock propagation) in the contact and shock stages, a face or edge patch gets the
// wrench of patch.h over all its touching points: it brings the patch exactly to rest or to
// sliding without rocking, or does nothing when the patch is at rest. Otherwise
// (collisions, two movable bodies, single points, a body tipping over an edge, a patch that
// holding would pull because one end of it lifts) the patch's
// approaching points get one impulse (impulse.h) at their centroid, weighted by approach
// speed, along their mean normal, plus torsional friction about the normal bounded by
// mu j_n r (r: the points' mean distance from the centroid). One impulse per patch, not one
// per point, is what lets a box come exactly to rest: sequential point impulses leave it
// rocking, and their order biases it sideways. Coulomb's limit applies to the pair's impulse
// over the whole step: the patch wrench is checked with what its pairs already transmitted
// this step added, and every impulse applied is added there.
int resolve_patches(StepContext& w, int a, Movable movable, const ContactSet& set, int64_t count,
                    double dt, ImpulseMode mode, double ramp_e, int* reactions, PatchMemo* memo) {
    const bool frozen = mode == SHOCK && !movable.b;
    if (w.timers.running >= 0) {
        w.timers.resolves[w.timers.running] += 1;
    }
    if (count == 0) {
        return 0;
    }
    const BodyStates& s = w.bodies;
    const BodyModel& model = w.model;
    // No contact approaching: every patch below would end at rest or unresolved with nothing
    // to apply (a patch's targets lie at or above v_n for e in [-1, 0], resolve_patch), so
    // the grouping is skipped: 11-20% of the resolves in the piles of 10 to 1000.
    if (!measure_approach(w, set, a, count, dt)) {
        return 0;
    }
    int applied = 0;
    for (int64_t seed = 0; seed < count; ++seed) {
        if (set.group[seed] >= 0) {
            continue;
        }
        const int b = static_cast<int>(set.partner[seed]);
        const double mu = std::sqrt(model.friction[a] * model.friction[b]);
        const int approaching = gather_patch(s, set, seed, count);
        const double e = restitution_for(w, a, b, mode, ramp_e);
        double single_e = e;  // the restitution of a single impulse at the patch's centre
        if (mode != COLLISION) {  // the collision stage predicts dt^2 g ahead: depth is no gap
            const double closing = closing_restitution(model, set, seed, count, dt);
            if (closing <= -1.0) {
                continue;
            }
            single_e = std::min(e, closing);
        }
        if (mode != COLLISION && (!movable.b || w.settings->contact_patches)) {
            const Vec3 prior = prior_impulse(w, set, seed, count);
            const PatchResult result =
                resolve_patch(s, model, a, b, movable, set, seed, count, e, mu, prior, dt,
                              w.settings->patch_reactions && mode == SHOCK,
                              patch_key(set, seed, count, movable, memo));
            if (result.outcome == APPLIED) {
                book_impulse(w, set, seed, count, patch_centroid(set, seed, count),
                             result.impulse, result.moment,
                             frozen && result.sliding, reactions);
                applied += 1;
                continue;
            }
            if (result.outcome == AT_REST) {
                continue;
            }
        }
        if (approaching == 0) {
            continue;
        }
        Vec3 c, n;
        double radius;
        approach_weighted_centre(set, seed, count, c, n, radius);
        const Vec3 ra = sub(c, set.centre_a[seed]), rb = sub(c, set.centre_b[seed]);
        const Vec3 v = relative_point_velocity(s, a, b, ra, rb);
        if (dot(v, n) >= -REST_SPEED) {
            continue;
        }
        Mat3 k = {};
        const bool jointed =
            (movable.a && model.articulated[a]) || (movable.b && model.articulated[b]);
        const auto add_body = [&](int i, Vec3 r) {
            if (model.articulated[i]) {
                add_articulated_point_matrix(s, model, i, r, k);  // mobility.h
            } else {
                add_point_mass_matrix(model.inverse_mass[i], s.inverse_inertia[i], r, k);
            }
        };
        if (movable.a) {
            add_body(a, ra);
        }
        if (movable.b) {
            add_body(b, rb);
        }
        const Vec3 j = jointed ? jointed_contact_impulse(k, v, n, single_e, mu)
                               : contact_impulse(k, v, n, single_e, mu);
        if (mu > 0.0 && radius > 0.0) {
            apply_with_spin_friction(s, model, a, b, movable, j, {0.0, 0.0, 0.0}, ra, rb, n,
                                     mu * dot(j, n) * radius);
        } else {
            apply_pair(s, model, a, b, movable, j, {0.0, 0.0, 0.0}, ra, rb);
        }
        book_impulse(w, set, seed, count, c, j, {0.0, 0.0, 0.0}, frozen, reactions);
        applied += 1;
    }
    return applied;
}

void resolve_world_contacts(StepContext& w, int64_t pairs, double dt, ImpulseMode mode, int passes) {
    const Vec3 lookahead = mode == COLLISION ? collision_lookahead(w.model, dt) : Vec3{0.0, 0.0, 0.0};
    const bool ramp = mode == CONTACT;
    if (ramp) {
        count_pairs_of_bodies(w, pairs);
        for (int64_t k = 0; k < pairs; ++k) {
            w.contacts.memo[k].members = 0;  // nothing kept from an earlier stage
        }
    }
    for (int group = 0; group < (ramp ? 2 : 1); ++group) {  // ramped pairs, then those alone
        for (int p = 0; p < passes; ++p) {
            const double ramp_e =
                group == 0 ? CONTACT_RESTITUTION_START * (1.0 - (p + 1.0) / passes) : 0.0;
            int applied = 0;
            for (int64_t k = 0; k < pairs; ++k) {
                const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
                const OwnPairs own = ramp ? own_pairs(w, k, pairs) : OwnPairs{ONE_BY_ONE, -1};
                if (ramp && (alone(w, a, b) || own.resolve == HELD) != (group == 1)) {
                    continue;
                }
                if (own.resolve == HELD) {  // the whole body at its first pair
                    applied += own.start == k ? resolve_held(w, k, dt) : 0;
                    continue;
                }
                // a squeezed body's pairs with its squeezing partners at its first pair, its
                // others (the table under a gripped cube) one by one
                if (own.resolve == SQUEEZED) {
                    applied += own.start == k ? resolve_squeeze(w, k, dt, ramp_e) : 0;
                    if (squeezes(w.model, b)) {
                        continue;
                    }
                }
                applied += resolve_pair(w, k, dt, lookahead, mode, ramp_e,
                                        {w.model.motion[a] == DYNAMIC, w.model.motion[b] == DYNAMIC});
            }
            if (applied == 0) {
                break;
            }
        }
    }
}

}  // namespace rg
