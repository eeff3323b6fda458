// Python face of the renderer's core (src/render/frames.h): rigid_gym._core.FrameRenderer, which
// rigid_gym/render.py builds from its tessellated scene and draws one world or a batch with.
// Drawing releases the GIL; one renderer draws one batch at a time.
#include <memory>
#include <mutex>
#include <string>

#include "bindings/array_args.h"
#include "render/frames.h"

namespace rg {

namespace {

Vec3 vector_arg(nb::handle value, const char* where) {
    return rows<const Vec3>(array_arg<const double>(value, where, {3}))[0];
}

Mat3 matrix_arg(nb::handle value, const char* where) {
    return rows<const Mat3>(array_arg<const double>(value, where, {3, 3}))[0];
}

template <class T, class S>
Array<T> copied(const ArrayArg<S>& a) {
    const Span<const T> values = rows<const T>(a);
    Array<T> out;
    out.assign(values.data, values.size);
    return out;
}

std::string text(const char* where, const std::string& what) { return std::string(where) + what; }

// A FrameRenderer, its camera and light, and the lock that keeps two Python threads from
// drawing into its buffers at once.
struct BoundRenderer {
    FrameRenderer renderer;
    FrameView view{};
    std::mutex drawing;

    explicit BoundRenderer(FrameRenderer r) : renderer(std::move(r)) {}
};

}  // namespace

void bind_render(nb::module_& m) {
    nb::class_<BoundRenderer> cls(
        m, "FrameRenderer",
        "Frames of copies of one triangle soup (src/render/frames.h): every copy's picture in one "
        "call, on the core's threads. rigid_gym.render.Renderer builds and drives it.");
    cls.def(
        "__init__",
        [](BoundRenderer* self, nb::handle corners, nb::handle normals, nb::handle owner,
           nb::handle colors, nb::handle alpha, int64_t num_background, int64_t num_casters,
           int64_t num_opaque,
           int64_t num_bodies, int64_t num_markers, int64_t width, int64_t height,
           int64_t shadow_side) {
            const char* where = "FrameRenderer: ";
            const auto c = array_arg<const double>(corners, "FrameRenderer: corners", {-1, 3});
            const int64_t count = extent(c, 0);
            if (count % 3 != 0) {
                throw nb::value_error(text(where, "corners must be 3 per triangle, got " +
                                                      std::to_string(count)).c_str());
            }
            const int64_t triangles = count / 3;
            const auto n = array_arg<const double>(normals, "FrameRenderer: normals", {count, 3});
            const auto o = array_arg<const int32_t>(owner, "FrameRenderer: owner", {count});
            const auto k = array_arg<const double>(colors, "FrameRenderer: colors",
                                                   {triangles, 3});
            const auto a = array_arg<const double>(alpha, "FrameRenderer: alpha", {triangles});
            if (num_bodies < 0 || num_markers < 0) {
                throw nb::value_error(text(where, "num_bodies and num_markers must be >= 0")
                                          .c_str());
            }
            if (!(0 <= num_background && 0 <= num_casters &&
                  num_background + num_casters <= num_opaque && num_opaque <= triangles)) {
                throw nb::value_error(
                    text(where, "need 0 <= num_background, num_casters and num_background + "
                                "num_casters <= num_opaque <= triangles (" +
                                    std::to_string(triangles) + "), got " +
                                    std::to_string(num_background) + ", " +
                                    std::to_string(num_casters) + ", " +
                                    std::to_string(num_opaque)).c_str());
            }
            if (width < 1 || height < 1 || shadow_side < 0 || (shadow_side > 0 && shadow_side <= 4)) {
                throw nb::value_error(text(where, "width and height must be >= 1 and "
                                                  "shadow_side 0 or > 4").c_str());
            }
            check_indices(rows<const int32_t>(o), 0, num_bodies + num_markers,
                          "FrameRenderer: owner", "instances: bodies, then markers");
            FrameMesh mesh;
            mesh.corners = copied<Vec3>(c);
            mesh.normals = copied<Vec3>(n);
            mesh.owner = copied<int32_t>(o);
            mesh.colors = copied<Vec3>(k);
            mesh.alpha = copied<double>(a);
            mesh.num_background = num_background;
            mesh.num_casters = num_casters;
            mesh.num_opaque = num_opaque;
            mesh.num_bodies = num_bodies;
            mesh.num_markers = num_markers;
            new (self) BoundRenderer(
                FrameRenderer(std::move(mesh), width, height, shadow_side));
        },
        nb::arg("corners"), nb::arg("normals"), nb::arg("owner"), nb::arg("colors"),
        nb::arg("alpha"), nb::arg("num_background"), nb::arg("num_casters"),
        nb::arg("num_opaque"), nb::arg("num_bodies"),
        nb::arg("num_markers"), nb::arg("width"), nb::arg("height"), nb::arg("shadow_side"),
        "The soup (copied): corners, normals (3T, 3) float64 in their instance's frame, owner "
        "(3T,) int32 (body b < num_bodies, else marker b - num_bodies), colors (T, 3) in "
        "[0, 1], alpha (T,); triangles [0, num_background) are the background (drawn again only "
        "when the view or their poses change), the next num_casters cast shadows, [0, "
        "num_opaque) are opaque. Frames of width x height pixels, a shadow map of shadow_side^2 texels (0: "
        "none).");
    cls.def(
        "set_view",
        [](BoundRenderer& self, nb::handle eye, nb::handle axes, double focal, double near,
           nb::handle light, nb::handle light_axes, double ambient, nb::handle background) {
            FrameView v;
            v.eye = vector_arg(eye, "FrameRenderer.set_view: eye");
            v.axes = matrix_arg(axes, "FrameRenderer.set_view: axes");
            v.focal = focal;
            v.near = near;
            v.light = vector_arg(light, "FrameRenderer.set_view: light");
            v.light_axes = matrix_arg(light_axes, "FrameRenderer.set_view: light_axes");
            v.ambient = ambient;
            v.background = vector_arg(background, "FrameRenderer.set_view: background");
            std::lock_guard<std::mutex> lock(self.drawing);
            self.view = v;
        },
        nb::arg("eye"), nb::arg("axes"), nb::arg("focal"), nb::arg("near"), nb::arg("light"),
        nb::arg("light_axes"), nb::arg("ambient"), nb::arg("background"),
        "The camera and light of every later frame (src/render/frames.h, FrameView): eye (3,) m, "
        "axes (3, 3) rows right, up, forward; focal, pixels; near, m; light (3,) unit vector "
        "towards the light; light_axes (3, 3) rows u, v, light; ambient; background (3,) RGB.");
    cls.def(
        "render",
        [](BoundRenderer& self, nb::handle body_rotation, nb::handle body_position,
           nb::handle marker_rotation, nb::handle marker_position, nb::handle worlds,
           nb::handle images) {
            const FrameRenderer& r = self.renderer;
            const int64_t n = r.mesh().num_bodies, m = r.mesh().num_markers;
            const auto br = array_arg<const double>(
                body_rotation, "FrameRenderer.render: body_rotation", {-1, n, 3, 3});
            const int64_t b = extent(br, 0);
            const auto bp = array_arg<const double>(
                body_position, "FrameRenderer.render: body_position", {b, n, 3});
            const auto mr = array_arg<const double>(
                marker_rotation, "FrameRenderer.render: marker_rotation", {m, 3, 3});
            const auto mp = array_arg<const double>(
                marker_position, "FrameRenderer.render: marker_position", {b, m, 3});
            const auto w = array_arg<const int64_t>(worlds, "FrameRenderer.render: worlds", {-1});
            const auto im = array_arg<uint8_t>(images, "FrameRenderer.render: images",
                                               {extent(w, 0), r.height(), r.width(), 3});
            check_indices(rows<const int64_t>(w), 0, b, "FrameRenderer.render: worlds",
                          "copies of the poses");
            const FramePoses poses = {rows<const Mat3>(br), rows<const Vec3>(bp),
                                      rows<const Mat3>(mr), rows<const Vec3>(mp)};
            nb::gil_scoped_release unlocked;
            std::lock_guard<std::mutex> lock(self.drawing);
            self.renderer.render(poses, rows<const int64_t>(w), self.view, rows<Rgb8>(im));
        },
        nb::arg("body_rotation"), nb::arg("body_position"), nb::arg("marker_rotation"),
        nb::arg("marker_position"), nb::arg("worlds"), nb::arg("images"),
        "Draw copy worlds[k] (k,) int64 into images[k] ((k, H, W, 3) uint8), shared out over "
        "the core's threads: body_rotation (B, n, 3, 3) and body_position (B, n, 3) m are the "
        "copies' bodies (World.state's rotation and position), marker_rotation (m, 3, 3) the "
        "markers' orientations (every copy's), marker_position (B, m, 3) m each copy's "
        "markers.");
}

}  // namespace rg
