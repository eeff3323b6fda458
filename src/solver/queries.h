// Queries of a batch's current state that the step does not need: the broad phase's pairs and
// the contacts at the current poses (World.candidate_pairs, World.contacts). They use buffers
// of their own, so asking never disturbs what the last step listed.
#pragma once

#include <vector>

#include "solver/world.h"

namespace rg {

// World w's candidate pairs at its current poses (dt = 0), boxes grown by margin (m): 2 body
// indices (a, b) per pair, in the broad phase's order.
std::vector<int32_t> candidate_pairs(Batch& batch, double margin, int w);

// Contacts as flat rows over worlds [first, last), deepest first within each pair: every
// point of one body inside another or touching it (depth > -CLOSED_GAP, patch.h: a body
// resting on another touches it to round-off, at a depth of about +-1e-16 m), or within
// margin (m) of it.
struct ContactRows {
    std::vector<int32_t> world, body_a, body_b;
    std::vector<double> point, normal, depth;  // point and normal: 3 per row
};

ContactRows detect_contacts(Batch& batch, double margin, int first, int last);

}  // namespace rg
