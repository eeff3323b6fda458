// Pair and contact queries (queries.h).
#include "solver/queries.h"

#include <algorithm>

#include "collision/narrow_phase.h"
#include "solver/patch.h"

namespace rg {

std::vector<int32_t> candidate_pairs(Batch& batch, double margin, int w) {
    const int n = batch.num_bodies();
    const StepContext s = batch.world(w);
    PairListBuffers buffers;  // one world's, apart from the batch's
    int64_t capacity = std::max<int64_t>(8, 2 * n);
    while (true) {
        buffers.allocate_bodies(1, n);  // order 0..n-1, no reach
        buffers.allocate_pairs(1, capacity);
        const PairLists lists = buffers.rows(0);
        const int64_t count = find_world_pairs(batch.geometry(), s.model.motion, s.bodies, margin,
                                               0.0, 0.0, batch.settings().sweep, lists);
        if (count <= capacity) {
            std::vector<int32_t> pairs(2 * count);
            for (int64_t k = 0; k < count; ++k) {
                pairs[2 * k] = lists.pair_a[k];
                pairs[2 * k + 1] = lists.pair_b[k];
            }
            return pairs;
        }
        capacity = 2 * count;
    }
}

ContactRows detect_contacts(Batch& batch, double margin, int first, int last) {
    const Geometry& geo = batch.geometry();
    margin += CLOSED_GAP;  // resting contacts: touching to round-off, as the solver counts them
    ContactRows rows;
    Array<Vec3> point(64), normal(64);
    Array<double> depth(64);
    for (int w = first; w < last; ++w) {
        const StepContext s = batch.world(w);
        const std::vector<int32_t> pairs = candidate_pairs(batch, margin, w);
        for (size_t k = 0; k < pairs.size(); k += 2) {
            const int a = pairs[k], b = pairs[k + 1];
            const Pose pa = {s.bodies.position[a], s.bodies.rotation[a]};
            const Pose pb = {s.bodies.position[b], s.bodies.rotation[b]};
            int found = collide_bodies(geo, a, b, pa, pb, margin,
                                       {point.span(), normal.span(), depth.span()}, 0);
            if (found > depth.size()) {
                point.assign(2 * found, {});
                normal.assign(2 * found, {});
                depth.assign(2 * found, 0.0);
                found = collide_bodies(geo, a, b, pa, pb, margin,
                                       {point.span(), normal.span(), depth.span()}, 0);
            }
            for (int c = 0; c < found; ++c) {
                rows.world.push_back(w);
                rows.body_a.push_back(a);
                rows.body_b.push_back(b);
                rows.point.insert(rows.point.end(), {point[c].x, point[c].y, point[c].z});
                rows.normal.insert(rows.normal.end(), {normal[c].x, normal[c].y, normal[c].z});
                rows.depth.push_back(depth[c]);
            }
        }
    }
    return rows;
}

}  // namespace rg
