// The step's stage timers: how many times each stage ran and, while timing is on, the
// seconds spent in it, kept per world and filled by step_world as it goes (as Box2D v3 fills
// b2Profile inside b2World_Step and MuJoCo fills mjData.timer inside mj_step), so the one
// driver of the step is also the one that times it. Counting is always on (an add per
// stage). The clock is read only while timing is on (World(profile=True)), as MuJoCo reads
// it only when a clock callback (mjcb_time) is set: a read costs 20-100 ns, a share of a
// small scene's step of a few microseconds that the environments should not pay
// (benchmarks/solver.py --timers measures it).
#pragma once

#include <chrono>
#include <cstdint>

#include "base/span.h"
#include "solver/stages.h"

namespace rg {

// Seconds on a monotonic clock (the origin is arbitrary).
inline double clock_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

// One world's timers, accumulated over every step since the world was made, and the stage
// running now. A stage's time is its own: a stage run inside another (the impulse stages
// inside a relisting) stops the outer one's clock until it ends.
struct StageTimers {
    Span<double> seconds;     // (STAGE_COUNT,) s of wall time, while `timed`
    Span<int64_t> calls;      // (STAGE_COUNT,) runs of the stage
    Span<int64_t> resolves;   // (STAGE_COUNT,) contact sets the stage resolved (resolve_patches:
                              //   a pair's contacts, or a body's with all its supports)
    bool timed = false;       // read the clock
    int running = -1;         // the stage whose time is counting, -1: none
    double since = 0.0;       // s, when its time last started counting

    // Charge the time since `since` to the running stage and let `next` run from now.
    void switch_to(int next) {
        if (timed) {
            const double now = clock_seconds();
            if (running >= 0) {
                seconds[running] += now - since;
            }
            since = now;
        }
        running = next;
    }
};

// One run of a stage, counted when made and timed from then until it goes out of scope.
class StageTimer {
public:
    StageTimer(StageTimers& timers, Stage stage) : timers_(timers), stage_(stage), outer_(timers.running) {
        timers.calls[stage] += 1;
        timers.switch_to(stage);
    }
    ~StageTimer() { timers_.switch_to(outer_); }
    // Not a run after all (its time still counts): one given up, to run again.
    void uncount() const { timers_.calls[stage_] -= 1; }
    StageTimer(const StageTimer&) = delete;
    StageTimer& operator=(const StageTimer&) = delete;

private:
    StageTimers& timers_;
    Stage stage_;
    int outer_;
};

}  // namespace rg
