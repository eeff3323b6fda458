// Python face of the envs' observation rows (src/envs/observation.h):
// rigid_gym._core.gather_observations, used by envs/core.py.
#include "bindings/array_args.h"
#include "envs/observation.h"

namespace rg {

void bind_observation(nb::module_& m) {
    m.def(
        "gather_observations",
        [](nb::handle position, nb::handle velocity, nb::handle rotation,
           nb::handle angular_velocity, nb::handle worlds, nb::handle index, nb::handle minus,
           nb::handle out) {
            const auto x = array_arg<const double>(position, "gather_observations: position",
                                                   {-1, -1, 3});
            const int64_t b = extent(x, 0), n = extent(x, 1);
            const auto v = array_arg<const double>(velocity, "gather_observations: velocity",
                                                   {b, n, 3});
            const auto r = array_arg<const double>(rotation, "gather_observations: rotation",
                                                   {b, n, 3, 3});
            const auto w = array_arg<const double>(
                angular_velocity, "gather_observations: angular_velocity", {b, n, 3});
            const auto rows_of =
                array_arg<const int64_t>(worlds, "gather_observations: worlds", {-1});
            const auto i = array_arg<const int64_t>(index, "gather_observations: index", {-1});
            const int64_t size = extent(i, 0);
            const auto mi =
                array_arg<const int64_t>(minus, "gather_observations: minus", {size});
            const auto o = array_arg<double>(out, "gather_observations: out",
                                             {extent(rows_of, 0), size});
            check_indices(rows<const int64_t>(rows_of), 0, b, "gather_observations: worlds",
                          "worlds");
            check_indices(rows<const int64_t>(i), 0, 18 * n, "gather_observations: index",
                          "state entries");
            check_indices(rows<const int64_t>(mi), -1, 18 * n, "gather_observations: minus",
                          "state entries, -1: none");
            ObservationQuery q;
            q.position = rows<const Vec3>(x);
            q.velocity = rows<const Vec3>(v);
            q.rotation = rows<const Mat3>(r);
            q.angular_velocity = rows<const Vec3>(w);
            q.num_bodies = n;
            q.worlds = rows<const int64_t>(rows_of);
            q.index = rows<const int64_t>(i);
            q.minus = rows<const int64_t>(mi);
            nb::gil_scoped_release unlocked;
            return gather_observations(q, rows<double>(o));
        },
        nb::arg("position"), nb::arg("velocity"), nb::arg("rotation"),
        nb::arg("angular_velocity"), nb::arg("worlds"), nb::arg("index"), nb::arg("minus"),
        nb::arg("out"),
        "Observation rows of the worlds `worlds` (k,) int64 into out (k, m) float64 "
        "(src/envs/observation.h); returns whether every entry is finite. A world's state entries "
        "are its positions (n x 3, m), velocities (n x 3, m/s), rotations (n x 9, row-major) "
        "and angular velocities (n x 3, rad/s) side by side (the arrays of World.state, "
        "(B, n, ...)); entry j of a row is entry index[j] (m,) int64, minus entry minus[j] "
        "(m,) int64 where that is >= 0.");
}

}  // namespace rg
