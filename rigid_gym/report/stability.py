"""Stiff and extreme cases, each judged by numeric pass criteria.

Every case runs one or more worlds with :func:`simulate`, which records whether the state
stayed finite, the largest growth of total energy, the deepest overlap (sampled) and the
largest displacement, and turns them into :class:`Check` s against bounds stated here with
their reasons. A case passes when all its checks pass; nothing is retuned to pass.

Bounds used throughout (the reasons are printed in the report):
* energy: E(t) - E(0) <= ``ENERGY_ROUND_OFF`` x (KE0 + sum m |g| |z|): the impulse step can
  only remove energy (restitution <= 1, inelastic contact passes), so any growth beyond float64
  round-off of the energy sum (1e-16 per term, with room for 1e4 steps and a 100x margin) is
  a solver error;
* penetration: 2 % of the thinnest dimension of the bodies in contact (2 mm for the 0.1 m
  cubes): below what a viewer notices, and well above the g dt^2 = 0.17 mm one step of gravity
  can sink a resting body at dt = 1/240;
* drift of a resting configuration: 1 mm (1 % of a cube's edge) over the whole run.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

import rigid_gym as rg
from rigid_gym import quaternion as quat
from rigid_gym._core import DYNAMIC
from rigid_gym.report import scenes
from rigid_gym.report.scenes import CUBE_HALF, G

ENERGY_ROUND_OFF = 1e-10
"""Allowed energy growth as a fraction of the energy scale KE0 + sum m |g| |z| (see above)."""
PENETRATION_FRACTION = 0.02
"""Allowed overlap as a fraction of the thinnest body dimension in contact."""
DRIFT_BOUND = 1e-3
"""Allowed displacement of any body of a resting configuration, m."""
PROBES = 20
"""Overlap is sampled (``World.contacts``) this many times per run, evenly, and at the end."""


@dataclass(frozen=True)
class Check:
    """One pass criterion: ``value`` (in ``unit``) must be <= ``bound`` (>= when
    ``at_least``); NaN never passes. ``reason`` says why the bound is what it is."""

    name: str
    value: float
    bound: float
    unit: str
    reason: str
    at_least: bool = False

    @property
    def passed(self) -> bool:
        if not np.isfinite(self.value):
            return False
        return self.value >= self.bound if self.at_least else self.value <= self.bound


@dataclass
class Run:
    """What :func:`simulate` saw. finite: state finite throughout; energy_gain J (max of
    E(t) - E(0)); energy_scale J; depth m (deepest sampled overlap); drift m (largest
    displacement from the start); cost: wall seconds of World.step per simulated second."""

    world: rg.World
    finite: bool
    energy_gain: float
    energy_scale: float
    depth: float
    drift: float
    cost: float


@dataclass
class StiffResult:
    """One case: checks, optional extra table (header, rows) and the solver phases used."""

    key: str
    title: str
    checks: list[Check]
    cost: float
    phases: dict
    table: tuple[list[str], list[list[str]]] | None = None
    note: str = ""

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)


def total_energy(world: rg.World) -> float:
    """Kinetic plus gravitational potential energy, J."""
    return float(world.kinetic_energy() + world.potential_energy())


def energy_scale(world: rg.World) -> float:
    """KE0 + sum m |g| |z| over dynamic bodies, J: the size of the terms summed into E."""
    dynamic = world.model.motion == DYNAMIC
    mass = 1.0 / world.model.inverse_mass[0, dynamic]
    g = np.linalg.norm(world.model.gravity)
    return float(world.kinetic_energy() + np.sum(mass * g * np.abs(world.position[dynamic, 2])))


def simulate(world: rg.World, seconds: float, probes: int = PROBES) -> Run:
    """Step ``world`` for ``seconds`` (s), watching energy every step and overlap ``probes``
    times, with its stages timed so that ``world.profile()`` has each phase's share (the cost
    then includes a clock read per phase). Stops early (finite=False) if the state becomes
    non-finite."""
    world.profiling = True
    steps = round(seconds / world.dt)
    if steps < 1:
        raise ValueError(f"simulate: seconds must cover at least one step of {world.dt} s, "
                         f"got {seconds!r}")
    start = world.position.copy()
    e0, scale = total_energy(world), energy_scale(world)
    probe_at = set(np.linspace(0, steps, probes + 1).astype(int)[1:])
    gain, depth, stepping, finite = 0.0, world.contacts().depth.max(initial=0.0), 0.0, True
    for k in range(1, steps + 1):
        t0 = time.perf_counter()
        world.step()
        stepping += time.perf_counter() - t0
        energy = total_energy(world)
        if not np.isfinite(energy) or not np.all(np.isfinite(world.position)):
            finite = False
            break
        gain = max(gain, energy - e0)
        if k in probe_at:
            depth = max(depth, world.contacts().depth.max(initial=0.0))
    drift = float(np.abs(world.position - start).max()) if finite else float("nan")
    return Run(world, finite, gain, scale, float(depth), drift, stepping / (world.steps * world.dt))


# -- the checks every case shares ------------------------------------------------------------

def finite_check(run: Run, label: str = "") -> Check:
    return Check(f"{label}state finite (1 = yes)", float(run.finite), 1.0, "",
                 "NaN or inf anywhere is a failure", at_least=True)


def energy_check(run: Run, label: str = "") -> Check:
    return Check(f"{label}energy growth", run.energy_gain, ENERGY_ROUND_OFF * run.energy_scale,
                 "J", f"impulses only remove energy; {ENERGY_ROUND_OFF:g} of the energy scale "
                 f"{run.energy_scale:.3g} J is round-off")


def penetration_check(run: Run, thinnest: float, label: str = "") -> Check:
    return Check(f"{label}deepest overlap", run.depth, PENETRATION_FRACTION * thinnest, "m",
                 f"{PENETRATION_FRACTION:.0%} of the thinnest dimension in contact "
                 f"({thinnest:g} m)")


def drift_check(run: Run, label: str = "") -> Check:
    return Check(f"{label}largest drift", run.drift, DRIFT_BOUND, "m",
                 "a resting configuration must stay put (1% of a cube edge)")


def resting_checks(run: Run, thinnest: float = 2 * CUBE_HALF, label: str = "") -> list[Check]:
    return [finite_check(run, label), energy_check(run, label),
            penetration_check(run, thinnest, label), drift_check(run, label)]


def resting_case(key: str, title: str, scene: rg.Scene, seconds: float) -> StiffResult:
    """A configuration that must stay at rest for ``seconds`` at dt = 1/240 s."""
    run = simulate(rg.World(scene, dt=1 / 240), seconds)
    return StiffResult(key, title, resting_checks(run), run.cost, run.world.profile())


# -- the cases ---------------------------------------------------------------------------------

def towers(scale: float) -> list[StiffResult]:
    """10-, 20- and 40-cube towers (0.1 m cubes, 1 kg, mu 0.5) standing for 10 s x scale."""
    return [resting_case(f"tower_{n}", f"{n}-cube tower, {10 * scale:g} s",
                         scenes.cube_stack(n), 10 * scale) for n in (10, 20, 40)]


def pyramid(scale: float) -> list[StiffResult]:
    """The 55-box pyramid (10 rows, each box on two) standing for 10 s x scale."""
    return [resting_case("pyramid_55", f"55-box pyramid, {10 * scale:g} s", scenes.pyramid(10),
                         10 * scale)]


def heavy_on_light(scale: float) -> list[StiffResult]:
    """A cube 100x and 1000x heavier than the cube under it, 10 s x scale."""
    return [resting_case(f"heavy_on_light_{r}", f"heavy on light {r}:1, {10 * scale:g} s",
                         scenes.cube_stack(2, masses=[1.0, float(r)]), 10 * scale)
            for r in (100, 1000)]


BALL_OFFSETS = (0.02, 0.025, 0.03)  # m: over the box's top face, its edge, just beyond it


def ball_on_light_box(scale: float) -> list[StiffResult]:
    """A 0.5 kg ball dropped at 3 m/s on a 10 g box (50:1) over its top face, its edge and just
    beyond it, 0.25 s x scale each: the ball strikes the box's edge on a slanted normal, and
    shock propagation's reaction to that impulse must not spin the light box up (it sent it
    off at 36 m/s, 41 J from the ball's 2.3 J)."""
    checks, cost, phases = [], 0.0, {}
    for offset in BALL_OFFSETS:
        label = f"{offset * 100:g} cm off axis: "
        run = simulate(rg.World(scenes.ball_on_box_edge(offset), dt=1 / 240),
                       max(0.25 * scale, 1 / 240))
        checks += [finite_check(run, label), energy_check(run, label)]
        cost, phases = max(cost, run.cost), run.world.profile()
    return [StiffResult("ball_on_light_box", "0.5 kg ball dropped at 3 m/s on a 10 g box's top "
                        f"edge, {0.25 * scale:g} s", checks, cost, phases)]


