// Sleeping: an island whose last step changed nothing is not stepped again, exactly.
//
// The step is a deterministic function of the state. Bodies joined by listed pairs or by
// joints (joints.h) form islands (static and kinematic bodies join nothing: they take no
// impulse, so the pairs and joints they share carry nothing from one island to another).
// What the impulse stages do to an island depends only on its own bodies, its pairs and
// joints and the static or kinematic bodies it touches:
// a pair's resolve reads and writes only its two bodies, so pairs of other islands commute
// with it, and the passes or sweeps that other islands still need find this island as their
// last one left it and apply nothing. The pairs of an island are listed in the order of
// their (a, b) indices (broad_phase.h), so the same pairs are the same sequence.
//
// So if, at the start of a step, every body of an island and every static or kinematic body
// it touches is exactly (bit for bit) as it was at the start of the last step, the island
// has the same bodies and the same number of listed pairs as then, no force, torque or
// attachment acts on it in this step or acted in the last, and the last step left it where
// it began (forget_moved: not a body put back between steps), this step would leave it
// exactly where the last one did: where it is. (Its pairs are then the same: the broad phase lists
// an island's pairs from its bodies' and their partners' states, and a partner unchanged
// since the last step was listed then.)
// The island is then asleep for the step: its pairs are moved behind the awake pairs, which
// are all the impulse stages see (their order kept); its bodies are left out of the
// velocity and position updates (which would give them the last step's velocities and move
// them by those, i.e. nowhere: a fixed point); and each of its pairs reports the impulse it
// transmitted in the last step, as stepping it would. A settled stack is such a fixed point;
// anything touching it (a moving body listed with one of its bodies joins the island and
// changes it), a force, a moving kinematic body it touches, wakes it.
//
// Piles and pyramids are no such fixed points: round-off moves them by ~1e-17 m a step. With
// Settings::sleep_speed > 0 an island that is not disturbed (the same bodies and pairs, its
// partners unchanged, no force or attachment) and whose every point has moved slower than
// sleep_speed for SLEEP_TIME is stopped: its velocities are zeroed and it sleeps, as Box2D
// and MuJoCo put islands to sleep. Stopped, it is a fixed point of the comparison above and
// stays asleep until it is disturbed. That changes trajectories, so it is off by default.
//
// What the comparison cannot see wakes a world from Python (Batch::forget): new masses,
// friction or restitution, a reset or load, attaching and detaching. A relist in a step
// (step.cpp) wakes its world too, and so does a step run again because its contacts
// overflowed the pool (contacts.h). A growth of the pair buffers wakes nothing: every world
// keeps its last step's pairs. The test of exactness is stepping with sleeping on and off and
// comparing every state and impulse bit for bit (tests/test_solver.py).
#pragma once

#include "solver/world.h"

namespace rg {

// s: how long an island must have moved slower than Settings::sleep_speed to be stopped
// (Box2D's time to sleep).
constexpr double SLEEP_TIME = 0.5;

// At the start of a step of dt s, before the broad phase: rest.kept, the bodies whose pairs
// with each other the broad phase takes from the last step's list (broad_phase.h, Carried).
// A static or kinematic body unchanged since the last step began, and a dynamic body that
// slept through it as part of a fixed point (rest.resting: not one stopped in that step,
// whose listing saw it moving) and is unchanged since: the list is a function of the two
// bodies' states and dt, so each such pair is listed as it was then. None after a change of
// dt or a forgotten world. What a body asleep costs a step is then this comparison; its pairs
// with a moving body are still tested.
void mark_kept(StepContext& w, double dt);

// At the start of a step of dt s, after the broad phase (its count pairs; pair_impulse
// zeroed) and before the step keeps its starting velocities: find the islands, decide which
// sleep (stopping the slow ones, with Settings::sleep_speed), move their pairs behind the
// awake ones (rest.awake_pairs says how many those are) with the last step's impulses, and
// keep this step's islands and states for the next.
void mark_asleep(StepContext& w, int64_t count, double dt);

// At the start of a step of dt s, before anything else: is the world still at rest? Every
// dynamic body slept through the last step (Rest::at_rest), and no body's state changed
// since that step began, no force or torque acts (an attachment or a change from Python
// forgets the world: Batch::forget). Then each island is the fixed point of the
// argument above and the step would change nothing: not the states, the listed pairs, their
// order or impulses. The caller skips the step whole; this only counts each body's time
// below Settings::sleep_speed on, as the step would. Its cost is the comparison of each
// body's state with its snapshot. A step of another dt than the last is always run.
bool still_at_rest(StepContext& w, double dt);

// Reorder the count pairs: those without an asleep body first, then those with one, each in
// their order; returns how many are awake.
int64_t move_asleep_last(StepContext& w, int64_t count);

// At the end of a step (after the impulse stages): its listed pairs and their impulses, for the
// next step's asleep pairs.
void keep_pair_impulses(StepContext& w);

// At the end of a step: forget the snapshot of every awake dynamic body the step moved. A
// state equal to the last step's start is a fixed point only if that step left it there:
// a body put back between steps (set_pose and set_velocity before each step, an impulse
// that cancels gravity's) starts each step as the last one did, yet each step moves it.
void forget_moved(StepContext& w);

// No body sleeps in the rest of this step (all its count pairs are awake) or in the next.
void wake_world(StepContext& w, int64_t count);

}  // namespace rg
