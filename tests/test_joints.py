"""Joints (src/solver/joints.h, rigid_gym/joints.py): input checks, closed forms, limits,
motors, collisions and sleeping of joined bodies, determinism."""

import copy
import pickle
import subprocess
import sys

import numpy as np
import pytest

import rigid_gym as rg
from rigid_gym import analytic
from rigid_gym.report import cases, scenes
from rigid_gym.report.scenes import G
from rigid_gym.report.stability import joint_separation

DT = 1 / 240


def box_scene(**body):
    scene = rg.Scene()
    scene.add_ground()
    cube = scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0, 0, 0.5), **body)
    return scene, cube


# -- input ------------------------------------------------------------------------------------

@pytest.mark.parametrize("call, message", [
    (lambda s, c: s.add_revolute_joint(7, None, (0, 0, 0), (0, 1, 0)), r"body_a: must be .* \[0, 1\]"),
    (lambda s, c: s.add_revolute_joint("nothing", None, (0, 0, 0), (0, 1, 0)), "no body named"),
    (lambda s, c: s.add_revolute_joint(c, 9, (0, 0, 0), (0, 1, 0)), r"body_b: must be .* or None"),
    (lambda s, c: s.add_revolute_joint(c, c, (0, 0, 0), (0, 1, 0)), "the same body"),
    (lambda s, c: s.add_revolute_joint(0, None, (0, 0, 0), (0, 1, 0)), "neither body is dynamic"),
    (lambda s, c: s.add_revolute_joint(0, c, (0, 0, 0), (0, 1, 0)), "give the dynamic body as body_a"),
    (lambda s, c: s.add_revolute_joint(c, None, (0, np.nan, 0), (0, 1, 0)), "anchor: must be finite"),
    (lambda s, c: s.add_revolute_joint(c, None, (0, 0, 0), (0, 0, 0)), "axis must be a nonzero"),
    (lambda s, c: s.add_revolute_joint(c, None, (0, 0, 0), (0, 1, 0), limits=(0.5, 0.1)),
     "lower <= upper"),
    (lambda s, c: s.add_revolute_joint(c, None, (0, 0, 0), (0, 1, 0), limits=(np.nan, 0.1)),
     "not NaN"),
    (lambda s, c: s.add_revolute_joint(c, None, (0, 0, 0), (0, 1, 0), limits=(-4, 0)),
     r"\[-pi, pi\]"),
    (lambda s, c: s.add_prismatic_joint(c, None, (0, 0, 0), (1, 0, 0), max_motor_force=-1),
     r"maximum motor force: must be finite and >= 0"),
    (lambda s, c: s.add_revolute_joint(c, None, (0, 0, 0), (0, 1, 0), motor_speed=np.inf),
     "motor_speed: must be finite"),
])
def test_bad_joints_are_refused_with_what_and_where(call, message):
    scene, cube = box_scene()
    with pytest.raises(ValueError, match=message):
        call(scene, cube)
    assert scene.joints == []


def test_joints_need_their_stages_and_the_world_checks_its_setters():
    scene, cube = box_scene()
    scene.add_prismatic_joint(cube, None, (0, 0, 0.5), (0, 0, 1), limits=(-0.1, 0.1))
    with pytest.raises(ValueError, match="joint_passes is 0"):
        rg.World(scene, config=rg.SolverConfig.for_scene(scene, joint_passes=0))
    world = rg.World(scene)
    with pytest.raises(ValueError, match=r"joint: must be a name or an int in \[0, 0\]"):
        world.set_joint_motor(1, speed=1.0)
    with pytest.raises(ValueError, match="lower <= upper"):
        world.set_joint_limits(0, (1.0, -1.0))
    with pytest.raises(ValueError, match="max_motor: must be finite and >= 0 N"):
        world.set_joint_motor("joint0", max_motor=-2.0)


def test_for_scene_leaves_the_joint_stages_out_without_joints():
    """A scene without joints gets joint_passes 0 and runs no joint stage; a config with
    joint passes on such a scene steps it to the same bits (nothing to solve)."""
    scene, _ = box_scene()
    assert rg.SolverConfig.for_scene(scene).joint_passes == 0
    plain = rg.World(scene)
    passes = rg.World(scene, config=rg.SolverConfig.for_scene(scene, joint_passes=20))
    plain.step(120)
    passes.step(120)
    for mine, theirs in zip(plain.state, passes.state):
        np.testing.assert_array_equal(mine, theirs)
    calls = plain.profile()
    assert calls["joint_velocity"]["calls"] == calls["joint_position"]["calls"] == 0
    assert not calls["joint_velocity"]["on"]
    jointed = scenes.pendulum(0.1)
    assert rg.SolverConfig.for_scene(jointed).joint_passes == 20
    world = rg.World(jointed)
    world.step(3)
    assert world.profile()["joint_position"]["calls"] == 3