SPIN_RATE = 300.0  # rad/s
SPIN_TILT = np.radians(4.0)  # rad: how far the spin axis starts from the major principal axis
SPIN_DT = 1 / 60


def fast_spinner(scale: float) -> list[StiffResult]:
    """Torque-free body I = (1, 2, 3) kg m^2 at |omega| = 300 rad/s with dt = 1/60 s: |omega|
    dt = 5 rad, 3.2 quarter turns per step (the update sub-steps to quarter turns). Once about
    the major axis exactly (the exact rotation update is exact there) and once 4 deg off it
    (the body wobbles at ~300 rad/s, the rate the update must follow)."""
    checks, cost, profile = [], 0.0, {}
    for label, tilt in (("on axis: ", 0.0), ("4 deg off axis: ", SPIN_TILT)):
        omega = SPIN_RATE * np.array([np.sin(tilt), 0.0, np.cos(tilt)])
        world = rg.World(scenes.spinning_body((1.0, 2.0, 3.0), omega), dt=SPIN_DT)
        e0, l0 = world.kinetic_energy(), world.body_angular_momentum[0].copy()
        run = simulate(world, 10 * scale)
        energy = abs(world.kinetic_energy() / e0 - 1.0)
        momentum = np.linalg.norm(world.body_angular_momentum[0] - l0) / np.linalg.norm(l0)
        checks += [finite_check(run, label),
                   Check(f"{label}|L| change, relative", float(momentum), 1e-12, "",
                         "world L is the stored state and no torque acts: exact to round-off"),
                   Check(f"{label}|E/E0 - 1| at the end", float(energy), 1e-3, "",
                         "E = L.omega/2 measures the orientation error; 0.1% keeps the "
                         "motion recognisable"),
                   energy_check(run, label)]
        cost, profile = max(cost, run.cost), world.profile()
    return [StiffResult("fast_spinner", f"fast spinner, |omega| dt = {SPIN_RATE * SPIN_DT:.1f} "
                        f"rad, {10 * scale:g} s", checks, cost, profile)]


