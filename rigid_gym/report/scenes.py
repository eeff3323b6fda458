"""The standard scenes shared by the tests, the benchmarks and the report.

Every builder returns a fresh :class:`rigid_gym.Scene` (SI units, z up, gravity -9.81 m/s^2
unless stated). Cubes have half edge ``CUBE_HALF`` = 0.05 m (0.1 m edge).
"""

from __future__ import annotations

import numpy as np

import rigid_gym as rg
from rigid_gym import quaternion as quat

G = 9.81
"""Magnitude of gravity, m/s^2."""
CUBE_HALF = 0.05
"""Half edge of the standard cube, m."""


def dropped_ball(restitution: float, height: float = 1.0, radius: float = 0.05) -> rg.Scene:
    """A 1 kg frictionless sphere whose lowest point is ``height`` (m) above the ground, both
    with ``restitution`` (a pair uses the larger)."""
    scene = rg.Scene()
    scene.add_ground(restitution=restitution, friction=0.0)
    scene.add_body(rg.Sphere(radius), mass=1.0, position=(0, 0, height + radius),
                   restitution=restitution, friction=0.0)
    return scene


def free_ball(height: float = 10.0, velocity=(1.0, 0.0, 5.0)) -> rg.Scene:
    """A 1 kg sphere in free flight (no ground) from ``height`` (m) with ``velocity`` (3,) m/s."""
    scene = rg.Scene()
    scene.add_body(rg.Sphere(0.05), mass=1.0, position=(0, 0, height), velocity=velocity)
    return scene


def sliding_box(friction: float, speed: float, half_extents=(CUBE_HALF,) * 3) -> rg.Scene:
    """A 1 kg box (default the standard cube) resting on the ground, launched along +x at
    ``speed`` (m/s)."""
    scene = rg.Scene()
    scene.add_ground(friction=friction)
    scene.add_body(rg.Box(half_extents), mass=1.0, friction=friction,
                   position=(0, 0, half_extents[2]), velocity=(speed, 0, 0))
    return scene


def incline(theta_deg: float, friction: float, half_extents=(CUBE_HALF,) * 3) -> rg.Scene:
    """A 1 kg box (default the standard cube) at rest on a static plane tilted by
    ``theta_deg`` (degrees) about y; the plane is body 0, the box body 1."""
    theta = np.radians(theta_deg)
    q = np.array([np.cos(theta / 2), 0.0, np.sin(theta / 2), 0.0])
    normal = quat.rotate(q, np.array([0.0, 0.0, 1.0]))
    scene = rg.Scene()
    scene.add_body(rg.Plane(), static=True, orientation=q, friction=friction, name="incline")
    scene.add_body(rg.Box(half_extents), mass=1.0, friction=friction,
                   position=normal * half_extents[2], orientation=q)
    return scene


def sliding_sphere(speed: float, friction: float = 0.3, radius: float = 0.05) -> rg.Scene:
    """A 1 kg sphere on the ground launched along +x at ``speed`` (m/s) without spin."""
    scene = rg.Scene()
    scene.add_ground(friction=friction)
    scene.add_body(rg.Sphere(radius), mass=1.0, friction=friction, position=(0, 0, radius),
                   velocity=(speed, 0, 0))
    return scene


def struck_row(count: int, speed: float) -> rg.Scene:
    """``count`` 1 kg standard cubes side by side along +x on a frictionless ground, each
    touching the next (bodies 1..count); the first moves into the others at ``speed`` (m/s).
    Every restitution is 0."""
    scene = rg.Scene()
    scene.add_ground(friction=0.0)
    for k in range(count):
        scene.add_body(rg.Box((CUBE_HALF,) * 3), mass=1.0, friction=0.0,
                       position=(2 * CUBE_HALF * k, 0, CUBE_HALF),
                       velocity=(speed if k == 0 else 0.0, 0, 0))
    return scene


WALL_HALF = 0.005
"""Half the thickness of the thin wall, m (a 1 cm wall)."""
BULLET_HALF = 0.01
"""Half edge of the cubes fired at the wall, m (2 cm cubes)."""