# -- closed forms -----------------------------------------------------------------------------

@pytest.mark.parametrize("amplitude, bound", [(cases.PENDULUM_SMALL, 2e-5), (cases.PENDULUM_WIDE, 5e-5)])
def test_pendulum_period_matches_the_elliptic_integral(amplitude, bound):
    """RATTLE is second order: 7.1e-6 at 3 deg and 1.9e-5 at 90 deg at dt = 1/240, a quarter
    of that at 1/480. A first-order joint scheme (plain Newton on the predicted poses) was
    3% short at 90 deg."""
    case = cases.pendulum_case(amplitude)
    errors = [case.measure(rg.World(case.build(), dt=dt))[0] for dt in (DT, DT / 2)]
    assert errors[0] < bound
    assert 3.5 < errors[0] / errors[1] < 4.5


def test_physical_pendulum_period():
    error = cases.physical_pendulum_error(rg.World(scenes.physical_pendulum(cases.ROD_AMPLITUDE),
                                                   dt=DT))[0]
    assert error < 5e-5


def test_motor_holds_below_its_torque_and_gives_way_above_it():
    held = rg.World(scenes.motor_arm(cases.ARM_HOLD * cases.arm_torque()), dt=DT)
    assert cases.motor_hold_error(held)[0] < 1e-12
    # the reaction: the motor's impulse is the weight's torque over the step, within its bound
    motor = held.joint_impulses().motor[0]
    assert motor == pytest.approx(-cases.arm_torque() * DT, rel=1e-9)
    # just enough, and just short of enough
    enough = rg.World(scenes.motor_arm(1.0001 * cases.arm_torque()), dt=DT)
    enough.step(240)
    assert abs(enough.joint_coordinates()[0]) < 1e-12
    short = rg.World(scenes.motor_arm(0.999 * cases.arm_torque()), dt=DT)
    short.step(240)
    assert short.joint_coordinates()[0] > 1e-4
    gives = rg.World(scenes.motor_arm(cases.ARM_GIVE * cases.arm_torque()), dt=DT)
    assert cases.motor_give_error(gives)[0] < 0.01  # first order: alpha dt / (2 w) = 0.0067


def test_motor_reaches_its_speed_within_one_step_with_torque_to_spare():
    scene = rg.Scene(gravity=(0, 0, 0))
    wheel = scene.add_body(rg.Sphere(0.1), mass=1.0)
    scene.add_revolute_joint(wheel, None, (0, 0, 0), (0, 0, 1), motor_speed=3.0,
                             max_motor_torque=100.0)
    world = rg.World(scene, dt=DT)
    world.step()
    np.testing.assert_allclose(world.angular_velocity[0], (0, 0, 3.0), atol=1e-12)
    world.set_joint_motor(0, speed=-1.0, max_motor=0.004 * 240)  # 0.004 N m s a step
    world.step()
    assert world.angular_velocity[0, 2] == pytest.approx(3.0 - 0.004 / 0.004, abs=1e-9)


def test_slider_accelerates_at_g_sin_theta_and_stays_on_its_line():
    accel, off = cases.slider_errors(rg.World(scenes.slider(cases.SLIDER_DEG), dt=DT))
    assert accel < 1e-12 and off < 1e-12


def test_limits_stop_a_revolute_and_a_prismatic_joint():
    scene = scenes.pendulum(0.3)
    scene.joints.clear()
    scene.add_revolute_joint(0, None, (0, 0, 0), (0, 1, 0), limits=(-0.1, 0.2))
    world = rg.World(scene, dt=DT)  # released 0.3 rad out: its angle grows from 0
    highest = 0.0
    for _ in range(480):
        world.step()
        angle = world.joint_coordinates()[0]
        highest = max(highest, angle)
        assert -0.1 - 1e-9 <= angle <= 0.2 + 1e-9
    assert highest == pytest.approx(0.2, abs=1e-9)  # it swings down onto the upper limit

    scene, cube = box_scene()
    scene.add_prismatic_joint(cube, None, (0, 0, 0.5), (0, 0, 1), limits=(-0.2, 0.0))
    world = rg.World(scene, dt=DT)
    world.step(240)  # falls 0.2 m onto the limit and rests there, above the ground
    assert world.joint_coordinates()[0] == pytest.approx(-0.2, abs=1e-9)
    assert world.velocity[cube] == pytest.approx(np.zeros(3), abs=1e-9)


