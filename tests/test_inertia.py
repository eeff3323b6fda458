"""Mass properties (rigid_gym.inertia), the mesh distances they use (src/collision/mesh_distance.h) and
the test meshes."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate

from rigid_gym import _core
from rigid_gym import quaternion as quat
from rigid_gym.inertia import (
    MassProperties,
    combine,
    inverse_moments,
    mass_properties,
    mass_properties_grid,
    mass_properties_monte_carlo,
    principal_axes,
)
from rigid_gym.meshes import bowl_mesh, box_mesh, l_shape_mesh, prism_mesh
from rigid_gym.shapes import Box, Capsule, Compound, Mesh, Plane, Pose, Sphere

DENSITY = 750.0  # kg/m^3, so that nothing passes only because density = 1
HALF_EXTENTS = (0.1, 0.2, 0.3)  # m
# An L whose edges (0.3 of 1.0 and 0.8) do not fall on the grid lines of every resolution.
L_OUTER, L_THICKNESS, L_HALF_DEPTH = (1.0, 0.8), 0.3, 0.2  # m


def l_shape_boxes() -> Compound:
    """The two boxes that make :func:`l_shape_mesh` with the L_* sizes: the arm along x and the
    rest of the arm along y."""
    (lx, ly), t, hz = L_OUTER, L_THICKNESS, L_HALF_DEPTH
    return Compound([
        (Box((lx / 2, t / 2, hz)), Pose((lx / 2, t / 2, 0.0))),
        (Box((t / 2, (ly - t) / 2, hz)), Pose((t / 2, (ly + t) / 2, 0.0))),
    ])


def assert_same(actual: MassProperties, expected: MassProperties, rtol: float = 1e-12):
    """Mass, centre and tensor agree to ``rtol`` of the mass, the body's size and |I|."""
    size = math.sqrt(np.trace(expected.inertia) / expected.mass)  # radius of gyration, m
    assert actual.mass == pytest.approx(expected.mass, rel=rtol)
    np.testing.assert_allclose(actual.center, expected.center, rtol=0, atol=rtol * size)
    np.testing.assert_allclose(actual.inertia, expected.inertia, rtol=0,
                               atol=rtol * np.linalg.norm(expected.inertia))


def relative_errors(estimate: MassProperties, exact: MassProperties) -> tuple[float, float]:
    """(relative mass error, relative Frobenius error of the inertia tensor)."""
    mass = abs(estimate.mass - exact.mass) / exact.mass
    inertia = np.linalg.norm(estimate.inertia - exact.inertia) / np.linalg.norm(exact.inertia)
    return mass, inertia


def random_orientation(rng: np.random.Generator) -> np.ndarray:
    """(4,) uniformly random unit quaternion."""
    return quat.normalize(rng.normal(size=4))


def winding(mesh: Mesh, points) -> np.ndarray:
    p = np.ascontiguousarray(points, dtype=np.float64)
    out = np.empty(len(p))
    _core.winding_number(p, mesh.vertices, mesh.triangles, out)
    return out


# --- closed forms -------------------------------------------------------------------------


def test_sphere_closed_form():
    r = 0.3
    mass = DENSITY * 4 / 3 * math.pi * r**3
    props = mass_properties(Sphere(r), DENSITY)
    assert props.mass == pytest.approx(mass, rel=1e-15)
    np.testing.assert_array_equal(props.center, 0.0)
    np.testing.assert_allclose(props.inertia, 2 / 5 * mass * r**2 * np.eye(3), rtol=1e-15)


def test_box_closed_form():
    a, b, c = (2 * h for h in HALF_EXTENTS)  # full side lengths
    mass = DENSITY * a * b * c
    props = mass_properties(Box(HALF_EXTENTS), DENSITY)
    assert props.mass == pytest.approx(mass, rel=1e-15)
    expected = mass / 12 * np.diag([b**2 + c**2, a**2 + c**2, a**2 + b**2])
    np.testing.assert_allclose(props.inertia, expected, rtol=1e-15)


