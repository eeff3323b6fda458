"""World: batching, determinism, kinematic and static bodies, setters and queries."""

import time

import numpy as np
import pytest

import rigid_gym as rg
from rigid_gym import _core
from rigid_gym.meshes import l_shape_mesh
from rigid_gym.report.scenes import cube_stack, pile


def mixed_scene():
    """A few tumbling bodies of every solid shape, no contacts yet."""
    scene = rg.Scene(gravity=(0.0, 0.0, -9.81))
    scene.add_ground()
    scene.add_body(rg.Box((0.1, 0.2, 0.3)), mass=2.0, position=(0, 0, 1), angular_velocity=(1, 2, 3))
    scene.add_body(rg.Sphere(0.1), density=500.0, position=(1, 0, 1), velocity=(0, 1, 0))
    scene.add_body(rg.Capsule(0.05, 0.2), mass=0.5, position=(0, 1, 1), angular_velocity=(4, 0, 1))
    scene.add_body(l_shape_mesh(), density=300.0, position=(2, 2, 1), angular_velocity=(0.3, -2, 1))
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), position=(0, 0, 0.5), kinematic=True,
                   velocity=(0.1, 0, 0), angular_velocity=(0, 0, 1))
    return scene


def random_initial_velocities(world, rng, worlds):
    for w in worlds:
        for i in (1, 2, 3, 4):
            world.set_velocity(i, rng.normal(size=3), rng.normal(size=3) * 5, world=w)


def test_batched_world_equals_separate_worlds_bit_for_bit(step_both_ways):
    """1000 worlds stepped together give, per world, exactly what 1000 separate single worlds
    give, whether a step runs on the calling thread or the core's threads take ranges of
    worlds (independent work, only reordered). 20 steps of free flight with a kinematic body;
    test_solver checks batching with contacts."""
    num_worlds, steps = 1000, 20
    scene = mixed_scene()  # one scene: its mesh's distance grid is computed once
    batched = rg.World(scene, dt=1 / 240, num_worlds=num_worlds,
                       config=rg.SolverConfig(rotation_order=3))
    random_initial_velocities(batched, np.random.default_rng(1), range(num_worlds))
    step_both_ways(batched, steps)
    rng = np.random.default_rng(1)
    for w in range(num_worlds):
        single = rg.World(scene, dt=1 / 240, config=rg.SolverConfig(rotation_order=3))
        random_initial_velocities(single, rng, [None])
        single.step(steps)
        for name in ("position", "orientation", "velocity", "angular_velocity"):
            np.testing.assert_array_equal(getattr(batched, name)[w], getattr(single, name))


def test_same_input_gives_bit_identical_trajectories():
    runs = []
    for _ in range(2):
        world = rg.World(mixed_scene(), dt=1 / 240)
        world.apply_force(1, (1.0, 2.0, 3.0), point=(0.0, 0.1, 1.0))
        world.step(200)
        runs.append(np.concatenate([world.position.ravel(), world.orientation.ravel()]))
    np.testing.assert_array_equal(runs[0], runs[1])


def test_reset_restores_the_initial_state():
    world = rg.World(mixed_scene(), dt=1 / 240)
    first = world.position.copy(), world.orientation.copy()
    world.step(100)
    world.reset()
    assert world.time == 0.0
    np.testing.assert_array_equal(world.position, first[0])
    np.testing.assert_array_equal(world.orientation, first[1])


def test_kinematic_body_moves_by_its_velocity_and_ignores_gravity():
    world = rg.World(mixed_scene(), dt=1 / 100)
    x0 = world.position[5].copy()
    world.step(100)
    np.testing.assert_allclose(world.position[5], x0 + (0.1, 0, 0), atol=1e-14)
    q = world.orientation[5]
    np.testing.assert_allclose(q, [np.cos(0.5), 0, 0, np.sin(0.5)], atol=1e-14)
    world.set_velocity(5, (0, 0, 1.0))
    world.step(100)
    np.testing.assert_allclose(world.position[5], x0 + (0.1, 0, 1.0), atol=1e-14)


