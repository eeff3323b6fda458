// Constants the Python side builds scenes and geometry with, and the single-contact impulse
// formulas for their tests: one source for both languages.
#include <nanobind/stl/array.h>

#include "bindings/arrays.h"
#include "base/body.h"
#include "collision/geometry.h"
#include "solver/impulse.h"
#include "solver/integrate.h"
#include "collision/narrow_phase.h"
#include "solver/patch.h"
#include "solver/step.h"

namespace rg {

namespace {

Mat3 matrix(const std::array<std::array<double, 3>, 3>& k) {
    Mat3 m;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            m.m[i][j] = k[i][j];
        }
    }
    return m;
}

std::array<std::array<double, 3>, 3> rows_of(const Mat3& m) {
    std::array<std::array<double, 3>, 3> k;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            k[i][j] = m.m[i][j];
        }
    }
    return k;
}

Vec3 vec(const std::array<double, 3>& v) { return {v[0], v[1], v[2]}; }

}  // namespace

void bind_geometry(nb::module_& m) {
    m.attr("STATIC") = static_cast<int>(STATIC);
    m.attr("KINEMATIC") = static_cast<int>(KINEMATIC);
    m.attr("DYNAMIC") = static_cast<int>(DYNAMIC);
    m.attr("SPHERE") = static_cast<int>(SPHERE);
    m.attr("CAPSULE") = static_cast<int>(CAPSULE);
    m.attr("BOX") = static_cast<int>(BOX);
    m.attr("MESH") = static_cast<int>(MESH);
    m.attr("PLANE") = static_cast<int>(PLANE);
    m.attr("CAPSULE_CORE_SAMPLES") = CAPSULE_CORE_SAMPLES;
    m.attr("TOUCHING_GAP") = CLOSED_GAP;
    std::vector<double> corners;
    for (const Vec3& c : BOX_CORNERS) {
        corners.insert(corners.end(), {c.x, c.y, c.z});
    }
    m.attr("BOX_CORNERS") = hand_over(std::move(corners), {8, 3});
    std::vector<int32_t> edges;
    for (const auto& e : BOX_EDGES) {
        edges.insert(edges.end(), {e[0], e[1]});
    }
    m.attr("BOX_EDGES") = hand_over(std::move(edges), {12, 2});
    m.attr("MAX_ROTATION_SUBSTEPS") = MAX_ROTATION_SUBSTEPS;
    m.def("rotation_substeps", &rotation_substeps, nb::arg("speed"), nb::arg("dt"),
          "Sub-steps of the rotation update for angular speed |omega| (rad/s) over dt (s): "
          "quarter turns, at most MAX_ROTATION_SUBSTEPS (src/solver/integrate.h).");
    m.def(
        "add_point_mass_matrix",
        [](double inverse_mass, const std::array<std::array<double, 3>, 3>& rotation,
           const std::array<double, 3>& inverse_moments, const std::array<double, 3>& r,
           const std::array<std::array<double, 3>, 3>& k) {
            Mat3 out = matrix(k);
            add_point_mass_matrix(inverse_mass, inverse_inertia(matrix(rotation), vec(inverse_moments)),
                                  vec(r), out);
            return rows_of(out);
        },
        nb::arg("inverse_mass"), nb::arg("rotation"), nb::arg("inverse_moments"), nb::arg("r"),
        nb::arg("k"),
        "k + (1/M) 1 + r*^T I^-1 r* (src/solver/impulse.h) as nested lists, for one body: inverse "
        "mass 1/kg, rotation (3, 3), principal inverse moments (3,), lever r (3,) m.");
    m.def(
        "contact_impulse",
        [](const std::array<std::array<double, 3>, 3>& k, const std::array<double, 3>& v,
           const std::array<double, 3>& n, double e, double mu) {
            const Vec3 j = contact_impulse(matrix(k), vec(v), vec(n), e, mu);
            return std::array<double, 3>{j.x, j.y, j.z};
        },
        nb::arg("k"), nb::arg("v"), nb::arg("n"), nb::arg("e"), nb::arg("mu"),
        "The impulse (3,) N s on body 1 of a contact (src/solver/impulse.h): summed matrix k (3, 3), "
        "relative velocity v (3,) m/s with v.n < 0, normal n (3,), restitution e, friction mu.");
}

}  // namespace rg
