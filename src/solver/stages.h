// The step's stages: their order, names and the rules for which of them a step runs.
//
// step_world (step.cpp) runs them in this order, as Box2D v3's b2World_Step walks its
// b2SolverStage list; each stage's row in a world's timers (timers.h) is its index here, and
// World.profile() in Python reads the names and the rules from here (rigid_gym._core.STAGES,
// stage_rules). A new stage (continuous collision before the position update, say) is one
// entry here, with its name and its rule below, and one call in
// step_world (or impulse_stages, step.cpp).
#pragma once

#include <array>

#include "solver/settings.h"

namespace rg {

enum Stage : int {
    SLEEP_CHECK_STAGE,       // sleep.h: a world still at rest skips its step; unchanged bodies kept
    PREPARE_STAGE,           // held bodies placed, inverse inertia formed, reach cleared
    BROAD_STAGE,             // broad_phase.h: the pairs whose boxes may meet within the step
    SLEEP_ISLANDS_STAGE,     // sleep.h: islands found, the asleep ones' pairs put last
    COLLISION_STAGE,         // solver.h: old velocities, real restitution
    VELOCITY_STAGE,          // integrate.h: gravity and forces
    JOINT_VELOCITY_STAGE,    // joints.h: every joint's rows at rate 0, its limits and motor
    CONTACT_STAGE,           // solver.h: restitution ramped to 0
    SHOCK_STAGE,             // shock.cpp: level by level from the ground up
    JOINT_POSITION_STAGE,    // joints.h: pre-stabilisation, the poses the position update reaches
    RELIST_STAGE,            // step.cpp: a body sped past its box lists more pairs; impulses again
    OVERLAP_STAGE,           // overlap.h
    POSITION_STAGE,          // integrate.h
    JOINT_PROJECTION_STAGE,  // joints.h: the velocities the joints allow at the new poses
    SLEEP_RECORD_STAGE,      // sleep.h: the pairs, impulses and moved bodies the next step compares
    STAGE_COUNT,
};

// Their names, as World.profile() reports them.
inline constexpr const char* STAGE_NAMES[STAGE_COUNT] = {
    "sleep_check", "prepare", "broad_phase", "sleep_islands", "collision", "update_velocities",
    "joint_velocity", "contact", "shock_propagation", "joint_position", "relist",
    "overlap_correction", "update_positions", "joint_projection", "sleep_records"};

using StageSwitches = std::array<bool, STAGE_COUNT>;

// Which stages the steps of a scene with or without gravity and joints run under these
// settings. A stage switched on still skips a step in which it has nothing to do (step.cpp: no
// awake pair for the impulse stages, no contact found for overlap correction). Shock
// propagation orders bodies along gravity, so without it it never runs; the broad phase runs
// where an impulse stage may; the joint stages where the scene has joints.
inline StageSwitches stage_rules(const Settings& s, bool gravity, bool joints) {
    StageSwitches on{};
    on.fill(true);
    on[SLEEP_CHECK_STAGE] = on[SLEEP_ISLANDS_STAGE] = on[SLEEP_RECORD_STAGE] = s.sleep;
    on[BROAD_STAGE] = on[RELIST_STAGE] =
        s.collision_passes > 0 || s.contact_passes > 0 || s.shock_sweeps > 0;
    on[COLLISION_STAGE] = s.collision_passes > 0;
    on[CONTACT_STAGE] = s.contact_passes > 0;
    on[SHOCK_STAGE] = s.shock_sweeps > 0 && gravity;
    on[OVERLAP_STAGE] = s.overlap_correction > 0.0;
    on[JOINT_VELOCITY_STAGE] = on[JOINT_POSITION_STAGE] = on[JOINT_PROJECTION_STAGE] =
        s.joint_passes > 0 && joints;
    return on;
}

}  // namespace rg
