// Z-buffer rasterisation for the software renderer rigid_gym/render.py.
//
// Geometry is a triangle soup: triangle t has the corners 3t, 3t + 1, 3t + 2, wound
// counter-clockwise seen from outside (outward normals).
//     local, local_normal    (C,)        corners and unit shading normals in their owner's frame
//     owner                  (C,) int32  the instance (a body or a marker) that moves each corner
//     rotation, translation  (N,), (N,)  m: each instance's pose in the world
//     world, world_normal    (C,)        the corners in the world (written by raster_transform)
// Camera: `eye` m and `axes` whose rows are the unit right, up and forward directions; `focal`
// is the focal length in pixels. Screen coordinates are pixels, x to the right and y down,
// pixel (i, j) centred on (j + 0.5, i + 0.5).
// Per-pixel buffers (H, W): `nearness` (larger = nearer; 1/depth with depth in m for the
// camera, 0 = empty), `ids` (triangle index, -1 = empty) and `diffuse` (the Lambert factor
// max(0, n . light) in [0, 1], interpolated perspective-correctly).
// The shadow map uses the same fill into a nearness buffer alone, seen orthographically along
// the light.
//
// Indices (owner, ids, the triangle ranges) must be in range: the bindings check them.
#pragma once

#include <cstdint>

#include "base/math.h"
#include "base/span.h"

namespace rg {

// A (rows, columns) image of per-pixel values, C order.
template <class T>
struct Pixels {
    Span<T> values;  // rows * columns
    int64_t rows = 0;
    int64_t columns = 0;

    Span<T> row(int64_t i) const { return values.sub(i * columns, columns); }
    T& operator()(int64_t i, int64_t j) const { return row(i)[j]; }
};

// The buffers triangles are drawn into.
struct DepthBuffers {
    Pixels<double> nearness;
    Pixels<int32_t> ids;
    Pixels<double> diffuse;
};

// One pixel of an RGB image, laid out like a uint8 (3,) row.
struct Rgb8 {
    uint8_t r, g, b;
};
static_assert(sizeof(Rgb8) == 3, "Rgb8 must match a uint8 (3,) row");

// world = R p + x and world_normal = R n for every corner, with its owner's pose.
void raster_transform(Span<const Vec3> local, Span<const Vec3> local_normal,
                      Span<const int32_t> owner, Span<const Mat3> rotation,
                      Span<const Vec3> translation, Span<Vec3> world, Span<Vec3> world_normal);

// Draw triangles [first, last) with a perspective camera into the buffers.
//
// Back faces (seen from behind, by their geometric normal) are skipped; the rest are clipped
// at the plane `near` m in front of the eye. Each corner carries the Lambert factor
// max(0, n . light) of its shading normal; light: unit vector towards the light.
void rasterize(Span<const Vec3> world, Span<const Vec3> world_normal, int64_t first,
               int64_t last, Vec3 eye, const Mat3& axes, double focal, double near, Vec3 light,
               const DepthBuffers& out);

// Draw the faces of triangles [first, last) that face away from the light into an
// orthographic shadow map of nearness alone.
//
// light_axes: rows u, v (the map's x and y) and the unit vector towards the light; origin: m,
// the map's corner in (u, v) and the light coordinate at which nearness is 0; texel: m per
// texel. Nearness is the height along the light above origin.z. Using only the faces turned
// away from the light (the far side of each closed body) keeps lit surfaces from shadowing
// themselves.
void shadow_map(Span<const Vec3> world, int64_t first, int64_t last, const Mat3& light_axes,
                Vec3 origin, double texel, Pixels<double> nearness);

// Colour every pixel into `image` (H, W).
//
// A surface pixel of triangle t is color[t] (T,) in [0, 1] times
// ambient + (1 - ambient) * diffuse * lit, where lit is its unshadowed fraction (1 when
// `shadow` is empty); an empty pixel is `background`. Where `layer_ids` holds a translucent
// triangle f in front, its colour (unshadowed) is blended over with alpha[f].
//
// The surface point's shadow-map coordinates are light_offset + depth * to_light (x, y, 1),
// with (x, y) the pixel centre on the view plane at unit depth and depth = 1 / nearness, m:
// rows 0 and 1 give texels, row 2 the nearness to the light, m. A surface must be one
// `texel` (m) nearer the light than the point to shadow it. The map holds only the far sides
// of bodies, which lie behind any lit surface of the same body, so this small bias suffices:
// a body shadows its own lit side only near its terminator, where the diffuse light is weak
// anyway. ray_x (W,) is scratch: each column's x on the view plane, made once per frame.
void shade(Pixels<const double> nearness, Pixels<const int32_t> ids,
           Pixels<const double> diffuse, Pixels<const int32_t> layer_ids,
           Pixels<const double> layer_diffuse, Span<const Vec3> color, Span<const double> alpha,
           double focal, const Mat3& to_light, Vec3 light_offset, double texel,
           Pixels<const double> shadow, double ambient, Vec3 background, Pixels<Rgb8> image,
           Span<double> ray_x);

}  // namespace rg
