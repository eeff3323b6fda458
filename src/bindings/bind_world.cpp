// Python face of the batch: rigid_gym._core.Batch (used by rigid_gym/world.py).
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/tuple.h>

#include <algorithm>
#include <iterator>
#include <stdexcept>
#include <string>

#include "bindings/arrays.h"
#include "solver/integrate.h"
#include "solver/joints.h"
#include "solver/queries.h"
#include "solver/stages.h"
#include "solver/step.h"
#include "base/thread_pool.h"
#include "solver/world.h"

namespace rg {

namespace {

template <class T>
T item(const nb::dict& d, const char* key) {
    if (!d.contains(key)) {
        throw nb::key_error((std::string("rigid_gym core: missing ") + key).c_str());
    }
    return nb::cast<T>(d[key]);
}

Geometry read_geometry(const nb::dict& g) {
    Geometry geo;
    auto ints = [&](const char* key) { return read_rows<int32_t>(item<InArray<int32_t>>(g, key), {}, key); };
    auto vectors = [&](const char* key) { return read_rows<Vec3>(item<InArray<double>>(g, key), {3}, key); };
    geo.geom_body = ints("geom_body");
    geo.geom_type = ints("geom_type");
    geo.geom_size = vectors("geom_size");
    geo.geom_position = vectors("geom_position");
    geo.geom_rotation = read_rows<Mat3>(item<InArray<double>>(g, "geom_rotation"), {3, 3}, "geom_rotation");
    geo.geom_grid = ints("geom_grid");
    geo.body_geom_start = ints("body_geom_start");
    geo.sample_start = ints("sample_start");
    geo.sample_vertex_count = ints("sample_vertex_count");
    geo.sample_points = vectors("sample_points");
    geo.body_bound_center = vectors("body_bound_center");
    geo.body_bound_half = vectors("body_bound_half");
    geo.body_unbounded = ints("body_unbounded");
    geo.grid_offset = ints("grid_offset");
    geo.grid_shape = read_rows<Index3>(item<InArray<int32_t>>(g, "grid_shape"), {3}, "grid_shape");
    geo.grid_origin = vectors("grid_origin");
    geo.grid_spacing = read_rows<double>(item<InArray<double>>(g, "grid_spacing"), {}, "grid_spacing");
    geo.grid_values = read_rows<double>(item<InArray<double>>(g, "grid_values"), {}, "grid_values");
    geo.mesh_triangle_start = ints("mesh_triangle_start");
    geo.mesh_triangles = read_rows<Index3>(item<InArray<int32_t>>(g, "mesh_triangles"), {3}, "mesh_triangles");
    geo.mesh_vertices = vectors("mesh_vertices");
    return geo;
}

// Worlds [first, last) checked against the batch.
void check_worlds(const Batch& c, int first, int last, const char* method) {
    if (first < 0 || last > c.num_worlds() || first > last) {
        throw nb::index_error((std::string("Batch.") + method + ": worlds [" +
                               std::to_string(first) + ", " + std::to_string(last) +
                               ") outside [0, " + std::to_string(c.num_worlds()) + ")")
                                  .c_str());
    }
}

using Context = nb::class_<Batch>;

// A read-write numpy view (B, n, ...) of one of the batch's buffers, its name appended to
// `names` (the layout rigid_gym/world.py reads).
template <class S, class T>
void def_view(Context& cls, nb::list& names, const char* name, Array<T> Batch::*field,
              std::initializer_list<size_t> row_shape) {
    names.append(name);
    std::vector<size_t> tail(row_shape);
    cls.def_prop_ro(name, [field, tail](nb::handle self) {
        Batch& c = nb::cast<Batch&>(self);
        Array<T>& a = c.*field;
        const size_t b = c.num_worlds(), n = c.num_bodies();
        if (tail.empty()) {
            return view<S>(self, a.data(), {b, n});
        }
        if (tail.size() == 1) {
            return view<S>(self, a.data(), {b, n, tail[0]});
        }
        return view<S>(self, a.data(), {b, n, tail[0], tail[1]});
    }, nb::rv_policy::reference);
}

void bind_settings(nb::module_& m) {
    nb::class_<Settings>(m, "Settings",
                         "What SolverConfig decides, as the stages take it "
                         "(src/solver/settings.h): its defaults are SolverConfig's.")
        .def(nb::init<>())
        .def_rw("collision_passes", &Settings::collision_passes)
        .def_rw("contact_passes", &Settings::contact_passes)
        .def_rw("shock_sweeps", &Settings::shock_sweeps)
        .def_rw("rotation_order", &Settings::rotation_order)
        .def_rw("sweep", &Settings::sweep)
        .def_rw("sleep", &Settings::sleep)
        .def_rw("sleep_speed", &Settings::sleep_speed)
        .def_rw("detect_every_pass", &Settings::detect_every_pass)
        .def_rw("keep_energy", &Settings::keep_energy)
        .def_rw("overlap_correction", &Settings::overlap_correction)
        .def_rw("overlap_energy", &Settings::overlap_energy)
        .def_rw("joint_passes", &Settings::joint_passes)
        .def_rw("continuous", &Settings::continuous)
        .def_rw("contact_patches", &Settings::contact_patches)
        .def_rw("patch_reactions", &Settings::patch_reactions)
        .def_rw("exact_symmetric", &Settings::exact_symmetric);
    nb::list stages;
    for (const char* name : STAGE_NAMES) {
        stages.append(name);
    }
    m.attr("STAGES") = nb::tuple(stages);  // the step's stages in order (src/solver/stages.h)
    m.def(
        "stage_rules",
        [](const Settings& settings, bool gravity, bool joints) {
            const StageSwitches on = stage_rules(settings, gravity, joints);
            nb::list out;
            for (bool stage_on : on) {
                out.append(stage_on);
            }
            return nb::tuple(out);
        },
        nb::arg("settings"), nb::arg("gravity"), nb::arg("joints"),
        "Which stages (STAGES' order) the steps of a scene with or without gravity and joints "
        "run under these settings (src/solver/stages.h); one switched on still skips a step in which it "
        "has nothing to do.");
}

// A read-write numpy view (B, J) of one of the batch's per-world joint rows.
void def_joint_view(Context& cls, const char* name, Array<double> JointBuffers::*field,
                    const char* doc) {
    cls.def_prop_ro(name, [field](nb::handle self) {
        Batch& c = nb::cast<Batch&>(self);
        const size_t b = c.num_worlds(), j = c.joints.size();
        return view<double>(self, (c.joints.*field).data(), {b, j});
    }, nb::rv_policy::reference, doc);
}

// A copy (B, len(STAGES)) of a per-world stage table (seconds, calls, resolves).
template <typename T>
nb::ndarray<nb::numpy, T> stage_table(const Batch& c, const Array<T>& rows) {
    std::vector<T> values(rows.data(), rows.data() + rows.size());
    return hand_over(std::move(values), {static_cast<size_t>(c.num_worlds()),
                                         static_cast<size_t>(STAGE_COUNT)});
}

// A copy (B, J, 3) of per-world joint vectors.
nb::ndarray<nb::numpy, double> joint_vectors(const Batch& c, const Array<Vec3>& rows) {
    const double* first = reinterpret_cast<const double*>(rows.data());
    std::vector<double> values(first, first + 3 * rows.size());
    return hand_over(std::move(values), {static_cast<size_t>(c.num_worlds()),
                                         static_cast<size_t>(c.joints.size()), 3});
}

// The joints' model read into the batch (Batch::set_joints), checked for shape and bodies
// (the values were validated by rigid_gym.Scene).
void set_joints(Batch& c, InArray<int32_t> kind, InArray<int32_t> body_a,
                InArray<int32_t> body_b, InArray<double> anchor_a, InArray<double> anchor_b,
                InArray<double> axis_a, InArray<double> axis_b, InArray<double> reference) {
    Array<int32_t> kinds = read_rows<int32_t>(kind, {}, "joint kind");
    Array<int32_t> a = read_rows<int32_t>(body_a, {}, "joint body_a");
    Array<int32_t> b = read_rows<int32_t>(body_b, {}, "joint body_b");
    Array<Vec3> pa = read_rows<Vec3>(anchor_a, {3}, "joint anchor_a");
    Array<Vec3> pb = read_rows<Vec3>(anchor_b, {3}, "joint anchor_b");
    Array<Vec3> ua = read_rows<Vec3>(axis_a, {3}, "joint axis_a");
    Array<Vec3> ub = read_rows<Vec3>(axis_b, {3}, "joint axis_b");
    Array<Quat> q = read_rows<Quat>(reference, {4}, "joint reference");
    const int64_t j = kinds.size();
    if (a.size() != j || b.size() != j || pa.size() != j || pb.size() != j || ua.size() != j ||
        ub.size() != j || q.size() != j) {
        throw nb::value_error("Batch.set_joints: the joint rows differ in length");
    }
    for (int64_t k = 0; k < j; ++k) {
        if (kinds[k] < REVOLUTE || kinds[k] > FIXED || a[k] < 0 || a[k] >= c.num_bodies() ||
            c.motion[a[k]] != DYNAMIC || b[k] < WORLD_BODY || b[k] >= c.num_bodies() ||
            b[k] == a[k]) {
            throw nb::value_error(("Batch.set_joints: joint " + std::to_string(k) +
                                   " has a bad kind or bodies").c_str());
        }
    }
    c.set_joints(std::move(kinds), std::move(a), std::move(b), std::move(pa), std::move(pb),
                 std::move(ua), std::move(ub), std::move(q));
}

void bind_joints(Context& cls) {
    cls.def("set_joints", &set_joints, nb::arg("kind"), nb::arg("body_a"), nb::arg("body_b"),
            nb::arg("anchor_a"), nb::arg("anchor_b"), nb::arg("axis_a"), nb::arg("axis_b"),
            nb::arg("reference"),
            "The scene's joints (src/solver/joints.h): kind (J,) int32, body_a, body_b (J,) "
            "int32 (-1: the world), anchors (J, 3) m and unit axes (J, 3) in each body's "
            "frame, reference (J, 4) a's orientation in b's at coordinate 0. Once, before "
            "stepping; every world's limits open and motors off; the joint stages on.");
    def_joint_view(cls, "joint_lower", &JointBuffers::lower,
                   "(B, J) rad or m, each joint's lower limit (-inf: none); writable.");
    def_joint_view(cls, "joint_upper", &JointBuffers::upper,
                   "(B, J) rad or m, each joint's upper limit (inf: none); writable.");
    def_joint_view(cls, "joint_motor_speed", &JointBuffers::motor_speed,
                   "(B, J) rad/s or m/s, each motor's target speed; writable.");
    def_joint_view(cls, "joint_max_motor", &JointBuffers::max_motor,
                   "(B, J) N m or N, each motor's largest torque or force (0: none); writable.");
    cls.def_prop_ro(
        "joint_impulse", [](Batch& c) { return joint_vectors(c, c.joints.impulse); },
        nb::rv_policy::reference,
        "(B, J, 3) N s, each joint's impulse on its body a over the last step; a copy.");
    cls.def_prop_ro(
        "joint_angular_impulse",
        [](Batch& c) { return joint_vectors(c, c.joints.angular_impulse); },
        nb::rv_policy::reference,
        "(B, J, 3) N m s, each joint's angular impulse on its body a about a's centre of "
        "mass over the last step; a copy.");
    cls.def_prop_ro(
        "joint_motor_impulse",
        [](Batch& c) {
            const int64_t count = c.num_worlds() * c.joints.size();
            std::vector<double> values(count);
            for (int64_t k = 0; k < count; ++k) {
                values[k] = c.joints.accumulated[3 * k];
            }
            return hand_over(std::move(values), {static_cast<size_t>(c.num_worlds()),
                                                 static_cast<size_t>(c.joints.size())});
        },
        nb::rv_policy::reference,
        "(B, J) N m s or N s, each motor's impulse along its joint's axis over the last "
        "step's velocity solve; a copy.");
    cls.def(
        "joint_coordinates",
        [](Batch& c) {
            std::vector<double> values;
            values.reserve(c.num_worlds() * c.joints.size());
            for (int w = 0; w < c.num_worlds(); ++w) {
                const StepContext s = c.world(w);
                for (int64_t j = 0; j < c.joints.size(); ++j) {
                    values.push_back(joint_coordinate(s, j));
                }
            }
            return hand_over(std::move(values), {static_cast<size_t>(c.num_worlds()),
                                                 static_cast<size_t>(c.joints.size())});
        },
        "(B, J) each joint's coordinate at the current poses: rad (revolute, in (-pi, pi]), "
        "m (prismatic), 0 (fixed); a copy.");
}

}  // namespace

void bind_world(nb::module_& m) {
    bind_settings(m);
    Context cls(m, "Batch",
                "Every buffer the step reads and writes for a batch of worlds of one scene "
                "(src/solver/world.h). rigid_gym.World owns one; its state arrays are views of it.");
    cls.def(
        "__init__",
        [](Batch* self, int num_worlds, nb::dict geometry, InArray<int32_t> motion,
           std::array<double, 3> gravity, const Settings& settings, int64_t pair_contacts) {
            if (num_worlds < 1) {
                throw nb::value_error("Batch: num_worlds must be >= 1");
            }
            Geometry geo = read_geometry(geometry);
            const Array<int32_t> kinds = read_rows<int32_t>(motion, {}, "motion");
            if (kinds.size() != geo.num_bodies() || kinds.size() + 1 != geo.body_geom_start.size()) {
                throw nb::value_error("Batch: motion and geometry disagree on the bodies");
            }
            std::vector<int32_t> classes(kinds.data(), kinds.data() + kinds.size());
            new (self) Batch(num_worlds, std::move(geo), std::move(classes),
                             {gravity[0], gravity[1], gravity[2]}, settings, pair_contacts);
        },
        nb::arg("num_worlds"), nb::arg("geometry"), nb::arg("motion"), nb::arg("gravity"),
        nb::arg("settings"), nb::arg("pair_contacts"));
    // the state (rigid_gym.world.State), the per-world model and the attachments, in order
    nb::list state, model, attached;
    def_view<double>(cls, state, "position", &Batch::position, {3});
    def_view<double>(cls, state, "orientation", &Batch::orientation, {4});
    def_view<double>(cls, state, "velocity", &Batch::velocity, {3});
    def_view<double>(cls, state, "angular_momentum", &Batch::angular_momentum, {3});
    def_view<double>(cls, state, "angular_velocity", &Batch::angular_velocity, {3});
    def_view<double>(cls, state, "rotation", &Batch::rotation, {3, 3});
    def_view<double>(cls, state, "force", &Batch::force, {3});
    def_view<double>(cls, state, "torque", &Batch::torque, {3});
    def_view<double>(cls, model, "inverse_mass", &Batch::inverse_mass, {});
    def_view<double>(cls, model, "inverse_moments", &Batch::inverse_moments, {3});
    def_view<double>(cls, model, "friction", &Batch::friction, {});
    def_view<double>(cls, model, "restitution", &Batch::restitution, {});
    def_view<int32_t>(cls, attached, "attach_parent", &Batch::attach_parent, {});
    def_view<double>(cls, attached, "attach_offset_position", &Batch::attach_offset_position, {3});
    def_view<double>(cls, attached, "attach_offset_orientation", &Batch::attach_offset_orientation,
                     {4});
    m.attr("STATE") = nb::tuple(state);
    m.attr("MODEL") = nb::tuple(model);
    m.attr("ATTACHMENTS") = nb::tuple(attached);
    bind_joints(cls);
    cls.def(
        "step",
        [](Batch& c, int64_t steps, double dt) {
            if (steps < 0 || !(dt > 0.0)) {
                throw nb::value_error("Batch.step: steps >= 0, dt > 0");
            }
            nb::gil_scoped_release unlocked;
            advance(c, steps, dt);
        },
        nb::arg("steps"), nb::arg("dt"),
        "Advance every world by `steps` steps of dt (s), counting (and, when timed, timing) "
        "each stage (src/solver/timers.h); the GIL is released meanwhile.");
    cls.def(
        "refresh",
        [](Batch& c, int first, int last) {
            check_worlds(c, first, last, "refresh");
            for (int w = first; w < last; ++w) {
                const StepContext s = c.world(w);
                refresh_rotation_and_angular_velocity(s.bodies, s.model);
            }
        },
        "R(q) and omega = I^-1 L of worlds [first, last), after q or L were set.");
    cls.def(
        "place_attached",
        [](Batch& c, int first, int last) {
            check_worlds(c, first, last, "place_attached");
            for (int w = first; w < last; ++w) {
                const StepContext s = c.world(w);
                place_attached(s.bodies, s.attached);
            }
        },
        "Put every attached body of worlds [first, last) at its offset from its parent.");
    cls.def(
        "forget",
        [](Batch& c, int first, int last) {
            check_worlds(c, first, last, "forget");
            c.forget(first, last);
        },
        "No body of worlds [first, last) sleeps in their next step.");
    cls.def(
        "pairs",
        [](Batch& c, int w) {
            check_worlds(c, w, w + 1, "pairs");
            const int64_t count = std::min(c.pair_count[w], c.pair_capacity());
            const int64_t base = static_cast<int64_t>(w) * c.pair_capacity();
            std::vector<int32_t> a(count), b(count);
            std::vector<double> impulse(3 * count);
            for (int64_t k = 0; k < count; ++k) {
                a[k] = c.lists.pair_a[base + k];
                b[k] = c.lists.pair_b[base + k];
                const Vec3 j = c.pair_impulse[base + k];
                impulse[3 * k] = j.x;
                impulse[3 * k + 1] = j.y;
                impulse[3 * k + 2] = j.z;
            }
            const size_t rows = count;
            return std::make_tuple(hand_over(std::move(a), {rows}), hand_over(std::move(b), {rows}),
                                   hand_over(std::move(impulse), {rows, 3}));
        },
        "World w's pairs listed by the last step (body_a (k,), body_b (k,)) and the impulse "
        "each transmitted to its body a in it ((k, 3), N s); copies.");
    cls.def_prop_ro(
        "pair_counts",
        [](Batch& c) {
            std::vector<int64_t> counts(c.pair_count.data(), c.pair_count.data() + c.num_worlds());
            return hand_over(std::move(counts), {static_cast<size_t>(c.num_worlds())});
        },
        nb::rv_policy::reference,
        "(B,) pairs the last step listed in each world; a copy.");
    cls.def_prop_ro(
        "shared",
        [](Batch& c) -> std::optional<bool> {
            if (c.sharing.last() == 0) {
                return std::nullopt;
            }
            return c.sharing.last() == 2;
        },
        "Whether the last step was shared out over the thread pool (True) or ran on the "
        "calling thread (False), as the batch's measured costs chose (src/solver/sharing.h); None "
        "before a batch of several worlds has stepped with more than one thread.");
    cls.def(
        "force_sharing",
        [](Batch& c, std::optional<bool> shared) {
            c.sharing.force(shared.has_value() ? static_cast<int>(*shared) : -1);
        },
        nb::arg("shared").none(),
        "Step every call from now on shared out over the pool (True) or on the calling thread "
        "(False), or as the batch's timings choose (None, the default; the choice starts "
        "afresh, shared then alone): src/solver/sharing.h. One world or a pool of one thread always "
        "steps on the calling thread.");
    cls.def_prop_ro(
        "stages",
        [](Batch& c) {
            nb::list out;
            for (bool stage_on : c.stages()) {
                out.append(stage_on);
            }
            return nb::tuple(out);
        },
        "Which stages (STAGES' order) this batch's steps run: stage_rules of its settings and "
        "its scene's gravity.");
    cls.def_rw("timed", &Batch::timed,
               "Read the clock in every stage of every step, for stage_seconds (src/solver/timers.h).");
    cls.def_prop_ro(
        "stage_seconds", [](Batch& c) { return stage_table(c, c.stage_seconds); },
        nb::rv_policy::reference,
        "(B, len(STAGES)) s each world spent in each stage of its steps so far, while timed; "
        "a copy.");
    cls.def_prop_ro(
        "stage_calls", [](Batch& c) { return stage_table(c, c.stage_calls); },
        nb::rv_policy::reference,
        "(B, len(STAGES)) how many times each world ran each stage so far; a copy.");
    cls.def_prop_ro(
        "stage_resolves", [](Batch& c) { return stage_table(c, c.stage_resolves); },
        nb::rv_policy::reference,
        "(B, len(STAGES)) how many contact sets (a pair's contacts, or a body's with all its "
        "supports) each world's stages resolved so far; a copy.");
    cls.def_prop_ro(
        "asleep",
        [](Batch& c) {
            std::vector<uint8_t> flags(c.asleep.data(), c.asleep.data() + c.asleep.size());
            return hand_over(std::move(flags), {static_cast<size_t>(c.num_worlds()),
                                                static_cast<size_t>(c.num_bodies())});
        },
        nb::rv_policy::reference,
        "(B, n) which bodies slept through the last step (1) or not (0); a copy.");
    cls.def(
        "candidate_pairs",
        [](Batch& c, double margin, int w) {
            check_worlds(c, w, w + 1, "candidate_pairs");
            std::vector<int32_t> pairs = candidate_pairs(c, margin, w);
            const size_t k = pairs.size() / 2;
            return hand_over(std::move(pairs), {k, 2});
        },
        "World w's broad-phase pairs at its current poses, boxes grown by margin (m): (k, 2) "
        "body indices (src/solver/queries.h).");
    cls.def(
        "contacts",
        [](Batch& c, double margin, int first, int last) {
            check_worlds(c, first, last, "contacts");
            ContactRows rows;
            {
                nb::gil_scoped_release unlocked;
                rows = detect_contacts(c, margin, first, last);
            }
            const size_t k = rows.depth.size();
            return std::make_tuple(hand_over(std::move(rows.world), {k}),
                                   hand_over(std::move(rows.body_a), {k}),
                                   hand_over(std::move(rows.body_b), {k}),
                                   hand_over(std::move(rows.point), {k, 3}),
                                   hand_over(std::move(rows.normal), {k, 3}),
                                   hand_over(std::move(rows.depth), {k}));
        },
        "Contacts at the current poses of worlds [first, last) (src/solver/queries.h): world, body_a, "
        "body_b (k,), point, normal (k, 3), depth (k,).");
    // Snapshots (World.save_state, copy.deepcopy): every buffer, the step's carried-over
    // bookkeeping (sleeping, the contact pools' limits, the broad phase's order) included, so
    // a copy steps on bit for bit as the original does.
    cls.def("copy", [](const Batch& c) { return Batch(c); },
            "A new batch holding a copy of every buffer of this one.");
    cls.def(
        "assign",
        [](Batch& c, const Batch& from) {
            if (from.num_worlds() != c.num_worlds() || from.num_bodies() != c.num_bodies()) {
                throw nb::value_error("Batch.assign: another batch or scene");
            }
            // Python holds numpy views of the state, the model and the attachments: copying
            // equal-sized vectors reuses their storage, checked here
            const void* before[] = {c.position.data(), c.orientation.data(), c.rotation.data(),
                                    c.inverse_mass.data(), c.attach_parent.data()};
            c = from;
            const void* after[] = {c.position.data(), c.orientation.data(), c.rotation.data(),
                                   c.inverse_mass.data(), c.attach_parent.data()};
            if (!std::equal(std::begin(before), std::end(before), std::begin(after))) {
                throw std::runtime_error("Batch.assign: the state moved in memory");
            }
        },
        nb::arg("source"),
        "Make every buffer of this batch a copy of `source`'s (a batch of the same scene "
        "and batch, e.g. from copy()), in place: numpy views of this one stay valid.");
    nb::class_<BatchSharing>(m, "BatchSharing",
                             "The choice between stepping a batch on the calling thread and "
                             "sharing it out over the pool, as each Batch makes it from "
                             "its own timings (src/solver/sharing.h); here to be fed timings by hand.")
        .def(nb::init<>())
        .def("share", &BatchSharing::share, "Share the next call out over the pool?")
        .def("record", &BatchSharing::record, nb::arg("shared"), nb::arg("seconds"),
             nb::arg("world_steps"),
             "The call ran shared or not and took `seconds` for `world_steps` world-steps.");
    m.def("num_threads", [] { return ThreadPool::instance().size(); },
          "Threads a batch of worlds is shared out over, the calling thread included.");
    m.def("set_num_threads", [](int threads) { ThreadPool::set_size(threads); },
          "Share batches out over this many threads (0: the cores this process may use, at "
          "most RIGID_GYM_NUM_THREADS). Not while a batch steps.");
}

}  // namespace rg
