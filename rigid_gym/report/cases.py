"""Closed-form cases of the accuracy report: a scene, the exact answer, and how far a run is
from it.

Each :class:`Case` builds its scene (``rigid_gym.report.scenes``), and ``measure`` steps a
fresh :class:`rigid_gym.World` of it and returns one error per metric (dimensionless relative
errors unless the metric's unit says m). ``settings`` are the solver variants swept, as
``SolverConfig`` overrides of ``SolverConfig.for_scene``: the pass counts and the rotation
order where they can change the answer.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

import rigid_gym as rg
from rigid_gym import analytic
from rigid_gym.report import scenes
from rigid_gym.report.scenes import G

Settings = dict[str, dict[str, object]]
"""A case's solver settings: label -> SolverConfig overrides."""

PASS_SETTINGS: Settings = {"default": {}, "2 contact passes": {"contact_passes": 2},
                 "narrow phase every pass": {"detect_every_pass": True}}
BOUNCE_SETTINGS: Settings = {**PASS_SETTINGS, "1 collision pass": {"collision_passes": 1}}
ROTATION_SETTINGS: Settings = {**{f"rotation order {k}": {"rotation_order": k} for k in (1, 2, 3)},
                     "rotation order 2, energy not kept": {"rotation_order": 2,
                                                            "keep_energy": False}}


@dataclass(frozen=True)
class Case:
    """One closed-form case.

    key: short identifier (file names). title: what is simulated. exact: the closed form, as
    text. metrics: name of each error ``measure`` returns, with its unit. build: () -> Scene.
    measure: (World) -> tuple of errors, one per metric (NaN when the run could not produce
    the quantity, e.g. a bounce never seen). settings: label -> SolverConfig overrides.
    note: what to know when reading the case's numbers (printed under the table).
    """

    key: str
    title: str
    exact: str
    metrics: tuple[str, ...]
    build: Callable[[], rg.Scene]
    measure: Callable[[rg.World], tuple[float, ...]]
    settings: Settings
    note: str = ""


# -- exact answers and the errors against them ----------------------------------------------

FREE_FALL_SECONDS = 1.0


def free_fall_error(world: rg.World) -> tuple[float]:
    """|x(T) - x0 - v0 T - g T^2/2| / |g T^2/2| after T = 1 s of flight."""
    body = world.scene.bodies[0]
    world.step(round(FREE_FALL_SECONDS / world.dt))
    exact, _ = analytic.free_fall_continuous(body.position, body.velocity, world.scene.gravity,
                                             world.time)
    scale = 0.5 * np.linalg.norm(world.scene.gravity) * world.time ** 2
    return (float(np.linalg.norm(world.position[0] - exact) / scale),)


BOUNCE_HEIGHT = 1.0  # m, drop height of the lowest point
BOUNCES = 3


def apex_heights(world: rg.World, count: int, radius: float, limit: float) -> np.ndarray:
    """Heights (m) of the ball's lowest point (body 1) at its first ``count`` apexes (where
    v_z turns from > 0 to <= 0), searching at most ``limit`` s; fewer if not all were seen."""
    found: list[float] = []
    previous = 0.0
    while len(found) < count and world.time < limit:
        world.step()
        v = world.velocity[1, 2]
        if previous > 0.0 >= v:
            found.append(world.position[1, 2] - radius)
        previous = v
    return np.array(found)


def bounce_error(apexes: np.ndarray, restitution: float, height: float, count: int) -> float:
    """max_k |apex_k / (e^(2k) h0) - 1| over the first ``count`` apexes; NaN if fewer seen."""
    if len(apexes) < count:
        return float("nan")
    expected = height * restitution ** (2 * np.arange(1, count + 1))
    return float(np.max(np.abs(apexes / expected - 1.0)))


def bounce_case(restitution: float) -> Case:
    def measure(world):
        # each bounce lasts 2 sqrt(2 h / g); allow twice the total before giving up
        flight = 2 * np.sqrt(2 * BOUNCE_HEIGHT / G) * np.sum(restitution ** np.arange(BOUNCES))
        apexes = apex_heights(world, BOUNCES, world.scene.bodies[1].shape.radius, 2 * flight)
        return (bounce_error(apexes, restitution, BOUNCE_HEIGHT, BOUNCES),)

    return Case(f"bounce_e{restitution:g}".replace(".", ""),
                f"ball dropped from {BOUNCE_HEIGHT:g} m, e = {restitution:g}",
                "apex k = e^(2k) h0", ("apex height, max relative error over 3 bounces",),
                lambda: scenes.dropped_ball(restitution, BOUNCE_HEIGHT), measure,
                BOUNCE_SETTINGS,
                "the reflection uses the velocity before the impact step's gravity, an "
                "O(g dt / v_impact) error per bounce whose size depends on where the impact "
                "falls within a step, so errors scatter about a first-order trend; the third "
                "apex (e^6 h0 = 1.6 cm at e = 0.5) dominates." if restitution < 1 else
                "every bounce loses 2 g dt / v_impact of its height (notes/physics.md), first "
                "order; energy never grows.")


SLIDE_MU, SLIDE_SPEED = 0.5, 2.0


def slide_error(world: rg.World) -> tuple[float]:
    """|d - v0^2 / (2 mu g)| / (v0^2 / (2 mu g)) once the box has stopped."""
    exact = SLIDE_SPEED ** 2 / (2 * SLIDE_MU * G)
    world.step(int(2 * SLIDE_SPEED / (SLIDE_MU * G) / world.dt) + 10)
    return (abs(world.position[1, 0] - exact) / exact,)


INCLINE_MU = 0.5


