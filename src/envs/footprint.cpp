// The gripper's command and its lowest centre over the boxes under it (footprint.h).
#include "envs/footprint.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rg {

namespace {

// m: footprints must overlap by more than this for a box to count as under another.
constexpr double FOOTPRINT_SLACK = 1e-3;

constexpr double INF = std::numeric_limits<double>::infinity();

// A box: centre m, rotation (columns: its axes in the world), half extents m.
struct Box {
    const Vec3& centre;
    const Mat3& rotation;
    const Vec3& half;
};

// Coordinate `axis` of corner k (0-7, signs by its bits: x slowest) of a box, m.
double corner(const Box& box, int k, int axis) {
    const double sx = k < 4 ? -1.0 : 1.0;
    const double sy = k % 4 < 2 ? -1.0 : 1.0;
    const double sz = k % 2 == 0 ? -1.0 : 1.0;
    const Mat3& r = box.rotation;
    return box.centre[axis] + r(axis, 0) * sx * box.half.x + r(axis, 1) * sy * box.half.y +
           r(axis, 2) * sz * box.half.z;
}

// The lowest and highest z of a box's corners, m.
struct ZRange {
    double low, high;
};

ZRange z_range(const Box& box) {
    ZRange range = {INF, -INF};
    for (int k = 0; k < 8; ++k) {
        const double z = corner(box, k, 2);
        range = {std::min(range.low, z), std::max(range.high, z)};
    }
    return range;
}

// Do the shadows of boxes a and b on the table overlap by at most FOOTPRINT_SLACK along the
// in-plane axis (ax, ay)?
bool separated_along(double ax, double ay, const Box& a, const Box& b) {
    double low_a = INF, low_b = INF;
    double high_a = -INF, high_b = -INF;
    for (int k = 0; k < 8; ++k) {
        const double pa = corner(a, k, 0) * ax + corner(a, k, 1) * ay;
        const double pb = corner(b, k, 0) * ax + corner(b, k, 1) * ay;
        low_a = std::min(low_a, pa);
        high_a = std::max(high_a, pa);
        low_b = std::min(low_b, pb);
        high_b = std::max(high_b, pb);
    }
    return std::min(high_a, high_b) - std::max(low_a, low_b) <= FOOTPRINT_SLACK;
}

// Whether boxes a and b overlap in their shadows on the table by more than FOOTPRINT_SLACK:
// separating axes x, y and the normals of the projected box edges.
bool footprints_overlap(const Box& a, const Box& b) {
    if (separated_along(1.0, 0.0, a, b)) {
        return false;
    }
    if (separated_along(0.0, 1.0, a, b)) {
        return false;
    }
    for (const Mat3* r : {&a.rotation, &b.rotation}) {
        for (int k = 0; k < 3; ++k) {  // box axis k projected on the table
            const double ex = (*r)(0, k), ey = (*r)(1, k);
            const double norm = std::sqrt(ex * ex + ey * ey);
            if (norm > 1e-9 && separated_along(-ey / norm, ex / norm, a, b)) {
                return false;
            }
        }
    }
    return true;
}

// The product a b of two rotations.
Mat3 product(const Mat3& a, const Mat3& b) {
    Mat3 out{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            out.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
        }
    }
    return out;
}

// The lowest z (m) the pad's centre may take for `part` to rest on `box`, given the part's
// bottom `bottom` (m) and `height` from it to the pad's centre (m): -INF unless the box is
// under the part (its top below the part's bottom before the move, `drop` m up, and their
// footprints overlapping).
double resting_on(const Box& part, double bottom, double height, double drop, const Box& box) {
    const double top = z_range(box).high;
    if (top <= bottom - drop + FOOTPRINT_SLACK && footprints_overlap(part, box)) {
        return top + height;
    }
    return -INF;
}

// The lowest z (m) the gripper's centre may take at a target of height `target_z`: where one
// of the first `parts` work parts (at the target) would rest on the table, on the top of one
// of the work boxes or of the fixtures' box parts (of the world whose bodies start at `first`)
// under its footprint. A box counts as under a part if its top is below the part's bottom
// before the move (the part's bottom at the target minus `drop`, the move's z, m); box `skip`
// (the held one, or -1) is ignored.
double lowest_centre(const FootprintQuery& q, int64_t first, double target_z, double drop,
                     int parts, int64_t skip) {
    double lowest = -INF;
    for (int p = 0; p < parts; ++p) {
        const Box part = {q.parts_x[p], q.parts_r[p], q.parts_half[p]};
        const double bottom = z_range(part).low;
        const double height = target_z - bottom;  // from this part's bottom to the pad's centre
        lowest = std::max(lowest, height);        // resting on the table (z = 0)
        for (int64_t k = 0; k < q.boxes_x.size; ++k) {
            if (k != skip) {
                const Box box = {q.boxes_x[k], q.boxes_r[k], q.halves[k]};
                lowest = std::max(lowest, resting_on(part, bottom, height, drop, box));
            }
        }
        for (int64_t k = 0; k < q.fixed_bodies.size; ++k) {
            const int64_t body = first + q.fixed_bodies[k];
            const Mat3& r = q.rotations[body];
            const Vec3 centre = to_world(q.positions[body], r, q.fixed_offsets[k]);
            const Mat3 rotation = product(r, q.fixed_rotations[k]);
            const Box box = {centre, rotation, q.fixed_halves[k]};
            lowest = std::max(lowest, resting_on(part, bottom, height, drop, box));
        }
    }
    return lowest;
}

}  // namespace

