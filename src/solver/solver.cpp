// The collision and contact stages, and the per-pair resolve they share with shock
// propagation (solver.h).
#include "solver/solver.h"

#include <algorithm>
#include <cmath>

#include "solver/contacts.h"
#include "solver/impulse.h"

namespace rg {

namespace {

constexpr double CONTACT_RESTITUTION_START = -0.9;
// Supports whose velocity fields differ by less than this (m/s, rad/s) move as one: their
// contacts can share a patch (the seed partner's velocity field is used for all of them).
constexpr double SAME_MOTION = 1e-9;
// Contacts of a pair whose normals agree within this cosine form one patch (one impulse).
constexpr double PATCH_COS = 0.95;

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
    return resolve_patches(w, a, movable, set, std::min(count, set.depth.size), dt, mode, ramp_e);
}

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
                    double dt, ImpulseMode mode, double ramp_e) {
    if (count == 0) {
        return 0;
    }
    const BodyStates& s = w.bodies;
    const BodyModel& model = w.model;
    // approach speed of every contact, kept in set.depth (negative: approaching), and the
    // separation at the start of the step that it and the predicted depth imply
    bool any_approaching = false;
    for (int64_t i = 0; i < count; ++i) {
        const Vec3 v = relative_velocity(w, set, a, static_cast<int>(set.partner[i]), i);
        const double vn = dot(v, set.normal[i]);
        set.gap[i] = -(set.depth[i] + dt * vn);
        set.depth[i] = vn;
        set.group[i] = -1;
        any_approaching = any_approaching || vn < -REST_SPEED;
    }
    // No contact approaching: every patch below would end at rest or unresolved with nothing
    // to apply (a patch's targets lie at or above v_n for e in [-1, 0], resolve_patch), so
    // the grouping is skipped: 11-20% of the resolves in the piles of 10 to 1000.
    if (!any_approaching) {
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
        if (mode != COLLISION && !movable.b) {
            const Vec3 prior = prior_impulse(w, set, seed, count);
            const PatchResult result =
                resolve_patch(s, model, a, b, movable, set, seed, count, e, mu, prior, dt);
            if (result.outcome == APPLIED) {
                record_impulse(w, set, seed, result.impulse);
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
        if (movable.a) {
            add_point_mass_matrix(model.inverse_mass[a], s.inverse_inertia[a], ra, k);
        }
        if (movable.b) {
            add_point_mass_matrix(model.inverse_mass[b], s.inverse_inertia[b], rb, k);
        }
        const Vec3 j = contact_impulse(k, v, n, single_e, mu);
        if (mu > 0.0 && radius > 0.0) {
            apply_with_spin_friction(s, model, a, b, movable, j, {0.0, 0.0, 0.0}, ra, rb, n,
                                     mu * dot(j, n) * radius);
        } else {
            apply_pair(s, model, a, b, movable, j, {0.0, 0.0, 0.0}, ra, rb);
        }
        record_impulse(w, set, seed, j);
        applied += 1;
    }
    return applied;
}

void resolve_world_contacts(StepContext& w, int64_t pairs, double dt, ImpulseMode mode, int passes) {
    const Vec3 lookahead = mode == COLLISION ? collision_lookahead(w.model, dt) : Vec3{0.0, 0.0, 0.0};
    const bool ramp = mode == CONTACT;
    if (ramp) {
        count_pairs_of_bodies(w, pairs);
    }
    for (int group = 0; group < (ramp ? 2 : 1); ++group) {  // ramped pairs, then those alone
        for (int p = 0; p < passes; ++p) {
            const double ramp_e =
                group == 0 ? CONTACT_RESTITUTION_START * (1.0 - (p + 1.0) / passes) : 0.0;
            int applied = 0;
            for (int64_t k = 0; k < pairs; ++k) {
                const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
                if (ramp && alone(w, a, b) != (group == 1)) {
                    continue;
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