def test_capsule_matches_integrals_over_slices():
    """Independent check: integrate thin discs along z. A disc of radius s(z) at height z has
    mass dm = rho pi s^2 dz, I_zz = dm s^2 / 2 and I_xx = dm (s^2 / 4 + z^2); s = r on the
    cylinder and s^2 = r^2 - (|z| - h)^2 on the caps. quad is accurate to ~1e-14 here."""
    r, h = 0.2, 0.35
    props = mass_properties(Capsule(r, h), DENSITY)

    def s2(z):
        return r * r - max(abs(z) - h, 0.0) ** 2

    def integral(f):
        return integrate.quad(f, -h - r, h + r, points=[-h, h], epsabs=0, epsrel=1e-13)[0]

    mass = integral(lambda z: DENSITY * math.pi * s2(z))
    i_zz = integral(lambda z: DENSITY * math.pi * s2(z) ** 2 / 2)
    i_xx = integral(lambda z: DENSITY * math.pi * s2(z) * (s2(z) / 4 + z * z))
    assert props.mass == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(props.center, 0.0, atol=1e-15)
    np.testing.assert_allclose(props.inertia, np.diag([i_xx, i_xx, i_zz]), rtol=1e-12)


def test_plane_has_no_mass_properties():
    with pytest.raises(ValueError, match="Plane has no volume"):
        mass_properties(Plane(), DENSITY)
    with pytest.raises(TypeError, match="str"):
        mass_properties("box", DENSITY)


# --- meshes and compounds -----------------------------------------------------------------


def test_mesh_cube_equals_box_closed_form():
    assert_same(mass_properties(box_mesh(HALF_EXTENTS), DENSITY),
                mass_properties(Box(HALF_EXTENTS), DENSITY))


def test_moved_mesh_cube_equals_moved_box():
    """A cube mesh whose vertices are rotated and moved 10 m away: the polyhedral integrals must
    still give the box's tensor, turned, about the moved centre."""
    pose = Pose((10.0, -7.0, 3.0), random_orientation(np.random.default_rng(1)))
    cube = box_mesh(HALF_EXTENTS)
    moved = Mesh(pose.apply(cube.vertices), cube.triangles)
    expected = combine([(mass_properties(Box(HALF_EXTENTS), DENSITY), pose)])
    assert_same(mass_properties(moved, DENSITY), expected)


def test_l_mesh_equals_compound_of_its_two_boxes():
    props = mass_properties(l_shape_mesh(L_OUTER, L_THICKNESS, L_HALF_DEPTH), DENSITY)
    assert_same(props, mass_properties(l_shape_boxes(), DENSITY))
    assert abs(props.inertia[0, 1]) > 1e-3 * props.inertia[2, 2]  # a real product of inertia


def test_two_boxes_side_by_side_equal_the_box_they_form():
    half = Box((0.25, 0.2, 0.3))
    pair = Compound([(half, Pose((-0.25, 0.0, 0.0))), (half, Pose((0.25, 0.0, 0.0)))])
    assert_same(mass_properties(pair, DENSITY), mass_properties(Box((0.5, 0.2, 0.3)), DENSITY))


@settings(max_examples=50, deadline=None)
@given(
    position=st.tuples(*[st.floats(-5.0, 5.0)] * 3),
    orientation=st.tuples(*[st.floats(-1.0, 1.0)] * 4).filter(
        lambda q: np.linalg.norm(q) > 0.1),
)
def test_posed_box_transforms_like_a_tensor(position, orientation):
    """One posed part: mass unchanged, centre = pose position, I = R I_box R^T."""
    pose = Pose(position, quat.normalize(orientation))
    box = mass_properties(Box(HALF_EXTENTS), DENSITY)
    props = mass_properties(Compound([(Box(HALF_EXTENTS), pose)]), DENSITY)
    rotation = pose.rotation()
    assert props.mass == pytest.approx(box.mass, rel=1e-15)
    np.testing.assert_allclose(props.center, position, rtol=0, atol=1e-14)
    np.testing.assert_allclose(props.inertia, rotation @ box.inertia @ rotation.T,
                               rtol=0, atol=1e-13 * np.linalg.norm(box.inertia))


