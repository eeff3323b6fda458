// Shock propagation: level by level from the ground up, the levels below frozen (solver.h).
//
// The contact graph has an edge from each supporting body to the body it supports, judged by
// the contact normal against gravity; side contacts get both directions. Its levels
// (levels.h) are resolved in order: each body of a level against all its frozen supports at
// once, then the pairs inside the level with both bodies movable, then (if those applied
// anything) the supports again, for up to `sweeps` sweeps. Every support pair then ends
// non-approaching at the predicted poses, as long as the graph ordered every pair the levels'
// impulses bring into contact; a step whose levels brought apart bodies together builds the
// graph again from the new velocities and resolves the levels again (brought_together).
// A frozen support takes no impulse; with Settings::patch_reactions the sliding friction a
// body gets against a frozen dynamic support is held back as the support's reaction, applied
// once the levels are done, and the levels are resolved again (solver.h), so friction
// between bodies keeps momentum. A resolve that must apply nothing (its bodies' velocities
// as at its last resolve, which applied nothing: quiet) is skipped, bit for bit the same: in
// the falling pile of 1000 the reactions' rounds ran all 4 in 203 of the first 231 stages,
// from level 1 up, and 89% of their resolves applied nothing.
#include <algorithm>
#include <cmath>

#include "solver/contacts.h"
#include "solver/levels.h"
#include "solver/mobility.h"
#include "solver/solver.h"

