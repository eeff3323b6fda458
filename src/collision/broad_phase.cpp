// Sort and sweep, brute force, the turned-box test and the pair ordering (broad_phase.h).
#include "collision/broad_phase.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace rg {

namespace {

// Added to |cos| between two boxes' axes in the separating-axis test: for nearly parallel
// edges the cross-product axis is nearly zero and its projections are round-off, which must
// not separate the boxes (Ericson, Real-Time Collision Detection, 4.4.1).
constexpr double BOX_AXIS_SLACK = 1e-9;

// World box of body i, grown by margin (m).
Aabb world_bounds(const Geometry& geo, int i, Vec3 x, const Mat3& r, double margin) {
    const Vec3 c = geo.body_bound_center[i];
    const Vec3 e = geo.body_bound_half[i];
    Aabb box;
    for (int k = 0; k < 3; ++k) {
        const double centre = x[k] + r.m[k][0] * c.x + r.m[k][1] * c.y + r.m[k][2] * c.z;
        const double half = std::fabs(r.m[k][0]) * e.x + std::fabs(r.m[k][1]) * e.y +
                            std::fabs(r.m[k][2]) * e.z + margin;
        set_component(box.lo, k, centre - half);
        set_component(box.hi, k, centre + half);
    }
    return box;
}

// Every comparison is made and the six are combined without branches: in the sweep, whether
// two boxes that overlap along x also overlap along y and z is close to a coin toss, and a
// mispredicted branch costs more than the comparisons it would skip.
bool boxes_overlap(const Aabb& a, const Aabb& b) {
    return !(a.lo.x > b.hi.x) & !(b.lo.x > a.hi.x) & !(a.lo.y > b.hi.y) & !(b.lo.y > a.hi.y) &
           !(a.lo.z > b.hi.z) & !(b.lo.z > a.hi.z);
}

// Do bodies i and j's boxes (their own frames' bound boxes, grown by reach[i] and reach[j]
// m on every side) overlap? Separating axes: the 3 face normals of each box and the 9 cross
// products of their edges (Gottschalk, Lin & Manocha 1996; Ericson 4.4.1).
bool turned_boxes_overlap(const Geometry& geo, const BodyStates& bodies, Span<const double> reach,
                          int i, int j) {
    const Mat3& ra = bodies.rotation[i];
    const Mat3& rb = bodies.rotation[j];
    const Vec3 ci = geo.body_bound_center[i], cj = geo.body_bound_center[j];
    const Vec3 hi = geo.body_bound_half[i], hj = geo.body_bound_half[j];
    const double ea[3] = {hi.x + reach[i], hi.y + reach[i], hi.z + reach[i]};
    const double eb[3] = {hj.x + reach[j], hj.y + reach[j], hj.z + reach[j]};
    // cosines between i's axis k and j's axis l at [3 k + l]; with the slack where |.| is used
    double c[9], a[9];
    for (int k = 0; k < 3; ++k) {
        for (int l = 0; l < 3; ++l) {
            c[3 * k + l] = ra.m[0][k] * rb.m[0][l] + ra.m[1][k] * rb.m[1][l] + ra.m[2][k] * rb.m[2][l];
            a[3 * k + l] = std::fabs(c[3 * k + l]) + BOX_AXIS_SLACK;
        }
    }
    // centre of j's box minus centre of i's, in i's frame
    const Vec3 xi = bodies.position[i], xj = bodies.position[j];
    double t[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < 3; ++k) {
        const double d = xj[k] + rb.m[k][0] * cj.x + rb.m[k][1] * cj.y + rb.m[k][2] * cj.z -
                         xi[k] - ra.m[k][0] * ci.x - ra.m[k][1] * ci.y - ra.m[k][2] * ci.z;
        t[0] += ra.m[k][0] * d;
        t[1] += ra.m[k][1] * d;
        t[2] += ra.m[k][2] * d;
    }
    for (int k = 0; k < 3; ++k) {  // i's face normals
        double extent = ea[k];
        for (int l = 0; l < 3; ++l) {
            extent += eb[l] * a[3 * k + l];
        }
        if (std::fabs(t[k]) > extent) {
            return false;
        }
    }
    for (int l = 0; l < 3; ++l) {  // j's face normals
        double extent = eb[l];
        double along = 0.0;
        for (int k = 0; k < 3; ++k) {
            extent += ea[k] * a[3 * k + l];
            along += t[k] * c[3 * k + l];
        }
        if (std::fabs(along) > extent) {
            return false;
        }
    }
    for (int k = 0; k < 3; ++k) {  // i's edge k crossed with j's edge l
        const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        for (int l = 0; l < 3; ++l) {
            const int l1 = (l + 1) % 3, l2 = (l + 2) % 3;
            const double extent = ea[k1] * a[3 * k2 + l] + ea[k2] * a[3 * k1 + l] +
                                  eb[l1] * a[3 * k + l2] + eb[l2] * a[3 * k + l1];
            const double along = t[k2] * c[3 * k1 + l] - t[k1] * c[3 * k2 + l];
            if (std::fabs(along) > extent) {
                return false;
            }
        }
    }
    return true;
}

// True when some point of box `box` lies within margin of the plane body's half-space (the
// plane z <= 0 of its frame).
bool box_below_plane(const BodyStates& bodies, const Aabb& box, int plane, double margin) {
    const Mat3& r = bodies.rotation[plane];
    const Vec3 x = bodies.position[plane];
    double height = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double centre = 0.5 * (box.lo[k] + box.hi[k]);
        const double half = 0.5 * (box.hi[k] - box.lo[k]);
        height += r.m[k][2] * (centre - x[k]) - std::fabs(r.m[k][2]) * half;
    }
    return height <= margin;
}