def cubes_at_wall(count: int, speed: float, spread: float, distance: float = 0.3) -> rg.Scene:
    """No gravity: a static wall 1 cm thick and 1 m square (body 0, its faces at
    x = +-WALL_HALF) and ``count`` 0.1 kg cubes of half edge BULLET_HALF, frictionless, e = 0,
    10 cm apart along y, fired along +x at ``speed`` (m/s). Cube k's leading face starts
    ``distance`` + k ``spread`` / ``count`` (m) before the wall's near face: the cubes meet the
    wall at ``count`` phases of a step that travels ``spread``."""
    scene = rg.Scene(gravity=(0.0, 0.0, 0.0))
    scene.add_body(rg.Box((WALL_HALF, 0.5, 0.5)), static=True, friction=0.0, name="wall")
    for k in range(count):
        lead = -WALL_HALF - distance - k * spread / count
        scene.add_body(rg.Box((BULLET_HALF,) * 3), mass=0.1, friction=0.0,
                       position=(lead - BULLET_HALF, 0.1 * (k - (count - 1) / 2), 0.0),
                       velocity=(speed, 0.0, 0.0))
    return scene


TABLE_HALF = (0.15, 0.15, 0.02)
"""Half extents of a table top, m (4 cm thick)."""
PLATE_HALF = (0.05, 0.05, 0.001)
"""Half extents of the dropped plates, m (2 mm thick)."""


def plates_on_tables(tops, release: float) -> rg.Scene:
    """Static table tops (half extents TABLE_HALF) side by side along x, 0.4 m apart, their top
    faces at heights ``tops`` (m), bodies 0 .. len(tops) - 1; above each a 0.05 kg plate (half
    extents PLATE_HALF) lying flat, at rest, its bottom face at ``release`` (m), bodies
    len(tops) ... Every restitution is 0, friction 0.5."""
    scene = rg.Scene()
    for k, top in enumerate(tops):
        scene.add_body(rg.Box(TABLE_HALF), static=True, position=(0.4 * k, 0.0, top - TABLE_HALF[2]),
                       name=f"table{k}")
    for k in range(len(tops)):
        scene.add_body(rg.Box(PLATE_HALF), mass=0.05, position=(0.4 * k, 0.0, release + PLATE_HALF[2]),
                       name=f"plate{k}")
    return scene


def spinning_body(moments, omega) -> rg.Scene:
    """A torque-free body (no gravity) with principal ``moments`` (3,) kg m^2 spinning at
    ``omega`` (3,) rad/s, body axes = world axes at t = 0."""
    scene = rg.Scene(gravity=(0.0, 0.0, 0.0))
    scene.add_body(rg.Box((0.1, 0.2, 0.3)), mass=1.0, inertia=moments, angular_velocity=omega)
    return scene


def cube_stack(count: int, masses=None, friction: float = 0.5) -> rg.Scene:
    """``count`` cubes resting on each other on the ground (bodies 1..count, bottom first),
    1 kg each unless ``masses`` (count,) kg is given."""
    scene = rg.Scene()
    scene.add_ground(friction=friction)
    for k in range(count):
        scene.add_body(rg.Box((CUBE_HALF,) * 3), mass=1.0 if masses is None else masses[k],
                       friction=friction, position=(0, 0, CUBE_HALF + 2 * CUBE_HALF * k))
    return scene


def pyramid(rows: int) -> rg.Scene:
    """A pyramid of 1 kg cubes, ``rows`` on the bottom row, each box resting on two
    (rows (rows + 1) / 2 boxes: 55 for 10 rows)."""
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    for r in range(rows):
        for k in range(rows - r):
            x = (k - (rows - r - 1) / 2) * 2 * CUBE_HALF
            scene.add_body(rg.Box((CUBE_HALF,) * 3), mass=1.0, friction=0.5,
                           position=(x, 0, CUBE_HALF + 2 * CUBE_HALF * r))
    return scene


def pyramid_and_ball(rows: int, speed: float = 1.0) -> rg.Scene:
    """``pyramid(rows)`` and a 0.2 kg ball of 3 cm radius on the ground 2 m from its centre,
    rolling towards it at ``speed`` m/s (away from it for a negative speed): a resting island
    beside one moving body. The ball is the last body."""
    scene = pyramid(rows)
    scene.add_body(rg.Sphere(0.03), mass=0.2, friction=0.5, position=(-2.0, 0.0, 0.03),
                   velocity=(speed, 0.0, 0.0))
    return scene


