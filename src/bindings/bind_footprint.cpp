// Python face of the gripper's command (src/envs/footprint.h): rigid_gym._core.command_pads, used by
// envs/effector.py.
#include <string>

#include "bindings/array_args.h"
#include "envs/footprint.h"

namespace rg {

void bind_footprint(nb::module_& m) {
    m.def(
        "command_pads",
        [](nb::handle motions, nb::handle positions, nb::handle rotations, nb::handle velocities,
           int64_t pad, nb::handle pad_half, nb::handle objects, nb::handle halves,
           nb::handle held, nb::handle fixed_bodies, nb::handle fixed_offsets,
           nb::handle fixed_rotations, nb::handle fixed_halves, nb::handle low,
           nb::handle high, double step_distance, double step_time, nb::handle boxes_x,
           nb::handle boxes_r, nb::handle targets, nb::handle lowest) {
            const auto mo = array_arg<const double>(motions, "command_pads: motions", {-1, 3});
            const int64_t b = extent(mo, 0);
            const auto x = array_arg<const double>(positions, "command_pads: positions",
                                                   {b, -1, 3});
            const int64_t n = extent(x, 1);
            const auto r = array_arg<const double>(rotations, "command_pads: rotations",
                                                   {b, n, 3, 3});
            const auto v = array_arg<double>(velocities, "command_pads: velocities", {b, n, 3});
            if (pad < 0 || pad >= n) {
                throw nb::value_error(("command_pads: pad " + std::to_string(pad) +
                                       " is not a body, outside [0, " + std::to_string(n) + ")")
                                          .c_str());
            }
            if (!(step_time > 0.0)) {
                throw nb::value_error(("command_pads: step_time must be > 0 s, got " +
                                       std::to_string(step_time))
                                          .c_str());
            }
            const auto ph = array_arg<const double>(pad_half, "command_pads: pad_half", {3});
            const auto o = array_arg<const int64_t>(objects, "command_pads: objects", {-1});
            const int64_t k = extent(o, 0);
            const auto hv = array_arg<const double>(halves, "command_pads: halves", {k, 3});
            const auto hd = array_arg<const int64_t>(held, "command_pads: held", {b});
            const auto fb = array_arg<const int64_t>(fixed_bodies, "command_pads: fixed_bodies",
                                                     {-1});
            const int64_t f = extent(fb, 0);
            const auto fo = array_arg<const double>(fixed_offsets, "command_pads: fixed_offsets",
                                                    {f, 3});
            const auto fr = array_arg<const double>(fixed_rotations,
                                                    "command_pads: fixed_rotations", {f, 3, 3});
            const auto fh = array_arg<const double>(fixed_halves, "command_pads: fixed_halves",
                                                    {f, 3});
            const auto lo = array_arg<const double>(low, "command_pads: low", {3});
            const auto hi = array_arg<const double>(high, "command_pads: high", {3});
            const auto bx = array_arg<double>(boxes_x, "command_pads: boxes_x", {k, 3});
            const auto br = array_arg<double>(boxes_r, "command_pads: boxes_r", {k, 3, 3});
            const auto t = array_arg<double>(targets, "command_pads: targets", {b, 3});
            const auto w = array_arg<double>(lowest, "command_pads: lowest", {b});
            check_indices(rows<const int64_t>(o), 0, n, "command_pads: objects", "bodies");
            check_indices(rows<const int64_t>(hd), -1, k, "command_pads: held",
                          "indices into objects, -1: none");
            check_indices(rows<const int64_t>(fb), 0, n, "command_pads: fixed_bodies", "bodies");
            // the parts under test are the pad and the box it holds: two at most
            Vec3 parts_x[2], parts_half[2];
            Mat3 parts_r[2];
            FootprintQuery q;
            q.positions = rows<const Vec3>(x);
            q.rotations = rows<const Mat3>(r);
            q.num_bodies = n;
            q.pad = pad;
            q.pad_half = rows<const Vec3>(ph)[0];
            q.objects = rows<const int64_t>(o);
            q.halves = rows<const Vec3>(hv);
            q.held = rows<const int64_t>(hd);
            q.fixed_bodies = rows<const int64_t>(fb);
            q.fixed_offsets = rows<const Vec3>(fo);
            q.fixed_rotations = rows<const Mat3>(fr);
            q.fixed_halves = rows<const Vec3>(fh);
            q.parts_x = {parts_x, 2};
            q.parts_r = {parts_r, 2};
            q.parts_half = {parts_half, 2};
            q.boxes_x = rows<Vec3>(bx);
            q.boxes_r = rows<Mat3>(br);
            PadCommand c;
            c.motions = rows<const Vec3>(mo);
            c.step_distance = step_distance;
            c.low = rows<const Vec3>(lo)[0];
            c.high = rows<const Vec3>(hi)[0];
            c.step_time = step_time;
            c.velocities = rows<Vec3>(v);
            c.targets = rows<Vec3>(t);
            c.lowest = rows<double>(w);
            nb::gil_scoped_release unlocked;
            command_pads(q, c);
        },
        nb::arg("motions"), nb::arg("positions"), nb::arg("rotations"), nb::arg("velocities"),
        nb::arg("pad"), nb::arg("pad_half"), nb::arg("objects"), nb::arg("halves"),
        nb::arg("held"), nb::arg("fixed_bodies"), nb::arg("fixed_offsets"),
        nb::arg("fixed_rotations"), nb::arg("fixed_halves"), nb::arg("low"), nb::arg("high"),
        nb::arg("step_distance"),
        nb::arg("step_time"), nb::arg("boxes_x"), nb::arg("boxes_r"), nb::arg("targets"),
        nb::arg("lowest"),
        "One env step's command of the gripper of every world (src/envs/footprint.h): the pad's "
        "target is its centre plus step_distance (m) x motion, clamped to [low, high] (3,) m; "
        "a downward move stops where the pad, or the box it holds, would rest on the table, "
        "on the top of a box or of a fixture's box part under its footprint (never lifting the "
        "pad); the pad's velocity is "
        "set to reach the target in step_time (s). motions (B, 3) in [-1, 1]; positions "
        "(B, n, 3) m, rotations (B, n, 3, 3) and velocities (B, n, 3) m/s (written: the pads') "
        "of every body; pad: the pad's body index, pad_half (3,) m; objects (K,) int64 the "
        "boxes' body indices and halves (K, 3) m their half extents (the same in every world); "
        "held (B,) int64 the held box (an index into objects, -1: none); fixed_bodies (F,) "
        "int64 the static bodies of the fixtures' box parts, fixed_offsets (F, 3) m and "
        "fixed_rotations (F, 3, 3) each part's pose in its body's frame, fixed_halves (F, 3) m "
        "its half extents (F = 0: none). Work arrays, "
        "overwritten: boxes_x (K, 3), boxes_r (K, 3, 3), targets (B, 3), lowest (B,).");
}

}  // namespace rg