def test_static_ground_never_moves():
    world = rg.World(mixed_scene(), dt=1 / 100)
    world.step(10)
    np.testing.assert_array_equal(world.position[0], 0.0)
    with pytest.raises(ValueError, match="static"):
        world.set_velocity(0, (1, 0, 0))


def test_impulse_off_centre_changes_momentum_and_spin():
    """j at r from the centre: delta V = j / M, delta L = r x j."""
    scene = rg.Scene(gravity=(0, 0, 0))
    scene.add_body(rg.Box((0.5, 0.5, 0.5)), mass=2.0)
    world = rg.World(scene)
    world.apply_impulse(0, (0.0, 4.0, 0.0), point=(0.5, 0.0, 0.0))
    np.testing.assert_allclose(world.velocity[0], [0, 2.0, 0])
    np.testing.assert_allclose(world.body_angular_momentum[0], [0, 0, 2.0])
    inertia = 2.0 * (1.0 + 1.0) / 12  # M (b^2 + c^2) / 12 with full edges 1 m
    np.testing.assert_allclose(world.angular_velocity[0], [0, 0, 2.0 / inertia])


def test_force_and_torque_act_for_one_step():
    scene = rg.Scene(gravity=(0, 0, 0))
    scene.add_body(rg.Sphere(0.5), mass=2.0)
    world = rg.World(scene, dt=0.1)
    world.apply_force(0, (4.0, 0, 0))
    world.apply_torque(0, (0, 0, 1.0))
    world.step(3)
    np.testing.assert_allclose(world.velocity[0], [0.2, 0, 0])
    np.testing.assert_allclose(world.body_angular_momentum[0], [0, 0, 0.1])
    np.testing.assert_allclose(world.linear_momentum(), [0.4, 0, 0])


def test_energy_and_momentum_queries():
    scene = rg.Scene(gravity=(0, 0, -10.0))
    scene.add_body(rg.Sphere(1.0), mass=3.0, position=(1, 0, 2), velocity=(0, 2, 0),
                   angular_velocity=(0, 0, 5))
    world = rg.World(scene, num_worlds=2)
    moment = 0.4 * 3.0
    np.testing.assert_allclose(world.kinetic_energy(), [0.5 * 3 * 4 + 0.5 * moment * 25] * 2)
    np.testing.assert_allclose(world.potential_energy(), [3 * 10 * 2] * 2)
    # X x M V = (1, 0, 2) x (0, 6, 0) = (-12, 0, 6), plus the spin L = (0, 0, 1.2 * 5)
    np.testing.assert_allclose(world.angular_momentum()[0], [-12.0, 0, 6 + moment * 5])


def test_mesh_body_is_stored_at_its_centre_of_mass_in_its_principal_frame():
    """An L-shaped mesh: world.position is its centre of mass, and body_from_shape maps shape
    points into the principal frame, where the inertia is diagonal."""
    mesh = l_shape_mesh()
    props = rg.mass_properties(mesh, 1.0)
    scene = rg.Scene()
    scene.add_body(mesh, density=1.0, position=(1.0, 2.0, 3.0))
    body = scene.bodies[0]
    world = rg.World(scene)
    np.testing.assert_allclose(world.position[0], np.array([1.0, 2.0, 3.0]) + props.center, atol=1e-14)
    r = body.body_from_shape.rotation()
    principal = r @ props.inertia @ r.T
    np.testing.assert_allclose(principal, np.diag(body.principal_moments), atol=1e-12)
    np.testing.assert_allclose(body.body_from_shape.apply(props.center), 0.0, atol=1e-14)


STAGES = ["sleep_check", "prepare", "broad_phase", "sleep_islands", "collision",
          "update_velocities", "joint_velocity", "contact", "shock_propagation", "joint_position",
          "relist", "overlap_correction", "update_positions", "joint_projection", "sleep_records"]
SLEEP_STAGES = ["sleep_check", "sleep_islands", "sleep_records"]
JOINT_STAGES = ["joint_velocity", "joint_position", "joint_projection"]