void lowest_centres(const FootprintQuery& q, Span<double> out) {
    for (int64_t w = 0; w < q.targets.size; ++w) {
        const int64_t first = w * q.num_bodies;  // world w's bodies
        const Vec3 target = q.targets[w];
        const Vec3 pad = q.positions[first + q.pad];
        q.parts_x[0] = target;
        q.parts_half[0] = q.pad_half;
        q.parts_r[0] = q.rotations[first + q.pad];
        int parts = 1;
        const int64_t h = q.held[w];
        if (h >= 0) {
            const int64_t body = q.objects[h];
            q.parts_x[1] = add(q.positions[first + body], sub(target, pad));
            q.parts_half[1] = q.halves[h];
            q.parts_r[1] = q.rotations[first + body];
            parts = 2;
        }
        for (int64_t c = 0; c < q.carried.size; ++c) {  // moved with the pad, as the held box
            const int64_t body = first + q.carried[c];
            const Mat3& r = q.rotations[body];
            q.parts_x[parts] = add(q.positions[body], sub(target, pad));
            q.parts_half[parts] = q.carried_halves[c];
            q.parts_r[parts] = r;
            if (q.carried_sweeps.size > 0) {  // the box it sweeps: half the move on each side
                const Vec3 d = q.carried_sweeps[w * q.carried.size + c];
                const Vec3 local = rotate_inverse(r, d);
                q.parts_x[parts] = add(q.parts_x[parts], scale(0.5, d));
                q.parts_half[parts] = add(q.parts_half[parts],
                                          {0.5 * std::abs(local.x), 0.5 * std::abs(local.y),
                                           0.5 * std::abs(local.z)});
            }
            ++parts;
        }
        for (int64_t k = 0; k < q.objects.size; ++k) {
            q.boxes_x[k] = q.positions[first + q.objects[k]];
            q.boxes_r[k] = q.rotations[first + q.objects[k]];
        }
        out[w] = lowest_centre(q, first, target.z, target.z - pad.z, parts, h);
    }
}

void grasps(const FootprintQuery& q, Span<const int64_t> worlds, double margin,
            Span<int64_t> held, Span<double> width) {
    const Vec3& low_half = q.carried_halves[0];
    const Vec3& high_half = q.carried_halves[1];
    for (int64_t i = 0; i < worlds.size; ++i) {
        const int64_t first = worlds[i] * q.num_bodies;
        const Vec3& pad = q.positions[first + q.carried[0]];  // the pads' x and z
        const double low = pad.y + low_half.y;  // the inner faces
        const double high = q.positions[first + q.carried[1]].y - high_half.y;
        width[i] = high - low;
        held[i] = -1;
        for (int64_t k = 0; k < q.objects.size; ++k) {
            const Vec3& c = q.positions[first + q.objects[k]];
            const Mat3& r = q.rotations[first + q.objects[k]];
            const Vec3& h = q.halves[k];
            double extent[3];  // the bounding box's half extents, whatever the box's turn
            for (int axis = 0; axis < 3; ++axis) {
                extent[axis] = std::abs(r(axis, 0)) * h.x + std::abs(r(axis, 1)) * h.y +
                               std::abs(r(axis, 2)) * h.z;
            }
            if (std::abs(c.y - extent[1] - low) <= margin &&
                std::abs(c.y + extent[1] - high) <= margin &&
                std::abs(c.x - pad.x) < low_half.x + extent[0] - margin &&
                std::abs(c.z - pad.z) < low_half.z + extent[2] - margin) {
                held[i] = k;
                break;
            }
        }
    }
}

void command_pads(FootprintQuery query, const PadCommand& c) {
    const int64_t worlds = c.motions.size;
    for (int64_t w = 0; w < worlds; ++w) {
        const Vec3 pad = query.positions[w * query.num_bodies + query.pad], m = c.motions[w];
        const Vec3 moved = {pad.x + c.step_distance * m.x, pad.y + c.step_distance * m.y,
                            pad.z + c.step_distance * m.z};
        c.targets[w] = {std::min(std::max(moved.x, c.low.x), c.high.x),
                        std::min(std::max(moved.y, c.low.y), c.high.y),
                        std::min(std::max(moved.z, c.low.z), c.high.z)};
    }
    query.targets = {c.targets.data, c.targets.size};
    lowest_centres(query, c.lowest);
    for (int64_t w = 0; w < worlds; ++w) {
        const int64_t body = w * query.num_bodies + query.pad;
        const Vec3 pad = query.positions[body];
        Vec3 target = c.targets[w];
        target.z = std::max(target.z, std::min(pad.z, c.lowest[w]));
        c.velocities[body] = {(target.x - pad.x) / c.step_time, (target.y - pad.y) / c.step_time,
                              (target.z - pad.z) / c.step_time};
    }
}

}  // namespace rg
