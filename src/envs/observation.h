// The envs' observation rows, gathered from the state of the worlds they observe.
//
// An env's observation is entries of its world's state in a fixed order, some as offsets from
// another entry (a cube's position relative to the pad): envs/core.py builds the order once
// (observation_index), and every step reads all copies in one pass here instead of a dozen
// numpy calls, each of which costs a single env more than the pass.
#pragma once

#include <cstdint>

#include "base/math.h"
#include "base/span.h"

namespace rg {

// The state of B worlds of n bodies, and what to gather. A world's state entries are numbered
// as its positions (n x 3), velocities (n x 3), rotations (n x 9, row-major) and angular
// velocities (n x 3) laid side by side: 18 n entries. Every index must be in range (the
// bindings check them).
struct ObservationQuery {
    Span<const Vec3> position;          // (B n,) m
    Span<const Vec3> velocity;          // (B n,) m/s
    Span<const Mat3> rotation;          // (B n,)
    Span<const Vec3> angular_velocity;  // (B n,) rad/s
    int64_t num_bodies = 0;             // n
    Span<const int64_t> worlds;         // (k,) the worlds observed, a row each
    Span<const int64_t> index;          // (m,) the state entry of each observation entry
    Span<const int64_t> minus;          // (m,) the entry subtracted from it, -1: none
};

// Row r of out ((k m,), row-major) is world worlds[r]'s observation: entry j is its state
// entry index[j], minus its entry minus[j] where that is >= 0. Returns whether every entry
// written is finite.
bool gather_observations(const ObservationQuery& query, Span<double> out);

}  // namespace rg
