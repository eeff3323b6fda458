"""Bad input is rejected when the scene or world is built, with a message saying what and where."""

import numpy as np
import pytest

import rigid_gym as rg
from rigid_gym.checks import in_range, integer


def scene_with(**body):
    scene = rg.Scene()
    scene.add_body(body.pop("shape", rg.Sphere(0.1)), name="ball", **body)
    return scene


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"mass": -1.0}, r"body 0 \('ball'\): mass: must be finite and > 0 kg, got -1.0"),
        ({"mass": 0.0}, r"mass: must be finite and > 0 kg, got 0.0"),
        ({"density": -5.0}, r"density: must be finite and > 0 kg/m\^3, got -5.0"),
        ({"mass": np.nan}, r"mass: must be finite"),
        ({"mass": 1.0, "density": 1.0}, r"exactly one of mass"),
        ({}, r"exactly one of mass"),
        ({"mass": 1.0, "position": (0, np.nan, 0)}, r"body 0 \('ball'\): position: must be finite"),
        ({"mass": 1.0, "velocity": (np.inf, 0, 0)}, r"velocity: must be finite"),
        ({"mass": 1.0, "position": (0, 0)}, r"position: expected shape \(3,\)"),
        ({"mass": 1.0, "orientation": (1, 0, 0, 0.1)}, r"orientation: quaternion .* unit norm"),
        ({"mass": 1.0, "friction": -0.1}, r"friction: must be finite and >= 0, got -0.1"),
        ({"mass": 1.0, "restitution": 1.5}, r"restitution: must be finite and in \[0, 1\], got 1.5"),
        ({"mass": 1.0, "inertia": (1.0, 1.0, 3.0)}, r"triangle inequality"),
        ({"mass": 1.0, "inertia": (-1.0, 1.0, 1.0)}, r"moments must be >= 0"),
        ({"mass": 1.0, "inertia": [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]}, r"symmetric"),
        ({"mass": 1.0, "kinematic": True}, r"kinematic body has infinite mass"),
        ({"shape": rg.Plane(), "mass": 1.0}, r"only static bodies"),
        ({"shape": "box", "mass": 1.0}, r"shape must be one of"),
    ],
)
def test_bad_body_is_rejected_naming_body_and_field(kwargs, message):
    with pytest.raises(ValueError, match=message):
        scene_with(**kwargs)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: rg.Sphere(0.0), r"Sphere.radius: must be finite and > 0"),
        (lambda: rg.Sphere(np.nan), r"Sphere.radius: must be finite"),
        (lambda: rg.Box((0.1, -0.1, 0.1)), r"Box.half_extents: every entry must be > 0"),
        (lambda: rg.Box((0.1, 0.1)), r"Box.half_extents: expected shape \(3,\)"),
        (lambda: rg.Capsule(0.1, 0.0), r"Capsule.half_length: must be finite and > 0"),
        (lambda: rg.Pose(orientation=(2, 0, 0, 0)), r"Pose.orientation: quaternion"),
        (lambda: rg.Compound([]), r"Compound.parts: needs at least one"),
    ],
)
def test_bad_shape_is_rejected(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def cube_mesh_arrays():
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    t = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, t


def test_closed_cube_mesh_is_accepted():
    v, t = cube_mesh_arrays()
    assert rg.Mesh(v, t).volume() == pytest.approx(8.0)


def test_open_mesh_is_rejected():
    v, t = cube_mesh_arrays()
    with pytest.raises(ValueError, match="open"):
        rg.Mesh(v, t[:-1])


def test_inside_out_mesh_is_rejected():
    v, t = cube_mesh_arrays()
    with pytest.raises(ValueError, match="inside-out"):
        rg.Mesh(v, t[:, ::-1])


def test_mesh_with_nan_vertex_is_rejected():
    v, t = cube_mesh_arrays()
    v[3, 1] = np.nan
    with pytest.raises(ValueError, match="Mesh.vertices: must be finite"):
        rg.Mesh(v, t)


def test_duplicate_body_names_are_rejected():
    scene = rg.Scene()
    scene.add_body(rg.Sphere(0.1), mass=1.0, name="a")
    with pytest.raises(ValueError, match="name 'a' is already used"):
        scene.add_body(rg.Sphere(0.1), mass=1.0, name="a")


@pytest.mark.parametrize("dt", [0.0, -1 / 240, np.nan, np.inf, "fast"])
def test_bad_time_step_is_rejected(dt):
    with pytest.raises(ValueError, match="World.dt"):
        rg.World(scene_with(mass=1.0), dt=dt)


@pytest.mark.parametrize("num_worlds", [0, -3, 2.5, True])
def test_bad_world_count_is_rejected(num_worlds):
    with pytest.raises(ValueError, match="num_worlds"):
        rg.World(scene_with(mass=1.0), num_worlds=num_worlds)


def test_bad_gravity_and_empty_scene_are_rejected():
    with pytest.raises(ValueError, match="Scene.gravity: must be finite"):
        rg.Scene(gravity=(0, 0, np.nan))
    with pytest.raises(ValueError, match="no bodies"):
        rg.World(rg.Scene())


def test_bad_setter_input_is_rejected():
    world = rg.World(scene_with(mass=1.0), num_worlds=3)
    with pytest.raises(ValueError, match=r"set_velocity: velocity must be finite"):
        world.set_velocity(0, (np.nan, 0, 0))
    with pytest.raises(ValueError, match=r"World.set_velocity: body: must be a name or an int in \[0, 0\], got 4"):
        world.set_velocity(4, (0, 0, 0))
    with pytest.raises(ValueError, match=r"World.apply_force: world: must be None or an int in \[0, 2\], got 3"):
        world.apply_force(0, (0, 0, 1), world=3)
    with pytest.raises(ValueError, match=r"orientation"):
        world.set_pose(0, orientation=(1, 1, 0, 0))
    with pytest.raises(ValueError, match=r"shape \(3,\) or \(3, 3\)"):
        world.apply_impulse(0, np.zeros((2, 3)))


def test_bad_material_is_rejected_naming_the_range():
    scene = rg.Scene()
    ground = scene.add_ground()
    cube = scene.add_body(rg.Box((0.05,) * 3), mass=1.0, position=(0, 0, 0.05))
    world = rg.World(scene)
    for kwargs, message in (({"mass": 0.0}, r"mass: must be finite and > 0 kg, got 0.0"),
                            ({"mass": np.nan}, "mass: must be finite"),
                            ({"friction": -0.1}, r"friction: must be finite and >= 0, got -0.1"),
                            ({"restitution": 1.5},
                             r"restitution: must be finite and in \[0, 1\], got 1.5"),
                            ({"mass": [1.0, 2.0]}, r"mass must have shape \(\)")):
        with pytest.raises(ValueError, match=message):
            world.set_material(cube, **kwargs)
    with pytest.raises(ValueError, match="not dynamic"):
        world.set_material(ground, mass=1.0)
    # the derived config has no collision phase for this scene: a bounce would be lost
    with pytest.raises(ValueError, match="needs the collision phase"):
        world.set_material(cube, restitution=0.5)
    explicit = rg.World(scene, config=rg.SolverConfig())
    explicit.set_material(cube, restitution=0.5)
    assert explicit.model.restitution[0, cube] == 0.5


def test_bad_solver_config_is_rejected():
    with pytest.raises(ValueError, match="rotation_order must be one of"):
        rg.SolverConfig(rotation_order=4)
    with pytest.raises(ValueError, match="unknown option"):
        rg.SolverConfig.for_scene(rg.Scene(), rotation_ordr=2)
    with pytest.raises(ValueError, match=r"sleep_speed: must be finite and in \[0, 10\]"):
        rg.SolverConfig(sleep_speed=-0.1)
    with pytest.raises(ValueError, match="sleep_speed: expected a number of m/s, got True"):
        rg.SolverConfig(sleep_speed=True)


@pytest.mark.parametrize("check, message", [
    (lambda: integer(True, "f.n", 1), r"^f\.n: must be an int >= 1, got True$"),
    (lambda: integer(2.0, "f.n", 1), r"^f\.n: must be an int >= 1, got 2\.0$"),
    (lambda: integer(np.int64(5), "f.n", 0, 4),
     r"^f\.n: must be an int in \[0, 4\], got np.int64\(5\)$"),
    (lambda: integer(-1, "f.n", 0, 4, other="None"),
     r"^f\.n: must be None or an int in \[0, 4\], got -1$"),
    (lambda: integer(9, "f.n", high=8, unit="pixels"), r"^f\.n: must be an int <= 8 pixels"),
    (lambda: in_range(0.0, 0.0, np.inf, "f.x", open_low=True, unit="kg"),
     r"^f\.x: must be finite and > 0 kg, got 0\.0$"),
    (lambda: in_range(np.inf, 0.0, np.inf, "f.x"), r"^f\.x: must be finite and >= 0, got inf$"),
    (lambda: in_range([0.5, 1.5], 0.0, 1.0, "f.x"),
     r"^f\.x: must be finite and in \[0, 1\], got \[0\.5, 1\.5\]$"),
    (lambda: in_range("a", 0.0, 1.0, "f.x"), r"^f\.x: expected a number, got 'a'$"),
])
def test_the_integer_and_range_checks_state_what_where_and_the_allowed_range(check, message):
    with pytest.raises(ValueError, match=message):
        check()


def test_the_checks_return_the_values_they_pass():
    assert integer(np.int32(3), "f.n", 0, 3) == 3 and type(integer(np.int32(3), "f.n")) is int
    assert in_range(1, 0.0, 1.0, "f.x") == 1.0 and type(in_range(1, 0.0, 1.0, "f.x")) is float
    per_world = in_range(np.array([0.0, 1.0]), 0.0, 1.0, "f.x")
    assert per_world.dtype == np.float64 and per_world.tolist() == [0.0, 1.0]
    assert in_range(np.array(0.5), 0.0, 1.0, "f.x").shape == ()
