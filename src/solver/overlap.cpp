// The position projection after the impulse stages (overlap.h).
#include "solver/overlap.h"

#include <algorithm>
#include <cmath>

#include "solver/contacts.h"
#include "solver/joints.h"

namespace rg {

namespace {

// Gauss-Seidel sweeps over the pairs; they stop once one moves nothing.
constexpr int OVERLAP_ITERATIONS = 4;

// Relative margin by which a lifted body's energy is kept below its start's (pay_for_lifts).
constexpr double ROUND_OFF = 1e-12;

// With Settings::overlap_energy: a dynamic body held only by static bodies (w.pairs_of
// counts, as scratch, its joints and its pairs with a movable partner that took an impulse,
// have contacts within the speculative margin or were not found once for the step; the
// position update counts again) and lifted against gravity ends the step with no more
// energy, kinetic plus -M g . x, than it began with plus the work of its applied force and
// torque: where the step would gain, its velocity and angular momentum are scaled by the
// largest factor that gains none (to rest where none does). Static supports at e <= 1 add no
// energy, so a gain is the lift's: a top spinning on its tip, lifted each step out of the
// depth its nutation within the step sank it to, gained 0.5% of its energy in 2 s at
// dt = 1/240. Not every lift is a gain: a block pushed over about its edge is lifted in its
// steps too, yet none of them gains (paying the whole lift turned it 0.6% slower at 30 deg
// than the closed form's energy balance), and there nothing is taken. The applied work is
// counted at the final velocities, as gravity's is (symplectic Euler: free motion then loses
// M (a dt)^2 / 2 a step, never gains). A scaled velocity field approaches no static partner
// it did not approach, slides in the same directions and keeps its axis of rotation, so the
// contact conditions the impulse stages left hold still.
void pay_for_lifts(StepContext& w, int64_t pairs, double dt) {
    const int n = w.num_bodies();
    const BodyModel& model = w.model;
    for (int i = 0; i < n; ++i) {
        w.pairs_of[i] = 0;
    }
    for (int64_t k = 0; k < pairs; ++k) {
        const Vec3 j = w.pair_impulse[k];
        const bool near = w.contacts.first[k] < 0 || w.contacts.count[k] > 0;
        if (j.x == 0.0 && j.y == 0.0 && j.z == 0.0 && !near) {
            continue;
        }
        const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
        w.pairs_of[a] += model.motion[b] != STATIC ? 1 : 0;
        w.pairs_of[b] += model.motion[a] != STATIC ? 1 : 0;
    }
    const JointRows& joints = w.joints;
    for (int64_t j = 0; j < joints.size(); ++j) {
        w.pairs_of[joints.body_a[j]] += 1;
        if (joints.body_b[j] != WORLD_BODY) {
            w.pairs_of[joints.body_b[j]] += 1;
        }
    }
    const BodyStates& s = w.bodies;
    for (int i = 0; i < n; ++i) {
        const Vec3 shift = w.overlap_shift[i];
        if (model.motion[i] != DYNAMIC || w.pairs_of[i] != 0 || model.inverse_mass[i] == 0.0) {
            continue;
        }
        const double mass = 1.0 / model.inverse_mass[i];
        const double lift = -mass * dot(model.gravity, shift);  // J
        if (!(lift > 0.0)) {
            continue;
        }
        const Vec3 v = s.velocity[i], omega = s.angular_velocity[i];
        const double kinetic = 0.5 * (mass * dot(v, v) + dot(omega, s.angular_momentum[i]));
        // the step's energy gain, the applied force's and torque's work taken off (both at
        // the velocities the position update moves the body by), with v and L scaled by f:
        // a f^2 + b f + c; the largest f in [0, 1] that gains none, aimed ROUND_OFF of the
        // energies below so that round-off in the sums cannot leave a gain
        const Vec3 v0 = w.start[i], l0 = w.start[n + i], omega0 = w.start[2 * n + i];
        const double a = kinetic;
        const double b = -dt * (mass * dot(model.gravity, v) + dot(s.force[i], v) +
                                dot(s.torque[i], omega));
        const double kinetic0 = 0.5 * (mass * dot(v0, v0) + dot(omega0, l0));
        const double c = lift - kinetic0 + ROUND_OFF * (kinetic + kinetic0 + lift);
        if (!(a + b + c > 0.0)) {
            continue;
        }
        const double discriminant = b * b - 4.0 * a * c;
        const double f = c < 0.0 && discriminant > 0.0
                             ? std::clamp((-b + std::sqrt(discriminant)) / (2.0 * a), 0.0, 1.0)
                             : 0.0;
        s.velocity[i] = scale(f, v);
        s.angular_momentum[i] = scale(f, s.angular_momentum[i]);
        s.angular_velocity[i] = scale(f, s.angular_velocity[i]);
    }
}

}  // namespace

// Called before the position update: the contacts' separations at the final velocities are
// those after it, and the shifts found are added to the positions at once (the update then
// adds dt V, the same sum).
void correct_overlap(StepContext& w, int64_t pairs, double dt, double fraction) {
    const ContactSet& set = w.scratch;
    const Span<Vec3> shift = w.overlap_shift;
    for (int i = 0; i < w.num_bodies(); ++i) {
        shift[i] = {0.0, 0.0, 0.0};
    }
    bool moved_any = false;
    for (int iteration = 0; iteration < OVERLAP_ITERATIONS; ++iteration) {
        bool moved = false;
        for (int64_t k = 0; k < pairs; ++k) {
            const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
            const double wa = w.model.inverse_mass[a], wb = w.model.inverse_mass[b];
            if (!(wa + wb > 0.0)) {
                continue;
            }
            const int64_t count = std::min(
                gather_pair(w, {k, a, -SPECULATIVE_MARGIN}, dt, {0.0, 0.0, 0.0}, set, 0),
                set.depth.size);
            for (int64_t i = 0; i < count; ++i) {
                const Vec3 n = set.normal[i];
                const double depth = set.depth[i] - dot(sub(shift[a], shift[b]), n);
                if (!(depth > OVERLAP_SLOP)) {
                    continue;
                }
                const double delta = fraction * (depth - OVERLAP_SLOP) / (wa + wb);
                shift[a] = add(shift[a], scale(wa * delta, n));
                shift[b] = sub(shift[b], scale(wb * delta, n));
                moved = true;
            }
        }
        moved_any = moved_any || moved;
        if (!moved) {
            break;
        }
    }
    if (moved_any) {
        for (int i = 0; i < w.num_bodies(); ++i) {
            w.bodies.position[i] = add(w.bodies.position[i], shift[i]);
        }
        if (w.settings->overlap_energy) {
            pay_for_lifts(w, pairs, dt);
        }
    }
}

}  // namespace rg