// Record (i, j), ordered as the header says, if either is dynamic; returns the new count.
int64_t add_pair(int i, int j, Span<const int32_t> motion, const PairLists& lists, int64_t count) {
    if (motion[i] != DYNAMIC && motion[j] != DYNAMIC) {
        return count;
    }
    const bool i_first = motion[i] > motion[j] || (motion[i] == motion[j] && i < j);
    if (count < lists.pair_a.size) {
        lists.pair_a[count] = i_first ? i : j;
        lists.pair_b[count] = i_first ? j : i;
    }
    return count + 1;
}

// A pair's key a n + b back to (a, b): key / n and key % n through the reciprocal, corrected
// by one. Two 64-bit divisions a pair were most of a short list's sorting (q < 2^31 is off by
// less than 2^-21 before the truncation).
struct KeyDecoder {
    int64_t n;
    double inverse;

    explicit KeyDecoder(int64_t num_bodies)
        : n(num_bodies), inverse(1.0 / static_cast<double>(num_bodies)) {}

    std::pair<int32_t, int32_t> operator()(int64_t key) const {
        int64_t q = static_cast<int64_t>(static_cast<double>(key) * inverse);
        int64_t r = key - q * n;
        if (r < 0) {
            q -= 1;
            r += n;
        } else if (r >= n) {
            q += 1;
            r -= n;
        }
        return {static_cast<int32_t>(q), static_cast<int32_t>(r)};
    }
};

// Keys below this many are insertion-sorted: a radix pass costs its 256 counters however few
// keys it moves (a sleeping pyramid with one rolling ball tests ~2 pairs a step).
constexpr int64_t FEW_KEYS = 64;

