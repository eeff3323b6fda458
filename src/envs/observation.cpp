// The envs' observation rows (observation.h).
#include "envs/observation.h"

#include <cmath>

namespace rg {

namespace {

// State entry e of the world whose bodies start at row `first`.
double state_entry(const ObservationQuery& q, int64_t first, int64_t e) {
    const int64_t n = q.num_bodies;
    if (e < 3 * n) {
        return q.position[first + e / 3][static_cast<int>(e % 3)];
    }
    if (e < 6 * n) {
        return q.velocity[first + (e - 3 * n) / 3][static_cast<int>(e % 3)];
    }
    if (e < 15 * n) {
        const int64_t k = e - 6 * n;
        return q.rotation[first + k / 9].m[k % 9 / 3][k % 3];
    }
    return q.angular_velocity[first + (e - 15 * n) / 3][static_cast<int>(e % 3)];
}

}  // namespace

bool gather_observations(const ObservationQuery& q, Span<double> out) {
    const int64_t size = q.index.size;
    bool finite = true;
    for (int64_t r = 0; r < q.worlds.size; ++r) {
        const int64_t first = q.worlds[r] * q.num_bodies;
        for (int64_t j = 0; j < size; ++j) {
            double value = state_entry(q, first, q.index[j]);
            if (q.minus[j] >= 0) {
                value -= state_entry(q, first, q.minus[j]);
            }
            out[r * size + j] = value;
            finite &= std::isfinite(value);
        }
    }
    return finite;
}

}  // namespace rg