ROD_RADIUS, ROD_HALF_LENGTH = 0.01, 0.49  # m: 1.0 m long, 0.02 m thick (50:1)


def thin_rod(scale: float) -> list[StiffResult]:
    """A 1 kg capsule rod 50:1 dropped from 0.5 m tilted 30 deg onto the ground (mu 0.5);
    after 3 s x scale it must lie flat (centre height = radius within 2% of the diameter)."""
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    tilt = np.radians(30.0)
    scene.add_body(rg.Capsule(ROD_RADIUS, ROD_HALF_LENGTH), mass=1.0, friction=0.5,
                   position=(0, 0, 0.5), orientation=(np.cos(tilt / 2), np.sin(tilt / 2), 0, 0))
    seconds = max(3 * scale, 0.25)
    run = simulate(rg.World(scene, dt=1 / 240), seconds)
    height = abs(run.world.position[1, 2] - ROD_RADIUS) if run.finite else float("nan")
    checks = [finite_check(run), energy_check(run),
              penetration_check(run, 2 * ROD_RADIUS)]
    if scale >= 1:
        checks.append(Check("centre height - radius at the end", float(height),
                            PENETRATION_FRACTION * 2 * ROD_RADIUS, "m",
                            "the rod must come to lie flat on the ground"))
    return [StiffResult("thin_rod", f"thin rod 50:1 dropped at 30 deg, {seconds:g} s", checks,
                        run.cost, run.world.profile())]