def incline_slide_error(world: rg.World) -> tuple[float]:
    """|a - g (sin theta - mu cos theta)| / that, a from the velocity change between t = 0.5
    and 1 s (theta = 30 deg, tan theta > mu: sliding)."""
    theta = np.radians(30.0)
    half = round(0.5 / world.dt)
    world.step(half)
    v0 = world.velocity[1].copy()
    world.step(half)
    a = np.linalg.norm(world.velocity[1] - v0) / (half * world.dt)
    exact = G * (np.sin(theta) - INCLINE_MU * np.cos(theta))
    return (abs(a - exact) / exact,)


def incline_stick_error(world: rg.World) -> tuple[float]:
    """Distance (m) the block creeps between t = 1 and 2 s (theta = 20 deg, tan theta < mu:
    the exact answer is 0)."""
    second = round(1.0 / world.dt)
    world.step(second)
    start = world.position[1].copy()
    world.step(second)
    return (float(np.linalg.norm(world.position[1] - start)),)


ROLL_SPEED = 2.0


def rolling_error(world: rg.World) -> tuple[float]:
    """|v - 5/7 v0| / (5/7 v0) after 1 s (rolling starts at 2 v0 / (7 mu g) = 0.19 s)."""
    world.step(round(1.0 / world.dt))
    return (abs(world.velocity[1, 0] / (5 / 7 * ROLL_SPEED) - 1.0),)


ROW_COUNT, ROW_SPEED = 5, 1.0
ROW_SECONDS = 1 / 30


def struck_row_errors(world: rg.World) -> tuple[float, float]:
    """Each cube's speed along the row against ROW_SPEED / ROW_COUNT after ROW_SECONDS (the
    largest relative error), and the row's momentum against the strike's."""
    world.step(round(ROW_SECONDS / world.dt))
    speeds = world.velocity[1:ROW_COUNT + 1, 0]
    together = ROW_SPEED / ROW_COUNT
    return (float(np.abs(speeds - together).max() / together),
            abs(float(speeds.sum()) - ROW_SPEED) / ROW_SPEED)


WALL_SPEED, WALL_PHASES, WALL_SECONDS = 50.0, 8, 0.1  # m/s, starting phases, s


def wall_error(world: rg.World) -> tuple[float]:
    """How far (m) the furthest cube's leading face ends past the wall's near face after
    WALL_SECONDS (0 where every cube stays on its side; an overlap up to the 0.1 mm slop is
    the solver's tolerance, a cube through the wall metres)."""
    world.step(round(WALL_SECONDS / world.dt))
    leads = world.position[1:, 0] + scenes.BULLET_HALF
    return (max(0.0, float((leads + scenes.WALL_HALF).max())),)


PLATE_RELEASE, PLATE_SECONDS = 5.0, 2.0  # m, s
PLATE_TOPS = tuple(0.7 + k * 0.0103 for k in range(4))
"""m: table heights spread over the plates' fall in one step at dt = 1/240 (4.1 cm at the
9.9 m/s they reach), so the impact falls at 4 phases of the step."""


def plate_error(world: rg.World) -> tuple[float]:
    """Largest |plate bottom - table top| (m) over the tables after PLATE_SECONDS (exact 0:
    every plate rests on its table; one through its table falls on for ever)."""
    world.step(round(PLATE_SECONDS / world.dt))
    count = len(PLATE_TOPS)
    bottoms = world.position[count:, 2] - scenes.PLATE_HALF[2]
    return (float(np.abs(bottoms - np.array(PLATE_TOPS)).max()),)


TOP_MOMENTS = (1.0, 2.0, 3.0)  # kg m^2
TOP_OMEGA = (0.3, 0.0, 1.0)  # rad/s, body frame, on the omega_2 = 0 section
TOP_SECONDS = 10.0


def torque_free_errors(world: rg.World) -> tuple[float, float, float]:
    """Over 10 s: max |omega_body - exact| / |omega0| (Jacobi elliptic functions), max
    |E / E0 - 1|, and the relative error of the mean time between reversals of omega_2 (the
    intermediate-axis flip, 2 K(m) / lambda = 3.17 s; reversals found by linear interpolation
    between steps)."""
    steps = round(TOP_SECONDS / world.dt)
    times = world.dt * np.arange(1, steps + 1)
    exact = analytic.torque_free_angular_velocity(TOP_MOMENTS, TOP_OMEGA, times)
    e0 = world.kinetic_energy()
    omega = np.empty((steps, 3))
    energy = 0.0
    for k in range(steps):
        world.step()
        omega[k] = world.rotation[0].T @ world.angular_velocity[0]
        energy = max(energy, abs(world.kinetic_energy() / e0 - 1.0))
    omega_error = np.abs(omega - exact).max() / np.linalg.norm(TOP_OMEGA)
    w2 = omega[:, 1]
    sign_change = np.nonzero(np.sign(w2[:-1]) != np.sign(w2[1:]))[0]
    crossings = times[sign_change] - w2[sign_change] * world.dt / (w2[sign_change + 1]
                                                                   - w2[sign_change])
    period = analytic.torque_free_flip_period(TOP_MOMENTS, TOP_OMEGA)
    flip = abs(crossings[-1] / len(crossings) / period - 1.0) if len(crossings) else np.nan
    return float(omega_error), float(energy), float(flip)


STACK_COUNT, STACK_SECONDS = 10, 2.0


def stack_drift(world: rg.World) -> tuple[float]:
    """Largest displacement (m) of any cube of a resting 10-cube stack after 2 s (exact: 0)."""
    start = world.position.copy()
    world.step(round(STACK_SECONDS / world.dt))
    return (float(np.abs(world.position - start).max()),)


SPIN_TORQUE, SPIN_SECONDS = 0.5, 0.5  # N m about the body's z axis (I_z = 3 kg m^2), s