def test_combine_rejects_nothing_to_combine():
    with pytest.raises(ValueError, match="at least one"):
        combine([])


# --- mesh distances (src/collision/mesh_distance.h) -------------------------------------------------


def test_winding_number_of_the_l_including_its_notch():
    (lx, ly), t, hz = L_OUTER, L_THICKNESS, L_HALF_DEPTH
    mesh = l_shape_mesh(L_OUTER, L_THICKNESS, L_HALF_DEPTH)
    inside = [[0.5 * t, 0.5 * t, 0.0], [0.9 * lx, 0.5 * t, 0.1], [0.5 * t, 0.9 * ly, -0.1]]
    notch = [[t + 0.01, t + 0.01, 0.0], [0.9 * lx, 0.9 * ly, 0.0], [0.5 * lx, 0.5 * ly, hz / 2]]
    outside = [[-0.1, 0.1, 0.0], [0.1, 0.1, hz + 0.01], [2.0, -3.0, 1.0]]
    np.testing.assert_allclose(winding(mesh, inside), 1.0, atol=1e-12)
    np.testing.assert_allclose(winding(mesh, notch + outside), 0.0, atol=1e-12)


def test_winding_number_of_the_bowl():
    """Points in the bowl's cavity and above its rim are outside, points in its wall inside."""
    mesh = bowl_mesh(0.5, 0.4, segments=16, rings=4)
    np.testing.assert_allclose(winding(mesh, [[0, 0, -0.45], [0.3, 0.3, -0.05]]), 1.0, atol=1e-12)
    np.testing.assert_allclose(winding(mesh, [[0, 0, -0.2], [0, 0, 0.1], [0, 0, -0.6]]), 0.0,
                               atol=1e-12)


def test_signed_distance_of_mesh_cube_equals_box():
    points = np.random.default_rng(2).uniform(-1.5, 1.5, size=(5000, 3)) * HALF_EXTENTS
    expected = Box(HALF_EXTENTS).signed_distance(points)
    assert 0.2 < (expected < 0).mean() < 0.5  # inside and outside both well represented
    np.testing.assert_allclose(box_mesh(HALF_EXTENTS).signed_distance(points), expected,
                               rtol=0, atol=1e-12)


def test_signed_distance_of_the_l():
    """Hand values, and the sign agrees with the union of its two boxes everywhere."""
    t = L_THICKNESS
    mesh = l_shape_mesh(L_OUTER, L_THICKNESS, L_HALF_DEPTH)
    points = np.array([[t + 0.1, t + 0.05, 0.0],  # in the notch, 0.05 m from the inner wall
                       [0.1, 0.1, 0.0],  # inside, 0.1 m from the two outer walls
                       [-0.3, -0.4, 0.0]])  # beyond the outer corner (0, 0), 0.5 m away
    np.testing.assert_allclose(mesh.signed_distance(points), [0.05, -0.1, 0.5], atol=1e-15)
    samples = np.random.default_rng(3).uniform(-0.2, 1.2, size=(4000, 3)) * [1, 1, 0.4]
    np.testing.assert_array_equal(mesh.signed_distance(samples) <= 0,
                                  l_shape_boxes().signed_distance(samples) <= 0)


def test_zero_area_triangles_are_harmless():
    """A box whose bottom edge y = -b has an extra vertex at its middle: the cap fan then holds
    a zero-area triangle, whose distance the core takes from its edges (no 0/0)."""
    a, b, c = HALF_EXTENTS
    mesh = prism_mesh([[-a, -b], [0.0, -b], [a, -b], [a, b], [-a, b]], -c, c)
    corners = mesh.vertices[mesh.triangles]  # (T, 3 corners, 3)
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.linalg.norm(normals, axis=-1).min() == 0.0  # there is a zero-area triangle
    points = np.random.default_rng(5).uniform(-1.5, 1.5, size=(2000, 3)) * HALF_EXTENTS
    np.testing.assert_allclose(mesh.signed_distance(points),
                               Box(HALF_EXTENTS).signed_distance(points), rtol=0, atol=1e-12)
    assert_same(mass_properties(mesh, DENSITY), mass_properties(Box(HALF_EXTENTS), DENSITY))