def elastic(scale: float) -> list[StiffResult]:
    """e = 1: a ball dropped from 1 m and a cube dropped tilted (corner first) from 0.5 m,
    10 s x scale each: energy may never grow."""
    cube = rg.Scene()
    cube.add_ground(restitution=1.0, friction=0.5)
    q = quat.normalize(np.array([0.9, 0.3, 0.2, 0.1]))
    cube.add_body(rg.Box((CUBE_HALF,) * 3), mass=1.0, restitution=1.0, position=(0, 0, 0.5),
                  orientation=q)
    checks, cost, phases = [], 0.0, {}
    for label, scene in (("ball: ", scenes.dropped_ball(1.0)), ("tilted cube: ", cube)):
        run = simulate(rg.World(scene, dt=1 / 240), 10 * scale)
        checks += [finite_check(run, label), energy_check(run, label),
                   penetration_check(run, 2 * CUBE_HALF, label)]
        cost, phases = max(cost, run.cost), run.world.profile()
    return [StiffResult("restitution_1", f"e = 1, ball and tilted cube, {10 * scale:g} s", checks,
                        cost, phases)]


FLAT_BOX = (0.2, 0.2, 0.01)  # m half extents: cannot tip while mu < 20


def friction_extremes(scale: float) -> list[StiffResult]:
    """mu = 0: a cube sliding at 1 m/s keeps its velocity exactly, and slides down a 30 deg
    incline at g sin theta. mu = 5: a flat box (0.4 x 0.4 x 0.02 m, so it cannot tip) stops
    after v0^2 / (2 mu g), and holds on a 70 deg incline (tan 70 = 2.7 < 5)."""
    seconds = max(2 * scale, 0.5)
    results = []
    run = simulate(rg.World(scenes.sliding_box(0.0, 1.0), dt=1 / 240), seconds)
    slide = Check("mu=0 sliding: |v - v0|", float(abs(run.world.velocity[1, 0] - 1.0)), 1e-12,
                  "m/s", "no friction: nothing may slow the box (round-off only)")
    world = rg.World(scenes.incline(30.0, 0.0), dt=1 / 240)
    world.step(round(0.5 / world.dt))
    v0 = world.velocity[1].copy()
    incline_run = simulate(world, 0.5)
    a = np.linalg.norm(world.velocity[1] - v0) / 0.5
    accel = Check("mu=0 incline: |a / (g sin theta) - 1|", float(abs(a / (G * 0.5) - 1.0)), 1e-6,
                  "", "frictionless incline: a = g sin theta exactly")
    results.append(StiffResult("mu_0", f"mu = 0, {seconds:g} s", [
        finite_check(run), energy_check(run), slide, penetration_check(run, 2 * CUBE_HALF),
        energy_check(incline_run, "incline: "), accel], run.cost, run.world.profile()))

    mu, v = 5.0, 2.0
    run = simulate(rg.World(scenes.sliding_box(mu, v, FLAT_BOX), dt=1 / 240), seconds)
    exact = v * v / (2 * mu * G)
    stop = Check("mu=5 stop distance error", float(abs(run.world.position[1, 0] - exact)),
                 0.01 * exact + v / 240, "m", "as the slide-to-stop test: 1% + v0 dt")
    world = rg.World(scenes.incline(70.0, mu, FLAT_BOX), dt=1 / 240)
    world.step(round(0.5 / world.dt))
    hold = simulate(world, seconds)
    creep = Check("mu=5 70 deg incline: creep", hold.drift, 1e-6, "m",
                  "static friction holds exactly (as the 20 deg incline test)")
    results.append(StiffResult("mu_5", f"mu = 5, {seconds:g} s", [
        finite_check(run), energy_check(run), stop, penetration_check(run, 2 * FLAT_BOX[2]),
        energy_check(hold, "incline: "), creep], run.cost, run.world.profile()))
    return results


WALL_HALF = 0.005  # m: the wall is 1 cm thick
BALL_RADIUS = 0.05  # m
TUNNEL_DT = 1 / 240