def test_profile_reports_every_stage_timed_inside_the_step():
    """A box resting on the ground, kept awake, runs every stage its config switches on once
    per step (for_scene leaves the collision stage out: every restitution is 0; without
    sleeping its stages are off). The step
    counts its stages always and times them while profiling: the times are positive, they
    grow with every step, and together they fit inside the wall time of the step() calls; a
    world stepped without profiling counts the same calls, has no time and the same state to
    the bit."""
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0, 0, 0.05))
    config = rg.SolverConfig.for_scene(scene, sleep=False)
    timed, plain = rg.World(scene, config=config, profile=True), rg.World(scene, config=config)
    assert timed.profiling and not plain.profiling
    start = time.perf_counter()
    timed.step(5)
    elapsed = time.perf_counter() - start
    plain.step(5)
    profile = timed.profile()
    assert list(profile) == STAGES == list(_core.STAGES)
    off = ["collision", *SLEEP_STAGES, *JOINT_STAGES]
    assert not any(profile[name]["on"] for name in off)
    assert all(profile[name]["calls"] == 0 and profile[name]["seconds"] == 0.0 for name in off)
    ran = [name for name in STAGES if name not in off]
    assert all(profile[name]["on"] and profile[name]["calls"] == 5 for name in ran)
    assert all(profile[name]["seconds"] > 0.0 for name in ran)
    assert sum(p["seconds"] for p in profile.values()) <= elapsed
    untimed = plain.profile()
    assert [p["calls"] for p in untimed.values()] == [p["calls"] for p in profile.values()]
    assert all(p["seconds"] == 0.0 for p in untimed.values())
    for mine, theirs in zip(timed.state, plain.state):
        np.testing.assert_array_equal(mine, theirs)

    timed.step(3)
    later = timed.profile()
    assert all(later[name]["calls"] == 8 and later[name]["seconds"] > profile[name]["seconds"]
               for name in ran)
    timed.profiling = False
    timed.step(2)
    last = timed.profile()
    assert all(last[name]["calls"] == 10 and last[name]["seconds"] == later[name]["seconds"]
               for name in ran)
    with pytest.raises(ValueError, match="World.profiling"):
        timed.profiling = 1


def test_settings_cross_to_the_core_as_one_bound_struct():
    """SolverConfig's defaults are the core's (src/solver/settings.h), every field it hands the
    core arrives by name, and the stages it reports on are the core's rules for them: the same
    the World's batch steps by (shock propagation off without gravity, the broad phase off
    without any impulse stage, the sleep stages with sleeping, the joint stages with joints)."""
    defaults, config = _core.Settings(), rg.SolverConfig()
    for name in ("collision_passes", "contact_passes", "shock_sweeps", "rotation_order",
                 "sleep", "sleep_speed", "detect_every_pass", "keep_energy",
                 "overlap_correction", "joint_passes"):
        assert getattr(config, name) == getattr(defaults, name), name
    custom = rg.SolverConfig(collision_passes=3, contact_passes=0, shock_sweeps=0,
                             rotation_order=3, sleep=False, sleep_speed=0.02,
                             detect_every_pass=True, keep_energy=False, overlap_correction=0.5,
                             joint_passes=7)
    settings = custom.settings(sweep=True)
    assert (settings.collision_passes, settings.contact_passes, settings.shock_sweeps,
            settings.rotation_order, settings.sleep, settings.sleep_speed,
            settings.detect_every_pass, settings.keep_energy, settings.overlap_correction,
            settings.joint_passes, settings.sweep) == (3, 0, 0, 3, False, 0.02, True, False,
                                                       0.5, 7, True)
    assert list(config.phases()) == list(_core.STAGES)
    assert config.phases(gravity=False)["shock_propagation"] is False
    assert not any(config.phases(joints=False)[name] for name in JOINT_STAGES)
    assert all(config.phases()[name] for name in JOINT_STAGES)
    off = rg.SolverConfig(collision_passes=0, contact_passes=0, shock_sweeps=0, sleep=False)
    assert [name for name, on in off.phases().items() if not on] == [
        "sleep_check", "broad_phase", "sleep_islands", "collision", "contact",
        "shock_propagation", "relist", "sleep_records"]
    floating = rg.Scene(gravity=(0.0, 0.0, 0.0))
    floating.add_body(rg.Sphere(0.05), mass=1.0)
    floating.add_body(rg.Sphere(0.05), mass=1.0, position=(0.2, 0.0, 0.0))
    world = rg.World(floating, config=config)
    assert tuple(p["on"] for p in world.profile().values()) == world.core.stages
    assert world.core.stages == tuple(config.phases(gravity=False, joints=False).values())