def test_fixed_joint_holds_a_body_to_the_world_and_welds_two_into_one():
    scene, cube = box_scene()
    scene.add_fixed_joint(cube, None)
    world = rg.World(scene, dt=DT)
    start = world.position.copy()
    world.step(240)
    assert np.abs(world.position - start).max() < 1e-12
    impulse = world.joint_impulses().impulse[0]
    np.testing.assert_allclose(impulse, (0, 0, G * DT), rtol=1e-9, atol=1e-15)

    scene = rg.Scene(gravity=(0, 0, 0))
    a = scene.add_body(rg.Box((0.1, 0.02, 0.02)), mass=1.0, angular_velocity=(0, 0, 2.0),
                       velocity=(0, -0.2, 0))
    b = scene.add_body(rg.Sphere(0.05), mass=2.0, position=(0.3, 0, 0), velocity=(0, 0.6, 0))
    scene.add_fixed_joint(b, a, (0.2, 0, 0))
    world = rg.World(scene, dt=DT)
    relative = world.rotation[0].T @ (world.position[b] - world.position[a])
    momentum = world.linear_momentum().copy()
    world.step(480)
    np.testing.assert_allclose(world.rotation[0].T @ (world.position[b] - world.position[a]),
                               relative, atol=1e-12)
    np.testing.assert_allclose(world.linear_momentum(), momentum, atol=1e-12)


def test_a_joint_to_a_moving_kinematic_body_drags_its_body_along():
    scene = rg.Scene()
    hand = scene.add_body(rg.Box((0.05, 0.05, 0.05)), kinematic=True, position=(0, 0, 1),
                          velocity=(0.5, 0, 0))
    bob = scene.add_body(rg.Sphere(0.02), mass=0.5, position=(0, 0, 0.7))
    scene.add_revolute_joint(bob, hand, (0, 0, 1), (0, 1, 0))
    world = rg.World(scene, dt=DT)
    world.step(480)
    assert joint_separation(world) < 1e-9
    assert world.position[bob, 0] > 0.5  # carried 1 m along x in 2 s, swinging behind


def test_joined_bodies_do_not_collide_and_sleep_as_one_island():
    """Two overlapping boxes welded together rest on the ground: their pair is never listed
    (Box2D's default), and they fall asleep in the same step, as one island."""
    scene = rg.Scene()
    scene.add_ground()
    a = scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0, 0, 0.05))
    b = scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0.08, 0, 0.05))
    scene.add_fixed_joint(b, a)
    world = rg.World(scene, dt=DT)
    asleep = []
    for _ in range(240):
        world.step()
        pairs = {tuple(p) for p in world.listed_pairs()[0].tolist()}
        assert (a, b) not in pairs and (b, a) not in pairs
        asleep.append(world.sleeping()[[a, b]].tolist())
    assert all(x == y for x, y in asleep)
    assert asleep[-1] == [True, True]


def test_sleeping_is_exact_with_joints():
    """A chain lying across the ground and a pendulum beside it, stepped with sleeping on and
    off: every state bit for bit the same."""
    def scene():
        s = scenes.hanging_chain(0.3, links=4)
        s.add_ground(height=-0.38)
        return s
    worlds = [rg.World(scene(), dt=DT, config=rg.SolverConfig.for_scene(scene(), sleep=on))
              for on in (True, False)]
    for world in worlds:
        world.step(600)
    for mine, theirs in zip(worlds[0].state, worlds[1].state):
        np.testing.assert_array_equal(mine, theirs)


def test_batched_and_threaded_joint_worlds_are_bit_identical_to_one():
    scene = scenes.hanging_chain(0.5)
    single = rg.World(scene, dt=DT)
    single.step(240)
    for shared in (True, False):
        batch = rg.World(scene, dt=DT, num_worlds=6)
        batch.core.force_sharing(shared)
        batch.step(240)
        for mine, theirs in zip(batch.state, single.state):
            for w in range(6):
                np.testing.assert_array_equal(mine[w], theirs[0])


CHILD = """
import hashlib, numpy as np, rigid_gym as rg
from rigid_gym.report import scenes
w = rg.World(scenes.hanging_chain(0.5), dt=1 / 240)
w.step(480)
print(hashlib.sha256(b"".join(np.ascontiguousarray(a).tobytes() for a in w.state)).hexdigest())
"""


def test_joint_trajectories_repeat_across_processes():
    runs = {subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True,
                           check=True).stdout for _ in range(2)}
    assert len(runs) == 1


