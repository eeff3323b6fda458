// What a patch wrench (patch.h) keeps of a patch from one contact pass to the next.
//
// Within a step a pair's contacts keep the points, normals and levers they were found with
// (contacts.h) and each body its inverse inertia I(t)^-1, so a patch with the same contacts
// has the same frame, the same matrix A of its wrench and the same factored system in every
// pass; only the velocities, and so the right-hand side, change. The contact stage keeps
// them per pair for the patch it resolved last and uses them while the patch holds the same
// contacts: the same arithmetic as building them again, bit for bit, at a fraction of the
// cost (the frame, A and its factors are most of a patch resolve's work).
#pragma once

#include <cstdint>

#include "base/math.h"

namespace rg {

// The patch seen from its centre: its geometry and the rotations it constrains.
struct PatchGeometry {
    Vec3 c, n;         // geometric centroid and mean normal (unit) of the patch's points
    Vec3 t1, t2;       // tangent basis
    Vec3 edge;         // an edge's direction
    double rho;        // m, the mean distance of the points from c
    Vec3 d[3];         // the constrained rotations: tip axes first, spin about n last
    int tips;          // 2 for a face, 1 for an edge
    Vec3 ra, rb;       // m, c from each body's predicted centre
};

// A patch's wrench matrix A and its static system factored (factor_dense), each built when
// first needed; their entries are written then (a resolve without a memo zeroes nothing else).
struct PatchSystem {
    bool has_matrix = false;   // matrix is the patch's A
    bool has_factors = false;  // factors and pivot hold the static system's (solvable)
    bool solvable = false;
    double matrix[6][6];
    double factors[6][6];
    int pivot[6];
};

struct PatchMemo {
    uint64_t members = 0;  // bit r: row r of the pair's contacts is in the patch; 0: none kept
    uint8_t movable = 0;   // bit 0: body a takes impulses, bit 1: body b (matrix holds theirs)
    bool point = false;    // the patch is a single point: no wrench
    PatchGeometry geometry = {};
    PatchSystem system = {};
};

// The memo of a pair's patch and the patch's contacts, or no memo (nullptr): a patch with a
// contact not in the pair's kept rows, or in a stage that keeps nothing.
struct PatchKey {
    PatchMemo* memo = nullptr;
    uint64_t members = 0;
    uint8_t movable = 0;
};

}  // namespace rg