namespace rg {

namespace {

// Contacts whose normal is within this cosine of horizontal do not say which body is below:
// the two bodies are put on the same level.
constexpr double SIDE_CONTACT = 0.1;

constexpr Vec3 NO_LOOKAHEAD = {0.0, 0.0, 0.0};

// Times the graph is built and its levels resolved in one step (brought_together). In the
// first 0.3 s of the pile of 1000 (scenes.pile, seed 0) a second round ran in 16 of the 116
// shock stages, a third in none; a settled scene needs one.
constexpr int SHOCK_ROUNDS = 3;

// Times the levels are resolved again in one round for the frictional reactions passed on to
// frozen supports (propagate_world_shock). A block sliding on a block needs one; a support
// that friction's reaction turns against its own frictional support, and a body on it that
// follows, a few; what the last leaves is the next step's. The rounds are a fixed-point
// iteration between a body and its support: the body's impulse is sized against the support
// held still, the support then takes it reversed and moves into (or away from) the body by
// k_s / k_b of their relative velocity, k being each one's mobility at the contact, and the
// next round answers that. The series converges to the two bodies' joint impulse where the
// support is the heavier at the point (k_s < k_b) and grows where it is the lighter: in the
// pile of 1000 (seed 2, step 98) a 62 g box under four bodies on its slanted faces took
// reactions that turned it at 64, 96 and 221 rad/s in successive rounds, and it struck a
// sphere 10 mm deep. So a support lighter at the point takes no reaction (solver.cpp,
// lighter_at), and as several bodies' reactions on one support can still add up to a growing
// series, a round whose reactions are larger than the last's (reaction_size) is diverging:
// they are dropped and the rounds stop, what the earlier ones passed on kept (14 times in the
// first 120 steps of that pile).
constexpr int REACTION_ROUNDS = 4;

// m: pairs this close at the predicted poses are ordered by the graph (graph.touching). The
// levels' impulses change velocities by up to metres per second in an impact (a body sinking
// into its supports is stopped, and rises into the one falling just above it), so a pair
// that does not touch yet may be brought into contact; ordered, the upper body is resolved
// against the lower after the lower has moved. All the contacts kept (SPECULATIVE_MARGIN) are
// within reach. Only the order is widened: a body's patches against its frozen supports take
// the contacts within GRAPH_MARGIN.
constexpr double GRAPH_REACH = SPECULATIVE_MARGIN;

// Which pairs are within GRAPH_REACH at the predicted poses (graph.touching) and the
// support edges between their bodies (lower to upper, both ways for side contacts), judged by
// the pair's deepest contact; returns the number of edges.
int64_t build_contact_graph(StepContext& w, int64_t pairs, double dt) {
    const Graph& graph = w.graph;
    const ContactSet& scratch = w.scratch;
    const Vec3 up = w.up;
    int64_t edges = 0;
    for (int64_t k = 0; k < pairs; ++k) {
        const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
        const int64_t found = std::min(
            gather_pair(w, {k, a, -GRAPH_REACH}, dt, NO_LOOKAHEAD, scratch, 0), scratch.depth.size);
        graph.touching[k] = found > 0;
        if (!graph.touching[k] || w.model.motion[b] != DYNAMIC) {
            continue;  // b is the ground or a gripper: a rests on level 0
        }
        int64_t deepest = 0;
        for (int64_t i = 1; i < found; ++i) {
            if (scratch.depth[i] > scratch.depth[deepest]) {
                deepest = i;
            }
        }
        const double rise = dot(scratch.normal[deepest], up);
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

// One body (graph node `node`) of the level being processed against all its frozen supports
// at once: their contacts (normals turned towards the body) go into w.wide and are resolved
// as patches, so a box straddling two frozen boxes is held by both (one support alone could
// hold it only with its centre of pressure on an edge). *reactions counts the frictional
// reactions passed on to frozen dynamic supports (resolve_patches).
int resolve_supported_body(StepContext& w, int64_t node, int64_t current, double dt,
                           int* reactions) {
    const Graph& graph = w.graph;
    const ContactSet& wide = w.wide;
    const int body = static_cast<int>(graph.nodes[node]);
    int64_t count = 0;
    int applied = 0;
    for (int64_t s = graph.body_pair_start[node]; s < graph.body_pair_start[node + 1]; ++s) {
        const int64_t k = graph.body_pairs[s];
        const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
        const int other = a == body ? b : a;
        if (w.model.motion[other] == DYNAMIC && graph.level[graph.node_of[other]] >= current) {
            continue;  // not frozen: resolved pair by pair
        }
        const int64_t found = gather_pair(w, {k, body, -GRAPH_MARGIN}, dt, NO_LOOKAHEAD, wide, count);
        if (count + found > wide.depth.size) {
            // no room to combine it: resolve this support on its own rather than drop it
            applied += resolve_pair(w, k, dt, NO_LOOKAHEAD, SHOCK, 0.0, {a == body, b == body});
            continue;
        }
        count += found;
    }
    return applied +
           resolve_patches(w, body, {true, false}, wide, count, dt, SHOCK, 0.0, reactions);
}

// The next tick of graph.clock, which orders the stage's resolves and velocity changes.
int64_t tick(const Graph& graph) { return ++graph.clock[0]; }

// Body i's velocity changed (graph.changed_at).
void mark_changed(const Graph& graph, int i) { graph.changed_at[i] = tick(graph); }

// After a resolve of bodies a and b (b < 0: a alone) that applied `took` impulses: their
// velocities changed, or the resolve is quiet from now (quiet_since, its slot of
// graph.quiet_since or graph.pair_quiet_since).
void note_resolve(const Graph& graph, int took, int64_t& quiet_since, int a, int b) {
    if (took > 0) {
        mark_changed(graph, a);
        if (b >= 0) {
            mark_changed(graph, b);
        }
        quiet_since = -1;
    } else {
        quiet_since = tick(graph);
    }
}

// Would resolving node `node` (of level `current`) against its frozen supports apply nothing
// for sure? So when its last such resolve applied nothing (graph.quiet_since) and neither it
// nor a frozen dynamic support of it has changed its velocity since: a resolve is a function
// of those velocities and of its pairs' step totals (unchanged: nothing was applied to them),
// the contacts' detection being as that resolve left it. Skipping it is exact, bit for bit.
bool quiet(const StepContext& w, int64_t node, int64_t current) {
    const Graph& graph = w.graph;
    const int body = static_cast<int>(graph.nodes[node]);
    const int64_t since = graph.quiet_since[body];
    if (since < 0 || graph.changed_at[body] > since) {
        return false;
    }
    for (int64_t s = graph.body_pair_start[node]; s < graph.body_pair_start[node + 1]; ++s) {
        const int64_t k = graph.body_pairs[s];
        const int other = w.lists.pair_a[k] == body ? w.lists.pair_b[k] : w.lists.pair_a[k];
        if (w.model.motion[other] == DYNAMIC && graph.level[graph.node_of[other]] < current &&
            graph.changed_at[other] > since) {
            return false;
        }
    }
    return true;
}

// resolve_supported_body for nodes by_level[start:end] of level `current`, but those that are
// quiet; impulses applied.
int resolve_level_supports(StepContext& w, int64_t start, int64_t end, int64_t current, double dt,
                           int* reactions) {
    const Graph& graph = w.graph;
    int applied = 0;
    for (int64_t s = start; s < end; ++s) {
        const int64_t node = graph.by_level[s];
        if (quiet(w, node, current)) {
            continue;
        }
        const int body = static_cast<int>(graph.nodes[node]);
        const int took = resolve_supported_body(w, node, current, dt, reactions);
        note_resolve(graph, took, graph.quiet_since[body], body, -1);
        applied += took;
    }
    return applied;
}

// Resolve the pairs inside level `current` (both bodies movable), but those whose last
// resolve applied nothing with neither body changed since (exact, as quiet); impulses applied.
int resolve_level_pairs(StepContext& w, int64_t current, double dt) {
    const Graph& graph = w.graph;
    int applied = 0;
    for (int64_t s = graph.level_pair_start[current]; s < graph.level_pair_start[current + 1];
         ++s) {
        const int64_t k = graph.level_pairs[s];
        const int a = w.lists.pair_a[k], b = w.lists.pair_b[k];
        const int64_t since = graph.pair_quiet_since[k];
        if (since >= 0 && graph.changed_at[a] < since && graph.changed_at[b] < since) {
            continue;
        }
        const int took = resolve_pair(w, k, dt, NO_LOOKAHEAD, SHOCK, 0.0, {true, true});
        note_resolve(graph, took, graph.pair_quiet_since[k], a, b);
        applied += took;
    }
    return applied;
}

// The levels of the m nodes in order from level `lowest` up, each against its frozen supports,
// then its inside pairs (see top); returns how many frictional reactions were passed on to
// frozen supports. Resolves that would apply nothing for sure are skipped (quiet): the
// second sweep of a level that settled in its first, and in the rounds again for reactions
// every body that neither they nor the changes they made reached.
int resolve_levels(StepContext& w, int64_t m, double dt, int64_t lowest) {
    const Graph& graph = w.graph;
    int reactions = 0;
    int64_t start = 0;
    while (start < m && graph.level[graph.by_level[start]] < lowest) {
        start += 1;  // levels below every body that moved: as they were left
    }
    while (start < m) {
        const int64_t current = graph.level[graph.by_level[start]];
        int64_t end = start;
        while (end < m && graph.level[graph.by_level[end]] == current) {
            end += 1;
        }
        if (current > 0) {
            for (int sweep = 0; sweep < w.settings->shock_sweeps; ++sweep) {
                // each body of the level against all its frozen supports at once
                int applied = resolve_level_supports(w, start, end, current, dt, &reactions);
                // then the pairs inside the level, both bodies movable
                const int inside = resolve_level_pairs(w, current, dt);
                // and the supports again: the last impulse of a sweep must not leave a body of
                // the level moving into a frozen one (a box pressed sideways by its neighbour
                // into a wall sank into it, 3 mm in 1 s, when the sweep ended on their pair)
                if (inside > 0) {
                    applied +=
                        inside + resolve_level_supports(w, start, end, current, dt, &reactions);
                }
                if (applied == 0) {
                    break;  // another sweep would find the same state and do nothing too
                }
            }
        }
        start = end;
    }
    return reactions;
}

// Apply the reactions held back in w.reaction (solver.h) to their bodies and clear them;
// returns the lowest level of a body that took one (the levels below it are unchanged).
int64_t apply_reactions(StepContext& w) {
    const int n = w.num_bodies();
    const BodyStates& s = w.bodies;
    int64_t lowest = w.graph.level.size;
    for (int i = 0; i < n; ++i) {
        Vec3 p = w.reaction[i], l = w.reaction[n + i];
        if (p.x == 0.0 && p.y == 0.0 && p.z == 0.0 && l.x == 0.0 && l.y == 0.0 && l.z == 0.0) {
            continue;
        }
        admit(s, w.model, i, p, l);  // what an articulated body's joints let through
        s.velocity[i] = add(s.velocity[i], scale(w.model.inverse_mass[i], p));
        s.angular_momentum[i] = add(s.angular_momentum[i], l);
        s.angular_velocity[i] = rotate(s.inverse_inertia[i], s.angular_momentum[i]);
        w.reaction[i] = {0.0, 0.0, 0.0};
        w.reaction[n + i] = {0.0, 0.0, 0.0};
        mark_changed(w.graph, i);
        lowest = std::min(lowest, w.graph.level[w.graph.node_of[i]]);
    }
    return lowest;
}

// The size of the reactions held back in w.reaction: the sum of their linear impulses' norms,
// N s.
double reaction_size(const StepContext& w) {
    double size = 0.0;
    for (int i = 0; i < w.num_bodies(); ++i) {
        size += std::sqrt(dot(w.reaction[i], w.reaction[i]));
    }
    return size;
}

// Forget the reactions held back in w.reaction.
void drop_reactions(StepContext& w) {
    for (int64_t i = 0; i < w.reaction.size; ++i) {
        w.reaction[i] = {0.0, 0.0, 0.0};
    }
}

// Did the levels' impulses bring a pair into contact that was apart when the graph was
// built? Its bodies overlap at the predicted poses now, and the graph ordered them by
// nothing: the lower one, pushed up off its supports, runs into a body that was falling
// just above it, and a body processed earlier is not stopped by one processed later.
bool brought_together(StepContext& w, int64_t pairs, double dt) {
    for (int64_t k = 0; k < pairs; ++k) {
        if (!w.graph.touching[k] &&
            gather_pair(w, {k, w.lists.pair_a[k], 0.0}, dt, NO_LOOKAHEAD, w.scratch, 0) > 0) {
            return true;
        }
    }
    return false;
}

// A new graph: no resolve of the m nodes or the pairs has been found quiet yet.
void forget_quiet(StepContext& w, int64_t pairs, int64_t m) {
    const Graph& graph = w.graph;
    for (int64_t v = 0; v < m; ++v) {
        graph.quiet_since[graph.nodes[v]] = -1;
        graph.changed_at[graph.nodes[v]] = -1;
    }
    for (int64_t k = 0; k < pairs; ++k) {
        graph.pair_quiet_since[k] = -1;
    }
    graph.clock[0] = 0;
}

}  // namespace

void propagate_world_shock(StepContext& w, int64_t pairs, double dt) {
    const Graph& graph = w.graph;
    const int64_t m = graph_nodes(graph, w.lists, pairs, w.num_bodies());
    for (int round = 0; round < SHOCK_ROUNDS; ++round) {
        const int64_t edges = build_contact_graph(w, pairs, dt);
        contact_levels(graph, w.model.motion, edges, m);
        pairs_by_body(graph, w.lists, pairs, m);
        pairs_by_level(graph, w.lists, pairs, m);
        forget_quiet(w, pairs, m);
        // friction's reactions passed on to frozen supports (Settings::patch_reactions) move
        // them against their own supports: the levels are resolved again from the ground up
        // while any were passed on (a block sliding on a block on a frictionless floor: once)
        int reactions = resolve_levels(w, m, dt, 0);
        double size = reactions > 0 ? reaction_size(w) : 0.0;
        for (int again = 0; reactions > 0 && again < REACTION_ROUNDS; ++again) {
            reactions = resolve_levels(w, m, dt, apply_reactions(w));
            const double next = reactions > 0 ? reaction_size(w) : 0.0;
            if (next > size) {  // the rounds diverge: stop them
                drop_reactions(w);
                reactions = 0;
            }
            size = next;
        }
        if (reactions > 0) {
            apply_reactions(w);  // what the last round passed on: the next step's to settle
        }
        if (!brought_together(w, pairs, dt)) {
            break;
        }
    }
    forget_nodes(graph, m);
}

}  // namespace rg