def spin_up_error(world: rg.World) -> tuple[float]:
    """|theta(T) - tau T^2 / (2 I_z)| / that: a free body at rest turned by a constant torque
    about its principal z axis for T = 0.5 s (a rotation about a fixed axis: exact at every
    rotation order that integrates the torque at the order it claims)."""
    steps = round(SPIN_SECONDS / world.dt)
    for _ in range(steps):
        world.apply_torque(0, (0.0, 0.0, SPIN_TORQUE))
        world.step()
    rotation = world.rotation[0]
    angle = np.arctan2(rotation[1, 0], rotation[0, 0])
    exact = 0.5 * SPIN_TORQUE / TOP_MOMENTS[2] * (steps * world.dt) ** 2
    return (abs(angle - exact) / exact,)


PUSH_SLIDE_MU, PUSH_SLIDE_FORCE = 0.1, 0.2  # the push in units of m g: slides (tips above 0.25)
PUSH_TIP_MU, PUSH_TIP_FORCE = 0.6, 0.3
PUSH_SECONDS, TIP_DEG = 0.4, 30.0


def push_at_top(world: rg.World, force: float, until_tilt_deg: float = 90.0):
    """Push the standing block along +x at the centre of its top face with ``force`` x m g
    for PUSH_SECONDS (or until it tilts ``until_tilt_deg``). Returns the push time (s), the
    velocity x at its end (m/s), the tilt (rad) and the x travel of the leading bottom edge
    (m)."""
    half = np.array(scenes.BLOCK_HALF)
    edge_local = np.array([half[0], 0.0, -half[2]])
    edge0 = world.position[1] + world.rotation[1] @ edge_local
    steps = 0
    for _ in range(round(PUSH_SECONDS / world.dt)):
        top = world.position[1] + world.rotation[1] @ np.array([0.0, 0.0, half[2]])
        world.apply_force(1, (force * G, 0.0, 0.0), point=top)
        world.step()
        steps += 1
        if world.rotation[1][2, 2] < np.cos(np.radians(until_tilt_deg)):
            break
    tilt = float(np.arccos(min(1.0, world.rotation[1][2, 2])))
    edge = world.position[1] + world.rotation[1] @ edge_local
    return steps * world.dt, float(world.velocity[1, 0]), tilt, float(edge[0] - edge0[0])


def push_slide_errors(world: rg.World) -> tuple[float, float]:
    """Pushed at its top with F = 0.2 m g on mu = 0.1 (tipping needs F > m g w / (2 h) =
    0.25 m g): |v(T) / T - (F/m - mu g)| / (F/m - mu g) over T = 0.4 s, and the tilt (rad,
    exact 0)."""
    seconds, vx, tilt, _ = push_at_top(world, PUSH_SLIDE_FORCE)
    exact = (PUSH_SLIDE_FORCE - PUSH_SLIDE_MU) * G
    return (abs(vx / seconds - exact) / exact, tilt)


def push_tip_error(world: rg.World) -> tuple[float]:
    """Pushed at its top with F = 0.3 m g on mu = 0.6: it tips about its leading bottom edge,
    which friction holds (the ideal pivot needs |f| / N = 0.27 < mu), so the edge's travel by
    30 deg of tilt is exactly 0 (m)."""
    _, _, tilt, travel = push_at_top(world, PUSH_TIP_FORCE, TIP_DEG)
    return (abs(travel) if np.degrees(tilt) >= TIP_DEG else float("nan"),)


PENDULUM_SMALL, PENDULUM_WIDE = 0.05, 0.5 * np.pi  # rad
PERIOD_CROSSINGS = 4


def period_error(world: rg.World, exact: float) -> float:
    """|T - exact| / exact, T twice the mean time between the first PERIOD_CROSSINGS passes
    of body 0's centre through x = 0 (below the pivot), each found by linear interpolation
    between steps."""
    crossings: list[float] = []
    previous = world.position[0, 0]
    while len(crossings) < PERIOD_CROSSINGS and world.time < 2.0 * PERIOD_CROSSINGS * exact:
        world.step()
        x = world.position[0, 0]
        if (previous > 0.0) != (x > 0.0):
            crossings.append(world.time - world.dt * x / (x - previous))
        previous = x
    if len(crossings) < PERIOD_CROSSINGS:
        return float("nan")
    return abs(2.0 * float(np.mean(np.diff(crossings))) / exact - 1.0)


def pendulum_case(amplitude: float) -> Case:
    inertia = 1.0 * (scenes.PENDULUM_LENGTH ** 2 + 0.4 * scenes.PENDULUM_BOB ** 2)
    exact = analytic.pendulum_period(inertia, 1.0, scenes.PENDULUM_LENGTH, G, amplitude)
    return Case(f"pendulum_{np.degrees(amplitude):.0f}deg",
                f"pendulum, 1 kg bob (r = 1 cm) on a revolute joint 1 m below the pivot, "
                f"released at {np.degrees(amplitude):.3g} deg",
                "T = 4 sqrt(I / (m g L)) K(sin(theta0 / 2)), I = m (L^2 + 2 r^2 / 5)",
                ("period, relative error",), lambda: scenes.pendulum(amplitude),
                lambda world: (period_error(world, exact),), {"default": {}},
                "the joint stages are RATTLE (src/solver/joints.h): a symplectic scheme whose "
                "period error is second order in dt; the bob's own inertia is in I (4e-5 of "
                "m L^2)." if amplitude < 0.1 else
                "the elliptic integral: 18% longer than the small-amplitude period; energy "
                "oscillates by O(dt) (the velocity update is symplectic Euler) and does not "
                "drift.")


ROD_AMPLITUDE = 0.05  # rad


