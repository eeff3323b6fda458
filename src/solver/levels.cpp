// Tarjan's components, the levels of the condensed graph, and counting sorts (levels.h).
#include "solver/levels.h"

#include <algorithm>

namespace rg {

namespace {

// Tarjan's algorithm without recursion over the graph whose node v has the successors
// graph.targets[edge_start[v] : edge_start[v + 1]]. Writes graph.component and returns the
// count. Components come out in reverse topological order: an edge between components
// always goes from a higher number to a lower one.
int64_t strongly_connected_components(const Graph& graph, int64_t n) {
    for (int64_t v = 0; v < n; ++v) {
        graph.index[v] = -1;
        graph.low[v] = 0;
        graph.on_stack[v] = 0;
    }
    int64_t counter = 0, count = 0, top = 0;
    for (int64_t root = 0; root < n; ++root) {
        if (graph.index[root] >= 0) {
            continue;
        }
        int64_t depth = 0;
        int64_t v = root;
        while (true) {
            if (graph.index[v] < 0) {  // first visit
                graph.index[v] = graph.low[v] = counter++;
                graph.stack[top++] = v;
                graph.on_stack[v] = 1;
                graph.next_edge[v] = graph.edge_start[v];
                graph.calls[depth++] = v;
            }
            v = graph.calls[depth - 1];
            if (graph.next_edge[v] < graph.edge_start[v + 1]) {
                const int64_t u = graph.targets[graph.next_edge[v]++];
                if (graph.index[u] < 0) {
                    v = u;
                    continue;
                }
                if (graph.on_stack[u]) {
                    graph.low[v] = std::min(graph.low[v], graph.index[u]);
                }
                continue;
            }
            if (graph.low[v] == graph.index[v]) {
                while (true) {
                    const int64_t x = graph.stack[--top];
                    graph.on_stack[x] = 0;
                    graph.component[x] = count;
                    if (x == v) {
                        break;
                    }
                }
                count += 1;
            }
            depth -= 1;
            if (depth == 0) {
                break;
            }
            const int64_t parent = graph.calls[depth - 1];
            graph.low[parent] = std::min(graph.low[parent], graph.low[v]);
            v = parent;
        }
    }
    return count;
}

}  // namespace

void counting_sort(Span<const int64_t> keys, int64_t n, int64_t num_keys, Span<int64_t> counts,
                   Span<int64_t> out) {
    for (int64_t k = 0; k < num_keys + 1; ++k) {
        counts[k] = 0;
    }
    for (int64_t v = 0; v < n; ++v) {
        counts[keys[v] + 1] += 1;
    }
    for (int64_t k = 0; k < num_keys; ++k) {
        counts[k + 1] += counts[k];
    }
    for (int64_t v = 0; v < n; ++v) {
        out[counts[keys[v]]++] = v;
    }
}

int64_t graph_nodes(const Graph& graph, const PairLists& lists, int64_t pairs, int num_bodies) {
    int64_t m = 0;
    for (int64_t k = 0; k < pairs; ++k) {
        for (const int64_t v : {static_cast<int64_t>(lists.pair_a[k]), static_cast<int64_t>(lists.pair_b[k])}) {
            if (graph.node_of[v] < 0) {
                graph.node_of[v] = 0;
                graph.nodes[m++] = v;
            }
        }
    }
    if (m * 16 < num_bodies) {  // few: sorting them costs less than a scan of every body
        std::sort(graph.nodes.data, graph.nodes.data + m);
    } else {
        int64_t at = 0;
        for (int64_t v = 0; v < num_bodies; ++v) {
            if (graph.node_of[v] >= 0) {
                graph.nodes[at++] = v;
            }
        }
    }
    for (int64_t i = 0; i < m; ++i) {
        graph.node_of[graph.nodes[i]] = i;
    }
    return m;
}

void forget_nodes(const Graph& graph, int64_t m) {
    for (int64_t i = 0; i < m; ++i) {
        graph.node_of[graph.nodes[i]] = -1;
    }
}

void contact_levels(const Graph& graph, Span<const int32_t> motion, int64_t num_edges, int64_t m) {
    // CSR form of the edges, each node's successors in edge order
    for (int64_t v = 0; v < m + 1; ++v) {
        graph.edge_start[v] = 0;
    }
    for (int64_t k = 0; k < num_edges; ++k) {
        graph.edge_start[graph.node_of[graph.edge_from[k]] + 1] += 1;
    }
    for (int64_t v = 0; v < m; ++v) {
        graph.edge_start[v + 1] += graph.edge_start[v];
        graph.counts[v] = graph.edge_start[v];
    }
    for (int64_t k = 0; k < num_edges; ++k) {
        graph.targets[graph.counts[graph.node_of[graph.edge_from[k]]]++] = graph.node_of[graph.edge_to[k]];
    }
    const int64_t count = strongly_connected_components(graph, m);
    for (int64_t c = 0; c < count; ++c) {
        graph.component_level[c] = 1;
    }
    // topological order: components from the highest number down
    for (int64_t v = 0; v < m; ++v) {
        graph.level[v] = count - 1 - graph.component[v];  // used as the sort key
    }
    counting_sort({graph.level.data, graph.level.size}, m, count, graph.counts, graph.by_component);
    for (int64_t i = 0; i < m; ++i) {
        const int64_t v = graph.by_component[i];
        const int64_t c = graph.component[v];
        for (int64_t k = graph.edge_start[v]; k < graph.edge_start[v + 1]; ++k) {
            const int64_t u = graph.targets[k];
            if (graph.component[u] != c) {
                graph.component_level[graph.component[u]] =
                    std::max(graph.component_level[graph.component[u]], graph.component_level[c] + 1);
            }
        }
    }
    for (int64_t v = 0; v < m; ++v) {
        graph.level[v] = motion[graph.nodes[v]] == DYNAMIC ? graph.component_level[graph.component[v]] : 0;
    }
    counting_sort({graph.level.data, graph.level.size}, m, m + 1, graph.counts, graph.by_level);
}

void pairs_by_body(const Graph& graph, const PairLists& lists, int64_t pairs, int64_t m) {
    const Span<int64_t> start = graph.body_pair_start, fill = graph.counts;
    for (int64_t v = 0; v < m + 1; ++v) {
        start[v] = 0;
    }
    for (int64_t k = 0; k < pairs; ++k) {
        if (graph.touching[k]) {
            start[graph.node_of[lists.pair_a[k]] + 1] += 1;
            start[graph.node_of[lists.pair_b[k]] + 1] += 1;
        }
    }
    for (int64_t v = 0; v < m; ++v) {
        start[v + 1] += start[v];
        fill[v] = start[v];
    }
    for (int64_t k = 0; k < pairs; ++k) {
        if (graph.touching[k]) {
            graph.body_pairs[fill[graph.node_of[lists.pair_a[k]]]++] = k;
            graph.body_pairs[fill[graph.node_of[lists.pair_b[k]]]++] = k;
        }
    }
}

void pairs_by_level(const Graph& graph, const PairLists& lists, int64_t pairs, int64_t m) {
    const Span<int64_t> start = graph.level_pair_start, fill = graph.counts;
    const auto level_of = [&](int body) { return graph.level[graph.node_of[body]]; };
    const auto inside = [&](int64_t k) {
        const int64_t la = level_of(lists.pair_a[k]);
        return graph.touching[k] && la > 0 && la == level_of(lists.pair_b[k]);
    };
    for (int64_t l = 0; l < m + 2; ++l) {
        start[l] = 0;
    }
    for (int64_t k = 0; k < pairs; ++k) {
        if (inside(k)) {
            start[level_of(lists.pair_a[k]) + 1] += 1;
        }
    }
    for (int64_t l = 0; l < m + 1; ++l) {
        start[l + 1] += start[l];
        fill[l] = start[l];
    }
    for (int64_t k = 0; k < pairs; ++k) {
        if (inside(k)) {
            graph.level_pairs[fill[level_of(lists.pair_a[k])]++] = k;
        }
    }
}

}  // namespace rg
