// Python face of the rasteriser (src/raster.h): rigid_gym._core.raster_transform, rasterize,
// shadow_map and shade, used by rigid_gym/render.py. Each runs on the calling thread with the
// GIL released.
#include <string>

#include "array_args.h"
#include "raster.h"

namespace rg {

namespace {

template <class T, class S>
Pixels<T> pixels(const ArrayArg<S>& a) {
    return {rows<T>(a), extent(a, 0), extent(a, 1)};
}

Vec3 vector_arg(nb::handle value, const char* where) {
    return rows<const Vec3>(array_arg<const double>(value, where, {3}))[0];
}

Mat3 matrix_arg(nb::handle value, const char* where) {
    return rows<const Mat3>(array_arg<const double>(value, where, {3, 3}))[0];
}

// The writable (H, W) buffers nearness, ids and diffuse of one picture.
struct BufferArgs {
    ArrayArg<double> nearness;
    ArrayArg<int32_t> ids;
    ArrayArg<double> diffuse;

    BufferArgs(const std::string& function, nb::handle n, nb::handle i, nb::handle d)
        : nearness(array_arg<double>(n, (function + ": nearness").c_str(), {-1, -1})),
          ids(array_arg<int32_t>(i, (function + ": ids").c_str(),
                                 {extent(nearness, 0), extent(nearness, 1)})),
          diffuse(array_arg<double>(d, (function + ": diffuse").c_str(),
                                    {extent(nearness, 0), extent(nearness, 1)})) {}

