// The choice between sharing a batch out and stepping it alone (sharing.h).
#include "solver/sharing.h"

#include <algorithm>

namespace rg {

bool BatchSharing::share() const {
    if (forced_ >= 0) {
        return forced_ == 1;
    }
    return calls_ == next_probe_ ? !chosen_ : chosen_;
}

void BatchSharing::restart() {
    samples_ = 0;
    chosen_ = true;
    next_probe_ = calls_ + 1;
    interval_ = FIRST_PROBE;
    last_cost_ = 0.0;
}

void BatchSharing::force(int way) {
    forced_ = way;
    if (way < 0) {  // what was measured before the forced calls may no longer hold
        restart();
    }
}

void BatchSharing::record(bool shared, double seconds, int64_t world_steps) {
    const double cost = world_steps > 0 ? seconds / static_cast<double>(world_steps) : 0.0;
    if (calls_ == next_probe_) {  // a probe: the next one further off
        next_probe_ = calls_ + interval_;
        interval_ = std::min(2 * interval_, LAST_PROBE);
    }
    if (calls_ > 0 && shared != last_shared_ && cost > 0.0 && last_cost_ > 0.0) {
        const double ratio = shared ? cost / last_cost_ : last_cost_ / cost;
        std::copy_backward(ratio_, ratio_ + SAMPLES - 1, ratio_ + SAMPLES);
        ratio_[0] = ratio;
        samples_ = std::min(samples_ + 1, SAMPLES);
        double sorted[SAMPLES];
        std::copy(ratio_, ratio_ + samples_, sorted);
        std::nth_element(sorted, sorted + samples_ / 2, sorted + samples_);
        chosen_ = sorted[samples_ / 2] < 1.0;
        if ((ratio < 1.0) != chosen_) {  // a pair against the choice: look again soon
            interval_ = FIRST_PROBE;
            next_probe_ = std::min(next_probe_, calls_ + FIRST_PROBE);
        }
    }
    calls_ += 1;
    last_shared_ = shared;
    last_cost_ = cost;
}

}  // namespace rg
