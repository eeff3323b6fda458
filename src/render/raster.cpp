// The rasteriser's transform, fill, clipping, shadow map and shading (raster.h).
#include "render/raster.h"

#include <algorithm>
#include <cmath>

namespace rg {

namespace {

// A triangle corner on its way to the pixels: view x, y, z (m) before projection, screen
// x, y (pixels) and nearness z after it; d is the attribute interpolated over the triangle.
struct Corner {
    double x, y, z, d;
};

// (b - a) x (c - a) for the triangle with corners c, c + 1, c + 2 of `world`: its outward
// normal, of length twice its area (m^2).
Vec3 face_normal(Span<const Vec3> world, int64_t c) {
    const Vec3 a = world[c];
    return cross(sub(world[c + 1], a), sub(world[c + 2], a));
}

// matrix[row] . v.
double dot_row(const Mat3& matrix, int row, Vec3 v) {
    return matrix.m[row][0] * v.x + matrix.m[row][1] * v.y + matrix.m[row][2] * v.z;
}

// Twice the signed area of (a, b, p) for one edge a -> b and any p: > 0 when p lies left of
// a -> b (x right, y up).
//
// Always evaluated from the lexicographically smaller end, so the two triangles that share an
// edge get exactly opposite values and no pixel centre falls through the crack. That choice,
// and the differences of the ends, are made once per edge rather than at every pixel; along a
// row of pixels the term of the row's y is made once too (the same operations in the same
// order as at(), so the same bits).
struct Edge {
    double sx, sy;  // the smaller end
    double dx, dy;  // the other end minus it
    bool flip;      // the smaller end is b: the value is negated

    Edge(double ax, double ay, double bx, double by) {
        flip = !(ax < bx || (ax == bx && ay < by));
        sx = flip ? bx : ax;
        sy = flip ? by : ay;
        dx = flip ? ax - bx : bx - ax;
        dy = flip ? ay - by : by - ay;
    }

    double row(double py) const { return dx * (py - sy); }

    double at_row(double row_term, double px) const {
        const double area = row_term - dy * (px - sx);
        return flip ? -area : area;
    }

    double at(double px, double py) const { return at_row(row(py), px); }