    DepthBuffers buffers() const {
        return {pixels<double>(nearness), pixels<int32_t>(ids), pixels<double>(diffuse)};
    }
};

// ValueError unless triangles [first, last) are corners 3 first ... 3 last - 1 of `world`.
void check_triangles(int64_t first, int64_t last, const ArrayArg<const double>& world,
                     const char* where) {
    const int64_t triangles = extent(world, 0) / 3;
    if (first < 0 || first > last || last > triangles) {
        throw nb::value_error((std::string(where) + ": triangles [" + std::to_string(first) +
                               ", " + std::to_string(last) + ") outside the " +
                               std::to_string(triangles) + " of world")
                                  .c_str());
    }
}

}  // namespace

void bind_render(nb::module_& m) {
    m.def(
        "raster_transform",
        [](nb::handle local, nb::handle local_normal, nb::handle owner, nb::handle rotation,
           nb::handle translation, nb::handle world, nb::handle world_normal) {
            const auto l = array_arg<const double>(local, "raster_transform: local", {-1, 3});
            const int64_t c = extent(l, 0);
            const auto ln = array_arg<const double>(local_normal,
                                                    "raster_transform: local_normal", {c, 3});
            const auto o = array_arg<const int32_t>(owner, "raster_transform: owner", {c});
            const auto r = array_arg<const double>(rotation, "raster_transform: rotation",
                                                   {-1, 3, 3});
            const auto t = array_arg<const double>(translation, "raster_transform: translation",
                                                   {extent(r, 0), 3});
            const auto w = array_arg<double>(world, "raster_transform: world", {c, 3});
            const auto wn = array_arg<double>(world_normal, "raster_transform: world_normal",
                                              {c, 3});
            check_indices(rows<const int32_t>(o), 0, extent(r, 0), "raster_transform: owner",
                          "rows of rotation and translation");
            nb::gil_scoped_release unlocked;
            raster_transform(rows<const Vec3>(l), rows<const Vec3>(ln), rows<const int32_t>(o),
                             rows<const Mat3>(r), rows<const Vec3>(t), rows<Vec3>(w),
                             rows<Vec3>(wn));
        },
        nb::arg("local"), nb::arg("local_normal"), nb::arg("owner"), nb::arg("rotation"),
        nb::arg("translation"), nb::arg("world"), nb::arg("world_normal"),
        "world = R p + x and world_normal = R n for every corner, with its owner's pose "
        "(src/raster.h): local, local_normal (C, 3) float64 in the owner's frame; owner (C,) "
        "int32; rotation (N, 3, 3), translation (N, 3) float64, m; world, world_normal (C, 3) "
        "float64, written.");
    m.def(
        "rasterize",
        [](nb::handle world, nb::handle world_normal, int64_t first, int64_t last,
           nb::handle eye, nb::handle axes, double focal, double near, nb::handle light,
           nb::handle nearness, nb::handle ids, nb::handle diffuse) {
            const auto w = array_arg<const double>(world, "rasterize: world", {-1, 3});
            const auto wn = array_arg<const double>(world_normal, "rasterize: world_normal",
                                                    {extent(w, 0), 3});
            check_triangles(first, last, w, "rasterize");
            const Vec3 e = vector_arg(eye, "rasterize: eye");
            const Mat3 a = matrix_arg(axes, "rasterize: axes");
            const Vec3 l = vector_arg(light, "rasterize: light");
            const BufferArgs out("rasterize", nearness, ids, diffuse);
            nb::gil_scoped_release unlocked;
            rasterize(rows<const Vec3>(w), rows<const Vec3>(wn), first, last, e, a, focal, near,
                      l, out.buffers());
        },
        nb::arg("world"), nb::arg("world_normal"), nb::arg("first"), nb::arg("last"),
        nb::arg("eye"), nb::arg("axes"), nb::arg("focal"), nb::arg("near"), nb::arg("light"),
        nb::arg("nearness"), nb::arg("ids"), nb::arg("diffuse"),
        "Draw triangles first to last - 1 of the soup world, world_normal (C, 3) float64 with "
        "a perspective camera into the buffers nearness, ids (int32), diffuse (H, W) "
        "(src/raster.h). Back faces are skipped, the rest clipped at the plane near m in front "
        "of the eye (3,) m; axes (3, 3) rows: right, up, forward; focal: pixels; light (3,): "
        "unit vector towards the light, for each corner's Lambert factor max(0, n . light).");
    m.def(
        "shadow_map",
        [](nb::handle world, int64_t count, nb::handle light_axes, nb::handle origin,
           double texel, nb::handle nearness, nb::handle ids, nb::handle diffuse) {
            const auto w = array_arg<const double>(world, "shadow_map: world", {-1, 3});
            check_triangles(0, count, w, "shadow_map");
            const Mat3 a = matrix_arg(light_axes, "shadow_map: light_axes");
            const Vec3 o = vector_arg(origin, "shadow_map: origin");
            const BufferArgs out("shadow_map", nearness, ids, diffuse);
            nb::gil_scoped_release unlocked;
            shadow_map(rows<const Vec3>(w), count, a, o, texel, out.buffers());
        },
        nb::arg("world"), nb::arg("count"), nb::arg("light_axes"), nb::arg("origin"),
        nb::arg("texel"), nb::arg("nearness"), nb::arg("ids"), nb::arg("diffuse"),
        "Draw the faces of triangles 0 to count - 1 of world (C, 3) float64 that face away "
        "from the light into an orthographic shadow map nearness, ids (int32), diffuse (S, S) "
        "(src/raster.h). light_axes (3, 3): rows u, v (the map's x and y) and the unit vector "
        "towards the light; origin (3,) m: the map's corner in (u, v) and the light coordinate "
        "at which nearness is 0; texel: m per texel.");
    m.def(
        "shade",
        [](nb::handle nearness, nb::handle ids, nb::handle diffuse, nb::handle layer_ids,
           nb::handle layer_diffuse, nb::handle color, nb::handle alpha, double focal,
           nb::handle to_light, nb::handle light_offset, double texel, nb::handle shadow,
           double ambient, nb::handle background, nb::handle image) {
            const auto i = array_arg<const int32_t>(ids, "shade: ids", {-1, -1});
            const int64_t h = extent(i, 0), w = extent(i, 1);
            const auto n = array_arg<const double>(nearness, "shade: nearness", {h, w});
            const auto d = array_arg<const double>(diffuse, "shade: diffuse", {h, w});
            const auto li = array_arg<const int32_t>(layer_ids, "shade: layer_ids", {h, w});
            const auto ld = array_arg<const double>(layer_diffuse, "shade: layer_diffuse", {h, w});
            const auto c = array_arg<const double>(color, "shade: color", {-1, 3});
            const int64_t t = extent(c, 0);
            const auto a = array_arg<const double>(alpha, "shade: alpha", {t});
            const Mat3 tl = matrix_arg(to_light, "shade: to_light");
            const Vec3 lo = vector_arg(light_offset, "shade: light_offset");
            const auto s = array_arg<const double>(shadow, "shade: shadow", {-1, -1});
            const Vec3 b = vector_arg(background, "shade: background");
            const auto im = array_arg<uint8_t>(image, "shade: image", {h, w, 3});
            check_indices(rows<const int32_t>(i), -1, t, "shade: ids", "rows of color, -1: none");
            check_indices(rows<const int32_t>(li), -1, t, "shade: layer_ids",
                          "rows of color, -1: none");
            nb::gil_scoped_release unlocked;
            shade(pixels<const double>(n), pixels<const int32_t>(i), pixels<const double>(d),
                  pixels<const int32_t>(li), pixels<const double>(ld), rows<const Vec3>(c),
                  rows<const double>(a), focal, tl, lo, texel, pixels<const double>(s), ambient,
                  b, pixels<Rgb8>(im));
        },
        nb::arg("nearness"), nb::arg("ids"), nb::arg("diffuse"), nb::arg("layer_ids"),
        nb::arg("layer_diffuse"), nb::arg("color"), nb::arg("alpha"), nb::arg("focal"),
        nb::arg("to_light"), nb::arg("light_offset"), nb::arg("texel"), nb::arg("shadow"),
        nb::arg("ambient"), nb::arg("background"), nb::arg("image"),
        "Colour every pixel into image (H, W, 3) uint8 (src/raster.h): a surface pixel of "
        "triangle t = ids[i, j] (H, W) is color[t] (T, 3) times ambient + (1 - ambient) * "
        "diffuse * lit, lit its unshadowed fraction in the shadow map shadow (S, S; (0, 0): no "
        "shadows), reached through light_offset (3,) + depth * to_light (3, 3) @ (x, y, 1) and "
        "one texel (m) of bias; an empty pixel is background (3,). A translucent triangle "
        "f = layer_ids[i, j] in front is blended over with alpha[f] (T,).");
}

}  // namespace rg