# --- sampled estimates --------------------------------------------------------------------

SAMPLED_SHAPES = {
    "sphere": Sphere(0.5),
    "capsule": Capsule(0.2, 0.3),
    "l_mesh": l_shape_mesh(L_OUTER, L_THICKNESS, L_HALF_DEPTH),
}


@pytest.mark.parametrize("name", SAMPLED_SHAPES)
def test_grid_converges(name):
    """Measured relative inertia errors at resolution 64: sphere 0.14%, capsule 0.24%, L 0.31%
    (16: 2.5%, 2.5%, 0.8%). Only the cells cut by the surface are wrong and their share falls
    like 1/resolution; the bound 1% leaves about 3x room."""
    shape = SAMPLED_SHAPES[name]
    exact = mass_properties(shape, DENSITY)
    coarse = relative_errors(mass_properties_grid(shape, DENSITY, 16), exact)
    fine = relative_errors(mass_properties_grid(shape, DENSITY, 64), exact)
    assert fine[0] < coarse[0] and fine[1] < coarse[1]
    assert fine[0] < 1e-2 and fine[1] < 1e-2


def test_grid_is_exact_in_mass_for_a_box_and_second_order_in_inertia():
    """Every cell centre of the box's own bounding box is inside, so the mass is exact; each
    cell's midpoint rule misses its own moment h^2/12 M, so the tensor error is ~1/res^2."""
    exact = mass_properties(Box(HALF_EXTENTS), DENSITY)
    errors = [relative_errors(mass_properties_grid(Box(HALF_EXTENTS), DENSITY, n), exact)
              for n in (8, 16)]
    assert errors[0][0] < 1e-14 and errors[1][0] < 1e-14
    assert errors[1][1] == pytest.approx(errors[0][1] / 4, rel=1e-9)


@pytest.mark.parametrize("name", SAMPLED_SHAPES)
def test_monte_carlo_converges(name):
    """The standard error falls like samples^-1/2: over 20 seeds the relative inertia error at
    1e5 samples averaged 0.4-0.5% and never passed 0.8% (max over seeds and these shapes), so
    2% is about 4 standard errors; seed 0 gives 0.5-0.7%. At 1e3 samples it is ~5%."""
    shape = SAMPLED_SHAPES[name]
    exact = mass_properties(shape, DENSITY)
    few = relative_errors(mass_properties_monte_carlo(shape, DENSITY, 1_000), exact)
    many = relative_errors(mass_properties_monte_carlo(shape, DENSITY, 100_000), exact)
    assert many[1] < few[1]
    assert many[0] < 2e-2 and many[1] < 2e-2


def test_monte_carlo_is_deterministic_for_a_seed():
    shape = SAMPLED_SHAPES["capsule"]
    first = mass_properties_monte_carlo(shape, DENSITY, 3000, seed=7)
    again = mass_properties_monte_carlo(shape, DENSITY, 3000, seed=7)
    other = mass_properties_monte_carlo(shape, DENSITY, 3000, seed=8)
    assert first.mass == again.mass
    np.testing.assert_array_equal(first.center, again.center)
    np.testing.assert_array_equal(first.inertia, again.inertia)
    assert other.mass != first.mass


def test_bowl_exact_matches_grid():
    """A 256-triangle nonconvex mesh: measured grid error at resolution 32 is 0.35% in mass and
    0.25% in inertia; 1% bounds."""
    mesh = bowl_mesh(0.5, 0.4, segments=16, rings=4)
    exact = mass_properties(mesh, DENSITY)
    errors = relative_errors(mass_properties_grid(mesh, DENSITY, 32), exact)
    assert errors[0] < 1e-2 and errors[1] < 1e-2
    assert exact.center[2] < -0.2  # the shell's mass hangs below its rim


def test_sampled_estimates_need_points_inside():
    """A grid of one cell samples only the centre of the bounding box, which the bowl lacks."""
    with pytest.raises(ValueError, match="no sample point fell inside"):
        mass_properties_grid(bowl_mesh(0.5, 0.4, segments=8, rings=2), DENSITY, 1)


