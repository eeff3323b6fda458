// rigid_gym._core: the compiled solver core. Each bind_*.cpp adds one area's names.
#include <nanobind/nanobind.h>

namespace nb = nanobind;

namespace rg {
void bind_world(nb::module_& m);
void bind_mesh(nb::module_& m);
void bind_render(nb::module_& m);
void bind_footprint(nb::module_& m);
void bind_observation(nb::module_& m);
void bind_geometry(nb::module_& m);
}  // namespace rg

NB_MODULE(_core, m) {
    m.doc() = "rigid_gym's solver core in C++ (src/): the step, its stages and the queries.";
    rg::bind_world(m);
    rg::bind_mesh(m);
    rg::bind_render(m);
    rg::bind_footprint(m);
    rg::bind_observation(m);
    rg::bind_geometry(m);
}