def test_the_state_layout_is_the_cores():
    """World's named arrays are the core's views, named by the core's layout lists."""
    world = rg.World(mixed_scene(), num_worlds=2)
    assert rg.world.State._fields == _core.STATE
    assert rg.world.Model._fields[1:5] == _core.MODEL
    assert len(rg.world.Attachments._fields) == len(_core.ATTACHMENTS)
    for name, array in zip(_core.STATE, world.state):
        assert np.shares_memory(array, getattr(world.core, name)), name
    for name, array in zip(_core.ATTACHMENTS, world.attached):
        assert np.shares_memory(array, getattr(world.core, name)), name


def test_profile_counts_the_contact_sets_each_impulse_stage_resolves():
    """World.profile()'s resolves: the contact sets (a pair's contacts, or a body's with all
    its frozen supports) each stage resolved. A box resting on the ground, kept awake, is a
    pair alone: each step's contact stage resolves it twice (the pass that stops gravity's
    approach, then one that applies nothing and ends the stage) and shock propagation once
    against its frozen support. Two stacked boxes share the lower box, so the contact stage
    runs its restitution ramp, every pass applying: 2 pairs x 10 passes a step. No other
    stage resolves anything."""
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0, 0, 0.05))
    config = rg.SolverConfig.for_scene(scene, sleep=False)
    alone = rg.World(scene, config=config)
    alone.step(3)
    resolves = {name: p["resolves"] for name, p in alone.profile().items()}
    assert resolves == {name: {"contact": 6, "shock_propagation": 3}.get(name, 0)
                        for name in STAGES}
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0, 0, 0.15))
    stacked = rg.World(scene, config=config)
    stacked.step(240)
    before = stacked.profile()
    stacked.step(1)
    after = stacked.profile()
    assert after["contact"]["resolves"] - before["contact"]["resolves"] == 2 * config.contact_passes


def test_profile_counts_skipped_and_repeated_stages():
    """Bodies in free flight, with no pair that could touch, skip the impulse stages, and so
    does a box asleep on the ground (its pair is not awake); once that box has slept through
    a step its world is at rest and runs no stage at all; in a falling pile the impulses of
    some steps speed a body past its box, and those steps run the impulse stages again with
    the pairs that adds (the relisting check and the position update run once per step, the
    broad phase again in a step run again for room). A batch counts every world's stages."""
    flying = rg.World(mixed_scene())
    flying.step(5)
    calls = {name: p["calls"] for name, p in flying.profile().items()}
    assert calls == {"sleep_check": 5, "prepare": 5, "broad_phase": 5, "sleep_islands": 5,
                     "collision": 0, "update_velocities": 5, "joint_velocity": 0, "contact": 0,
                     "shock_propagation": 0, "joint_position": 0, "relist": 5,
                     "overlap_correction": 0, "update_positions": 5, "joint_projection": 0,
                     "sleep_records": 5}

    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0, 0, 0.05))
    resting = rg.World(scene)
    resting.step(5)
    calls = {name: p["calls"] for name, p in resting.profile().items()}
    assert resting.sleeping()[1] and calls["broad_phase"] == calls["update_positions"] == 2
    assert calls["contact"] == calls["shock_propagation"] == 1  # asleep from the second step
    assert calls["sleep_check"] == 5 and calls["sleep_records"] == 2  # at rest from the third

    single, batch = rg.World(pile(30)), rg.World(pile(30), num_worlds=3)
    single.step(150)
    batch.step(150)
    calls = {name: p["calls"] for name, p in single.profile().items()}
    assert calls["relist"] == calls["update_positions"] == 150
    # a step given up for room (its pairs or contacts overflowed) runs again whole
    assert calls["prepare"] >= calls["broad_phase"] >= 150
    assert calls["update_velocities"] > 150 and calls["contact"] > 150
    assert calls["contact"] == calls["shock_propagation"] <= calls["update_velocities"]
    assert {name: p["calls"] for name, p in batch.profile().items()} == {
        name: 3 * count for name, count in calls.items()}