# --- principal axes and inverse moments ---------------------------------------------------


def test_principal_axes_of_a_rotated_box():
    moments = np.diag(mass_properties(Box(HALF_EXTENTS), DENSITY).inertia)
    rotation = quat.to_matrix(random_orientation(np.random.default_rng(4)))
    tensor = rotation @ np.diag(moments) @ rotation.T
    found, axes = principal_axes(tensor)
    np.testing.assert_allclose(found, np.sort(moments), rtol=1e-12)
    assert np.linalg.det(axes) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(axes @ np.diag(found) @ axes.T, tensor,
                               atol=1e-12 * np.abs(tensor).max())


def test_principal_axes_of_the_l_are_proper():
    tensor = mass_properties(l_shape_mesh(L_OUTER, L_THICKNESS, L_HALF_DEPTH), DENSITY).inertia
    moments, axes = principal_axes(tensor)
    assert np.linalg.det(axes) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(axes @ np.diag(moments) @ axes.T, tensor,
                               atol=1e-12 * np.abs(tensor).max())


def test_principal_axes_keep_a_diagonal_tensor_as_it_is():
    tensor = np.diag([3.0, 1.0, 2.0])
    tensor[0, 1] = tensor[1, 0] = 1e-16  # round-off, below 1e-14 of the largest moment
    moments, axes = principal_axes(tensor)
    np.testing.assert_array_equal(moments, [3.0, 1.0, 2.0])
    np.testing.assert_array_equal(axes, np.eye(3))


def test_principal_axes_reject_a_non_symmetric_tensor():
    with pytest.raises(ValueError, match="symmetric"):
        principal_axes([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def test_inverse_moments_of_rod_point_and_body():
    np.testing.assert_array_equal(inverse_moments([2.0, 2.0, 0.0]), [0.5, 0.5, 0.0])
    np.testing.assert_array_equal(inverse_moments([2.0, 2.0, 1e-15]), [0.5, 0.5, 0.0])
    np.testing.assert_array_equal(inverse_moments([0.0, 0.0, 0.0]), [0.0, 0.0, 0.0])
    np.testing.assert_allclose(inverse_moments([1.0, 2.0, 4.0]), [1.0, 0.5, 0.25])


# --- validation ---------------------------------------------------------------------------


@pytest.mark.parametrize("density", [0.0, -1.0, math.nan, math.inf, "heavy", None])
def test_bad_density_is_rejected(density):
    for estimate in (lambda: mass_properties(Box(HALF_EXTENTS), density),
                     lambda: mass_properties_grid(Box(HALF_EXTENTS), density, 4),
                     lambda: mass_properties_monte_carlo(Box(HALF_EXTENTS), density, 10)):
        with pytest.raises(ValueError, match="density"):
            estimate()


@pytest.mark.parametrize("count", [0, -3, 2.5, True, "10"])
def test_bad_sample_counts_are_rejected(count):
    with pytest.raises(ValueError, match="resolution"):
        mass_properties_grid(Box(HALF_EXTENTS), DENSITY, count)
    with pytest.raises(ValueError, match="samples"):
        mass_properties_monte_carlo(Box(HALF_EXTENTS), DENSITY, count)


def test_open_mesh_is_rejected():
    cube = box_mesh(HALF_EXTENTS)
    with pytest.raises(ValueError, match="open"):
        Mesh(cube.vertices, cube.triangles[:-1])


def test_inside_out_mesh_is_rejected():
    cube = box_mesh(HALF_EXTENTS)
    with pytest.raises(ValueError, match="inside-out"):
        Mesh(cube.vertices, cube.triangles[:, ::-1])


def test_mass_properties_validate_their_arrays():
    with pytest.raises(ValueError, match="mass"):
        MassProperties(0.0, np.zeros(3), np.eye(3))
    with pytest.raises(ValueError, match="center"):
        MassProperties(1.0, np.zeros(2), np.eye(3))
    with pytest.raises(ValueError, match="inertia"):
        MassProperties(1.0, np.zeros(3), np.full((3, 3), math.nan))
