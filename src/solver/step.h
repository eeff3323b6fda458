// The step: its stages in order, for one world and for a batch of worlds.
#pragma once

#include "solver/world.h"

namespace rg {

// Advance world w by up to `steps` steps of dt (s), every stage of each in order, timing each
// stage into w.timers; returns how many were done. Fewer means the pair buffers were too
// small for the next step (nothing of that step was applied; the world's pair_count says how
// many pairs it needs), or its contact pool was (its velocities were put back and the world
// woken: contacts.h; contact_rows_needed says how many rows). Forces and torques act during
// the first step and are cleared by its position update.
int64_t step_world(StepContext& w, int64_t steps, double dt);

// Advance every world of the batch by `steps` steps (step_world), on the calling thread or
// sharing ranges of worlds out over the thread pool, whichever has been faster for this batch
// (sharing.h), growing the pair buffers and running again where they were too small. A
// world's arithmetic is the same whichever range and thread it is in, so results are
// bit-identical however the worlds are grouped.
void advance(Batch& batch, int64_t steps, double dt);

}  // namespace rg
