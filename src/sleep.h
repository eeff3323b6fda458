// Sleeping: a body whose last step changed nothing is not stepped again, exactly.
//
// The step is a deterministic function of the state. A dynamic body whose only listed pair is
// with one static or kinematic body (a cube resting on the table) is solved by that pair
// alone: the pair shares no movable body with any other, so the contact stage resolves it at
// e = 0 on its own (solver.cpp), and shock propagation puts the body on level 1 against its
// one frozen support; extra passes or sweeps that other bodies need find the same state again
// and apply nothing. So if, at the start of a step, such a body, its partner and its pair are
// exactly (bit for bit) as they were at the start of the last step, and no force, torque or
// attachment acts on it, this step would leave it exactly where the last one did: where it
// is. The body is then asleep for the step: its pair is moved behind the awake pairs, which
// are all the impulse stages see (their order kept, and what the stages do with a pair depends
// only on the pairs sharing a movable body with it); its velocities are put back before the
// position update (which then moves it by the same velocity as the last step's, i.e. nowhere:
// it is a fixed point); and its pair reports the impulse it transmitted in the last step, as
// stepping it would.
//
// What the comparison cannot see wakes a world from Python (StepContext::forget): new masses,
// friction or restitution, a reset or load, attaching and detaching. A relist in a step
// (step.cpp) wakes its world too. The test of exactness is stepping with sleeping on and off
// and comparing every state and impulse bit for bit (tests/test_solver.py).
#pragma once

#include "world.h"

namespace rg {

// Rest::partner values: no pair; more than one, or one with a dynamic body (also: forgotten).
constexpr int64_t NONE = -2;
constexpr int64_t SEVERAL = -1;

// At the start of a step, after the broad phase (its count pairs; pair_impulse zeroed):
// decide which bodies are asleep, move their pairs behind the awake ones (rest.awake_pairs
// says how many those are) with the last step's impulses, and keep this step's partners and
// states for the next.
void mark_asleep(WorldStep& w, int64_t count);

// Reorder the count pairs: those without an asleep body first, then those with one, each in
// their order; returns how many are awake.
int64_t move_asleep_last(WorldStep& w, int64_t count);

// At the end of the impulse stages: the impulse each body with one static or kinematic
// partner took through its pair (for the next step, should it sleep).
void keep_rest_impulses(WorldStep& w);

// No body sleeps in the rest of this step (all its count pairs are awake) or in the next.
void wake_world(WorldStep& w, int64_t count);

}  // namespace rg