def crosses_wall(speed: float, dt: float = TUNNEL_DT, continuous: bool = True) -> bool:
    """Whether a 1 kg ball (radius 5 cm) fired at ``speed`` (m/s) along +x, no gravity, from
    0.5 m before a static 1 cm wall (e = 0) ends up behind it; ``continuous``: the config's."""
    scene = rg.Scene(gravity=(0.0, 0.0, 0.0))
    scene.add_body(rg.Box((WALL_HALF, 1.0, 1.0)), static=True, friction=0.0)
    scene.add_body(rg.Sphere(BALL_RADIUS), mass=1.0, friction=0.0, position=(-0.5, 0, 0),
                   velocity=(speed, 0, 0))
    world = rg.World(scene, dt=dt,
                     config=rg.SolverConfig.for_scene(scene, dt, continuous=continuous))
    world.step(int(np.ceil(1.0 / (speed * dt))) + 2)
    return bool(world.position[1, 0] > 0.0)


def crossing_onset(speeds, crossed, bisections: int, continuous: bool) -> float:
    """The speed (m/s) where the ball first crosses, bisected between the last of ``speeds``
    that did not and the first that did (``crossed``); inf where none did."""
    if not any(crossed):
        return float("inf")
    first = int(np.argmax(crossed))
    low, high = (speeds[first - 1] if first else 0.0), speeds[first]
    for _ in range(bisections):
        mid = 0.5 * (low + high)
        low, high = (low, mid) if crosses_wall(mid, continuous=continuous) else (mid, high)
    return high


def tunnelling(scale: float) -> list[StiffResult]:
    """Fire the ball at speeds from 1 to 1000 m/s; bisect the speed where it first crosses,
    with continuous collision (the default) and without. Criterion: no crossing while v dt <
    the wall thickness (the guarantee of discrete detection, notes/physics.md §4)."""
    speeds = np.geomspace(1.0, 1000.0, 13 if scale >= 1 else 7)
    bisections = 12 if scale >= 1 else 5
    crossed = [crosses_wall(v) for v in speeds]
    discrete = [crosses_wall(v, continuous=False) for v in speeds]
    rows = [[f"{v:.3g}", f"{v * TUNNEL_DT * 100:.2f}", "crossed" if c else "stopped",
             "crossed" if d else "stopped"] for v, c, d in zip(speeds, crossed, discrete)]
    onset = crossing_onset(speeds, crossed, bisections, True)
    discrete_onset = crossing_onset(speeds, discrete, bisections, False)
    safe = 2 * WALL_HALF / TUNNEL_DT
    held = (f"no speed up to {speeds[-1]:.3g} m/s crosses" if onset == float("inf")
            else f"crossing starts at {onset:.3g} m/s")
    note = (f"With continuous collision (src/solver/continuous.h) {held}: the ball's contacts "
            "with the wall are found where it meets it. "
            f"Found at the end of the step alone (continuous=False), crossing starts at "
            f"{discrete_onset:.3g} m/s: v dt = {discrete_onset * TUNNEL_DT * 100:.2f} cm per "
            f"step against 1 cm of wall and a {2 * BALL_RADIUS * 100:g} cm ball. What happens "
            "then: once one step carries the ball's centre past the wall's mid-plane, the "
            "nearest wall face is the far one, and the impulse pushes the ball on through. So "
            "crossing becomes possible once v dt exceeds the ball's radius plus half the wall "
            f"({(BALL_RADIUS + WALL_HALF) * 100:.1f} cm); where the steps fall decides the exact "
            "speed. Discrete detection alone guarantees no crossing only while v dt < the wall "
            f"thickness ({safe:.3g} m/s).")
    check = Check("speed where crossing starts (the fastest tried where none crosses)",
                  float(min(onset, speeds[-1])), safe, "m/s",
                  "discrete detection must hold while v dt < wall thickness", at_least=True)
    return [StiffResult("tunnelling", f"ball vs 1 cm wall, dt = 1/{round(1 / TUNNEL_DT)}",
                        [check], float("nan"), {},
                        (["speed (m/s)", "v dt (cm)", "outcome", "continuous off"], rows), note)]


DTS = (1 / 1000, 1 / 240, 1 / 120, 1 / 60, 1 / 30)