// Sort keys[0:count) (a n + b < largest + 1), through spare; returns where they ended up. A
// least-significant-digit radix sort, a byte a pass (stable, no allocation): a pass is
// O(count) and there are ceil(log2(n^2) / 8) of them (3 for 1000 bodies), where a
// comparison sort takes log2(count) passes over the keys (13 for the ~6000 pairs of a pile
// of 1000).
Span<int64_t> sort_keys(Span<int64_t> keys, Span<int64_t> spare, int64_t count, uint64_t largest) {
    if (count < FEW_KEYS) {
        for (int64_t k = 1; k < count; ++k) {
            const int64_t key = keys[k];
            int64_t m = k - 1;
            while (m >= 0 && keys[m] > key) {
                keys[m + 1] = keys[m];
                m -= 1;
            }
            keys[m + 1] = key;
        }
        return keys;
    }
    Span<int64_t> src = keys, dst = spare;
    for (int shift = 0; shift < 64 && (largest >> shift) != 0; shift += 8) {
        int64_t start[257] = {};  // start[d + 1]: how many keys have digit d, then prefix sums
        for (int64_t k = 0; k < count; ++k) {
            start[((static_cast<uint64_t>(src[k]) >> shift) & 0xff) + 1] += 1;
        }
        for (int d = 0; d < 256; ++d) {
            start[d + 1] += start[d];
        }
        for (int64_t k = 0; k < count; ++k) {
            dst[start[(static_cast<uint64_t>(src[k]) >> shift) & 0xff]++] = src[k];
        }
        std::swap(src, dst);
    }
    return src;
}

// Put the count pairs in (a, b) order: the first `carried` taken from the last list and
// already in order, the rest in the order the sweep found them (find_world_pairs). The
// tested ones are sorted by their keys a n + b and merged into the carried ones in place,
// from the back: slot k is never below the carried pair read next, and once every tested
// pair is placed the carried pairs left are where they belong. So a sleeping pile beside
// one moving body moves only the carried pairs that sort after that body's.
void sort_pairs(const PairLists& lists, int64_t carried, int64_t count, int64_t num_bodies) {
    const int64_t tested = count - carried;
    for (int64_t k = 0; k < tested; ++k) {
        lists.keys[k] = static_cast<int64_t>(lists.pair_a[carried + k]) * num_bodies +
                        lists.pair_b[carried + k];
    }
    const uint64_t bodies = static_cast<uint64_t>(num_bodies);
    const Span<int64_t> sorted = sort_keys(lists.keys, lists.spare, tested, bodies * bodies - 1);
    const KeyDecoder decode(num_bodies);
    int64_t t = tested - 1, c = carried - 1;
    for (int64_t k = count - 1; t >= 0; --k) {
        if (c >= 0 &&
            static_cast<int64_t>(lists.pair_a[c]) * num_bodies + lists.pair_b[c] > sorted[t]) {
            lists.pair_a[k] = lists.pair_a[c];
            lists.pair_b[k] = lists.pair_b[c];
            c -= 1;
        } else {
            const auto [a, b] = decode(sorted[t--]);
            lists.pair_a[k] = a;
            lists.pair_b[k] = b;
        }
    }
}

// Insertion-sort the body indices by (lower x bound, index). Bodies move little between
// steps, so the previous step's order is nearly sorted: O(n) typically.
void sort_by_lower_x(Span<int64_t> order, Span<const Aabb> bounds) {
    for (int64_t k = 1; k < order.size; ++k) {
        const int64_t i = order[k];
        const double x = bounds[i].lo.x;
        int64_t m = k - 1;
        while (m >= 0 && (bounds[order[m]].lo.x > x || (bounds[order[m]].lo.x == x && order[m] > i))) {
            order[m + 1] = order[m];
            m -= 1;
        }
        order[m + 1] = i;
    }
}

}  // namespace

double swept_margin(const Geometry& geo, int i, Vec3 velocity, Vec3 angular_velocity,
                    double margin, double dt, double acceleration) {
    const Vec3 c = geo.body_bound_center[i];
    const Vec3 e = geo.body_bound_half[i];
    const double rx = std::fabs(c.x) + e.x, ry = std::fabs(c.y) + e.y, rz = std::fabs(c.z) + e.z;
    const double reach = std::sqrt(rx * rx + ry * ry + rz * rz);
    const Vec3 v = velocity, w = angular_velocity;
    const double speed = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    const double spin = std::sqrt(w.x * w.x + w.y * w.y + w.z * w.z);
    return margin + dt * (speed + spin * reach + acceleration * dt);
}