STATE_VIEWS = ("position", "orientation", "velocity", "angular_velocity",
               "body_angular_momentum", "rotation")


@pytest.mark.parametrize("num_worlds", [None, 2])
def test_state_views_are_read_only(num_worlds):
    """Every state view of a World, of a batch and of one world of a batch refuses a write
    (state changes go through the setters, which wake what they touch), and the refused
    write leaves the core's state as it was."""
    world = rg.World(mixed_scene(), num_worlds=num_worlds)
    before = tuple(array.copy() for array in world.state)
    seen = [(world, STATE_VIEWS)]
    if num_worlds is not None:  # a WorldView has no body_angular_momentum
        seen.append((world.view(1), STATE_VIEWS[:4] + STATE_VIEWS[5:]))
    for holder, names in seen:
        for name in names:
            view = getattr(holder, name)
            assert not view.flags.writeable, name
            with pytest.raises(ValueError, match="read-only"):
                view[...] = 3.0
    for array, old in zip(world.state, before):
        assert array.tobytes() == old.tobytes()


def test_an_attached_body_rides_with_its_parent_and_leaves_with_its_velocity():
    """World.attach keeps a body at its offset from a kinematic parent (pose to round-off,
    the parent's velocity, no spin) through steps, gravity and contacts; detach lets it go
    with the parent's velocity at that instant, after which it falls freely."""
    scene = rg.Scene()
    scene.add_ground()
    pad = scene.add_body(rg.Box((0.02, 0.02, 0.01)), kinematic=True, position=(0, 0, 0.5),
                         angular_velocity=(0, 0, 1.0))
    cube = scene.add_body(rg.Box((0.02, 0.02, 0.02)), mass=0.1, position=(0.01, 0, 0.47))
    for num_worlds in (None, 2):
        world = rg.World(scene, dt=1 / 240, num_worlds=num_worlds)
        view = world if num_worlds is None else world.view(1)
        offset = view.position[cube] - view.position[pad]
        view.set_velocity(pad, velocity=(0.3, 0.0, 0.1))
        view.attach(cube, pad)
        world.step(48)
        r = view.rotation[pad]
        np.testing.assert_allclose(view.position[cube], view.position[pad] + r @ offset,
                                   atol=1e-12)
        np.testing.assert_array_equal(view.velocity[cube], view.velocity[pad])
        np.testing.assert_array_equal(view.angular_velocity[cube], 0.0)
        view.set_velocity(pad, velocity=(0.0, 0.5, 0.0))
        view.detach(cube)
        np.testing.assert_array_equal(view.velocity[cube], [0.0, 0.5, 0.0])
        world.step(24)  # 0.1 s of free fall
        np.testing.assert_allclose(view.velocity[cube], [0.0, 0.5, -9.81 * 0.1], atol=1e-12)
        if num_worlds is not None:  # the other world never had an attachment
            assert world.position[0, cube, 2] < 0.47
    with pytest.raises(ValueError, match="must be dynamic and parent"):
        rg.World(scene).attach(pad, cube)


def test_a_reloaded_world_steps_exactly_as_a_new_one():
    """World.load (what an env's reset does) leaves nothing of the last episode behind: after
    a different stack has been stepped, loading another and stepping it gives the bits a new
    World of that scene gives."""
    from rigid_gym.report.scenes import cube_stack

    first, second = cube_stack(4, masses=[1.0, 2.0, 0.5, 1.0]), cube_stack(4)
    reloaded = rg.World(first, dt=1 / 240)
    reloaded.step(100)
    reloaded.load(second, 0)
    assert reloaded.time == 0.0
    new = rg.World(second, dt=1 / 240)
    reloaded.step(120)
    new.step(120)
    for name in ("position", "orientation", "velocity", "angular_velocity"):
        np.testing.assert_array_equal(getattr(reloaded, name), getattr(new, name))
    bouncy = rg.Scene()
    bouncy.add_ground(restitution=0.5)
    for k in range(4):
        bouncy.add_body(rg.Box((0.05,) * 3), mass=1.0, position=(0, 0, 0.05 + 0.1 * k))
    with pytest.raises(ValueError, match="another SolverConfig"):
        reloaded.load(bouncy, 0)