def dt_range(scale: float) -> list[StiffResult]:
    """The 10-cube tower for 5 s x scale at each dt from 1/1000 to 1/30 s."""
    checks, cost, phases = [], 0.0, {}
    for dt in DTS:
        run = simulate(rg.World(scenes.cube_stack(10), dt=dt), max(5 * scale, 4 * dt))
        checks += resting_checks(run, label=f"dt 1/{round(1 / dt)}: ")
        if dt == 1 / 240:
            cost, phases = run.cost, run.world.profile()
    return [StiffResult("dt_range", f"10-cube tower at dt = 1/1000 ... 1/30, {5 * scale:g} s each",
                        checks, cost, phases)]


SETTLE_DTS = (1 / 240, 1 / 60, 0.1)
SETTLE_SLOP = 1e-4  # m: overlap.h's OVERLAP_SLOP, the overlap the solver leaves uncorrected


def drop_and_settle(scale: float) -> list[StiffResult]:
    """A cube dropped 1 m onto the ground, and onto a cube resting there, at dt = 1/240, 1/60
    and 0.1 s: after 3 s each rests within the slop of its support (height error, either
    sign)."""
    checks, rows = [], []
    for on_cube in (False, True):
        for dt in SETTLE_DTS:
            world = rg.World(scenes.dropped_cubes(1.0, on_cube), dt=dt)
            world.step(round(3.0 / dt))
            top = len(world.position) - 1
            exact = CUBE_HALF * (3 if on_cube else 1)
            error = float(abs(world.position[top, 2] - exact))
            where = "on a cube" if on_cube else "on the ground"
            label = f"dt {dt:g} s" if dt >= 0.05 else f"dt 1/{round(1 / dt)}"
            checks.append(Check(f"{where}, {label}: rest height error", error, SETTLE_SLOP, "m",
                                "within the overlap slop of its support"))
            rows.append([where, label, f"{(world.position[top, 2] - exact) * 1e3:+.4f}"])
    return [StiffResult("drop_settle", "cube dropped 1 m, alone and onto a cube, 3 s", checks,
                        float("nan"), {}, (["support", "dt", "rest height - exact (mm)"], rows))]


def mass_range(scale: float) -> list[StiffResult]:
    """Two 7-cube towers in one scene with masses 1e-3, 1e-2, ..., 1e3 kg: light at the bottom
    (each cube 10x heavier than the one under it) and heavy at the bottom, 10 s x scale."""
    masses = np.logspace(-3, 3, 7)
    scene = scenes.cube_stack(7, masses=masses)
    for k, m in enumerate(masses[::-1]):
        scene.add_body(rg.Box((CUBE_HALF,) * 3), mass=float(m), friction=0.5,
                       position=(0.5, 0, CUBE_HALF + 2 * CUBE_HALF * k))
    return [resting_case("mass_range", f"masses 1e-3 to 1e3 kg, two towers, {10 * scale:g} s",
                         scene, 10 * scale)]


SLEEP_SPEED = 0.01
"""m/s: the stopping threshold the sleeping case measures (SolverConfig.sleep_speed)."""
TOUCH = 1e-3
"""m: the ball touches a box once they are this close (contacts stop a body short of its
partner by up to |g| dt^2, the speculative gap, so a resolved touch need not overlap)."""


def _first(flags: list[bool], start: int = 0) -> int:
    """Index of the first true flag from ``start`` on, or len(flags)."""
    return next((k for k in range(start, len(flags)) if flags[k]), len(flags))


