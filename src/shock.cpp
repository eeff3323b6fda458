// Shock propagation: level by level from the ground up, the levels below frozen (solver.h).
//
// The contact graph has an edge from each supporting body to the body it supports, judged by
// the contact normal against gravity; side contacts get both directions. Its levels
// (levels.h) are resolved in order: each body of a level against all its frozen supports at
// once, then the pairs inside the level with both bodies movable, for up to `sweeps` sweeps.
#include "levels.h"
#include "solver.h"

namespace rg {

namespace {

// Contacts whose normal is within this cosine of horizontal do not say which body is below:
// the two bodies are put on the same level.
constexpr double SIDE_CONTACT = 0.1;

// Bodies closer than this (m) at the predicted poses count as touching in shock propagation:
// in the contact graph (bodies falling together touch without overlapping, yet the upper one
// rests on the lower) and in a body's patches against its frozen supports (a rocking box's
// lifting corners belong to the face it rests on; the patch wrench decides whether the patch
// holds, j_n > 0, or separates).
constexpr double GRAPH_MARGIN = 1e-4;

constexpr Vec3 NO_LOOKAHEAD = {0.0, 0.0, 0.0};

// Which pairs touch at the predicted poses (graph.touching) and the support edges between
// their bodies (lower to upper, both ways for side contacts); returns the number of edges.
int64_t build_contact_graph(WorldStep& w, int64_t pairs, double dt) {
    const Graph& graph = w.graph;
    const Vec3 up = w.settings->up;
    int64_t edges = 0;
    for (int64_t k = 0; k < pairs; ++k) {
        const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
        graph.touching[k] = find_pair_contacts(w, w.scratch, a, b, dt, NO_LOOKAHEAD, GRAPH_MARGIN) > 0;
        if (!graph.touching[k] || w.model.motion[b] != DYNAMIC) {
            continue;  // b is the ground or a gripper: a rests on level 0
        }
        const double rise = dot(w.scratch.normal[0], up);
        if (rise > -SIDE_CONTACT) {  // b below a (or beside it)
            graph.edge_from[edges] = b;
            graph.edge_to[edges] = a;
            edges += 1;
        }
        if (rise < SIDE_CONTACT) {  // a below b (or beside it)
            graph.edge_from[edges] = a;
            graph.edge_to[edges] = b;
            edges += 1;
        }
    }
    return edges;
}

// One body of the level being processed against all its frozen supports at once: their
// contacts (deepest first per pair, normals turned towards body) go into w.wide and are
// resolved as patches, so a box straddling two frozen boxes is held by both (one support
// alone could hold it only with its centre of pressure on an edge).
int resolve_supported_body(WorldStep& w, int body, int64_t current, double dt) {
    const Graph& graph = w.graph;
    const ContactSet& scratch = w.scratch;
    const ContactSet& wide = w.wide;
    const int64_t capacity = wide.depth.size;
    int64_t count = 0;
    int applied = 0;
    for (int64_t s = graph.body_pair_start[body]; s < graph.body_pair_start[body + 1]; ++s) {
        const int64_t k = graph.body_pairs[s];
        const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
        const int other = a == body ? b : a;
        if (w.model.motion[other] == DYNAMIC && graph.level[other] >= current) {
            continue;  // not frozen: resolved pair by pair
        }
        const int64_t found = find_pair_contacts(w, scratch, a, b, dt, NO_LOOKAHEAD, GRAPH_MARGIN);
        if (count + found > capacity) {
            // no room to combine it: resolve this support on its own rather than drop it
            applied += resolve_pair(w, k, a, b, dt, NO_LOOKAHEAD, SHOCK, 0.0, {a == body, b == body});
            continue;
        }
        const double sign = a == body ? 1.0 : -1.0;
        for (int64_t i = 0; i < found; ++i) {
            wide.point[count] = scratch.point[i];
            wide.normal[count] = scale(sign, scratch.normal[i]);
            wide.partner[count] = other;
            wide.source[count] = k;
            wide.orient[count] = sign;
            count += 1;
        }
        wide.position[other] = scratch.position[other];
        wide.position[body] = scratch.position[body];
    }
    return applied + resolve_patches(w, body, {true, false}, wide, count, SHOCK, 0.0);
}

}  // namespace

void propagate_world_shock(WorldStep& w, int64_t pairs, double dt) {
    const Graph& graph = w.graph;
    const int n = w.num_bodies();
    const int64_t edges = build_contact_graph(w, pairs, dt);
    contact_levels(graph, w.model.motion, edges);
    pairs_by_body(graph, w.lists, pairs, n);
    counting_sort({graph.level.data, graph.level.size}, n, n + 1, graph.counts, graph.by_level);
    int64_t start = 0;
    while (start < n) {
        const int64_t current = graph.level[graph.by_level[start]];
        int64_t end = start;
        while (end < n && graph.level[graph.by_level[end]] == current) {
            end += 1;
        }
        if (current > 0) {
            for (int sweep = 0; sweep < w.settings->shock_sweeps; ++sweep) {
                int applied = 0;
                // each body of the level against all its frozen supports at once
                for (int64_t s = start; s < end; ++s) {
                    applied += resolve_supported_body(w, static_cast<int>(graph.by_level[s]), current, dt);
                }
                // then the pairs inside the level, both bodies movable
                for (int64_t k = 0; k < pairs; ++k) {
                    const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
                    if (graph.touching[k] && graph.level[a] == current && graph.level[b] == current) {
                        applied += resolve_pair(w, k, a, b, dt, NO_LOOKAHEAD, SHOCK, 0.0, {true, true});
                    }
                }
                if (applied == 0) {
                    break;  // another sweep would find the same state and do nothing too
                }
            }
        }
        start = end;
    }
}

}  // namespace rg
