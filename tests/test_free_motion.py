"""Free flight against closed forms: free fall, torque-free rotation, degenerate bodies."""

import numpy as np
import pytest

import rigid_gym as rg
from rigid_gym import _core, analytic
from rigid_gym import quaternion as quat
from rigid_gym.report import scenes

ASYMMETRIC_MOMENTS = (1.0, 2.0, 3.0)  # kg m^2, I1 < I2 < I3
OMEGA0 = (0.3, 0.0, 1.0)  # rad/s, body frame, on the omega_2 = 0 section (analytic.py)


def spinning_body(moments, omega, order, dt, num_worlds=None, keep_energy=True):
    return rg.World(scenes.spinning_body(moments, omega), dt=dt, num_worlds=num_worlds,
                    config=rg.SolverConfig(rotation_order=order, keep_energy=keep_energy))


def test_free_fall_matches_discrete_closed_form():
    """Symplectic Euler is exact for constant acceleration up to its own discretisation, so the
    only difference from the discrete closed form is round-off: 1e-12 (relative to the 100 m
    scale of the motion) leaves room for ~1000 steps of accumulated 1e-16 errors."""
    x0, v0, g, dt, steps = (0.0, 0.0, 10.0), (1.0, -2.0, 3.0), (0.5, 0.0, -9.81), 1 / 240, 1000
    scene = rg.Scene(gravity=g)
    scene.add_body(rg.Sphere(0.1), density=1000.0, position=x0, velocity=v0)
    world = rg.World(scene, dt=dt)
    world.step(steps)
    x, v = analytic.free_fall_discrete(x0, v0, g, dt, steps)
    np.testing.assert_allclose(world.position[0], x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(world.velocity[0], v, rtol=0, atol=1e-12)
    assert world.time == pytest.approx(steps * dt)
    # and the discrete answer is within O(dt) of the continuous one (x_n - x(t) = g t dt / 2)
    xc, _ = analytic.free_fall_continuous(x0, v0, g, steps * dt)
    np.testing.assert_allclose(x - xc, 0.5 * np.array(g) * steps * dt * dt, atol=1e-12)


@pytest.mark.parametrize("order", [1, 2, 3])
def test_torque_free_body_conserves_world_angular_momentum(order):
    """L is the stored state and no torque acts, so it can only change by round-off (it is
    never recomputed): 1e-14 relative."""
    world = spinning_body(ASYMMETRIC_MOMENTS, (3.0, 0.1, 5.0), order, dt=1 / 60)
    l0 = world.angular_momentum().copy()
    world.step(600)
    np.testing.assert_allclose(world.angular_momentum(), l0, rtol=1e-14, atol=0)
    assert np.all(np.isfinite(world.orientation))
    np.testing.assert_allclose(np.linalg.norm(world.orientation, axis=-1), 1.0, atol=1e-15)


def energy_error(order, dt, t_end=10.0, keep_energy=False):
    """Max relative kinetic-energy error over [0, t_end] of the torque-free top."""
    world = spinning_body(ASYMMETRIC_MOMENTS, OMEGA0, order, dt, keep_energy=keep_energy)
    e0 = world.kinetic_energy()
    worst = 0.0
    for _ in range(round(t_end / dt)):
        world.step()
        worst = max(worst, abs(world.kinetic_energy() / e0 - 1.0))
    return worst


@pytest.mark.parametrize("order, min_ratio", [(1, 1.8), (2, 3.5), (3, 7.0)])
def test_energy_error_shrinks_at_the_methods_order(order, min_ratio):
    """Energy 1/2 L.omega is the diagnostic for orientation error (L itself is exact) of the
    rotation update alone (keep_energy off: the projection would hide it). Halving dt must
    cut it by about 2^p: the bar is 2x for the basic update and 4x or more for the higher
    orders; the thresholds leave margin below the ratios measured by
    benchmarks/rotation_order.py between dt = 1/50 and 1/100 (2.24, 3.78 and 8.00)."""
    coarse, fine = energy_error(order, 1 / 50), energy_error(order, 1 / 100)
    assert coarse / fine > min_ratio, (coarse, fine)


@pytest.mark.parametrize("order, bound", [(1, 0.07), (2, 3.2e-4), (3, 1.1e-6)])
def test_body_angular_velocity_follows_the_elliptic_solution(order, bound):
    """Body-frame omega against Landau-Lifshitz's Jacobi-elliptic solution over 10 s at
    dt = 1/100; bounds are 2x the errors measured by benchmarks/rotation_order.py (3.5e-2,
    1.6e-4, 5.4e-7 rad/s), so a lost order of accuracy fails the test."""
    dt, steps = 1 / 100, 1000
    world = spinning_body(ASYMMETRIC_MOMENTS, OMEGA0, order, dt)
    errors = []
    exact = analytic.torque_free_angular_velocity(ASYMMETRIC_MOMENTS, OMEGA0,
                                                  dt * np.arange(1, steps + 1))
    for k in range(steps):
        world.step()
        body_omega = world.rotation[0].T @ world.angular_velocity[0]
        errors.append(np.abs(body_omega - exact[k]).max())
    assert max(errors) < bound


def test_intermediate_axis_flip_period():
    """Near the separatrix (L^2 just above 2 E I2) the body spends long stretches turning
    about +-axis 2 and flips between them every 2 K(m)/lambda (Dzhanibekov); third order at
    dt = 1/200 finds the flip interval within 1% of the closed form."""
    omega0, rate = (1.0, 0.0, 0.58), 200
    period = analytic.torque_free_flip_period(ASYMMETRIC_MOMENTS, omega0)
    world = spinning_body(ASYMMETRIC_MOMENTS, omega0, order=3, dt=1 / rate)
    omega2 = []
    for _ in range(int(2.5 * period * rate)):
        world.step()
        omega2.append((world.rotation[0].T @ world.angular_velocity[0])[1])
    crossings = np.nonzero(np.diff(np.sign(omega2)) != 0)[0]
    assert len(crossings) >= 2
    assert (crossings[1] - crossings[0]) / rate == pytest.approx(period, rel=0.01)


def test_quarter_turn_limit_splits_a_fast_step_into_substeps():
    """A step with |omega| dt = 2 rad (more than a quarter turn) is cut into two half steps, so
    it equals two steps of dt/2 bit for bit (no torque: L is constant; keep_energy off, as it
    acts once per step)."""
    omega = (0.5, 0.0, 2.0 / (1 / 50) / 1.1)
    coarse = spinning_body(ASYMMETRIC_MOMENTS, omega, 2, dt=1 / 50, keep_energy=False)
    fine = spinning_body(ASYMMETRIC_MOMENTS, omega, 2, dt=1 / 100, keep_energy=False)
    speed_dt = np.linalg.norm(coarse.angular_velocity[0]) * coarse.dt
    assert np.pi / 2 < speed_dt < np.pi
    coarse.step(10)
    fine.step(20)
    np.testing.assert_array_equal(coarse.orientation, fine.orientation)


@pytest.mark.parametrize("axis", ["minor", "major"])
@pytest.mark.parametrize("dt", [1 / 60, 1 / 240])
def test_a_fast_spinner_off_a_principal_axis_keeps_its_energy_and_momentum(axis, dt):
    """300 rad/s, 4 deg off the minor (I = 1) or the major (I = 3) axis: |omega| dt = 5 or 1.25
    rad, and the body wobbles at about the spin rate. Without keep_energy the update drifts
    towards the other axis (E -> 3 E0 off the major axis); with it, E stays at E0 to
    round-off over 10 s (1e-12 relative), never above it, and |L| is exact."""
    tilt = np.radians(4.0)
    direction = (np.cos(tilt), np.sin(tilt), 0.0) if axis == "minor" else (np.sin(tilt), 0.0,
                                                                           np.cos(tilt))
    world = spinning_body(ASYMMETRIC_MOMENTS, 300.0 * np.array(direction), 2, dt)
    e0, l0 = world.kinetic_energy(), world.angular_momentum().copy()
    highest = 0.0
    for _ in range(100):
        world.step(round(0.1 / dt))
        highest = max(highest, world.kinetic_energy() / e0 - 1.0)
    assert abs(world.kinetic_energy() / e0 - 1.0) < 1e-12
    assert highest < 1e-12
    np.testing.assert_array_equal(world.angular_momentum(), l0)
    drifting = spinning_body(ASYMMETRIC_MOMENTS, 300.0 * np.array(direction), 2, dt,
                             keep_energy=False)
    drifting.step(round(1.0 / dt))
    if axis == "major":
        assert drifting.kinetic_energy() / e0 - 1.0 > 0.5  # what the projection prevents


def test_bodies_listed_together_that_never_touch_keep_their_energy():
    """Four tumbling bodies 1 m apart falling for 10 s: past ~90 m/s their grown boxes meet
    and the broad phase lists neighbours as pairs, but they never touch (no impulse). Each is
    still free, so keep_energy holds its rotational energy to round-off, as for a body alone
    (1e-11 relative over 2,400 steps; the pairs must have been listed, or the test would not
    reach the case)."""
    scene = rg.Scene(gravity=(0.0, 0.0, -9.81))
    for k, shape in enumerate([rg.Box((0.1, 0.2, 0.3)), rg.Sphere(0.1), rg.Capsule(0.05, 0.2),
                               rg.Box((0.3, 0.1, 0.05))]):
        scene.add_body(shape, density=500.0, position=(k, 0.0, 10.0), velocity=(0.0, 1.0, 5.0),
                       angular_velocity=(3.0, 0.1 * k, 5.0))
    world = rg.World(scene, dt=1 / 240)

    def energies():
        return 0.5 * np.sum(world.body_angular_momentum * world.angular_velocity, axis=-1)

    start = energies()
    world.step(2400)
    assert len(world.listed_pairs()[0]) > 0
    assert np.all(np.abs(energies() / start - 1.0) < 1e-11)


def test_rotation_substeps_are_quarter_turns_and_at_most_64():
    """A step is cut into sub-steps of at most a quarter turn, but into no more than 64 of
    them (src/solver/integrate.h), so its cost is bounded whatever the speed; a NaN speed (never
    reached: setters refuse it) takes one."""
    dt = 1 / 240
    quarter = (np.pi / 2) / dt  # rad/s that turn a quarter per step
    assert _core.MAX_ROTATION_SUBSTEPS == 64
    for speed, substeps in ((0.0, 1), (0.9 * quarter, 1), (3.5 * quarter, 4),
                            (64 * quarter, 64), (65 * quarter, 64), (1e9, 64), (1e300, 64),
                            (np.inf, 64), (np.nan, 1)):
        assert _core.rotation_substeps(speed, dt) == substeps, speed


def test_a_box_spun_at_a_billion_radians_per_second_on_the_table_stays_finite():
    """1e9 rad/s (a corrupted state, or a user's typo): the capped rotation keeps each step
    short (benchmarks: 1000 steps well under a second) and every contact stays finite."""
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    cube = scene.add_body(rg.Box((0.025,) * 3), mass=0.1, position=(0.0, 0.0, 0.025))
    world = rg.World(scene, dt=1 / 240)
    world.set_velocity(cube, angular_velocity=(1e9, 0.0, 0.0))
    world.step(1000)
    for a in world.state:
        assert np.all(np.isfinite(a))
    assert np.all(np.isfinite(world.contacts(margin=0.01).depth))


def test_spin_about_a_principal_axis_is_exact_even_far_past_a_quarter_turn():
    """Constant omega along a principal axis: the exact-rotation update reproduces the angle
    |omega| t to round-off, however large |omega| dt is."""
    world = spinning_body(ASYMMETRIC_MOMENTS, (0.0, 0.0, 300.0), 1, dt=1 / 60)  # 5 rad per step
    world.step(7)
    angle = 300.0 * 7 / 60
    expected = np.array([np.cos(angle / 2), 0.0, 0.0, np.sin(angle / 2)])
    q = world.orientation[0]
    np.testing.assert_allclose(q * np.sign(q[0] * expected[0]), expected, atol=1e-13)


@pytest.mark.parametrize("order", [1, 2, 3])
def test_thin_rod_and_point_mass_spin_without_nan(order):
    """A rod (moments a, a, 0) and a point mass (0, 0, 0) have degenerate tensors: only the
    nonzero moments are inverted, so any spin stays finite. The rod's spin about its
    axis cannot be represented (it is dropped); its tumbling is torque-free and exact."""
    scene = rg.Scene(gravity=(0.0, 0.0, -9.81))
    rod = scene.add_body(rg.Capsule(0.001, 0.5), mass=1.0, inertia=(1 / 12, 1 / 12, 0.0),
                         angular_velocity=(2.0, 1.0, 50.0))
    point = scene.add_body(rg.Sphere(1e-3), mass=1.0, inertia=(0.0, 0.0, 0.0),
                           angular_velocity=(5.0, -3.0, 1.0), position=(1.0, 0.0, 0.0))
    world = rg.World(scene, dt=1 / 240, config=rg.SolverConfig(rotation_order=order))
    e0 = world.kinetic_energy() - 0.5 * np.sum(world.velocity ** 2)
    world.step(2400)
    assert np.all(np.isfinite(world.orientation)) and np.all(np.isfinite(world.angular_velocity))
    np.testing.assert_array_equal(world.angular_velocity[point], 0.0)
    np.testing.assert_allclose(world.body_angular_momentum[rod], [2 / 12, 1 / 12, 0.0], atol=1e-15)
    # the rod turns about an axis perpendicular to itself at constant rate
    np.testing.assert_allclose(np.linalg.norm(world.angular_velocity[rod]), np.sqrt(5.0), rtol=1e-12)
    rotational = world.kinetic_energy() - 0.5 * np.sum(world.velocity ** 2)
    assert rotational == pytest.approx(e0, rel=1e-12)
    axis = world.rotation[rod][:, 2]
    assert abs(axis @ world.angular_velocity[rod]) < 1e-12


def test_core_and_numpy_quaternions_agree():
    """The core's rotation matrices (src/base/math.h) are the numpy ones (rigid_gym.quaternion) of
    the same unit quaternions, and back."""
    rng = np.random.default_rng(0)
    q = quat.normalize(rng.normal(size=(50, 4)))
    scene = rg.Scene()
    for k in range(50):
        scene.add_body(rg.Sphere(0.1), density=1.0, orientation=q[k])
    world = rg.World(scene)
    np.testing.assert_allclose(world.rotation, quat.to_matrix(q), atol=1e-15)
    for k in range(50):
        np.testing.assert_allclose(np.abs(quat.from_matrix(world.rotation[k]) @ q[k]), 1.0, atol=1e-12)



def spun_up_angle_error(order, dt, seconds=0.5, tau=0.01):
    """Relative error of the angle a 0.1 m, 1 kg cube turns from rest under a constant torque
    tau (N m) about z for `seconds`, against theta = tau t^2 / (2 I)."""
    scene = rg.Scene(gravity=(0, 0, 0))
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0)
    world = rg.World(scene, dt=dt, config=rg.SolverConfig(rotation_order=order))
    steps = round(seconds / dt)
    for _ in range(steps):
        world.apply_torque(0, (0, 0, tau))
        world.step()
    moment = 1.0 * (0.1**2 + 0.1**2) / 12
    q = world.orientation[0]
    exact = 0.5 * tau / moment * (steps * dt) ** 2
    return abs(2 * np.arctan2(q[3], q[0]) - exact) / exact


@pytest.mark.parametrize("order", [2, 3])
def test_constant_torque_from_rest_turns_the_body_exactly(order):
    """Buss's update from the start of each step is exact for a constant angular acceleration
    about a principal axis, so only round-off remains (1e-12 of the angle; an update that
    counts the torque twice is off by 2/n = 1.7e-2 after n = 120 steps)."""
    assert spun_up_angle_error(order, 1 / 240) < 1e-12


def test_constant_torque_at_first_order_converges_at_first_order():
    """Order 1 rotates with the step's final omega (symplectic Euler): the angle's relative
    error is 1/n, halved when dt is halved."""
    e1, e2 = spun_up_angle_error(1, 1 / 240), spun_up_angle_error(1, 1 / 480)
    assert e1 == pytest.approx(1 / 120, rel=1e-6)
    assert e1 / e2 == pytest.approx(2.0, rel=1e-6)