def pile(count: int, seed: int = 0) -> rg.Scene:
    """``count`` boxes, spheres and capsules (about 5 cm, 500 kg/m^3) in columns of about 8
    over a walled square pit sized for them, about to fall onto each other. Layers are 9 cm
    apart, more than the sum of two bodies' bounding radii (4 + 4.3 cm), so nothing overlaps
    at the start (at 7 cm, randomly turned neighbours started 4.6 mm deep)."""
    rng = np.random.default_rng(seed)
    columns = max(1, int(np.ceil(np.sqrt(count / 8))))
    half = 0.06 * columns
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    for x, y, hx, hy in ((half + 0.05, 0, 0.05, half + 0.1), (-half - 0.05, 0, 0.05, half + 0.1),
                         (0, half + 0.05, half + 0.1, 0.05), (0, -half - 0.05, half + 0.1, 0.05)):
        scene.add_body(rg.Box((hx, hy, 0.5)), position=(x, y, 0.5), static=True)
    shapes = [rg.Box((0.025, 0.025, 0.025)), rg.Sphere(0.025), rg.Capsule(0.02, 0.02)]
    for k in range(count):
        column, layer = k % (columns * columns), k // (columns * columns)
        x = -half + 0.06 + 0.12 * (column % columns)
        y = -half + 0.06 + 0.12 * (column // columns)
        q = rng.normal(size=4)
        scene.add_body(shapes[k % 3], density=500.0, friction=0.5,
                       position=(x + rng.uniform(-0.01, 0.01), y + rng.uniform(-0.01, 0.01),
                                 0.05 + 0.09 * layer), orientation=q / np.linalg.norm(q))
    return scene


BLOCK_HALF = (0.05, 0.05, 0.1)  # m: the 0.1 x 0.1 x 0.2 m block pushed at its top


def standing_block(friction: float) -> rg.Scene:
    """A 1 kg block ``BLOCK_HALF`` standing on the ground, both of friction ``friction``."""
    scene = rg.Scene()
    scene.add_ground(friction=friction)
    scene.add_body(rg.Box(BLOCK_HALF), mass=1.0, position=(0.0, 0.0, BLOCK_HALF[2]),
                   friction=friction)
    return scene


def dropped_cubes(height: float, on_cube: bool = False) -> rg.Scene:
    """A cube released ``height`` (m) above the ground, or above a cube resting on it."""
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    base = 0.0
    if on_cube:
        scene.add_body(rg.Box((CUBE_HALF,) * 3), mass=1.0, friction=0.5,
                       position=(0.0, 0.0, CUBE_HALF))
        base = 2 * CUBE_HALF
    scene.add_body(rg.Box((CUBE_HALF,) * 3), mass=1.0, friction=0.5,
                   position=(0.0, 0.0, base + CUBE_HALF + height))
    return scene



PENDULUM_LENGTH, PENDULUM_BOB = 1.0, 0.01  # m: pivot to the bob's centre, bob radius


def pendulum(amplitude: float) -> rg.Scene:
    """A 1 kg sphere of radius PENDULUM_BOB hinged to the world at the origin about y by a
    revolute joint, its centre PENDULUM_LENGTH below the pivot turned out by ``amplitude``
    (rad), at rest. Body 0; joint 0."""
    scene = rg.Scene()
    bob = scene.add_body(rg.Sphere(PENDULUM_BOB), mass=1.0,
                         position=(PENDULUM_LENGTH * np.sin(amplitude), 0.0,
                                   -PENDULUM_LENGTH * np.cos(amplitude)))
    scene.add_revolute_joint(bob, None, (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    return scene


ROD_HALF = (0.01, 0.01, 0.25)  # m: a 0.5 m rod of square section


def physical_pendulum(amplitude: float) -> rg.Scene:
    """A 1 kg rod (half extents ROD_HALF, long along its z) hinged about y at one end to the
    world at the origin, hanging turned out by ``amplitude`` (rad), at rest. Body 0."""
    scene = rg.Scene()
    turn = np.array([np.cos(0.5 * amplitude), 0.0, -np.sin(0.5 * amplitude), 0.0])
    centre = ROD_HALF[2] * np.array([np.sin(amplitude), 0.0, -np.cos(amplitude)])
    rod = scene.add_body(rg.Box(ROD_HALF), mass=1.0, position=centre, orientation=turn)
    scene.add_revolute_joint(rod, None, (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    return scene


ARM_HALF = (0.2, 0.02, 0.02)  # m: a 0.4 m arm along x


def motor_arm(max_torque: float) -> rg.Scene:
    """A 1 kg arm (half extents ARM_HALF) held horizontal along +x from a revolute joint about
    y at its end (the world origin), whose motor (target speed 0) has ``max_torque`` (N m).
    Gravity turns it down with m g d = 1.962 N m. Body 0."""
    scene = rg.Scene()
    arm = scene.add_body(rg.Box(ARM_HALF), mass=1.0, position=(ARM_HALF[0], 0.0, 0.0))
    scene.add_revolute_joint(arm, None, (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), motor_speed=0.0,
                             max_motor_torque=max_torque)
    return scene


def slider(theta_deg: float) -> rg.Scene:
    """A 1 kg standard cube on a frictionless prismatic joint to the world along a line
    ``theta_deg`` below horizontal (in the x-z plane, descending along +x), at rest. Body 0."""
    theta = np.radians(theta_deg)
    scene = rg.Scene()
    cube = scene.add_body(rg.Box((CUBE_HALF,) * 3), mass=1.0, position=(0.0, 0.0, 0.0))
    scene.add_prismatic_joint(cube, None, (0.0, 0.0, 0.0), (np.cos(theta), 0.0, -np.sin(theta)))
    return scene


GRASP_CUBE_HALF = 0.025  # m: a 5 cm cube
GRASP_FINGER_HALF = (0.01, 0.01, 0.03)  # m: 2 cm wide, 6 cm tall fingers
GRASP_FINGER_MASS = 0.02  # kg
GRASP_OPENING = 0.08  # m: the fingers' widest opening, as a Panda hand's
GRASP_SLOWEST_DT = 0.05  # s: up to this dt each motor pushes with its full force every step
GRASP_SPACING = 0.5  # m between the grippers along y


def gripper(scene: rg.Scene, centre, cube_mass: float, grip: float, friction: float,
            ground: bool = False) -> tuple[int, int, tuple[int, int], tuple[int, int]]:
    """Add a floating parallel-jaw gripper to ``scene`` holding a GRASP_CUBE_HALF cube of
    ``cube_mass`` kg at ``centre`` (3,) m: a kinematic hand above it and two
    GRASP_FINGER_MASS fingers touching its faces across x, each on a prismatic joint to the
    hand along x outwards (coordinate 0 touching the cube, limits open to GRASP_OPENING in
    all, closed to 0) whose motor closes with at most ``grip`` N at a speed no step up to
    GRASP_SLOWEST_DT reaches, so that it squeezes with ``grip`` every step. Every body has
    ``friction``. ground: the cube rests on the ground (added) instead of hanging in the air.
    Returns (hand, cube, (finger -x, finger +x), (their joints))."""
    x, y, z = centre
    c, (fx, _, fz) = GRASP_CUBE_HALF, GRASP_FINGER_HALF
    if ground:
        scene.add_ground(friction=friction)
    bottom = z - c + 0.005  # the fingers' bottom, 5 mm above the cube's
    hand = scene.add_body(rg.Box((c + 2 * fx, 0.02, 0.01)), position=(x, y, bottom + 2 * fz + 0.01),
                          kinematic=True, friction=friction)  # on the fingers' tops
    cube = scene.add_body(rg.Box((c, c, c)), mass=cube_mass, position=(x, y, z),
                          friction=friction)
    speed = grip * GRASP_SLOWEST_DT / GRASP_FINGER_MASS
    fingers, joints = [], []
    for side in (-1.0, 1.0):
        at = (x + side * (c + fx), y, bottom + fz)
        finger = scene.add_body(rg.Box(GRASP_FINGER_HALF), mass=GRASP_FINGER_MASS, position=at,
                                friction=friction)
        joints.append(scene.add_prismatic_joint(
            finger, hand, at, (side, 0.0, 0.0), limits=(-c, 0.5 * GRASP_OPENING - c),
            motor_speed=-speed, max_motor_force=grip))
        fingers.append(finger)
    return hand, cube, (fingers[0], fingers[1]), (joints[0], joints[1])


def grasps(rows) -> rg.Scene:
    """One gripper (``gripper``) per row (cube mass kg, grip N, friction) of ``rows``, in the
    air GRASP_SPACING apart along y, each cube hanging between its fingers. Row k's bodies are
    4 k (hand), 4 k + 1 (cube), 4 k + 2 and 4 k + 3 (fingers); its joints 2 k and 2 k + 1."""
    scene = rg.Scene()
    for k, (mass, grip, friction) in enumerate(rows):
        gripper(scene, (0.0, GRASP_SPACING * k, 1.0), mass, grip, friction)
    return scene


HINGED_ROD_HALF = (0.25, 0.01, 0.01)  # m: a 0.5 m rod along x


def hinged_rod(restitution: float, omega: float) -> rg.Scene:
    """No gravity. A 1 kg rod (half extents HINGED_ROD_HALF) hinged at its end (the origin)
    about y to the world, horizontal along +x, turning at ``omega`` rad/s about y (its far end
    moving down), 1 cm above a static block under its far 10 cm; both with ``restitution``
    and friction 0.5. Body 0 the rod, 1 the block; joint 0."""
    hx, _, hz = HINGED_ROD_HALF
    scene = rg.Scene(gravity=(0.0, 0.0, 0.0))
    rod = scene.add_body(rg.Box(HINGED_ROD_HALF), mass=1.0, position=(hx, 0.0, 0.0),
                         velocity=(0.0, 0.0, -omega * hx), angular_velocity=(0.0, omega, 0.0),
                         restitution=restitution)
    scene.add_revolute_joint(rod, None, (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    scene.add_body(rg.Box((0.05, 0.2, 0.05)), position=(2 * hx - 0.05, 0.0, -hz - 0.06),
                   static=True, restitution=restitution)
    return scene


CHAIN_LINKS, CHAIN_LINK = 10, 0.1  # m: each link's length, joint to joint


def hanging_chain(angle: float, links: int = CHAIN_LINKS) -> rg.Scene:
    """``links`` 0.1 kg links (boxes 0.09 x 0.02 x 0.02 m, CHAIN_LINK apart) joined end to end
    by revolute joints about y, the first hinged to the world at the origin, hanging straight
    and turned out by ``angle`` (rad) from the vertical, at rest. Links are bodies 0..links-1;
    joint k holds link k to link k - 1 (the world for k = 0)."""
    scene = rg.Scene()
    down = np.array([np.sin(angle), 0.0, -np.cos(angle)])
    # the link's long axis x turned onto `down`: a turn about y by pi/2 - angle
    half = 0.5 * (0.5 * np.pi - angle)
    turn = np.array([np.cos(half), 0.0, np.sin(half), 0.0])
    previous = None
    for k in range(links):
        link = scene.add_body(rg.Box((0.45 * CHAIN_LINK, 0.01, 0.01)), mass=0.1,
                              position=(k + 0.5) * CHAIN_LINK * down, orientation=turn)
        scene.add_revolute_joint(link, previous, k * CHAIN_LINK * down, (0.0, 1.0, 0.0))
        previous = link
    return scene


BLOCK_MU = 0.3
"""Friction coefficient between the two blocks of ``block_on_block`` (its floor has none)."""


def block_on_block(mu: float = BLOCK_MU, behind: float = 0.4) -> rg.Scene:
    """A 1 kg block 1 x 0.2 x 0.1 m (body 1) on a frictionless ground, and a 1 kg standard cube
    (body 2) resting on it ``behind`` m behind its centre, ``mu`` between the two."""
    scene = rg.Scene()
    scene.add_ground(friction=0.0)
    scene.add_body(rg.Box((0.5, 0.1, 0.05)), mass=1.0, friction=mu, position=(0, 0, 0.05))
    scene.add_body(rg.Box((CUBE_HALF,) * 3), mass=1.0, friction=mu,
                   position=(-behind, 0, 0.1 + CUBE_HALF))
    return scene


TOP_MASS, TOP_ARM, TOP_TIP = 1.0, 0.05, 0.005
"""The heavy top: kg; m from its centre of mass to the centre of its round tip; the tip's radius."""


def spinning_top(moments, spin: float, tilt_deg: float, precession: float) -> rg.Scene:
    """A symmetric top (body 1): a TOP_MASS capsule of radius TOP_TIP and half length TOP_ARM
    with principal ``moments`` (I1, I1, I3) kg m^2 about its axis (body z), standing on its
    lower cap on a frictionless ground (e = 0) tilted ``tilt_deg`` about x, spinning at
    ``spin`` rad/s (omega . axis) and turning at ``precession`` rad/s about the vertical, its
    centre at rest: the start of steady precession when ``precession`` is the closed form's."""
    tilt = np.radians(tilt_deg)
    axis = np.array([0.0, -np.sin(tilt), np.cos(tilt)])
    omega = precession * np.array([0.0, 0.0, 1.0]) + (spin - precession * np.cos(tilt)) * axis
    scene = rg.Scene()
    scene.add_ground(friction=0.0, restitution=0.0)
    scene.add_body(rg.Capsule(TOP_TIP, TOP_ARM), mass=TOP_MASS, inertia=moments, friction=0.0,
                   position=(0, 0, TOP_ARM * np.cos(tilt) + TOP_TIP),
                   orientation=(np.cos(tilt / 2), np.sin(tilt / 2), 0, 0),
                   angular_velocity=omega)
    return scene


BAR_RADIUS = 0.02
"""m: radius of the round bars of ``plank_on_bars``."""


def plank_on_bars(bars=(-0.3, 0.2), friction: float = 0.5, radius: float = BAR_RADIUS) -> rg.Scene:
    """A 1 kg plank 1 x 0.1 x 0.02 m (body 3) resting across two static round bars (capsules
    of ``radius`` m, 0.4 m long, along y; bodies 1 and 2) at x = ``bars`` (m), their tops at
    0.1 m + radius; every friction ``friction``."""
    scene = rg.Scene()
    scene.add_ground(friction=friction)
    along_y = (np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0)
    for x in bars:
        scene.add_body(rg.Capsule(radius, 0.2), static=True, position=(x, 0, 0.1),
                       orientation=along_y, friction=friction)
    scene.add_body(rg.Box((0.5, 0.05, 0.01)), mass=1.0, friction=friction,
                   position=(0, 0, 0.1 + radius + 0.01))
    return scene


def ball_on_box_edge(offset: float, box_mass: float = 0.01, ball_mass: float = 0.5,
                     speed: float = 3.0) -> rg.Scene:
    """A ball (r = 2.5 cm, ``ball_mass`` kg) falling at ``speed`` m/s from 4 mm above a 5 cm
    box (``box_mass`` kg) resting on the ground, ``offset`` m off the box's axis in x (0.025:
    over its top edge); mu = 0.5 everywhere."""
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    scene.add_body(rg.Box((0.025,) * 3), mass=box_mass, friction=0.5, position=(0, 0, 0.025))
    scene.add_body(rg.Sphere(0.025), mass=ball_mass, friction=0.5,
                   position=(offset, 0, 0.079), velocity=(0, 0, -speed))
    return scene


def tiny_on_huge(offset=(0.13, 0.1), gap: float = 0.02) -> rg.Scene:
    """A 1 mm cube (body 2, 1e-6 kg) dropped from ``gap`` m onto a 1 m cube (body 1, 1000 kg:
    mass ratio 1e9) resting on the ground, ``offset`` (m) from the top face's centre."""
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    scene.add_body(rg.Box((0.5,) * 3), density=1000.0, friction=0.5, position=(0, 0, 0.5))
    scene.add_body(rg.Box((0.0005,) * 3), density=1000.0, friction=0.5,
                   position=(offset[0], offset[1], 1.0005 + gap))
    return scene