def physical_pendulum_error(world: rg.World) -> tuple[float]:
    """The rod's period against 4 sqrt(I / (m g d)) K(sin(theta0 / 2)) (2 pi sqrt(I / (m g
    d)) to 1.6e-4 at 0.05 rad), I about the pivot, d = 0.25 m."""
    hx, _, hz = scenes.ROD_HALF
    inertia = (hx * hx + hz * hz) / 3.0 + hz * hz  # about its centre (1 kg), moved to its end
    return (period_error(world, analytic.pendulum_period(inertia, 1.0, hz, G, ROD_AMPLITUDE)),)


ARM_HOLD, ARM_GIVE = 1.5, 0.5  # the motor's maximum torque in units of the arm's m g d
ARM_SECONDS, ARM_ANGLE = 1.0, np.radians(30.0)


def arm_torque() -> float:
    """m g d of the motor arm (1 kg, d = half its length), N m."""
    return 1.0 * G * scenes.ARM_HALF[0]


def motor_hold_error(world: rg.World) -> tuple[float]:
    """|angle| (rad) the arm turns in ARM_SECONDS while its motor (max ARM_HOLD m g d, target
    speed 0) holds it: exact 0."""
    world.step(round(ARM_SECONDS / world.dt))
    return (abs(float(world.joint_coordinates()[0])),)


def motor_give_error(world: rg.World) -> tuple[float]:
    """The arm's angular speed when it has turned ARM_ANGLE down against its motor at full
    torque (max ARM_GIVE m g d < m g d), against energy's sqrt(2 (m g d sin a - tau a) / I),
    relative; both interpolated to ARM_ANGLE between steps."""
    hx, _, hz = scenes.ARM_HALF
    inertia = (hx * hx + hz * hz) / 3.0 + hx * hx
    exact = analytic.arm_speed_past_motor(inertia, 1.0, hx, G, ARM_GIVE * arm_torque(),
                                          ARM_ANGLE)
    angle, speed = 0.0, 0.0
    while world.time < 2.0:
        world.step()
        now, spin = float(world.joint_coordinates()[0]), float(world.angular_velocity[0, 1])
        if now >= ARM_ANGLE:
            reached = speed + (spin - speed) * (ARM_ANGLE - angle) / (now - angle)
            return (abs(reached / exact - 1.0),)
        angle, speed = now, spin
    return (float("nan"),)


SLIDER_DEG = 30.0


def slider_errors(world: rg.World) -> tuple[float, float]:
    """A cube on a frictionless prismatic joint along a 30 deg slope: |a / (g sin theta) - 1|,
    a from the velocity change between t = 0.5 and 1 s; and its centre's largest distance
    (m) from the line at the end (exact 0)."""
    theta = np.radians(SLIDER_DEG)
    axis = np.array([np.cos(theta), 0.0, -np.sin(theta)])
    half = round(0.5 / world.dt)
    world.step(half)
    v0 = float(world.velocity[0] @ axis)
    world.step(half)
    a = (float(world.velocity[0] @ axis) - v0) / (half * world.dt)
    off = world.position[0] - (world.position[0] @ axis) * axis
    return (abs(a / (G * np.sin(theta)) - 1.0), float(np.linalg.norm(off)))


GRASP_ROWS = (  # (cube mass kg, grip N, friction, the hand's upward acceleration m/s^2)
    (0.1, 0.5, 0.5, 0.0), (0.1, 0.9, 0.5, 0.0), (0.1, 1.1, 0.5, 0.0), (0.1, 1.5, 0.5, 5.0),
    (0.1, 1.5, 0.5, 10.0), (0.2, 0.95, 1.0, 0.0), (0.2, 1.0, 1.0, 0.0), (0.5, 10.0, 0.5, 8.0),
    (0.5, 10.0, 0.5, 12.0), (2.0, 70.0, 0.3, 10.0), (2.0, 70.0, 0.3, 15.0))
GRASP_SECONDS = 0.1  # s measured, after the first step (the fingers' first squeeze)


def grasp_held(row) -> bool:
    """Whether friction holds row (m, F, mu, a)'s cube: m (g + a) < 2 mu F."""
    mass, grip, friction, lift = row
    return mass * (G + lift) < 2.0 * friction * grip


def grasp_errors(world: rg.World) -> tuple[float, float]:
    """The grippers of ``scenes.grasps`` (GRASP_ROWS), each hand moved up at its row's
    acceleration a from rest: the largest slip (m) of a held cube against its hand over
    GRASP_SECONDS (exact 0), and the largest |a_cube / (2 mu F / m - g) - 1| of the sliding
    ones (their cubes' acceleration over the same time: friction mu F on each face)."""
    hands = 4 * np.arange(len(GRASP_ROWS))
    lifts = np.array([row[3] for row in GRASP_ROWS])

    def step() -> None:
        for hand, lift in zip(hands, lifts):
            world.set_velocity(int(hand), (0.0, 0.0, lift * world.time))
        world.step()

    step()
    steps = max(1, round(GRASP_SECONDS / world.dt))
    offset = world.position[hands + 1, 2] - world.position[hands, 2]
    start = world.velocity[hands + 1, 2].copy()
    for _ in range(steps):
        step()
    slip = world.position[hands + 1, 2] - world.position[hands, 2] - offset
    accel = (world.velocity[hands + 1, 2] - start) / (steps * world.dt)
    held = np.array([grasp_held(row) for row in GRASP_ROWS])
    exact = np.array([2.0 * f * grip / m - G for m, grip, f, _ in GRASP_ROWS])
    return (float(np.max(np.abs(slip[held]))),
            float(np.max(np.abs(accel[~held] / exact[~held] - 1.0))))


BLOCK_FORCE, BLOCK_SECONDS = 10.0, 0.2  # N on the lower block (sliding needs > 2 mu m g = 5.9 N)