def sleeping(scale: float) -> list[StiffResult]:
    """What sleeping changes. Exact sleeping (the default) on the 10-cube stack, a bit-exact
    fixed point, against stepping every body, 10 s x scale. Stopping slow islands
    (sleep_speed = SLEEP_SPEED) on the 55-box pyramid, which round-off keeps moving: how far
    the stop leaves the boxes from where exact stepping has them, how far they move while
    asleep, and how many steps after a ball rolling into the pyramid first touches it (comes
    within TOUCH) the island is still asleep."""
    stack = scenes.cube_stack(10)
    on = rg.World(stack, dt=1 / 240)
    off = rg.World(stack, dt=1 / 240, config=rg.SolverConfig.for_scene(stack, sleep=False))
    for world in (on, off):
        world.step(round(10 * scale * 240))
    exact_gap = float(np.abs(on.position - off.position).max())
    scene = scenes.pyramid(10)
    ball = scene.add_body(rg.Sphere(0.03), mass=0.2, friction=0.5, position=(-1.5, 0.0, 0.03),
                          velocity=(1.0, 0.0, 0.0))
    boxes = np.arange(1, ball)
    stopping = rg.World(scene, dt=1 / 240, config=rg.SolverConfig.for_scene(
        scene, sleep_speed=SLEEP_SPEED))
    exact = rg.World(scene, dt=1 / 240)
    asleep, touched, poses, exact_poses = [], [], [], []
    for _ in range(round(3.0 / stopping.dt)):
        stopping.step()
        exact.step()
        contacts = stopping.contacts(margin=TOUCH)
        partner = np.where(contacts.body_a == ball, contacts.body_b,
                           np.where(contacts.body_b == ball, contacts.body_a, -1))
        asleep.append(bool(stopping.sleeping()[boxes].all()))
        touched.append(bool(np.isin(partner, boxes).any()))
        poses.append(stopping.position[boxes].copy())
        exact_poses.append(exact.position[boxes].copy())
    stopped, touch = _first(asleep), _first(touched)
    woken = _first([not a for a in asleep], stopped)
    if not stopped < min(touch, woken) < len(asleep):
        raise RuntimeError(f"sleeping case: the pyramid should stop (step {stopped}) before the "
                           f"ball touches it ({touch}) or wakes it ({woken}) within 3 s")
    before = min(touch, woken) - 1
    moved = float(np.abs(poses[before] - exact_poses[before]).max())
    drift = float(np.abs(np.array(poses[stopped:before + 1]) - poses[stopped]).max())
    late = max(0, woken - touch)  # the ball's pair is listed a few steps before the touch
    checks = [
        Check("stack, sleeping on vs off: largest position difference", exact_gap, 0.0, "m",
              "a bit-exact fixed point is skipped exactly: no bit may change"),
        Check(f"pyramid stopped at {SLEEP_SPEED:g} m/s: distance from exact stepping", moved,
              DRIFT_BOUND, "m", "stopping may move a resting configuration no further than it "
              "may drift"),
        Check("pyramid asleep: drift", drift, 0.0, "m",
              "a stopped island is a fixed point of the step"),
        Check("steps the island sleeps on after the ball's first touch", float(late), 0.0,
              "steps", "a touch wakes the island no later than the step it happens")]
    rows = [["stack, exact sleeping", f"{exact_gap:.3g}", "—", "—"],
            [f"pyramid, stopped at {SLEEP_SPEED:g} m/s after {stopped / 240:.2f} s",
             f"{moved:.3g}", f"{drift:.3g}", f"{late} (woken {touch - woken} steps before)"]]
    return [StiffResult("sleeping", "sleeping: exact on a stack, stopping slow islands on a "
                        "pyramid", checks, float("nan"), {},
                        (["scene", "difference from stepping every body (m)",
                          "drift asleep (m)", "steps asleep after the touch"], rows))]


def big_pile(scale: float) -> list[StiffResult]:
    """1000 boxes, spheres and capsules (5 cm) dropped into a pit, 2 s (quick: 100, 0.1 s):
    finite, no energy growth, overlap under 2% of the 4 cm thinnest body."""
    count, seconds = (1000, 2.0) if scale >= 1 else (100, 0.1)
    run = simulate(rg.World(scenes.pile(count), dt=1 / 240), seconds, probes=5)
    return [StiffResult("pile", f"pile of {count} bodies, {seconds:g} s", [
        finite_check(run), energy_check(run), penetration_check(run, 0.04)], run.cost,
        run.world.profile())]


CHAIN_ANGLE, CHAIN_SECONDS, CHAIN_DT = 0.5, 100.0, 1 / 240  # rad, s, s
CHAIN_SEPARATION = 1e-6
"""Allowed separation of a joint's two anchors, m."""
CHAIN_GROWTH = 0.02
"""Allowed energy growth, as a fraction of the chain's swing energy (see below)."""


