// The step: its stages in order, for one world and for a batch of worlds.
#pragma once

#include "world.h"

namespace rg {

// Bits of `phases`: which of a step's stages a call runs, in this order (the step's).
enum StepPhase : int {
    BROAD_PHASE = 1,
    COLLISION_PHASE = 2,
    VELOCITY_PHASE = 4,
    CONTACT_PHASE = 8,
    SHOCK_PHASE = 16,
    POSITION_PHASE = 32,
    EVERY_PHASE = 63,  // whole steps
    IMPULSE_PHASES = COLLISION_PHASE | VELOCITY_PHASE | CONTACT_PHASE | SHOCK_PHASE,
};

// Advance world w by up to `steps` steps of dt (s), running the stages whose bits are set in
// `phases` (EVERY_PHASE: whole steps); returns how many were done. Fewer means the pair
// buffers were too small for the next step (nothing of that step was applied; the world's
// pair_count says how many pairs it needs). Forces and torques act during the first step and
// are cleared by its position update.
int64_t step_world(WorldStep& w, int64_t steps, int phases, double dt);

// Advance every world of the context by `steps` steps (step_world), sharing ranges of worlds
// out over the thread pool, growing the pair buffers and running again where they were too
// small. A world's arithmetic is the same whichever range it is in, so results are
// bit-identical however the worlds are grouped.
void advance(StepContext& context, int64_t steps, int phases, double dt);

}  // namespace rg