def test_hanging_chain_keeps_its_joints_and_its_energy():
    """The report's chain for 10 s: joints within 1e-9 m, energy oscillating below 2% of the
    swing energy (0.8% at dt = 1/240: symplectic Euler's O(dt) oscillation)."""
    world = rg.World(scenes.hanging_chain(0.5), dt=DT)
    e0 = world.kinetic_energy() + world.potential_energy()
    bottom = -G * 0.1 * scenes.CHAIN_LINK * sum(k + 0.5 for k in range(scenes.CHAIN_LINKS))
    gain, apart = 0.0, 0.0
    for _ in range(2400):
        world.step()
        gain = max(gain, world.kinetic_energy() + world.potential_energy() - e0)
        apart = max(apart, joint_separation(world))
    assert apart < 1e-9
    assert gain / (e0 - bottom) < 0.02


def test_joint_coordinates_follow_the_bodies():
    assert analytic.pendulum_period(1.0, 1.0, 1.0, G, 1e-9) == pytest.approx(
        2 * np.pi / np.sqrt(G), rel=1e-12)
    scene = rg.Scene(gravity=(0, 0, 0))
    wheel = scene.add_body(rg.Sphere(0.1), mass=1.0, angular_velocity=(0, 0, 1.0))
    slide = scene.add_body(rg.Sphere(0.1), mass=1.0, position=(1, 0, 0), velocity=(0, 0.5, 0))
    scene.add_revolute_joint(wheel, None, (0, 0, 0), (0, 0, 1))
    scene.add_prismatic_joint(slide, None, (1, 0, 0), (0, 2, 0))
    world = rg.World(scene, dt=DT)
    world.step(240)
    np.testing.assert_allclose(world.joint_coordinates(), (1.0, 0.5), atol=1e-12)


def test_load_takes_a_scene_of_the_same_joints_with_other_motors():
    world = rg.World(scenes.motor_arm(cases.ARM_HOLD * cases.arm_torque()), num_worlds=2)
    world.load(scenes.motor_arm(cases.ARM_GIVE * cases.arm_torque()), world=1)
    world.step(120)
    turned = world.joint_coordinates()
    assert abs(turned[0, 0]) < 1e-12 and turned[1, 0] > 0.1
    other = scenes.motor_arm(1.0)
    other.joints.clear()
    other.add_revolute_joint(0, None, (0, 0, 0), (0, 0, 1))
    with pytest.raises(ValueError, match="joints differ"):
        world.load(other)


def test_snapshots_keep_the_joints_motors_and_limits():
    """save_state, copy.deepcopy and pickle of a jointed World step on bit for bit, with the
    motor and limits set after it was made (which its scene does not hold)."""
    world = rg.World(scenes.hanging_chain(0.5), dt=DT)
    world.set_joint_motor(0, speed=0.5, max_motor=0.02)
    world.set_joint_limits(3, (-0.2, 0.2))
    world.step(30)
    state_id = world.save_state()

    def trace(w: rg.World) -> bytes:
        out = []
        for _ in range(60):
            w.step()
            out.extend(a.tobytes() for a in w.state)
        return b"".join(out)

    twin, loaded = copy.deepcopy(world), pickle.loads(pickle.dumps(world))
    first = trace(world)
    world.set_joint_motor(0, max_motor=0.0)
    world.restore_state(state_id)
    assert trace(world) == first
    assert trace(twin) == first
    assert trace(loaded) == first


def two_components(with_pair: bool) -> rg.Scene:
    """A pendulum (body 0, joint 0) and, with_pair, two boxes welded together falling onto
    the ground beside it (they come to rest and sleep while the pendulum swings)."""
    scene = scenes.pendulum(1.0)
    if with_pair:
        scene.add_ground(height=-1.5)
        a = scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(3, 0, -1.4))
        b = scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(3.1, 0, -1.4))
        scene.add_fixed_joint(b, a)
    return scene


def test_each_component_of_joints_is_solved_on_its_own():
    """Joints joined through no body are separate systems: the pendulum swings to the same
    bits beside a welded pair that lands and sleeps, and stepping with sleeping on and off
    gives the same bits (an asleep component changes nothing of an awake one's solve)."""
    alone = rg.World(two_components(False), dt=DT)
    alone.step(720)
    worlds = [rg.World(two_components(True), dt=DT,
                       config=rg.SolverConfig.for_scene(two_components(True), sleep=on))
              for on in (True, False)]
    for world in worlds:
        world.step(720)
    assert worlds[0].sleeping()[[2, 3]].all() and not worlds[0].sleeping()[0]
    for mine, theirs in zip(worlds[0].state, worlds[1].state):
        np.testing.assert_array_equal(mine, theirs)
    for mine, theirs in zip(worlds[0].state, alone.state):
        np.testing.assert_array_equal(mine[:, 0], theirs[:, 0])
