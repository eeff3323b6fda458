// Settings: what SolverConfig (rigid_gym/config.py) decides, as the stages take it. The one
// home of each setting's default: SolverConfig's fields default to a Settings() made here
// (bound as rigid_gym._core.Settings), and the stage rules (stages.h) read these fields.
#pragma once

namespace rg {

struct Settings {
    int collision_passes = 5;         // solver.h; 0: stage off
    int contact_passes = 10;          // solver.h; 0: stage off
    int shock_sweeps = 2;             // shock.cpp; 0: stage off
    int rotation_order = 2;           // 1, 2 or 3 (integrate.h)
    bool sweep = false;               // broad phase by sort and sweep (else brute force)
    bool sleep = true;                // sleep.h
    double sleep_speed = 0.0;         // sleep.h: m/s under which a slow island is stopped; 0: exact only
    bool detect_every_pass = false;   // contacts.h: the narrow phase in every pass
    bool keep_energy = true;          // integrate.h: rotation update put back on the body's energy
    double overlap_correction = 1.0;  // overlap.h: fraction of excess overlap removed per step
    bool overlap_energy = true;       // overlap.h: a lifted body's step gains no energy
    int joint_passes = 20;            // joints.h: rounds of each joint solve; 0: joint stages off
    bool continuous = true;           // continuous.h: pairs that move far in a step found at impact
    bool contact_patches = true;      // solver.h: patch wrenches between movable bodies, and a
                                      //   body held by immovable ones against all of them at once
    bool patch_reactions = true;      // solver.h: shock impulses booked to pairs by the lever
                                      //   rule, friction's reaction passed to dynamic supports
    bool exact_symmetric = true;      // integrate.h: a symmetric body free of torque turns by its
                                      //   exact motion (symmetric_rotation), predicted so too
};

}  // namespace rg