def joint_separation(world: rg.World) -> float:
    """The largest distance (m) between the two anchors of any joint of ``world``'s scene
    (one world), at the current poses."""
    joints = world.scene.joints
    x, r = world.position, world.rotation
    worst = 0.0
    for j in joints:
        a = x[j.body_a] + r[j.body_a] @ j.anchor_a
        b = j.anchor_b if j.body_b < 0 else x[j.body_b] + r[j.body_b] @ j.anchor_b
        worst = max(worst, float(np.linalg.norm(a - b)))
    return worst


def hanging_chain(scale: float) -> list[StiffResult]:
    """A chain of 10 links on revolute joints, hinged to the world, released straight at 0.5
    rad from the vertical and swinging for 100 s at dt = 1/240 (every joint pre-stabilised
    and projected each step, src/solver/joints.h). The joints must hold, and the energy,
    which no force adds or removes, must not grow."""
    world = rg.World(scenes.hanging_chain(CHAIN_ANGLE), dt=CHAIN_DT)
    world.profiling = True
    links = scenes.CHAIN_LINKS
    bottom = -G * 0.1 * scenes.CHAIN_LINK * sum(k + 0.5 for k in range(links))
    e0 = total_energy(world)
    swing = e0 - bottom
    steps = round(CHAIN_SECONDS * scale / world.dt)
    energy, separation, finite, stepping = np.empty(steps), 0.0, True, 0.0
    for k in range(steps):
        t0 = time.perf_counter()
        world.step()
        stepping += time.perf_counter() - t0
        energy[k] = total_energy(world) - e0
        separation = max(separation, joint_separation(world))
        if not np.isfinite(energy[k]):
            finite = False
            break
    energy = energy[:k + 1]
    checks = [
        Check("state finite (1 = yes)", float(finite), 1.0, "", "NaN or inf anywhere is a failure",
              at_least=True),
        Check("largest joint separation", separation, CHAIN_SEPARATION, "m",
              "pre-stabilisation puts every joint within 1e-12 m of its anchor at the end of "
              "each step where its Newton steps converge; 1 um is far below anything seen"),
        Check("energy growth / swing energy", float(energy.max() / swing), CHAIN_GROWTH, "",
              "the velocity update is symplectic Euler: energy oscillates by O(g dt v) about "
              "a constant (0.8% of the swing energy at dt = 1/240) and must not grow beyond "
              "that; the table shows it does not drift"),
    ]
    tenths = np.array_split(energy, 10)
    table = (["tenth of the run", "largest energy growth / swing energy"],
             [[str(n + 1), f"{part.max() / swing:.3g}"] for n, part in enumerate(tenths)
              if len(part)])
    return [StiffResult("hanging_chain", f"10-link chain, released at {CHAIN_ANGLE:g} rad, "
                        f"{CHAIN_SECONDS * scale:g} s at dt = 1/240", checks,
                        stepping / (world.steps * world.dt), world.profile(), table,
                        note="Released from 1 rad its end links whip past 100 rad/s (0.4 rad "
                        "a step); pre-stabilisation's Newton steps on the predicted poses "
                        "then fail to converge in some steps and the energy is not kept (up "
                        "to +12% of the swing energy within 100 s, joints apart by up to 1.3 "
                        "mm): such a chain needs a smaller dt.")]


CASES: tuple[Callable[[float], list[StiffResult]], ...] = (
    towers, pyramid, heavy_on_light, ball_on_light_box, fast_spinner, thin_rod, elastic,
    friction_extremes, tunnelling, dt_range, drop_and_settle, mass_range, sleeping, big_pile,
    hanging_chain)
"""Every stiff/extreme case: (scale) -> results; scale 1 is the full report, < 1 shortens
runs (the quick report)."""


def run_all(scale: float) -> list[StiffResult]:
    """Every case at ``scale`` (1 = full durations), in report order."""
    if not 0.0 < scale <= 1.0:
        raise ValueError(f"run_all: scale must be in (0, 1], got {scale!r}")
    return [result for case in CASES for result in case(scale)]

