// The envs' gripper command: where the pad goes in an env step, and how low it may go before
// it, or the box it holds, lands on the table or on top of another box.
//
// The gripper stops a downward move where the pad, or the object it holds, would rest on the
// table (z = 0), on the top of a free box under its footprint, or on the top of a box part of a
// static fixture under it (envs/effector.py). Footprints are the boxes' shadows on the table,
// compared by separating axes in the plane.
#pragma once

#include <cstdint>

#include "base/math.h"
#include "base/span.h"

namespace rg {

// The batch of worlds lowest_centres reads, and the work rows it fills. B worlds of n bodies
// each, K boxes; every index must be in range (the bindings check them).
struct FootprintQuery {
    Span<const Vec3> targets;    // (B,) m, the pad's centre at its target
    Span<const Vec3> positions;  // (B n,) m, every body of every world
    Span<const Mat3> rotations;  // (B n,)
    int64_t num_bodies = 0;      // n
    int64_t pad = 0;             // the pad's body index
    Vec3 pad_half = {};          // m
    Span<const int64_t> objects;  // (K,) the boxes' body indices, the same in every world
    Span<const Vec3> halves;     // (K,) m, their half extents
    Span<const int64_t> held;    // (B,) the held box, an index into objects (-1: none)
    // The fixtures' box parts, F of them: part i belongs to body fixed_bodies[i] (static), lies
    // at fixed_offsets[i] and turned by fixed_rotations[i] in that body's frame, with half
    // extents fixed_halves[i] (the same in every world; the body's pose is each world's).
    Span<const int64_t> fixed_bodies;  // (F,)
    Span<const Vec3> fixed_offsets;    // (F,) m
    Span<const Mat3> fixed_rotations;  // (F,)
    Span<const Vec3> fixed_halves;     // (F,) m
    // The bodies that move with the pad (a parallel gripper's fingers), C of them, boxes of
    // half extents carried_halves[i]; C may be 0 (the suction pad).
    Span<const int64_t> carried;        // (C,) body indices
    Span<const Vec3> carried_halves;    // (C,) m
    // (B C,) m: how far each carried body moves relative to the pad over the step (a finger
    // closing or opening), world frame; its part is then the box it sweeps (the box's place
    // at the start and at the end, and between). Empty: none moves.
    Span<const Vec3> carried_sweeps;
    // Work rows, overwritten world by world: the parts (the pad, then the held box, then the
    // carried bodies) and the boxes of the world in hand.
    Span<Vec3> parts_x;     // (2 + C,) m
    Span<Mat3> parts_r;     // (2 + C,)
    Span<Vec3> parts_half;  // (2 + C,) m
    Span<Vec3> boxes_x;     // (K,) m
    Span<Mat3> boxes_r;     // (K,)
};

// For the gripper of every world: the lowest z (m) its centre may take at its target, into
// out (B,). That is where one of its parts (the pad, the object it holds and the carried
// bodies, at the target) would rest on the table or on the top of one of the boxes, or of the fixtures' box parts,
// under its footprint. A box counts as under a part if its top is below the part's bottom
// before the move (the part's bottom at the target minus the move's z, m); the held box is
// ignored.
void lowest_centres(const FootprintQuery& query, Span<double> out);

// A parallel gripper's grasp in the worlds `worlds` (indices into the query's batch), from
// the query's positions, rotations, boxes (objects, halves) and carried bodies, whose first
// two are the fingers (towards -y, then towards +y: they slide along y and never turn): into
// held (k,) the box each world's fingers hold (an index into objects, the first if several,
// -1: none) and into width (k,) m the opening between the fingers' inner faces. A box is held
// where both inner faces lie within `margin` (m) of its bounding box's faces along y and
// overlap it by more than `margin` along x and along z: both pads on it.
void grasps(const FootprintQuery& query, Span<const int64_t> worlds, double margin,
            Span<int64_t> held, Span<double> width);

// One env step's command of every world's pad (the query's targets are ignored: the targets
// are made here).
struct PadCommand {
    Span<const Vec3> motions;  // (B,) each axis in [-1, 1]
    double step_distance = 0;  // m of motion per unit, along each axis
    Vec3 low = {}, high = {};  // m, the workspace the pad's centre stays in
    double step_time = 0;      // s, the env step
    Span<Vec3> velocities;     // (B n,) m/s, every body of every world: the pads' are written
    Span<Vec3> targets;        // (B,) m, work rows
    Span<double> lowest;       // (B,) m, work rows
};

// Command every pad: its target is its centre plus step_distance * motion, clamped to the
// workspace; a downward move stops at lowest_centres' z for that target, but never lifts the
// pad above where it is; the pad's velocity is set to reach its target in step_time (the pad
// is kinematic, and never turns). The arithmetic is numpy's on (B, 3) arrays, in its order.
void command_pads(FootprintQuery query, const PadCommand& command);

// The grippers of a batch of B worlds as the envs drive them (envs/effector.py): what every
// command reads, fixed when they are made, and the command's work rows.
struct Pads {
    int64_t pad = 0;             // the pad's body index
    Vec3 pad_half = {};          // m
    Array<int64_t> objects;      // (K,) the boxes' body indices, the same in every world
    Array<Vec3> halves;          // (K,) m, their half extents
    Array<int64_t> fixed_bodies;  // (F,) the fixtures' box parts (FootprintQuery), F may be 0
    Array<Vec3> fixed_offsets;    // (F,) m
    Array<Mat3> fixed_rotations;  // (F,)
    Array<Vec3> fixed_halves;     // (F,) m
    Array<int64_t> carried;       // (C,) bodies moved with the pad (FootprintQuery), C may be 0
    Array<Vec3> carried_halves;   // (C,) m
    Vec3 low = {}, high = {};    // m, the workspace the pad's centre stays in
    double step_distance = 0;    // m of motion per unit, along each axis
    double step_time = 0;        // s, the env step
    Array<Vec3> boxes_x;         // (K,) work rows of FootprintQuery
    Array<Mat3> boxes_r;         // (K,)
    Array<Vec3> parts_x;         // (2 + C,) work rows of FootprintQuery
    Array<Mat3> parts_r;         // (2 + C,)
    Array<Vec3> parts_half;      // (2 + C,) m
    Array<Vec3> targets;         // (B,) work rows of PadCommand
    Array<double> lowest;        // (B,)
};

}  // namespace rg