int64_t find_world_pairs(const Geometry& geo, Span<const int32_t> motion,
                         const BodyStates& bodies, double margin, double dt,
                         double acceleration, bool sweep, const PairLists& lists,
                         Carried carried) {
    const int n = static_cast<int>(bodies.position.size);
    const Array<int32_t>& unbounded = geo.body_unbounded;
    const bool carrying = carried.kept.size == n;
    for (int i = 0; i < n; ++i) {
        if (unbounded[i] == 0 && !(carrying && carried.kept[i])) {  // a kept body's box holds
            const double grown = swept_margin(geo, i, bodies.velocity[i], bodies.angular_velocity[i],
                                              margin, dt, acceleration);
            lists.reach[i] = std::max(lists.reach[i], grown);
            lists.bounds[i] = world_bounds(geo, i, bodies.position[i], bodies.rotation[i],
                                           lists.reach[i]);
        }
    }
    // known: both bodies kept (a pair of two bodies not kept, or of one, is tested). The
    // known pairs come first, in the last list's order, then the tested ones (sort_pairs)
    const auto known = [&](int i, int j) { return carrying && carried.kept[i] && carried.kept[j]; };
    int64_t count = 0;
    const KeyDecoder decode(n);
    for (int64_t k = 0; carrying && k < carried.keys.size; ++k) {
        const auto [a, b] = decode(carried.keys[k]);
        if (known(a, b)) {
            count = add_pair(a, b, motion, lists, count);
        }
    }
    const int64_t known_pairs = count;
    for (int p = 0; p < n; ++p) {
        if (unbounded[p] == 0) {
            continue;
        }
        for (int i = 0; i < n; ++i) {
            if (unbounded[i] == 0 && !known(i, p) && box_below_plane(bodies, lists.bounds[i], p, 0.0)) {
                count = add_pair(i, p, motion, lists, count);
            }
        }
    }
    const Span<const double> reach = {lists.reach.data, lists.reach.size};
    if (sweep) {
        sort_by_lower_x(lists.order, {lists.bounds.data, lists.bounds.size});
        for (int oi = 0; oi < n; ++oi) {
            const int i = static_cast<int>(lists.order[oi]);
            if (unbounded[i] != 0) {
                continue;
            }
            for (int oj = oi + 1; oj < n; ++oj) {
                const int j = static_cast<int>(lists.order[oj]);
                if (unbounded[j] != 0) {
                    continue;
                }
                if (lists.bounds[j].lo.x > lists.bounds[i].hi.x) {
                    break;
                }
                if (!known(i, j) && boxes_overlap(lists.bounds[i], lists.bounds[j]) &&
                    turned_boxes_overlap(geo, bodies, reach, i, j)) {
                    count = add_pair(i, j, motion, lists, count);
                }
            }
        }
    } else {
        // every pair of bounded bodies of which one is not kept, once, each tested as (lower
        // index, higher) as without carrying: O(n) per body not kept, so a sleeping pyramid
        // beside one rolling ball costs the ball's n tests. lists.order (the sweep's) holds
        // the bodies not kept.
        int64_t m = 0;
        for (int i = 0; i < n; ++i) {
            if (unbounded[i] == 0 && !(carrying && carried.kept[i])) {
                lists.order[m++] = i;
            }
        }
        for (int64_t t = 0; t < m; ++t) {
            const int i = static_cast<int>(lists.order[t]);
            for (int j = carrying ? 0 : i + 1; j < n; ++j) {
                if (unbounded[j] != 0 || !(j > i || (j != i && carried.kept[j]))) {
                    continue;  // a pair of two bodies not kept is met from the lower one
                }
                const int lo = std::min(i, j), hi = std::max(i, j);
                if (boxes_overlap(lists.bounds[lo], lists.bounds[hi]) &&
                    turned_boxes_overlap(geo, bodies, reach, lo, hi)) {
                    count = add_pair(lo, hi, motion, lists, count);
                }
            }
        }
    }
    if (count <= lists.pair_a.size) {
        sort_pairs(lists, known_pairs, count, n);
    }
    return count;
}

}  // namespace rg