def pull_lower_block(world: rg.World) -> tuple[int, float, float]:
    """Pull the lower block (body 1) along +x by BLOCK_FORCE for BLOCK_SECONDS (whole steps) ->
    (the steps, the impulse given F T, N s, the two blocks' momentum along x, N s: 1 kg each)."""
    steps = round(BLOCK_SECONDS / world.dt)
    for _ in range(steps):
        world.apply_force(1, (BLOCK_FORCE, 0.0, 0.0))
        world.step()
    return (steps, BLOCK_FORCE * steps * world.dt,
            float(world.velocity[1, 0] + world.velocity[2, 0]))


def block_on_block_errors(world: rg.World) -> tuple[float, float]:
    """The lower block pulled along +x by BLOCK_FORCE for BLOCK_SECONDS on a frictionless
    floor, the upper one sliding on it: |p - F T| / (F T) of the two blocks' momentum (exact
    whatever the friction between them), and |v_upper / (mu g T) - 1| (it slides at mu g)."""
    steps, pulled, momentum = pull_lower_block(world)
    upper = float(world.velocity[2, 0]) / (scenes.BLOCK_MU * G * steps * world.dt)
    return abs(momentum - pulled) / pulled, abs(upper - 1.0)


STICKING_MU = 1.0
"""Friction between the blocks of the sticking case: the cube needs F / 2 = 5 N of the 9.8 N
that mu m g allows, so it sticks."""


def block_sticking_errors(world: rg.World) -> tuple[float, float]:
    """The lower block pulled by BLOCK_FORCE for BLOCK_SECONDS, the cube on it sticking: |p -
    F T| / (F T) of the two blocks' momentum, and |v_cube / (F T / 2 m) - 1| (both move as one
    body of 2 kg)."""
    _, pulled, momentum = pull_lower_block(world)
    return abs(momentum - pulled) / pulled, abs(float(world.velocity[2, 0]) / (pulled / 2) - 1.0)


HEAVY_TOP_MOMENTS = (6.5e-4, 6.5e-4, 1.2e-3)  # kg m^2: a flat top, I3 near 2 I1
HEAVY_TOP_SPIN, HEAVY_TOP_TILT, HEAVY_TOP_SECONDS = 300.0, 30.0, 2.0  # rad/s, deg, s


def steady_precession() -> float:
    """The heavy symmetric top's slow steady precession (rad/s) on a frictionless floor: its
    centre of mass stays put, so the moments are about it, and the tip's normal force m g
    turns L: Omega (I3 omega3 - I1 Omega cos theta) = m g l, the smaller root (m g l /
    (I3 omega3) for a fast top: 0.2% less here)."""
    i1, _, i3 = HEAVY_TOP_MOMENTS
    a = i1 * np.cos(np.radians(HEAVY_TOP_TILT))
    b = i3 * HEAVY_TOP_SPIN
    c = scenes.TOP_MASS * G * scenes.TOP_ARM
    return float((b - np.sqrt(b * b - 4 * a * c)) / (2 * a))


def heavy_top_errors(world: rg.World) -> tuple[float, float]:
    """The top started in steady precession, over HEAVY_TOP_SECONDS: |rate / Omega - 1| of
    its axis's mean turning rate about the vertical (azimuth unwrapped step by step), and the
    largest growth of its energy (kinetic plus m g z), max(E) / E0 - 1 or 0 (nothing adds
    energy: the floor is frictionless and e = 0)."""
    steps = round(HEAVY_TOP_SECONDS / world.dt)

    def energy() -> float:
        return world.kinetic_energy() + scenes.TOP_MASS * G * float(world.position[1, 2])

    e0, highest = energy(), energy()
    azimuth = np.empty(steps + 1)
    axis = world.rotation[1][:, 2]
    azimuth[0] = np.arctan2(axis[1], axis[0])
    for k in range(steps):
        world.step()
        highest = max(highest, energy())
        axis = world.rotation[1][:, 2]
        azimuth[k + 1] = np.arctan2(axis[1], axis[0])
    rate = (np.unwrap(azimuth)[-1] - azimuth[0]) / (steps * world.dt)
    return abs(rate / steady_precession() - 1.0), max(highest / e0 - 1.0, 0.0)


PLANK_SECONDS = 5.0


def point_speed(world: rg.World, body: int, reach: float) -> float:
    """m/s: a bound on the speed of any point of ``body`` within ``reach`` m of its centre,
    |v| + |omega| reach."""
    return float(np.linalg.norm(world.velocity[body])
                 + np.linalg.norm(world.angular_velocity[body]) * reach)


def plank_on_bars_errors(world: rg.World) -> tuple[float, float]:
    """The plank resting across two round bars for PLANK_SECONDS (exact: at rest): its
    largest point speed at the end (m/s) and how far its centre moved (m)."""
    start = world.position[3].copy()
    world.step(round(PLANK_SECONDS / world.dt))
    return point_speed(world, 3, 0.51), float(np.linalg.norm(world.position[3] - start))


def tiny_on_huge_error(world: rg.World) -> tuple[float]:
    """The 1 mm cube 1 s after it was dropped onto the 1 m cube: its largest point speed (m/s;
    exact: at rest)."""
    world.step(round(1.0 / world.dt))
    return (point_speed(world, 2, 0.0005 * np.sqrt(3.0)),)


KNIFE_BARS = (-0.3, 0.2)  # m: the bars' x, the plank's centre at 0


