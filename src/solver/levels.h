// The contact graph's levels for shock propagation: bodies ordered from the ground up.
//
// An edge goes from each supporting body to the body it supports (shock.cpp decides which is
// which from the contact normal against gravity; side contacts get both). Cycles (bodies
// supporting each other side by side) are collapsed into one node by Tarjan's strongly
// connected components; the condensed graph is a DAG, and each body's level is 1 + the
// highest level among its supports (static and kinematic bodies: level 0).
#pragma once

#include "solver/world.h"

namespace rg {

// graph.nodes: the bodies of the first `pairs` listed pairs, in index order, and graph.node_of
// for them; returns how many (m). Its cost follows the pairs, not the world's bodies, where
// there are few; a body of no pair would be a node alone on level 1 (0 if not dynamic) with
// nothing to resolve, so leaving it out changes no other node's level or order.
int64_t graph_nodes(const Graph& graph, const PairLists& lists, int64_t pairs, int num_bodies);

// graph.node_of back to -1 for the m nodes.
void forget_nodes(const Graph& graph, int64_t m);

// graph.level for each of the m nodes, from the edges graph.edge_from/edge_to[:num_edges]
// (bodies), and graph.by_level: the nodes ordered by level, ties by index.
void contact_levels(const Graph& graph, Span<const int32_t> motion, int64_t num_edges, int64_t m);

// CSR adjacency of the touching pairs: node v's pairs are
// graph.body_pairs[body_pair_start[v] : body_pair_start[v + 1]], in pair order.
void pairs_by_body(const Graph& graph, const PairLists& lists, int64_t pairs, int64_t m);

// CSR lists of the touching pairs whose two bodies share a level (above 0): level l's are
// graph.level_pairs[level_pair_start[l] : level_pair_start[l + 1]], in pair order. Shock
// propagation resolves them level by level; one pass over the pairs finds them all, where
// scanning every pair for every level costs pairs x levels.
void pairs_by_level(const Graph& graph, const PairLists& lists, int64_t pairs, int64_t m);

// out[:n] = the indices 0..n-1 ordered by keys[:n] (ints in [0, num_keys)), ties by index
// (a stable sort); counts: (>= num_keys + 1,) scratch.
void counting_sort(Span<const int64_t> keys, int64_t n, int64_t num_keys, Span<int64_t> counts,
                   Span<int64_t> out);

}  // namespace rg
