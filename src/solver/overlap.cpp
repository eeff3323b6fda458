// The position projection after the impulse stages (overlap.h).
#include "solver/overlap.h"

#include <algorithm>

#include "solver/contacts.h"

namespace rg {

namespace {

// Gauss-Seidel sweeps over the pairs; they stop once one moves nothing.
constexpr int OVERLAP_ITERATIONS = 4;

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
    }
}

}  // namespace rg
