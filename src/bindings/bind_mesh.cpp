// Python face of the mesh distances (src/collision/mesh_distance.h): rigid_gym._core.winding_number and
// signed_distance, used by rigid_gym/shapes.py, geometry.py (distance grids) and the tests.
#include <string>

#include "bindings/array_args.h"
#include "collision/geometry.h"
#include "collision/mesh_distance.h"

namespace rg {

namespace {

using MeshFunction = void (*)(Span<const Vec3>, Span<const Vec3>, Span<const Index3>,
                              Span<double>);

// Check the arguments of `function` (named `name`) and run it with the GIL released.
void call_checked(MeshFunction function, const std::string& name, nb::handle points,
                  nb::handle vertices, nb::handle triangles, nb::handle out) {
    const auto p = array_arg<const double>(points, (name + ": points").c_str(), {-1, 3});
    const auto v = array_arg<const double>(vertices, (name + ": vertices").c_str(), {-1, 3});
    const auto t = array_arg<const int32_t>(triangles, (name + ": triangles").c_str(), {-1, 3});
    const auto o = array_arg<double>(out, (name + ": out").c_str(), {extent(p, 0)});
    check_indices(rows<const int32_t>(t), 0, extent(v, 0), (name + ": triangles").c_str(),
                  "indices of vertices");
    nb::gil_scoped_release unlocked;
    function(rows<const Vec3>(p), rows<const Vec3>(v), rows<const Index3>(t), rows<double>(o));
}

}  // namespace

void bind_mesh(nb::module_& m) {
    m.def(
        "winding_number",
        [](nb::handle points, nb::handle vertices, nb::handle triangles, nb::handle out) {
            call_checked(winding_number, "winding_number", points, vertices, triangles, out);
        },
        nb::arg("points"), nb::arg("vertices"), nb::arg("triangles"), nb::arg("out"),
        "Generalised winding number of each point: the signed solid angles of all triangles / "
        "4 pi (src/collision/mesh_distance.h). points (P, 3) float64, m; vertices (V, 3) float64, m; "
        "triangles (T, 3) int32, counter-clockwise seen from outside; out (P,) float64, "
        "written: 1 inside a closed outward mesh, 0 outside, 1/2 on the surface (up to "
        "rounding). Right for nonconvex meshes too (Jacobson et al. 2013). The points are "
        "shared out over the core's threads, the GIL released.");
    m.def(
        "signed_distance",
        [](nb::handle points, nb::handle vertices, nb::handle triangles, nb::handle out) {
            call_checked(signed_distance, "signed_distance", points, vertices, triangles, out);
        },
        nb::arg("points"), nb::arg("vertices"), nb::arg("triangles"), nb::arg("out"),
        "Signed distance of each point to the mesh surface, m (src/collision/mesh_distance.h). points "
        "(P, 3) float64, m; vertices (V, 3) float64, m; triangles (T, 3) int32; out (P,) "
        "float64, written. Magnitude: exact distance to the nearest triangle. Sign: negative "
        "where the winding number exceeds 1/2 (inside), positive elsewhere. The points are "
        "shared out over the core's threads, the GIL released.");
}

}  // namespace rg