def knife_edge_error(world: rg.World) -> tuple[float]:
    """The plank resting on two frictionless bars of 5 mm radius for 1 s: the largest error of
    the reactions ``World.contacts`` reports for the last step (each bar's pair impulse / dt)
    against the lever rule, m g (x2 - x) / (x2 - x1) and m g (x - x1) / (x2 - x1), relative to
    m g."""
    world.step(round(1.0 / world.dt))
    contacts = world.contacts()
    weight = float(np.linalg.norm(world.scene.gravity))  # the plank is 1 kg
    x = float(world.position[3, 0])
    (x1, x2), errors = KNIFE_BARS, []
    for bar, exact in ((1, (x2 - x) / (x2 - x1)), (2, (x - x1) / (x2 - x1))):
        rows = np.nonzero(contacts.body_b == bar)[0]
        if len(rows) == 0:
            return (float("nan"),)
        reaction = contacts.pair_impulse[rows[0]] / world.dt  # on the plank, its pair's a
        errors.append(abs(reaction[2] / weight - exact))
    return (max(errors),)


CASES = (
    Case("free_fall", "ball in free flight for 1 s", "x0 + v0 t + g t^2 / 2",
         ("position, relative error",), scenes.free_ball, free_fall_error, {"default": {}}),
    bounce_case(0.5),
    bounce_case(1.0),
    Case("slide", f"cube sliding at {SLIDE_SPEED:g} m/s, mu = {SLIDE_MU:g}",
         "stops after v0^2 / (2 mu g)", ("slide distance, relative error",),
         lambda: scenes.sliding_box(SLIDE_MU, SLIDE_SPEED), slide_error, PASS_SETTINGS,
         "the discrete answer is v0^2 / (2 mu g) - v0 dt / 2 (positions use the new velocity), "
         "so the error is first order and equals v0 dt / 2 to round-off."),
    Case("incline_slide", f"cube on a 30 deg incline, mu = {INCLINE_MU:g}",
         "slides at a = g (sin theta - mu cos theta)", ("acceleration, relative error",),
         lambda: scenes.incline(30.0, INCLINE_MU), incline_slide_error, PASS_SETTINGS),
    Case("incline_stick", f"cube on a 20 deg incline, mu = {INCLINE_MU:g}",
         "sticks (tan theta < mu): creep 0", ("creep over 1 s, m",),
         lambda: scenes.incline(20.0, INCLINE_MU), incline_stick_error, PASS_SETTINGS),
    Case("rolling", f"sphere launched sliding at {ROLL_SPEED:g} m/s, mu = 0.3",
         "ends rolling at 5/7 v0", ("final speed, relative error",),
         lambda: scenes.sliding_sphere(ROLL_SPEED), rolling_error, PASS_SETTINGS),
    Case("struck_row", f"row of {ROW_COUNT} touching 1 kg cubes, frictionless, the first struck "
         f"at {ROW_SPEED:g} m/s, e = 0, {1e3 * ROW_SECONDS:.0f} ms",
         "moves as one at v0 / 5 (momentum kept, perfectly inelastic)",
         ("cube speed, max relative error", "momentum, relative error"),
         lambda: scenes.struck_row(ROW_COUNT, ROW_SPEED), struck_row_errors, PASS_SETTINGS,
         "the contact passes carry the strike down the row within a step (Gauss-Seidel: each "
         "pass passes part of it on); what a step leaves, the next steps carry on, so the "
         "error falls with dt and, at a dt, with the number of passes. At dt = 1/240 the "
         "cubes agree to 5e-9 (with one impulse per patch between two cubes, contact_patches "
         "off, they turn slightly while the strike passes and keep a spread of a few um/s)."),
    Case("wall", f"{WALL_PHASES} cubes of 2 cm fired at {WALL_SPEED:g} m/s at a 1 cm wall, "
         f"{WALL_PHASES} starting phases of a step at 1/240, e = 0", "stays on its side: 0 past it",
         ("leading face past the wall, max over the cubes, m",),
         lambda: scenes.cubes_at_wall(WALL_PHASES, WALL_SPEED, WALL_SPEED / 240),
         wall_error, {**PASS_SETTINGS, "continuous off": {"continuous": False}},
         "a cube moves 21 cm a step at dt = 1/240 against 1 cm of wall. Found at the end of "
         "the step alone, contacts miss the wall or meet it past its mid-plane, where the "
         "nearest way out is forwards (continuous off: through at all 8 phases). Swept "
         "(src/solver/continuous.h), each cube's contacts are found where it meets the wall "
         "and carried on to the end of the step; the contact passes stop it where the step "
         "began, up to a step short of the wall (GBF's inelastic contact at predicted poses)."),
    Case("plate", f"2 mm plates dropped flat from {PLATE_RELEASE:g} m onto 4 cm table tops at "
         f"{len(PLATE_TOPS)} heights, e = 0", "rests on the table: 0 from its top",
         ("plate bottom from table top, max over the tables, m",),
         lambda: scenes.plates_on_tables(PLATE_TOPS, PLATE_RELEASE), plate_error,
         {**PASS_SETTINGS, "continuous off": {"continuous": False}},
         "the plates arrive at 9.9 m/s, 4.1 cm a step at dt = 1/240. Found at the end of the "
         "step alone, a plate whose centre is predicted past the table's mid-plane is pushed "
         "out downwards (box-box's least overlap) and falls through (continuous off: 2 of the 4 "
         "at dt = 1/240); swept, "
         "its contacts are found on the top face. The contact passes stop it where the step "
         "began, and it falls the rest of the way under gravity and rests."),
    Case("torque_free", "torque-free body, I = (1, 2, 3) kg m^2, omega0 = (0.3, 0, 1) rad/s, 10 s",
         "Jacobi elliptic functions (Landau-Lifshitz §37)",
         ("body angular velocity, max relative error", "energy, max relative error",
          "flip period, relative error"),
         lambda: scenes.spinning_body(TOP_MOMENTS, TOP_OMEGA), torque_free_errors,
         ROTATION_SETTINGS),
    Case("spin_up", f"body at rest, constant torque {SPIN_TORQUE:g} N m about I_z = "
         f"{TOP_MOMENTS[2]:g} kg m^2, {SPIN_SECONDS:g} s", "theta = tau t^2 / (2 I)",
         ("angle, relative error",), lambda: scenes.spinning_body(TOP_MOMENTS, (0.0, 0.0, 0.0)),
         spin_up_error, {f"rotation order {k}": {"rotation_order": k} for k in (1, 2, 3)},
         "order 1 turns by the step's new angular velocity (symplectic Euler), an error of "
         "dt / T; orders 2 and 3 integrate the torque exactly."),
    Case("push_slide", f"block 0.1 x 0.1 x 0.2 m pushed at its top, F = {PUSH_SLIDE_FORCE:g} m g, "
         f"mu = {PUSH_SLIDE_MU:g}", "slides upright at a = F/m - mu g",
         ("mean acceleration, relative error", "tilt, rad"),
         lambda: scenes.standing_block(PUSH_SLIDE_MU), push_slide_errors, PASS_SETTINGS),
    Case("push_tip", f"block 0.1 x 0.1 x 0.2 m pushed at its top, F = {PUSH_TIP_FORCE:g} m g, "
         f"mu = {PUSH_TIP_MU:g}", "tips about a fixed edge: travel 0",
         (f"edge travel by {TIP_DEG:g} deg of tilt, m",),
         lambda: scenes.standing_block(PUSH_TIP_MU), push_tip_error, PASS_SETTINGS),
    pendulum_case(PENDULUM_SMALL),
    pendulum_case(PENDULUM_WIDE),
    Case("physical_pendulum", f"rod 0.5 m, 1 kg, hinged at its end, released at "
         f"{ROD_AMPLITUDE:g} rad", "T = 2 pi sqrt(I / (m g d)) (with K(sin(theta0 / 2)))",
         ("period, relative error",), lambda: scenes.physical_pendulum(ROD_AMPLITUDE),
         physical_pendulum_error, {"default": {}}),
    Case("motor_hold", f"arm 0.4 m, 1 kg, held horizontal by a revolute motor of max "
         f"{ARM_HOLD:g} m g d, {ARM_SECONDS:g} s", "held: turn 0", ("turn, rad",),
         lambda: scenes.motor_arm(ARM_HOLD * arm_torque()), motor_hold_error, {"default": {}},
         "the motor's impulse is bounded by max torque x dt over the step; the arm's weight "
         "needs m g d dt, within it, so the velocity solve holds the joint's rate at 0."),
    Case("motor_give", f"the same arm, motor of max {ARM_GIVE:g} m g d: it gives way",
         "w(30 deg) = sqrt(2 (m g d sin a - tau a) / I)", ("speed at 30 deg, relative error",),
         lambda: scenes.motor_arm(ARM_GIVE * arm_torque()), motor_give_error, {"default": {}},
         "the motor pushes back with its full torque all the way (its target speed 0 is "
         "never reached): energy gives the speed at any angle."),
    Case("slider", f"cube on a frictionless prismatic joint along a {SLIDER_DEG:g} deg slope",
         "a = g sin theta", ("acceleration, relative error", "distance from the line, m"),
         lambda: scenes.slider(SLIDER_DEG), slider_errors, {"default": {}}),
    Case("grasp", f"{len(GRASP_ROWS)} cubes (m = 0.1 to 2 kg) squeezed by two-finger "
         f"grippers (F = 0.5 to 70 N, mu = 0.3 to 1), hands accelerating up at a = 0 to 15 "
         f"m/s^2, {GRASP_SECONDS:g} s",
         "held (slip 0) while m (g + a) < 2 mu F, else slides at 2 mu F / m - g",
         ("held cubes' slip, m", "sliding cubes' acceleration, relative error"),
         lambda: scenes.grasps([row[:3] for row in GRASP_ROWS]), grasp_errors,
         PASS_SETTINGS,
         "the fingers are on prismatic joints to kinematic hands: a contact moves a finger only "
         "along its axis (src/solver/mobility.h), so friction on its face is the hand's, and "
         "each motor squeezes with F dt a step. The rows straddle the threshold by 2 to 20 %. "
         "At dt = 1/240 a held cube slips less than 1e-9 m and a sliding one's acceleration "
         "is within 1e-5: the step's friction is mu times its normal impulse (Coulomb's limit "
         "on the step's total), and that is F dt less m_f times the rate at which a finger "
         "closes a gap of up to 1e-6 m (speculative contact, patch.h) left by the carried "
         "depths of a sliding face. A 70 N finger (20 g) would move 6 cm in a step at 1/240 "
         "if nothing stopped it, through the 5 cm cube: its contact is found where it meets "
         "the cube (continuous collision, which for_scene switches on for the motors' "
         "speeds); with the narrow phase in every pass, and at dt >= 1/60, where it would "
         "move 1 m, the 70 N rows lose their grip."),
    Case("stack_drift", f"{STACK_COUNT}-cube stack resting for {STACK_SECONDS:g} s", "at rest: drift 0",
         ("largest displacement, m",), lambda: scenes.cube_stack(STACK_COUNT), stack_drift,
         {**PASS_SETTINGS, "no shock propagation": {"shock_sweeps": 0}}),
    Case("block_on_block", f"1 kg block pulled by {BLOCK_FORCE:g} N on a frictionless floor, a 1 kg "
         f"cube sliding on it (mu = {scenes.BLOCK_MU:g}), {BLOCK_SECONDS:g} s",
         "momentum F T; the cube at mu g t",
         ("momentum, relative error", "cube speed, relative error"), scenes.block_on_block,
         block_on_block_errors,
         {**PASS_SETTINGS, "no friction reactions": {"patch_reactions": False}},
         "shock propagation holds the lower block frozen while it resolves the cube on it; the "
         "sliding friction it applies there is passed on to the block as its reaction and the "
         "levels resolved again (SolverConfig.patch_reactions); without that the momentum grows "
         "beyond F T. At dt = 1/30 the cube, its slip first order in dt, reaches the block's "
         "back edge in the last steps and tips over it, resolved by single impulses, whose "
         "reactions are passed on too: the momentum is F T to round-off at every dt, the "
         "cube's speed off by 9% there. A static patch wrench's reaction is not passed on "
         "(docs/architecture.md): where the cube sticks (mu = 1), 5e-5 above F T."),
    Case("block_sticking", f"1 kg block pulled by {BLOCK_FORCE:g} N on a frictionless floor, a 1 kg "
         f"cube on its centre sticking to it (mu = {STICKING_MU:g}), {BLOCK_SECONDS:g} s",
         "momentum F T; both at F t / (2 m)",
         ("momentum, relative error", "cube speed, relative error"),
         lambda: scenes.block_on_block(STICKING_MU, 0.0), block_sticking_errors, PASS_SETTINGS,
         "the contact passes leave the cube slipping slightly on the block (its patch and the "
         "block's floor patch, resolved in turn, disturb each other); shock propagation stops "
         "the slip with a static patch wrench against the frozen block, whose reaction is not "
         "passed on (docs/architecture.md): the momentum ends 4e-5 above F T (4% with 2 "
         "contact passes), where 1e-6 is the aim. Passed on, a pyramid's levels needed 9 "
         "rounds a step to settle; cut at 4, it spread."),
    Case("heavy_top", f"symmetric top (I = {HEAVY_TOP_MOMENTS[0]:g}, {HEAVY_TOP_MOMENTS[2]:g} "
         f"kg m^2) spinning at {HEAVY_TOP_SPIN:g} rad/s on its tip, tilted {HEAVY_TOP_TILT:g} deg, "
         f"frictionless floor, e = 0, {HEAVY_TOP_SECONDS:g} s",
         "steady precession: Omega (I3 w3 - I1 Omega cos theta) = m g l; energy constant",
         ("precession rate, relative error", "energy growth, relative"),
         lambda: scenes.spinning_top(HEAVY_TOP_MOMENTS, HEAVY_TOP_SPIN, HEAVY_TOP_TILT,
                                     steady_precession()),
         heavy_top_errors, {**PASS_SETTINGS, "lifts free of cost": {"overlap_energy": False}},
         "a symmetric body's rotation is its exact torque-free motion (integrate.h), at any "
         "|omega| dt (1.25 rad at dt = 1/240; Buss's updates were unstable from ~0.4), and the "
         "contact stages predict its pose by the same motion. The tip's impulses are judged by "
         "the instantaneous velocity of the contact point, while the axis nutates within the "
         "step (|L| dt / I1 = 2.3 rad at 1/240): each step sinks the tip ~0.14 mm, which the "
         "overlap correction lifts out. What a step would gain by it is taken from the top's "
         "kinetic energy (SolverConfig.overlap_energy; free of cost, the energy grew 0.5% in "
         "2 s at 1/240): the energy never exceeds E0, and at 1/240 ends 8e-6 below it (the "
         "spin 1e-5 above). At 1/120 the nutation turns 4.6 rad a step, past half a turn, and "
         "the tilt wanders (24 to 33 deg; 18 to 39 at 1/60): the rate is off by 6% (18% at "
         "1/60)."),
    Case("plank_on_bars", "1 kg plank 1 x 0.1 x 0.02 m across two round bars (r = 2 cm), mu = 0.5, "
         f"{PLANK_SECONDS:g} s", "at rest", ("largest point speed, m/s", "centre moved, m"),
         scenes.plank_on_bars, plank_on_bars_errors, PASS_SETTINGS,
         "a capsule across a face narrower than itself touches it along a segment: its two "
         "ends are the contacts (narrow_cores.cpp); with one point the plank rocked and crept."),
    Case("tiny_on_huge", "1 mm cube dropped 2 cm onto a 1 m cube (mass ratio 1e9), 1 s",
         "at rest", ("largest point speed, m/s",), scenes.tiny_on_huge, tiny_on_huge_error,
         {**PASS_SETTINGS, "neither contact patches nor reactions":
             {"contact_patches": False, "patch_reactions": False}},
         "between two movable bodies the contact stage resolves a face patch by the patch "
         "wrench (SolverConfig.contact_patches), and shock propagation's patch wrench may take "
         "back part of the step's normal impulse (SolverConfig.patch_reactions); either holds "
         "the tiny cube at rest. With neither (one impulse at the patch's centroid) it still "
         "rocks at dt = 1/60: 7e-9 m/s after 1 s, 2e-6 m/s where its impact is found at the "
         "end of the step (continuous off) rather than where it meets the cube."),
    Case("knife_edges", "1 kg plank on two frictionless bars (r = 5 mm) at x = -0.3 and 0.2 m, "
         "reactions reported by World.contacts after 1 s", "lever rule: 0.4 m g and 0.6 m g",
         ("reaction, largest error relative to m g",),
         lambda: scenes.plank_on_bars(KNIFE_BARS, friction=0.0, radius=0.005), knife_edge_error,
         {**PASS_SETTINGS, "no lever rule": {"patch_reactions": False}},
         "both bars hold the plank in one patch; its impulse is split between their pairs by "
         "the patch's linear pressure distribution (SolverConfig.patch_reactions), which for "
         "two lines is the lever rule; without it the whole impulse is reported on one bar. At "
         "dt = 1/30 the plank, which falls g dt^2 = 11 mm a step against bars 10 mm thick, "
         "is found on them by continuous collision (continuous off: 3e-4); with the narrow "
         "phase in every pass there, 1.3e-6."),
)
"""Every closed-form case of the accuracy report, in report order."""
