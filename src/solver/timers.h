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

namespace rg {

// The step's stages, in step order: each one's row in a world's timers.
enum Stage : int {
    BROAD_STAGE,
    COLLISION_STAGE,
    VELOCITY_STAGE,
    CONTACT_STAGE,
    SHOCK_STAGE,
    POSITION_STAGE,
    STAGE_COUNT,
};

// Their names, as World.profile() reports them.
inline constexpr const char* STAGE_NAMES[STAGE_COUNT] = {
    "broad_phase", "collision", "update_velocities", "contact", "shock_propagation",
    "update_positions"};

// One world's timers, accumulated over every step since the world was made.
struct StageTimers {
    Span<double> seconds;  // (STAGE_COUNT,) s of wall time, while `timed`
    Span<int64_t> calls;   // (STAGE_COUNT,) runs of the stage
    bool timed = false;    // read the clock
};

// Seconds on a monotonic clock (the origin is arbitrary).
inline double clock_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

// Where the first stage starts: the time now, or 0 when not timed.
inline double start_timing(const StageTimers& timers) {
    return timers.timed ? clock_seconds() : 0.0;
}

// Count `calls` more runs of `stage` and, when timed, charge it the time since `since`
// (start_timing or the last lap); returns where the next stage starts.
inline double lap(const StageTimers& timers, Stage stage, double since, int64_t calls = 1) {
    timers.calls[stage] += calls;
    if (!timers.timed) {
        return 0.0;
    }
    const double now = clock_seconds();
    timers.seconds[stage] += now - since;
    return now;
}

}  // namespace rg