    // Narrow [lo, hi] (pixel indices of a row whose term is row_term) to a superset of the
    // pixels where at_row(row_term, px) / area >= 0: the exact crossing is widened by a pixel
    // on each side, so rounding can only keep too many, which the pixel test then rejects.
    // A NaN crossing (degenerate input) leaves the range as it is.
    void clip_row(double row_term, double area, double& lo, double& hi) const {
        if (dy == 0.0) {
            return;  // the value is the same along the row: the pixel test decides
        }
        const double crossing = sx + row_term / dy - 0.5;  // the pixel index where it is 0
        const bool rising = (flip ? dy : -dy) * area > 0.0;  // increases with px, over area
        if (rising) {
            lo = std::max(lo, std::ceil(crossing) - 1.0);
        } else {
            hi = std::min(hi, std::floor(crossing) + 1.0);
        }
    }
};

// Write triangle `triangle` into the pixels whose centres it covers (edges included) where it
// is nearer than `nearness` holds, and (when Attributes) its index into `ids` and its
// interpolated attribute into `diffuse`.
//
// a, b, c: screen x, y (pixels), nearness z > 0 and attribute d of the corners, either
// winding. z is interpolated linearly on screen (exact for 1/depth under perspective and for
// depth under an orthographic view); d is interpolated so that d z is linear, which is
// perspective-correct when z = 1/depth.
template <bool Attributes>
void fill(Corner a, Corner b, Corner c, int32_t triangle, const DepthBuffers& out) {
    const int64_t height = out.nearness.rows, width = out.nearness.columns;
    const double lo_x = std::max(std::min(std::min(a.x, b.x), c.x), -1.0);
    const double hi_x = std::min(std::max(std::max(a.x, b.x), c.x), width + 1.0);
    const double lo_y = std::max(std::min(std::min(a.y, b.y), c.y), -1.0);
    const double hi_y = std::min(std::max(std::max(a.y, b.y), c.y), height + 1.0);
    // Off screen the pixel ranges below are empty anyway; returning here also keeps their
    // conversions to integers within [-1, size + 1].
    if (!(lo_x <= hi_x && lo_y <= hi_y)) {
        return;
    }
    const int64_t j0 = std::max(static_cast<int64_t>(std::ceil(lo_x - 0.5)), int64_t{0});
    const int64_t j1 = std::min(static_cast<int64_t>(std::floor(hi_x - 0.5)), width - 1);
    const int64_t i0 = std::max(static_cast<int64_t>(std::ceil(lo_y - 0.5)), int64_t{0});
    const int64_t i1 = std::min(static_cast<int64_t>(std::floor(hi_y - 0.5)), height - 1);
    if (j0 > j1 || i0 > i1) {
        return;  // covers no pixel centre
    }
    const Edge ab(a.x, a.y, b.x, b.y), bc(b.x, b.y, c.x, c.y), ca(c.x, c.y, a.x, a.y);
    const double area = ab.at(c.x, c.y);
    if (!(std::fabs(area) > 0.0)) {
        return;
    }
    const double inverse_area = 1.0 / area;
    for (int64_t i = i0; i <= i1; ++i) {
        const double py = i + 0.5;
        const double row_a = bc.row(py), row_b = ca.row(py), row_c = ab.row(py);
        // the pixels of the row between the edges' crossings, a superset of those covered
        double lo = static_cast<double>(j0), hi = static_cast<double>(j1);
        bc.clip_row(row_a, area, lo, hi);
        ca.clip_row(row_b, area, lo, hi);
        ab.clip_row(row_c, area, lo, hi);
        if (!(lo <= hi)) {
            continue;
        }
        const int64_t first = static_cast<int64_t>(lo), last = static_cast<int64_t>(hi);
        const Span<double> nearness = out.nearness.row(i);
        for (int64_t j = first; j <= last; ++j) {
            const double px = j + 0.5;
            const double wa = bc.at_row(row_a, px) * inverse_area;
            const double wb = ca.at_row(row_b, px) * inverse_area;
            const double wc = ab.at_row(row_c, px) * inverse_area;
            if (wa < 0.0 || wb < 0.0 || wc < 0.0) {
                continue;
            }
            const double z = wa * a.z + wb * b.z + wc * c.z;
            if (z > nearness[j]) {
                nearness[j] = z;
                if constexpr (Attributes) {
                    out.ids.row(i)[j] = triangle;
                    out.diffuse.row(i)[j] = (wa * a.d * a.z + wb * b.d * b.z + wc * c.d * c.z) / z;
                }
            }
        }
    }
}

// Sutherland-Hodgman: the part of the triangle `corners` (view x, y, z in m and an
// attribute) with z >= `near` (m), as a convex polygon written into `out`. Returns its vertex
// count: 0, 3 or 4.
int clip_near(const Corner (&corners)[3], double near, Corner (&out)[4]) {
    int count = 0;
    for (int k = 0; k < 3; ++k) {
        const Corner& p = corners[k];
        const Corner& q = corners[(k + 1) % 3];
        const bool inside = p.z >= near, next_inside = q.z >= near;
        if (inside) {
            out[count++] = p;
        }
        if (inside != next_inside) {
            const double s = (near - p.z) / (q.z - p.z);
            out[count++] = {p.x + s * (q.x - p.x), p.y + s * (q.y - p.y), p.z + s * (q.z - p.z),
                            p.d + s * (q.d - p.d)};
        }
    }
    return count;
}

// floor(x) as the index of the first of two texels along a side of `size` texels, clamped to
// [-2, size]: index + 0 and index + 1 lie in the map exactly when they did before clamping,
// and the conversion is defined for any x (NaN gives size: outside).
int64_t texel_index(double floored, int64_t size) {
    return static_cast<int64_t>(std::max(-2.0, std::min(static_cast<double>(size), floored)));
}

// Fraction in [0, 1] of a point that the light reaches. u, v: its shadow-map position,
// texels; height: its nearness to the light in the map's units (m), bias included.
//
// The point is hidden by a texel that holds a surface nearer the light; the four texels
// around it are weighted bilinearly, so shadow edges blend over one texel.
double lit_fraction(double u, double v, double height, Pixels<const double> shadow) {
    if (!(u > -1.0 && v > -1.0 && u < shadow.columns + 1.0 && v < shadow.rows + 1.0)) {
        return 1.0;  // no texel of the map around it: exactly lit (and NaN is lit)
    }
    u = u - 0.5;  // texel (r, c) is centred on (c + 0.5, r + 0.5)
    v = v - 0.5;
    const double floor_u = std::floor(u), floor_v = std::floor(v);
    const int64_t ku = texel_index(floor_u, shadow.columns);
    const int64_t kv = texel_index(floor_v, shadow.rows);
    const double fu = u - floor_u, fv = v - floor_v;
    double lit = 0.0;
    for (int i = 0; i < 2; ++i) {
        for (int j = 0; j < 2; ++j) {
            const int64_t r = kv + i, c = ku + j;
            if (!(0 <= r && r < shadow.rows && 0 <= c && c < shadow.columns &&
                  shadow(r, c) > height)) {
                lit += (i == 1 ? fv : 1.0 - fv) * (j == 1 ? fu : 1.0 - fu);
            }
        }
    }
    return lit;
}

// A colour channel in [0, 1] (clamped) as the nearest of 0..255. With 0 as max's first
// argument a NaN channel (from NaN inputs) clamps to 0 instead of reaching the conversion.
uint8_t to_byte(double value) {
    return static_cast<uint8_t>(
        static_cast<int>(std::min(std::max(0.0, value), 1.0) * 255.0 + 0.5));
}

}  // namespace

void raster_transform(Span<const Vec3> local, Span<const Vec3> local_normal,
                      Span<const int32_t> owner, Span<const Mat3> rotation,
                      Span<const Vec3> translation, Span<Vec3> world, Span<Vec3> world_normal) {
    for (int64_t c = 0; c < local.size; ++c) {
        const Mat3& r = rotation[owner[c]];
        world[c] = add(rotate(r, local[c]), translation[owner[c]]);
        world_normal[c] = rotate(r, local_normal[c]);
    }
}

void rasterize(Span<const Vec3> world, Span<const Vec3> world_normal, int64_t first,
               int64_t last, Vec3 eye, const Mat3& axes, double focal, double near, Vec3 light,
               const DepthBuffers& out) {
    const double cx = 0.5 * out.nearness.columns, cy = 0.5 * out.nearness.rows;
    Corner corners[3];
    Corner polygon[4];
    Corner screen[4];
    for (int64_t t = first; t < last; ++t) {
        const int64_t c = 3 * t;
        const Vec3 n = face_normal(world, c);
        if (dot(world[c], n) >= dot(n, eye)) {
            continue;  // the eye is not on the outer side of the face's plane
        }
        for (int k = 0; k < 3; ++k) {
            const Vec3 view = rotate(axes, sub(world[c + k], eye));
            corners[k] = {view.x, view.y, view.z, std::max(dot(world_normal[c + k], light), 0.0)};
        }
        const int count = clip_near(corners, near, polygon);
        for (int k = 0; k < count; ++k) {
            const double inverse_depth = 1.0 / polygon[k].z;
            screen[k] = {cx + focal * polygon[k].x * inverse_depth,
                         cy - focal * polygon[k].y * inverse_depth, inverse_depth, polygon[k].d};
        }
        for (int k = 1; k < count - 1; ++k) {
            fill<true>(screen[0], screen[k], screen[k + 1], static_cast<int32_t>(t), out);
        }
    }
}

void shadow_map(Span<const Vec3> world, int64_t first, int64_t last, const Mat3& light_axes,
                Vec3 origin, double texel, Pixels<double> nearness) {
    const DepthBuffers out = {nearness, {}, {}};
    Corner corners[3];
    for (int64_t t = first; t < last; ++t) {
        const int64_t c = 3 * t;
        if (dot_row(light_axes, 2, face_normal(world, c)) > 0.0) {
            continue;
        }
        for (int k = 0; k < 3; ++k) {
            const Vec3 p = world[c + k];
            corners[k] = {(dot_row(light_axes, 0, p) - origin.x) / texel,
                          (dot_row(light_axes, 1, p) - origin.y) / texel,
                          dot_row(light_axes, 2, p) - origin.z, 0.0};
        }
        fill<false>(corners[0], corners[1], corners[2], static_cast<int32_t>(t), out);
    }
}

void shade(Pixels<const double> nearness, Pixels<const int32_t> ids,
           Pixels<const double> diffuse, Pixels<const int32_t> layer_ids,
           Pixels<const double> layer_diffuse, Span<const Vec3> color, Span<const double> alpha,
           double focal, const Mat3& to_light, Vec3 light_offset, double texel,
           Pixels<const double> shadow, double ambient, Vec3 background, Pixels<Rgb8> image,
           Span<double> ray_x) {
    const int64_t height = ids.rows, width = ids.columns;
    const double cx = 0.5 * width, cy = 0.5 * height;
    for (int64_t j = 0; j < width; ++j) {
        ray_x[j] = (j + 0.5 - cx) / focal;
    }
    for (int64_t i = 0; i < height; ++i) {
        const double y = (cy - i - 0.5) / focal;
        for (int64_t j = 0; j < width; ++j) {
            const int32_t t = ids(i, j);
            Vec3 rgb = background;
            if (t >= 0) {
                double lit = diffuse(i, j);
                if (lit > 0.0 && shadow.rows > 0) {
                    const Vec3 ray = {ray_x[j], y, 1.0};
                    const double depth = 1.0 / nearness(i, j);
                    const double u = light_offset.x + depth * dot_row(to_light, 0, ray);
                    const double v = light_offset.y + depth * dot_row(to_light, 1, ray);
                    const double h = light_offset.z + depth * dot_row(to_light, 2, ray);
                    lit *= lit_fraction(u, v, h + texel, shadow);
                }
                const double s = ambient + (1.0 - ambient) * lit;
                rgb = {color[t].x * s, color[t].y * s, color[t].z * s};
            }
            const int32_t f = layer_ids(i, j);
            if (f >= 0) {
                const double s = alpha[f] * (ambient + (1.0 - ambient) * layer_diffuse(i, j));
                const double keep = 1.0 - alpha[f];
                rgb = {keep * rgb.x + s * color[f].x, keep * rgb.y + s * color[f].y,
                       keep * rgb.z + s * color[f].z};
            }
            image(i, j) = {to_byte(rgb.x), to_byte(rgb.y), to_byte(rgb.z)};
        }
    }
}

}  // namespace rg