def test_set_material_changes_mass_inertia_friction_and_restitution():
    """A new mass: an impulse j then gives V = j / m and the inertia scales with the mass,
    so a spinning box keeps omega and its L scales (closed forms for a box of half
    extents a, b, c: I_x = m (b^2 + c^2) / 3). Per-world values go to their worlds only."""
    scene = rg.Scene(gravity=(0.0, 0.0, 0.0))
    box = scene.add_body(rg.Box((0.1, 0.2, 0.3)), mass=2.0, angular_velocity=(0.0, 0.0, 3.0))
    world = rg.World(scene, num_worlds=2)
    world.set_material(box, mass=np.array([4.0, 0.5]), friction=0.8)
    world.set_material(box, restitution=0.0, world=1)
    np.testing.assert_allclose(world.angular_velocity[:, box], [[0, 0, 3.0]] * 2, rtol=1e-15)
    for w, m in enumerate((4.0, 0.5)):
        inertia_z = m * (0.1**2 + 0.2**2) / 3.0
        np.testing.assert_allclose(world.body_angular_momentum[w, box, 2], 3.0 * inertia_z,
                                   rtol=1e-14)
    world.apply_impulse(box, (1.0, 0.0, 0.0))
    np.testing.assert_allclose(world.velocity[:, box, 0], [1.0 / 4.0, 1.0 / 0.5], rtol=1e-15)
    np.testing.assert_array_equal(world.model.friction[:, box], [0.8, 0.8])



def test_the_model_is_read_only_and_changes_through_set_material():
    """A write into World.model would change a body without waking it (a sleeping body is
    skipped because nothing about it changed), so every array of it is read-only;
    set_material changes it."""
    world = rg.World(cube_stack(1))
    for array in world.model:
        with pytest.raises(ValueError, match="read-only"):
            array[...] = array
    world.set_material(1, mass=2.0, friction=0.25)
    assert world.model.inverse_mass[0, 1] == 0.5 and world.model.friction[0, 1] == 0.25


def test_a_batch_steps_the_way_its_paired_timings_find_cheaper():
    """src/solver/sharing.h, fed timings by hand: the first two calls run one way each; then the
    cheaper way, with a probe of the other now and then; when the costs turn round, the
    choice follows within a few probes."""
    sharing = _core.BatchSharing()

    def run(calls, seconds_alone, seconds_shared):
        ways = []
        for _ in range(calls):
            shared = sharing.share()
            ways.append(shared)
            sharing.record(shared, seconds_shared if shared else seconds_alone, 16)
        return np.array(ways)

    first = run(300, 2e-3, 1e-3)  # shared twice as fast
    assert list(first[:2]) == [True, False]
    assert first[2:].sum() >= 290 and not first[2:].all()  # probes alone continue
    turned = run(600, 1e-3, 3e-3)  # now alone three times as fast
    assert turned[0]  # the choice holds until a probe shows otherwise
    assert turned[-200:].sum() <= 3  # then alone, but for the probes shared


@pytest.mark.usefixtures("two_threads")
def test_a_batch_can_be_made_to_step_one_way():
    batched = rg.World(mixed_scene(), num_worlds=4)
    for forced in (True, False, True, False):
        batched.core.force_sharing(forced)
        for _ in range(3):
            batched.step(1)
            assert batched.core.shared is forced
    batched.core.force_sharing(None)  # the timings choose again, from a new first pair
    ways = []
    for _ in range(2):
        batched.step(1)
        ways.append(batched.core.shared)
    assert ways == [True, False]


def test_one_world_or_one_thread_is_never_shared():
    single = rg.World(mixed_scene())
    single.step(3)
    assert single.core.shared is None
    _core.set_num_threads(1)
    try:
        batched = rg.World(mixed_scene(), num_worlds=4)
        for _ in range(3):
            batched.step(1)
        assert batched.core.shared is None
    finally:
        _core.set_num_threads(0)
