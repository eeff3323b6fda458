// Python face of the gripper's footprint test (src/footprint.h): rigid_gym._core.lowest_centres,
// used by envs/effector.py.
#include <string>

#include "array_args.h"
#include "footprint.h"

namespace rg {

void bind_footprint(nb::module_& m) {
    m.def(
        "lowest_centres",
        [](nb::handle targets, nb::handle positions, nb::handle rotations, int64_t pad,
           nb::handle pad_half, nb::handle objects, nb::handle halves, nb::handle held,
           nb::handle parts_x, nb::handle parts_r, nb::handle parts_half, nb::handle boxes_x,
           nb::handle boxes_r, nb::handle out) {
            const auto t = array_arg<const double>(targets, "lowest_centres: targets", {-1, 3});
            const int64_t b = extent(t, 0);
            const auto x = array_arg<const double>(positions, "lowest_centres: positions",
                                                   {b, -1, 3});
            const int64_t n = extent(x, 1);
            const auto r = array_arg<const double>(rotations, "lowest_centres: rotations",
                                                   {b, n, 3, 3});
            if (pad < 0 || pad >= n) {
                throw nb::value_error(("lowest_centres: pad " + std::to_string(pad) +
                                       " is not a body, outside [0, " + std::to_string(n) + ")")
                                          .c_str());
            }
            const auto ph = array_arg<const double>(pad_half, "lowest_centres: pad_half", {3});
            const auto o = array_arg<const int64_t>(objects, "lowest_centres: objects", {-1});
            const int64_t k = extent(o, 0);
            const auto hv = array_arg<const double>(halves, "lowest_centres: halves", {k, 3});
            const auto hd = array_arg<const int64_t>(held, "lowest_centres: held", {b});
            const auto px = array_arg<double>(parts_x, "lowest_centres: parts_x", {2, 3});
            const auto pr = array_arg<double>(parts_r, "lowest_centres: parts_r", {2, 3, 3});
            const auto ps = array_arg<double>(parts_half, "lowest_centres: parts_half", {2, 3});
            const auto bx = array_arg<double>(boxes_x, "lowest_centres: boxes_x", {k, 3});
            const auto br = array_arg<double>(boxes_r, "lowest_centres: boxes_r", {k, 3, 3});
            const auto w = array_arg<double>(out, "lowest_centres: out", {b});
            check_indices(rows<const int64_t>(o), 0, n, "lowest_centres: objects", "bodies");
            check_indices(rows<const int64_t>(hd), -1, k, "lowest_centres: held",
                          "indices into objects, -1: none");
            FootprintQuery q;
            q.targets = rows<const Vec3>(t);
            q.positions = rows<const Vec3>(x);
            q.rotations = rows<const Mat3>(r);
            q.num_bodies = n;
            q.pad = pad;
            q.pad_half = rows<const Vec3>(ph)[0];
            q.objects = rows<const int64_t>(o);
            q.halves = rows<const Vec3>(hv);
            q.held = rows<const int64_t>(hd);
            q.parts_x = rows<Vec3>(px);
            q.parts_r = rows<Mat3>(pr);
            q.parts_half = rows<Vec3>(ps);
            q.boxes_x = rows<Vec3>(bx);
            q.boxes_r = rows<Mat3>(br);
            nb::gil_scoped_release unlocked;
            lowest_centres(q, rows<double>(w));
        },
        nb::arg("targets"), nb::arg("positions"), nb::arg("rotations"), nb::arg("pad"),
        nb::arg("pad_half"), nb::arg("objects"), nb::arg("halves"), nb::arg("held"),
        nb::arg("parts_x"), nb::arg("parts_r"), nb::arg("parts_half"), nb::arg("boxes_x"),
        nb::arg("boxes_r"), nb::arg("out"),
        "The lowest z (m) the gripper's centre of every world may take at its target "
        "(src/footprint.h): where the pad, or the box it holds, would rest on the table or on "
        "the top of a box under its footprint. targets (B, 3) m, the pad's centre at its "
        "target; positions (B, n, 3) m, rotations (B, n, 3, 3) of every body; pad: the pad's "
        "body index, pad_half (3,) m; objects (K,) int64 the boxes' body indices and halves "
        "(K, 3) m their half extents (the same in every world); held (B,) int64 the held box "
        "(an index into objects, -1: none). Work arrays, overwritten: parts_x (2, 3), parts_r "
        "(2, 3, 3), parts_half (2, 3), boxes_x (K, 3), boxes_r (K, 3, 3). out (B,) m, written.");
}

}  // namespace rg
