// Python face of the gripper's command (src/envs/footprint.h): rigid_gym._core.Pads, used by
// envs/effector.py.
#include <nanobind/stl/array.h>

#include <string>

#include "bindings/array_args.h"
#include "envs/footprint.h"

namespace rg {

void bind_footprint(nb::module_& m) {
    nb::class_<Pads>(m, "Pads",
                     "The gripper pads of every world of a batch, as the envs drive them "
                     "(src/envs/footprint.h; envs/effector.py).")
        .def(
            "__init__",
            [](Pads* self, int64_t num_worlds, int64_t num_bodies, int64_t pad,
               std::array<double, 3> pad_half, nb::handle objects, nb::handle halves,
               nb::handle fixed_bodies, nb::handle fixed_offsets, nb::handle fixed_rotations,
               nb::handle fixed_halves, nb::handle carried, nb::handle carried_halves,
               std::array<double, 3> low, std::array<double, 3> high, double step_distance,
               double step_time) {
                if (num_worlds < 1) {
                    throw nb::value_error("Pads: num_worlds must be >= 1");
                }
                if (pad < 0 || pad >= num_bodies) {
                    throw nb::value_error(("Pads: pad " + std::to_string(pad) +
                                           " is not a body, outside [0, " +
                                           std::to_string(num_bodies) + ")")
                                              .c_str());
                }
                if (!(step_time > 0.0)) {
                    throw nb::value_error(
                        ("Pads: step_time must be > 0 s, got " + std::to_string(step_time)).c_str());
                }
                const auto o = array_arg<const int64_t>(objects, "Pads: objects", {-1});
                const int64_t k = extent(o, 0);
                const auto hv = array_arg<const double>(halves, "Pads: halves", {k, 3});
                check_indices(rows<const int64_t>(o), 0, num_bodies, "Pads: objects", "bodies");
                const auto fb = array_arg<const int64_t>(fixed_bodies, "Pads: fixed_bodies", {-1});
                const int64_t f = extent(fb, 0);
                const auto fo = array_arg<const double>(fixed_offsets, "Pads: fixed_offsets", {f, 3});
                const auto fr = array_arg<const double>(fixed_rotations, "Pads: fixed_rotations",
                                                        {f, 3, 3});
                const auto fh = array_arg<const double>(fixed_halves, "Pads: fixed_halves", {f, 3});
                check_indices(rows<const int64_t>(fb), 0, num_bodies, "Pads: fixed_bodies",
                              "bodies");
                const auto cb = array_arg<const int64_t>(carried, "Pads: carried", {-1});
                const int64_t c = extent(cb, 0);
                const auto ch = array_arg<const double>(carried_halves, "Pads: carried_halves",
                                                        {c, 3});
                check_indices(rows<const int64_t>(cb), 0, num_bodies, "Pads: carried", "bodies");
                Pads* p = new (self) Pads();
                p->pad = pad;
                p->pad_half = {pad_half[0], pad_half[1], pad_half[2]};
                p->objects.assign(rows<const int64_t>(o).data, k);
                p->halves.assign(rows<const Vec3>(hv).data, k);
                p->fixed_bodies.assign(rows<const int64_t>(fb).data, f);
                p->fixed_offsets.assign(rows<const Vec3>(fo).data, f);
                p->fixed_rotations.assign(rows<const Mat3>(fr).data, f);
                p->fixed_halves.assign(rows<const Vec3>(fh).data, f);
                p->carried.assign(rows<const int64_t>(cb).data, c);
                p->carried_halves.assign(rows<const Vec3>(ch).data, c);
                p->low = {low[0], low[1], low[2]};
                p->high = {high[0], high[1], high[2]};
                p->step_distance = step_distance;
                p->step_time = step_time;
                p->boxes_x.assign(k, {});
                p->boxes_r.assign(k, {});
                p->parts_x.assign(2 + c, {});
                p->parts_r.assign(2 + c, {});
                p->parts_half.assign(2 + c, {});
                p->targets.assign(num_worlds, {});
                p->lowest.assign(num_worlds, 0.0);
            },
            nb::kw_only(), nb::arg("num_worlds"), nb::arg("num_bodies"), nb::arg("pad"),
            nb::arg("pad_half"), nb::arg("objects"), nb::arg("halves"), nb::arg("fixed_bodies"),
            nb::arg("fixed_offsets"), nb::arg("fixed_rotations"), nb::arg("fixed_halves"),
            nb::arg("carried"), nb::arg("carried_halves"), nb::arg("low"),
            nb::arg("high"), nb::arg("step_distance"), nb::arg("step_time"),
            "B = num_worlds worlds of num_bodies bodies: pad is the pad's body index, pad_half "
            "(3,) m its half extents; objects (K,) int64 the boxes' body indices and halves "
            "(K, 3) m their half extents (the same in every world); fixed_bodies (F,) int64 the "
            "static bodies of the fixtures' box parts, fixed_offsets (F, 3) m and fixed_rotations "
            "(F, 3, 3) each part's pose in its body's frame, fixed_halves (F, 3) m its half "
            "extents (F = 0: none); carried (C,) int64 the bodies that move with the pad (a "
            "parallel gripper's fingers) and carried_halves (C, 3) m their half extents (C = 0: "
            "none); low, high (3,) m the workspace the pad's centre stays in; step_distance m of motion per unit of action; "
            "step_time s per env step.")
        .def(
            "command",
            [](Pads& p, nb::handle motions, nb::handle positions, nb::handle rotations,
               nb::handle velocities, nb::handle held, nb::handle carried_sweeps) {
                const int64_t b = p.targets.size(), k = p.objects.size();
                const auto mo = array_arg<const double>(motions, "Pads.command: motions", {b, 3});
                const auto x = array_arg<const double>(positions, "Pads.command: positions",
                                                       {b, -1, 3});
                const int64_t n = extent(x, 1);
                const auto r = array_arg<const double>(rotations, "Pads.command: rotations",
                                                       {b, n, 3, 3});
                const auto v = array_arg<double>(velocities, "Pads.command: velocities", {b, n, 3});
                const auto hd = array_arg<const int64_t>(held, "Pads.command: held", {b});
                check_indices(Span<const int64_t>{p.objects.data(), k}, 0, n,
                              "Pads.command: objects", "bodies");
                check_indices(rows<const int64_t>(hd), -1, k, "Pads.command: held",
                              "indices into objects, -1: none");
                check_indices(Span<const int64_t>{p.carried.data(), p.carried.size()}, 0, n,
                              "Pads.command: carried", "bodies");
                if (p.pad >= n) {
                    throw nb::value_error("Pads.command: the pad is not a body of positions");
                }
                Span<const Vec3> sweeps;
                if (!carried_sweeps.is_none()) {
                    const auto sw = array_arg<const double>(
                        carried_sweeps, "Pads.command: carried_sweeps",
                        {b, static_cast<int64_t>(p.carried.size()), 3});
                    sweeps = rows<const Vec3>(sw);
                }
                FootprintQuery q;
                q.positions = rows<const Vec3>(x);
                q.rotations = rows<const Mat3>(r);
                q.num_bodies = n;
                q.pad = p.pad;
                q.pad_half = p.pad_half;
                q.objects = {p.objects.data(), k};
                q.halves = {p.halves.data(), k};
                q.fixed_bodies = {p.fixed_bodies.data(), p.fixed_bodies.size()};
                q.fixed_offsets = {p.fixed_offsets.data(), p.fixed_offsets.size()};
                q.fixed_rotations = {p.fixed_rotations.data(), p.fixed_rotations.size()};
                q.fixed_halves = {p.fixed_halves.data(), p.fixed_halves.size()};
                q.carried = {p.carried.data(), p.carried.size()};
                q.carried_halves = {p.carried_halves.data(), p.carried_halves.size()};
                q.carried_sweeps = sweeps;
                q.held = rows<const int64_t>(hd);
                q.parts_x = p.parts_x.span();  // the pad, the held box, the carried bodies
                q.parts_r = p.parts_r.span();
                q.parts_half = p.parts_half.span();
                q.boxes_x = p.boxes_x.span();
                q.boxes_r = p.boxes_r.span();
                PadCommand c;
                c.motions = rows<const Vec3>(mo);
                c.step_distance = p.step_distance;
                c.low = p.low;
                c.high = p.high;
                c.step_time = p.step_time;
                c.velocities = rows<Vec3>(v);
                c.targets = p.targets.span();
                c.lowest = p.lowest.span();
                nb::gil_scoped_release unlocked;
                command_pads(q, c);
            },
            nb::arg("motions"), nb::arg("positions"), nb::arg("rotations"), nb::arg("velocities"),
            nb::arg("held"), nb::arg("carried_sweeps").none() = nb::none(),
            "One env step's command of the gripper of every world: the pad's target is its "
            "centre plus step_distance x motion, clamped to [low, high]; a downward move stops "
            "where the pad, the box it holds or a carried body would rest on the table, on the "
            "top of a box or of a fixture's box part under its footprint (never lifting the "
            "pad); the pad's velocity is set to reach the target in step_time. motions (B, 3) in "
            "[-1, 1]; positions (B, n, 3) m, rotations (B, n, 3, 3) and velocities (B, n, 3) m/s "
            "(written: the pads') of every body; held (B,) int64 the held box (an index into "
            "objects, -1: none); carried_sweeps None or (B, C, 3) m how far each carried body "
            "moves relative to the pad over the step (its part is then the box it sweeps).")
        .def(
            "grasps",
            [](Pads& p, nb::handle positions, nb::handle rotations, nb::handle worlds,
               double margin, nb::handle held, nb::handle width) {
                const int64_t b = p.targets.size(), k = p.objects.size();
                if (p.carried.size() < 2) {
                    throw nb::value_error("Pads.grasps: needs two carried bodies (the fingers)");
                }
                const auto x = array_arg<const double>(positions, "Pads.grasps: positions",
                                                       {b, -1, 3});
                const int64_t n = extent(x, 1);
                const auto r = array_arg<const double>(rotations, "Pads.grasps: rotations",
                                                       {b, n, 3, 3});
                const auto wo = array_arg<const int64_t>(worlds, "Pads.grasps: worlds", {-1});
                const int64_t count = extent(wo, 0);
                const auto hd = array_arg<int64_t>(held, "Pads.grasps: held", {count});
                const auto wd = array_arg<double>(width, "Pads.grasps: width", {count});
                check_indices(rows<const int64_t>(wo), 0, b, "Pads.grasps: worlds", "worlds");
                check_indices(Span<const int64_t>{p.objects.data(), k}, 0, n,
                              "Pads.grasps: objects", "bodies");
                check_indices(Span<const int64_t>{p.carried.data(), p.carried.size()}, 0, n,
                              "Pads.grasps: carried", "bodies");
                FootprintQuery q;
                q.positions = rows<const Vec3>(x);
                q.rotations = rows<const Mat3>(r);
                q.num_bodies = n;
                q.objects = {p.objects.data(), k};
                q.halves = {p.halves.data(), k};
                q.carried = {p.carried.data(), p.carried.size()};
                q.carried_halves = {p.carried_halves.data(), p.carried_halves.size()};
                nb::gil_scoped_release unlocked;
                grasps(q, rows<const int64_t>(wo), margin, rows<int64_t>(hd), rows<double>(wd));
            },
            nb::arg("positions"), nb::arg("rotations"), nb::arg("worlds"), nb::arg("margin"),
            nb::arg("held"), nb::arg("width"),
            "A parallel gripper's grasp in worlds (k,) int64 (src/envs/footprint.h: grasps), "
            "its fingers the first two carried bodies (towards -y, then +y): into held (k,) "
            "int64 the box both fingers' inner faces lie within margin m of along y (an index "
            "into objects, -1: none), into width (k,) m the opening between them. positions "
            "(B, n, 3) m and rotations (B, n, 3, 3) of every body.");
}

}  // namespace rg
