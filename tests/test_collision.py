"""Collision detection against hand-computed contacts.

Every case places bodies, calls ``World.contacts()`` and compares with a closed form. Contacts
have a point (world, m), a unit normal from body_b to body_a and a depth (m, > 0 overlapping);
pairs are ordered dynamic > kinematic > static (ties: the lower index is body_a), and within a
pair the deepest contact comes first.

Tolerances. Closed forms (sphere, capsule, box, plane against each other) are exact, so they
are checked to ``EXACT`` (rounding). A mesh answers phi from its exact signed distance sampled
on a grid of spacing h = (longest side) / ``Mesh.sdf_resolution`` and interpolated
trilinearly; since the exact phi is 1-Lipschitz and the interpolant is a convex combination of
the 8 node values, |phi_grid(p) - phi(p)| <= sum_i w_i |p - node_i|
<= sqrt(sum_i w_i |p - node_i|^2) = h sqrt(sum_k t_k (1 - t_k)) <= (sqrt(3) / 2) h, which is
``grid_bound(mesh)`` below: the bound for every depth measured in a mesh's phi. (Where the
mesh's exact phi is linear near the point, e.g. near a face of a box mesh aligned with the
grid, trilinear interpolation is exact.) Outside its grid a mesh answers cores (spheres and
capsules, whose centre may be far from the surface) exactly from its triangles.
"""

import dataclasses

import numpy as np
import pytest

import rigid_gym as rg
from rigid_gym import quaternion as quat
from rigid_gym.meshes import bowl_mesh, box_mesh, l_shape_mesh, prism_mesh

EXACT = 1e-12


def axis_angle(axis, angle):
    """Unit quaternion (w, x, y, z) of a rotation by ``angle`` (rad) about ``axis``."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * a])


def contacts(scene, margin=0.0, **config):
    return rg.World(scene, config=rg.SolverConfig(**config)).contacts(margin=margin)


def grid_bound(mesh):
    """(sqrt(3) / 2) h: the most a mesh's trilinear phi can differ from its exact phi, m."""
    lower, upper = mesh.bounds()
    return np.sqrt(3.0) / 2.0 * float(np.max(upper - lower)) / mesh.sdf_resolution


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def assert_unit_normals(c):
    np.testing.assert_allclose(np.linalg.norm(c.normal, axis=1), 1.0, atol=1e-12)


def assert_deepest_first(c):
    for pair in {(a, b) for a, b in zip(c.body_a, c.body_b)}:
        rows = np.flatnonzero((c.body_a == pair[0]) & (c.body_b == pair[1]))
        assert c.depth[rows[0]] == c.depth[rows].max()


def sorted_rows(points):
    """Rows sorted lexicographically (rounded), to compare point sets."""
    p = np.round(np.asarray(points), 9)
    return p[np.lexsort(p.T[::-1])]


# -- spheres and planes ------------------------------------------------------------------------


def test_sphere_sphere():
    scene = rg.Scene()
    scene.add_body(rg.Sphere(0.3), mass=1.0, position=(0.1, -0.2, 0.5))
    scene.add_body(rg.Sphere(0.2), mass=1.0, position=(0.4, 0.0, 0.6))
    c = contacts(scene)
    xa, xb = np.array([0.1, -0.2, 0.5]), np.array([0.4, 0.0, 0.6])
    n = unit(xa - xb)
    assert len(c.depth) == 1 and (c.body_a[0], c.body_b[0]) == (0, 1)
    np.testing.assert_allclose(c.depth[0], 0.5 - np.linalg.norm(xa - xb), atol=EXACT)
    np.testing.assert_allclose(c.normal[0], n, atol=EXACT)
    np.testing.assert_allclose(c.point[0], xa - 0.3 * n, atol=EXACT)  # A's deepest point in B


def test_sphere_plane_with_raised_ground():
    scene = rg.Scene()
    scene.add_ground(height=0.25)
    scene.add_body(rg.Sphere(0.3), mass=1.0, position=(1.0, 2.0, 0.5))
    c = contacts(scene)
    assert len(c.depth) == 1 and (c.body_a[0], c.body_b[0]) == (1, 0)
    np.testing.assert_allclose(c.depth[0], 0.05, atol=EXACT)
    np.testing.assert_allclose(c.normal[0], [0, 0, 1], atol=EXACT)
    np.testing.assert_allclose(c.point[0], [1.0, 2.0, 0.2], atol=EXACT)


def test_sphere_on_a_tilted_plane():
    """A static Plane body rotated 30 degrees about x: normal and depth follow its frame."""
    q = axis_angle((1, 0, 0), np.radians(30))
    n = quat.to_matrix(q)[:, 2]
    origin = np.array([0.3, -0.2, 0.1])
    scene = rg.Scene()
    scene.add_body(rg.Plane(), static=True, position=origin, orientation=q)
    centre = origin + (0.5, 0.4, 0) + 0.17 * n
    scene.add_body(rg.Sphere(0.2), mass=1.0, position=centre)
    c = contacts(scene)
    height = np.dot(centre - origin, n)
    assert len(c.depth) == 1
    np.testing.assert_allclose(c.depth[0], 0.2 - height, atol=EXACT)
    np.testing.assert_allclose(c.normal[0], n, atol=EXACT)
    np.testing.assert_allclose(c.point[0], centre - 0.2 * n, atol=EXACT)


# -- boxes ---------------------------------------------------------------------------------------


def test_box_resting_flat_on_the_ground_has_its_four_corners():
    """Translated and turned about z (to catch frame bugs): exactly the 4 bottom corners."""
    h = np.array([0.5, 0.3, 0.2])
    q = axis_angle((0, 0, 1), 0.7)
    x = np.array([2.0, -1.0, 0.19])
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Box(h), mass=1.0, position=x, orientation=q)
    c = contacts(scene)
    corners = [x + quat.to_matrix(q) @ (h * (sx, sy, -1)) for sx in (-1, 1) for sy in (-1, 1)]
    assert len(c.depth) == 4
    assert set(c.body_a) == {1} and set(c.body_b) == {0}
    np.testing.assert_allclose(c.depth, 0.01, atol=EXACT)
    np.testing.assert_allclose(c.normal, np.tile([0, 0, 1.0], (4, 1)), atol=EXACT)
    np.testing.assert_allclose(sorted_rows(c.point), sorted_rows(corners), atol=1e-9)


def test_box_on_an_edge_has_two_contacts():
    """Turned 45 degrees about x, the lowest edge runs along x at z = -0.3 sqrt 2."""
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Box((0.5, 0.3, 0.3)), mass=1.0, position=(0, 0, 0.3 * np.sqrt(2) - 0.01),
                   orientation=axis_angle((1, 0, 0), np.pi / 4))
    c = contacts(scene)
    assert len(c.depth) == 2
    np.testing.assert_allclose(c.depth, 0.01, atol=EXACT)
    np.testing.assert_allclose(c.normal, [[0, 0, 1.0]] * 2, atol=EXACT)
    np.testing.assert_allclose(sorted_rows(c.point), [[-0.5, 0, -0.01], [0.5, 0, -0.01]], atol=1e-9)


@pytest.mark.parametrize("upper_first", [True, False])
def test_stacked_cubes_touch_face_to_face(upper_first):
    """Aligned cubes, the upper one 1 cm into the lower: 4 contacts, normal +-z from body_b to
    body_a, depth 0.01, points covering the overlap square of the faces."""
    scene = rg.Scene()
    lower, upper = ((0, 0, 0.5), (0.2, -0.1, 1.49))
    for position in ((upper, lower) if upper_first else (lower, upper)):
        scene.add_body(rg.Box((0.5, 0.5, 0.5)), mass=1.0, position=position)
    c = contacts(scene)
    assert len(c.depth) == 4
    sign = 1.0 if upper_first else -1.0  # body_a is body 0: the normal points from 1 to 0
    np.testing.assert_allclose(c.normal, [[0, 0, sign]] * 4, atol=EXACT)
    np.testing.assert_allclose(c.depth, 0.01, atol=EXACT)
    np.testing.assert_allclose(c.point[:, :2].min(axis=0), [-0.3, -0.5], atol=1e-12)
    np.testing.assert_allclose(c.point[:, :2].max(axis=0), [0.5, 0.4], atol=1e-12)
    assert np.all((c.point[:, 2] >= 0.99 - 1e-12) & (c.point[:, 2] <= 1.0 + 1e-12))


def test_small_box_turned_on_a_big_box_has_its_four_bottom_corners():
    q = axis_angle((0, 0, 1), 0.4)
    x = np.array([0.1, 0.2, 1.0 + 0.1 - 0.003])
    scene = rg.Scene()
    scene.add_body(rg.Box((1.0, 1.0, 0.5)), static=True, position=(0, 0, 0.5))
    scene.add_body(rg.Box((0.2, 0.15, 0.1)), mass=1.0, position=x, orientation=q)
    c = contacts(scene)
    corners = [x + quat.to_matrix(q) @ ((0.2, 0.15, 0.1) * np.array([sx, sy, -1]))
               for sx in (-1, 1) for sy in (-1, 1)]
    assert len(c.depth) == 4
    np.testing.assert_allclose(c.depth, 0.003, atol=EXACT)
    np.testing.assert_allclose(c.normal, [[0, 0, 1.0]] * 4, atol=EXACT)
    # the small box's bottom face is the reference face (face axes tie; A's win), so the points
    # are the big box's top face clipped to it: below the small box's corners by the depth
    np.testing.assert_allclose(sorted_rows(c.point)[:, :2], sorted_rows(corners)[:, :2], atol=1e-9)
    np.testing.assert_allclose(c.point[:, 2], 1.0, atol=1e-12)


def test_box_box_edge_edge_crossing():
    """A's lowest edge (along x, A turned 45 degrees about x) crosses B's highest edge (along y,
    B turned 45 degrees about y) 1 cm deep: one contact, normal x cross y = z, depth 0.01."""
    s2 = np.sqrt(2.0)
    scene = rg.Scene()
    scene.add_body(rg.Box((0.5, 0.5, 0.5)), static=True, position=(0.2, 0, 0),
                   orientation=axis_angle((0, 1, 0), np.pi / 4))
    scene.add_body(rg.Box((0.5, 0.4, 0.4)), mass=1.0,
                   position=(0, -0.1, 0.5 * s2 + 0.4 * s2 - 0.01),
                   orientation=axis_angle((1, 0, 0), np.pi / 4))
    c = contacts(scene)
    assert len(c.depth) == 1 and (c.body_a[0], c.body_b[0]) == (1, 0)
    np.testing.assert_allclose(c.depth[0], 0.01, atol=1e-12)
    np.testing.assert_allclose(c.normal[0], [0, 0, 1], atol=1e-12)
    # the crossing: A's edge point above B's edge, 1 cm below B's ridge height 0.5 sqrt 2
    np.testing.assert_allclose(c.point[0], [0.2, -0.1, 0.5 * s2 - 0.01], atol=1e-12)


def test_box_box_edge_crossing_at_an_angle():
    """Edges crossing at 60 degrees: normal along e_a x e_b, depth exact."""
    s2 = np.sqrt(2.0)
    qb = axis_angle((0, 1, 0), np.pi / 4)
    qa = quat.multiply(axis_angle((0, 0, 1), np.pi / 3), axis_angle((1, 0, 0), np.pi / 4))
    scene = rg.Scene()
    scene.add_body(rg.Box((0.5, 0.5, 0.5)), static=True, orientation=qb)
    scene.add_body(rg.Box((0.5, 0.5, 0.5)), mass=1.0, position=(0, 0, s2 - 0.02), orientation=qa)
    c = contacts(scene)
    ea, eb = quat.to_matrix(qa)[:, 0], quat.to_matrix(qb)[:, 1]
    n = unit(np.cross(ea, eb))
    n *= np.sign(n[2])
    assert len(c.depth) == 1
    np.testing.assert_allclose(c.normal[0], n, atol=1e-12)
    np.testing.assert_allclose(c.depth[0], 0.02, atol=1e-12)


# -- capsules ------------------------------------------------------------------------------------


def test_capsule_lying_on_a_box_face_touches_at_its_ends():
    scene = rg.Scene()
    scene.add_body(rg.Box((0.5, 0.5, 0.5)), static=True)
    q = axis_angle((0, 1, 0), np.pi / 2)  # axis along x
    scene.add_body(rg.Capsule(0.1, 0.3), mass=1.0, position=(0.1, 0.2, 0.59), orientation=q)
    c = contacts(scene)
    assert len(c.depth) == 2
    np.testing.assert_allclose(c.depth, 0.01, atol=EXACT)
    np.testing.assert_allclose(c.normal, [[0, 0, 1.0]] * 2, atol=EXACT)
    np.testing.assert_allclose(sorted_rows(c.point), [[-0.2, 0.2, 0.49], [0.4, 0.2, 0.49]],
                               atol=1e-12)


EDGE_BOX = rg.Box((0.5, 0.5, 0.5))


def capsule_across_edge(radius, half_length, depth, tilt, offset, box=EDGE_BOX):
    """A capsule whose axis passes the edge {x = z = 0.5} of a static box of half extents 0.5
    at distance radius - depth, its axis tilted by ``tilt`` below +x; the point of the axis
    nearest to the edge lies ``offset`` (m) along the axis from the capsule's centre.
    Returns (scene, that nearest point, the normal from the edge to the axis)."""
    d = np.array([np.cos(tilt), 0, -np.sin(tilt)])
    n = np.array([np.sin(tilt), 0, np.cos(tilt)])  # from the edge to the axis
    nearest = np.array([0.5, 0.1, 0.5]) + (radius - depth) * n
    centre = nearest - offset * d
    q = quat.multiply(axis_angle((0, 1, 0), np.pi / 2 + tilt), [1, 0, 0, 0])  # z axis -> d
    assert np.allclose(quat.to_matrix(q)[:, 2], d)
    scene = rg.Scene()
    scene.add_body(box, static=True)
    scene.add_body(rg.Capsule(radius, half_length), mass=1.0, position=centre, orientation=q)
    return scene, nearest, n


@pytest.mark.parametrize("radius, half_length, offset", [(0.1, 0.4, 0.13), (0.01, 1.0, 0.37)])
def test_capsule_crossing_a_box_edge(radius, half_length, offset):
    """The deepest point is where the axis passes the edge, between the core's ends: one
    contact there, depth exact. The thin long rod (1 cm radius, 2 m) was missed entirely when
    the core was sampled at 5 fixed points."""
    scene, nearest, n = capsule_across_edge(radius, half_length, 0.004, np.radians(30), offset)
    c = contacts(scene)
    assert len(c.depth) == 1
    np.testing.assert_allclose(c.depth[0], 0.004, atol=1e-9)
    np.testing.assert_allclose(c.normal[0], n, atol=1e-6)
    np.testing.assert_allclose(c.point[0], nearest - radius * n, atol=1e-6)


def test_capsule_near_a_box_reports_its_deepest_core_point():
    """Random capsules near a box's edges and corners: the deepest contact is the deepest
    point of the core in the box, radius - min phi along the core, phi the box's exact signed
    distance (numpy) at 4001 points of the core. phi is 1-Lipschitz, so the sampled minimum
    is at most half a spacing (L / 8000 m, L the core's length) above the true one. The
    search for an interior minimum is skipped where phi rises inwards from an end; this
    checks that no skip loses a deeper interior point."""
    rng = np.random.default_rng(7)
    box = rg.Box((0.3, 0.2, 0.25))
    for _ in range(200):
        radius, half_length = rng.uniform(0.02, 0.2), rng.uniform(0.05, 0.6)
        q = unit(rng.normal(size=4))
        centre = rng.choice([-1.0, 1.0], 3) * box.half_extents + rng.uniform(-0.15, 0.15, 3)
        scene = rg.Scene()
        scene.add_body(box, static=True)
        scene.add_body(rg.Capsule(radius, half_length), mass=1.0, position=centre,
                       orientation=q)
        c = contacts(scene)
        axis = quat.to_matrix(q)[:, 2]
        core = centre + np.linspace(-half_length, half_length, 4001)[:, None] * axis
        deepest = radius - box.signed_distance(core).min()
        if deepest <= 0.0:
            assert len(c.depth) == 0 or c.depth.max() <= 2 * half_length / 8000 + EXACT
            continue
        assert len(c.depth) > 0
        assert deepest - 1e-9 <= c.depth.max() <= deepest + 2 * half_length / 8000 + 1e-9


def test_capsule_capsule_crossing_and_parallel():
    scene = rg.Scene()
    scene.add_body(rg.Capsule(0.1, 0.3), mass=1.0)  # axis z
    scene.add_body(rg.Capsule(0.15, 0.5), mass=1.0, position=(0.2, 0.1, 0.05),
                   orientation=axis_angle((1, 0, 0), np.pi / 2))  # axis y, through x = 0.2
    c = contacts(scene)
    assert len(c.depth) == 1 and (c.body_a[0], c.body_b[0]) == (0, 1)
    np.testing.assert_allclose(c.depth[0], 0.25 - 0.2, atol=EXACT)
    np.testing.assert_allclose(c.normal[0], [-1, 0, 0], atol=EXACT)
    np.testing.assert_allclose(c.point[0], [0.1, 0, 0.05], atol=EXACT)  # A's point inside B
    # side by side and parallel: one contact (the closest points of two parallel segments)
    scene = rg.Scene()
    scene.add_body(rg.Capsule(0.1, 0.3), mass=1.0)
    scene.add_body(rg.Capsule(0.1, 0.3), mass=1.0, position=(0, 0.19, 0.1))
    c = contacts(scene)
    assert len(c.depth) == 1
    np.testing.assert_allclose(c.depth[0], 0.01, atol=EXACT)
    np.testing.assert_allclose(c.normal[0], [0, -1, 0], atol=EXACT)


def test_capsule_end_on_the_ground_and_lying_on_it():
    scene = rg.Scene()
    scene.add_ground()
    q = axis_angle((0, 1, 0), np.radians(20))
    centre = np.array([0, 0, 0.5 * np.cos(np.radians(20)) + 0.09])
    scene.add_body(rg.Capsule(0.1, 0.5), mass=1.0, position=centre, orientation=q)
    c = contacts(scene)
    low_end = centre - 0.5 * quat.to_matrix(q)[:, 2]
    assert len(c.depth) == 1
    np.testing.assert_allclose(c.depth[0], 0.01, atol=EXACT)
    np.testing.assert_allclose(c.point[0], low_end - (0, 0, 0.1), atol=EXACT)
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Capsule(0.1, 0.5), mass=1.0, position=(0, 0, 0.09),
                   orientation=axis_angle((1, 0, 0), np.pi / 2))
    c = contacts(scene)
    assert len(c.depth) == 2
    np.testing.assert_allclose(sorted_rows(c.point), [[0, -0.5, -0.01], [0, 0.5, -0.01]],
                               atol=1e-12)


# -- sphere against a box: face, edge and corner regions -------------------------------------


@pytest.mark.parametrize("offset, nearest", [
    ((0.1, 0.2, 0.39), (0.1, 0.2, 0.3)),                 # above the top face
    ((0.1, 0.46, 0.36), (0.1, 0.4, 0.3)),                # beyond the edge y = 0.4, z = 0.3
    ((0.55, 0.45, 0.35), (0.5, 0.4, 0.3)),               # beyond the corner
    ((0.45, 0.0, 0.0), (0.5, 0.0, 0.0)),                 # centre inside, nearest face x = 0.5
])
def test_sphere_against_box_regions(offset, nearest):
    """Box turned and moved (frame bugs); offset and nearest point in the box's frame."""
    q = axis_angle((1, 2, 3), 0.9)
    r, x = quat.to_matrix(q), np.array([0.3, -0.4, 1.2])
    scene = rg.Scene()
    scene.add_body(rg.Box((0.5, 0.4, 0.3)), static=True, position=x, orientation=q)
    centre = x + r @ offset
    scene.add_body(rg.Sphere(0.1), mass=1.0, position=centre)
    c = contacts(scene)
    gap = np.subtract(offset, nearest)
    distance = np.linalg.norm(gap)
    inside = np.all(np.abs(offset) <= (0.5, 0.4, 0.3))
    n_local = unit(gap) * (-1 if inside else 1)
    assert len(c.depth) == 1 and (c.body_a[0], c.body_b[0]) == (1, 0)
    np.testing.assert_allclose(c.depth[0], 0.1 + (distance if inside else -distance), atol=EXACT)
    np.testing.assert_allclose(c.normal[0], r @ n_local, atol=1e-12)
    np.testing.assert_allclose(c.point[0], centre - 0.1 * (r @ n_local), atol=1e-12)


# -- meshes ---------------------------------------------------------------------------------------


def test_ball_touching_the_inner_wall_of_a_bowl():
    """A ball in the cavity of the static bowl (a nonconvex mesh), 45 degrees down its wall: the
    normal points into the cavity, from the wall towards the ball's centre (the hull of the
    bowl would push it up or out). Depth: against the mesh's exact signed distance (the mesh's
    facets lie inside the sphere of radius 0.4), within the grid bound. Direction: within 10
    degrees of the exact sphere's radial direction: the facets deviate from the sphere by up to
    pi / (4 rings) = 5.6 degrees (rings = 8) and pi / (2 segments) = 2.8 (segments = 32) and
    the trilinear gradient is a one-sided difference on the grid planes (measured 4.7)."""
    bowl = bowl_mesh()
    d = 0.3 / np.sqrt(2.0)
    centre = np.array([d, 0.0, -d])
    scene = rg.Scene()
    scene.add_body(bowl, static=True)
    scene.add_body(rg.Sphere(0.1), mass=1.0, position=centre)
    c = contacts(scene)
    assert len(c.depth) == 1 and (c.body_a[0], c.body_b[0]) == (1, 0)
    inward = -unit(centre)
    assert np.degrees(np.arccos(c.normal[0] @ inward)) < 10.0
    assert c.normal[0, 0] < -0.6  # towards the axis: from the wall, not from the hull
    expected = 0.1 - bowl.signed_distance(centre[None])[0]
    assert expected > 0.0
    assert abs(c.depth[0] - expected) <= grid_bound(bowl)
    # the point is the ball's deepest point, inside (or within the bound of) the wall
    assert bowl.signed_distance(c.point)[0] <= grid_bound(bowl)
    np.testing.assert_allclose(np.linalg.norm(c.point[0] - centre), 0.1, atol=1e-12)


def test_ball_resting_in_the_bottom_of_a_bowl():
    """At the bottom the normal is up (within 10 degrees: the pole is a shallow cone of facets
    tilted 5.6 degrees, seen from a grid node by one-sided differences along x and y:
    sqrt(2) tan 5.6 deg -> 7.9 degrees measured) and the depth within the grid bound."""
    bowl = bowl_mesh()
    centre = np.array([0.0, 0.0, -0.4 + 0.1 - 0.005])
    scene = rg.Scene()
    scene.add_body(bowl, static=True)
    scene.add_body(rg.Sphere(0.1), mass=1.0, position=centre)
    c = contacts(scene)
    assert len(c.depth) == 1
    assert c.normal[0, 2] > np.cos(np.radians(10.0))
    expected = 0.1 - bowl.signed_distance(centre[None])[0]
    assert abs(c.depth[0] - expected) <= grid_bound(bowl)


def test_ball_above_the_bowl_rim_or_in_its_middle_has_no_contact():
    scene = rg.Scene()
    scene.add_body(bowl_mesh(), static=True)
    scene.add_body(rg.Sphere(0.1), mass=1.0, position=(0, 0, -0.2))  # in the cavity, free
    scene.add_body(rg.Sphere(0.02), mass=1.0, position=(0.45, 0, 0.05))  # over the rim
    assert len(contacts(scene).depth) == 0


def test_big_ball_on_a_ramp_mesh_is_answered_exactly_outside_the_grid():
    """A ball much larger than the mesh's grid padding: its centre lies outside the grid, where
    the grid only bounds phi; the narrow phase then measures the exact distance to the
    triangles (before, the contact was missed or had a sideways normal)."""
    ramp = prism_mesh([[0, 0], [1, 0], [0, 0.5]], -0.5, 0.5)  # slope x + 2 y = 1
    n = unit([1.0, 2.0, 0.0])
    foot = np.array([0.5, 0.25, 0.1])
    for radius in (0.05, 0.3, 1.0):
        scene = rg.Scene()
        scene.add_body(ramp, static=True)
        scene.add_body(rg.Sphere(radius), mass=1.0, position=foot + (radius - 0.01) * n)
        c = contacts(scene)
        assert len(c.depth) == 1
        np.testing.assert_allclose(c.normal[0], n, atol=1e-9)
        np.testing.assert_allclose(c.depth[0], 0.01, atol=1e-9)
        np.testing.assert_allclose(c.point[0], foot - 0.01 * n, atol=1e-9)


def test_big_ball_at_the_corner_of_a_mesh_box():
    """Diagonally off a corner, far outside the grid: normal along the diagonal, exact depth."""
    scene = rg.Scene()
    scene.add_body(box_mesh((0.1, 0.1, 0.1)), static=True)
    diagonal = unit([1, 1, 1])
    scene.add_body(rg.Sphere(0.5), mass=1.0, position=0.1 + (0.5 - 0.002) * diagonal)
    c = contacts(scene)
    assert len(c.depth) == 1
    np.testing.assert_allclose(c.normal[0], diagonal, atol=1e-9)
    np.testing.assert_allclose(c.depth[0], 0.002, atol=1e-9)


def test_sphere_on_a_mesh_box_depth_within_the_grid_bound():
    mesh = box_mesh((0.4, 0.3, 0.2))
    rng = np.random.default_rng(0)
    for _ in range(10):
        x, y = rng.uniform(-0.35, 0.35), rng.uniform(-0.25, 0.25)
        depth = rng.uniform(0.0005, 0.02)
        scene = rg.Scene()
        scene.add_body(mesh, static=True)
        scene.add_body(rg.Sphere(0.03), mass=1.0, position=(x, y, 0.2 + 0.03 - depth))
        c = contacts(scene)
        assert len(c.depth) == 1
        assert abs(c.depth[0] - depth) <= grid_bound(mesh)
        assert c.normal[0, 2] > 0.99


def test_capsule_lying_in_a_mesh_box_and_across_its_edge():
    """Against a mesh a capsule has its ends and the refined local minima of phi along it."""
    mesh = box_mesh((0.5, 0.5, 0.5))
    scene = rg.Scene()
    scene.add_body(mesh, static=True)
    scene.add_body(rg.Capsule(0.1, 0.3), mass=1.0, position=(0.1, 0.2, 0.59),
                   orientation=axis_angle((0, 1, 0), np.pi / 2))
    c = contacts(scene)
    assert len(c.depth) == 2
    assert np.all(np.abs(c.depth - 0.01) <= grid_bound(mesh))
    np.testing.assert_allclose(sorted_rows(c.point)[:, :2], [[-0.2, 0.2], [0.4, 0.2]], atol=1e-9)
    scene, _nearest, n = capsule_across_edge(0.1, 0.4, 0.01, np.radians(30), 0.13, box=mesh)
    c = contacts(scene)
    assert len(c.depth) == 1
    assert abs(c.depth[0] - 0.01) <= grid_bound(mesh)
    assert np.degrees(np.arccos(np.clip(c.normal[0] @ n, -1, 1))) < 15.0


@pytest.mark.parametrize("resolution", [32, 128])
def test_capsule_across_the_ridges_of_a_mesh_keeps_its_deepest_three(resolution):
    """A capsule tilted across 4 parallel ridges of a saw-tooth prism mesh touches them 4, 14, 24
    and 34 mm deep and its ends touch nothing: each ridge is a local minimum of phi along the
    core; the deepest CAPSULE_CORE_SAMPLES - 2 = 3 are kept (the cap that
    ``geometry.max_pair_contacts`` relies on), at the ridges, depths within the grid bound.

    Limitation of the grid: the core passes 16-46 mm above sharp (103 degree) ridges, i.e.
    0.5-1.5 cells at the default resolution 32 (h = 31 mm), where the trilinear gradient of a
    kinked phi is poor: normals were measured up to 34 degrees off (and points up to 2 cm
    along the axis), so only their rough direction is checked there; at resolution 128 they
    are within 3 degrees and points within 1 cm."""
    top = [(1.0, 0.2)]
    for ridge in (0.8, 0.6, 0.4, 0.2):
        top += [(ridge + 0.05, 0.2), (ridge, 0.24), (ridge - 0.05, 0.2)]
    polygon = [(0.5, -0.5), (1.0, -0.5)] + top + [(0.0, 0.2), (0.0, -0.5)]
    saw = prism_mesh(polygon, -0.2, 0.2)
    saw = rg.Mesh(saw.vertices, saw.triangles, sdf_resolution=resolution)
    radius, slope = 0.05, -0.05
    depth_at = lambda x: 0.004 + 0.05 * (x - 0.2)
    centre = np.array([0.5, 0.24 + radius - depth_at(0.5), 0.0])
    q = quat.multiply(axis_angle((0, 0, 1), np.arctan(slope)), axis_angle((0, 1, 0), np.pi / 2))
    scene = rg.Scene()
    scene.add_body(saw, static=True)
    scene.add_body(rg.Capsule(radius, 0.6 * np.hypot(1, slope)), mass=1.0, position=centre,
                   orientation=q)
    c = contacts(scene)
    assert len(c.depth) == 3
    order = np.argsort(c.point[:, 0])
    assert np.all(np.abs(c.depth[order] - [0.014, 0.024, 0.034]) <= grid_bound(saw))
    exact = unit([-slope, 1, 0])  # perpendicular to the axis, in the plane of the ridge's tip
    if resolution == 128:
        np.testing.assert_allclose(c.point[order, 0], [0.4, 0.6, 0.8], atol=0.01)
        assert np.all(np.degrees(np.arccos(np.clip(c.normal @ exact, -1, 1))) < 3.0)
    else:
        np.testing.assert_allclose(c.point[order, 0], [0.4, 0.6, 0.8], atol=0.031)
        assert np.all(c.normal[:, 1] > 0.8)


def test_box_on_a_mesh_box_matches_box_on_box():
    """A Box resting on a box_mesh of the same size (a mesh goes through the sampled path)
    against the same Box on a Box (closed form): same normal and depth, and the contact
    points cover the same overlap rectangle."""
    results = []
    for lower in (rg.Box((0.5, 0.5, 0.5)), box_mesh((0.5, 0.5, 0.5))):
        scene = rg.Scene()
        scene.add_body(lower, static=True)
        scene.add_body(rg.Box((0.5, 0.5, 0.5)), mass=1.0, position=(0.1, 0.2, 0.99))
        results.append(contacts(scene))
    for c in results:
        assert len(c.depth) >= 4
        np.testing.assert_allclose(c.normal, np.tile([0, 0, 1.0], (len(c.depth), 1)), atol=1e-9)
        np.testing.assert_allclose(c.depth, 0.01, atol=1e-9)
        np.testing.assert_allclose(c.point[:, :2].min(axis=0), [-0.4, -0.3], atol=1e-9)
        np.testing.assert_allclose(c.point[:, :2].max(axis=0), [0.5, 0.5], atol=1e-9)
        assert np.all((c.point[:, 2] >= 0.49 - 1e-9) & (c.point[:, 2] <= 0.5 + 1e-9))


def test_mesh_on_the_ground():
    """A box mesh flat (4 vertex contacts) and the L mesh lying on its side (its 6 bottom
    vertices), turned about z and moved: vertices are exact against a plane."""
    q = axis_angle((0, 0, 1), 0.5)
    r = quat.to_matrix(q)
    for mesh, bottom in ((box_mesh((0.3, 0.2, 0.1)), -0.1), (l_shape_mesh(), -0.25)):
        x = np.array([1.0, -2.0, -bottom - 0.004])
        scene = rg.Scene()
        scene.add_ground()
        scene.add_body(mesh, density=100.0, position=x, orientation=q)
        c = contacts(scene)
        expected = [x + r @ v for v in mesh.vertices if np.isclose(v[2], bottom)]
        assert len(c.depth) == len(expected)
        np.testing.assert_allclose(c.depth, 0.004, atol=1e-12)
        np.testing.assert_allclose(c.normal, np.tile([0, 0, 1.0], (len(expected), 1)), atol=1e-12)
        np.testing.assert_allclose(sorted_rows(c.point), sorted_rows(expected), atol=1e-9)


def test_mesh_on_mesh():
    """A box mesh resting 5 mm deep on another: every point in the overlap slab, depths at most
    5 mm plus the grid bound, normals +z -- except, as GBF's point-wise method gives, for
    samples of the lower mesh lying nearer to a side face of the upper one than to its bottom
    face (within depth + bound of its sides): their normal is (a grid blend of) that side's
    (a limitation of sampled signed distances, which boxbox.py avoids for Box pairs)."""
    upper, lower = box_mesh((0.2, 0.2, 0.1)), box_mesh((0.5, 0.5, 0.1))
    scene = rg.Scene()
    scene.add_body(lower, static=True)
    scene.add_body(upper, mass=1.0, position=(0.1, 0, 0.2 - 0.005))
    c = contacts(scene)
    bound = max(grid_bound(upper), grid_bound(lower))
    assert len(c.depth) >= 4
    assert np.all((c.depth > 0) & (c.depth <= 0.005 + bound))
    assert np.all((c.point[:, 2] >= 0.095 - 1e-9) & (c.point[:, 2] <= 0.1 + 1e-9))
    near_side = ((np.abs(c.point[:, 0] - 0.1) >= 0.2 - 0.005 - bound)
                 | (np.abs(c.point[:, 1]) >= 0.2 - 0.005 - bound))
    assert np.all((c.normal[:, 2] > 0.99) | near_side)
    assert np.count_nonzero(c.normal[:, 2] > 0.99) >= 0.9 * len(c.depth)


def test_compound_of_two_boxes_on_the_ground():
    """Two boxes of different sizes whose bottoms are level: the 8 bottom corners, placed
    through the compound's principal frame (its centre of mass is off the shape origin)."""
    shape = rg.Compound(((rg.Box((0.2, 0.2, 0.2)), ((0.3, 0, 0), (1, 0, 0, 0))),
                         (rg.Box((0.1, 0.1, 0.1)), ((-0.3, 0, -0.1), (1, 0, 0, 0)))))
    q = axis_angle((0, 0, 1), 1.1)
    r, x = quat.to_matrix(q), np.array([0.5, 0.5, 0.2 - 0.006])
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(shape, mass=2.0, position=x, orientation=q)
    assert not np.allclose(scene.bodies[1].body_from_shape.position, 0.0)
    c = contacts(scene)
    corners = [(0.3 + 0.2 * sx, 0.2 * sy, -0.2) for sx in (-1, 1) for sy in (-1, 1)]
    corners += [(-0.3 + 0.1 * sx, 0.1 * sy, -0.2) for sx in (-1, 1) for sy in (-1, 1)]
    expected = [x + r @ p for p in corners]
    assert len(c.depth) == 8
    np.testing.assert_allclose(c.depth, 0.006, atol=1e-12)
    np.testing.assert_allclose(sorted_rows(c.point), sorted_rows(expected), atol=1e-9)


def test_compound_against_a_box():
    """A compound's parts each collide: the two feet of an arch on a static box."""
    foot = rg.Box((0.1, 0.1, 0.2))
    arch = rg.Compound(((foot, ((-0.4, 0, 0), (1, 0, 0, 0))), (foot, ((0.4, 0, 0), (1, 0, 0, 0))),
                        (rg.Box((0.5, 0.1, 0.05)), ((0, 0, 0.25), (1, 0, 0, 0)))))
    scene = rg.Scene()
    scene.add_body(rg.Box((1.0, 1.0, 0.5)), static=True)
    scene.add_body(arch, mass=1.0, position=(0, 0, 0.5 + 0.2 - 0.002))
    c = contacts(scene)
    assert len(c.depth) == 8
    np.testing.assert_allclose(c.depth, 0.002, atol=1e-12)
    assert np.all(np.abs(np.abs(c.point[:, 0]) - 0.4) <= 0.1 + 1e-12)


# -- frames, ordering, batching, buffers ------------------------------------------------------


def rigidly_moved(scene_bodies, q, t):
    """A scene whose bodies are those given ((shape, kwargs) with shape-frame poses) moved by
    the rigid motion x -> R(q) x + t."""
    r = quat.to_matrix(q)
    scene = rg.Scene()
    for shape, kw in scene_bodies:
        kw = dict(kw)
        kw["position"] = r @ np.asarray(kw.get("position", (0, 0, 0)), dtype=float) + t
        kw["orientation"] = quat.multiply(q, kw.get("orientation", (1, 0, 0, 0)))
        scene.add_body(shape, **kw)
    return scene


FRAME_SCENES = {
    "box on tilted ground": [(rg.Plane(), {"static": True}),
                             (rg.Box((0.3, 0.2, 0.1)), {"mass": 1.0, "position": (0, 0, 0.095)})],
    "edge on box": [(rg.Box((0.5, 0.5, 0.5)),
                     {"static": True, "orientation": axis_angle((0, 1, 0), 0.8)}),
                    (rg.Box((0.3, 0.3, 0.3)), {"mass": 1.0, "position": (0.05, 0.02, 0.95),
                                               "orientation": axis_angle((1, 0.2, 0), 0.7)})],
    "capsule on box": [(rg.Box((0.5, 0.5, 0.5)), {"static": True}),
                       (rg.Capsule(0.1, 0.3), {"mass": 1.0, "position": (0.1, 0, 0.58),
                                               "orientation": axis_angle((0, 1, 0.3), 1.3)})],
    "sphere in bowl": [(bowl_mesh(), {"static": True}),
                       (rg.Sphere(0.1), {"mass": 1.0, "position": (0.2, 0.1, -0.22)})],
    "L on box": [(rg.Box((1.0, 1.0, 0.2)), {"static": True}),
                 (l_shape_mesh(), {"density": 50.0, "position": (-0.3, -0.2, 0.2 + 0.25 - 0.004)})],
    "compound on ground": [(rg.Plane(), {"static": True}),
                           (rg.Compound(((rg.Box((0.2, 0.1, 0.1)), ((0.2, 0, 0), (1, 0, 0, 0))),
                                         (rg.Sphere(0.1), ((-0.2, 0, 0), (1, 0, 0, 0))))),
                            {"mass": 1.0, "position": (0, 0, 0.097)})],
}


@pytest.mark.parametrize("name", sorted(FRAME_SCENES))
def test_contacts_move_with_the_scene(name):
    """Moving every body of a scene by one rigid motion moves its contacts by it: points by
    x -> R x + t, normals by R, depths unchanged. Meshes are compared within the grid bound
    (the grid is fixed to the mesh, so in fact to rounding)."""
    bodies = FRAME_SCENES[name]
    base = contacts(rigidly_moved(bodies, (1, 0, 0, 0), np.zeros(3)))
    assert len(base.depth) > 0, name
    q = unit([0.8, 0.3, -0.4, 0.33])
    t = np.array([1.5, -2.0, 0.7])
    moved = contacts(rigidly_moved(bodies, q, t))
    r = quat.to_matrix(q)
    assert len(moved.depth) == len(base.depth)
    # the order of equally deep contacts may change: match each to the nearest moved point
    expected = base.point @ r.T + t
    match = np.argmin(np.linalg.norm(moved.point[:, None] - expected[None], axis=2), axis=0)
    assert len(set(match)) == len(match)
    np.testing.assert_allclose(moved.point[match], expected, atol=1e-9)
    np.testing.assert_allclose(moved.depth[match], base.depth, atol=1e-9)
    np.testing.assert_allclose(moved.normal[match], base.normal @ r.T, atol=1e-9)


def test_pairs_are_ordered_by_motion_class():
    """Dynamic > kinematic > static: the normal always points towards the more mobile body."""
    scene = rg.Scene()
    scene.add_body(rg.Box((0.5, 0.5, 0.5)), static=True)                          # 0
    scene.add_body(rg.Box((0.2, 0.2, 0.2)), kinematic=True, position=(0, 0, 0.69))  # 1
    scene.add_body(rg.Sphere(0.1), mass=1.0, position=(0, 0, 0.98))                # 2
    scene.add_body(rg.Box((0.1, 0.1, 0.1)), kinematic=True, position=(0.45, 0.45, 0.59))  # 3
    c = contacts(scene)
    pairs = sorted({(a, b) for a, b in zip(c.body_a, c.body_b)})
    assert pairs == [(2, 1)]  # kinematic-static pairs are skipped: nothing can respond
    np.testing.assert_allclose(c.normal, [[0, 0, 1.0]] * len(c.depth), atol=EXACT)


def test_turned_boxes_whose_world_boxes_overlap_are_not_paired():
    """Two unit cubes turned 45 degrees about z, diagonal neighbours: their world-aligned
    boxes (half width 0.707 m) overlap, but the cubes are 1.2 sqrt(2) - 1 = 0.697 m apart
    along the diagonal (a face normal of both): the broad phase's separating-axis test drops
    the pair. Moved to 0.5 sqrt(2) apart on each axis they touch face to face and are paired."""
    q = axis_angle((0, 0, 1), np.pi / 4)
    for offset, paired in ((1.2, False), (0.5 * np.sqrt(2) - 1e-6, True)):
        scene = rg.Scene()
        scene.add_body(rg.Box((0.5, 0.5, 0.5)), mass=1.0, orientation=q)
        scene.add_body(rg.Box((0.5, 0.5, 0.5)), mass=1.0, position=(offset, offset, 0),
                       orientation=q)
        world = rg.World(scene)
        assert (len(world.candidate_pairs()) == 1) == paired, offset


def test_boxes_within_the_margin_are_always_paired():
    """Random pairs of turned boxes near each other: wherever some point of A's surface is
    within the margin of B (B's exact signed distance, numpy, at corners, edge and face
    samples of A: an upper bound on their distance), the broad phase lists the pair. Cases
    that are listed while farther apart than that are allowed (the test is conservative), but
    the turned-box test must drop some that the world-aligned boxes keep."""
    rng = np.random.default_rng(3)
    margin = 0.01
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    s = np.linspace(-1.0, 1.0, 41)
    edges = np.concatenate([np.column_stack([s, np.full_like(s, y), np.full_like(s, z)])[:, perm]
                            for y in (-1, 1) for z in (-1, 1)
                            for perm in ([0, 1, 2], [1, 0, 2], [1, 2, 0])])
    faces = rng.uniform(-1, 1, (3000, 3))
    faces[np.arange(3000), rng.integers(0, 3, 3000)] = rng.choice([-1.0, 1.0], 3000)
    unit_surface = np.concatenate([corners, edges, faces])
    dropped = 0
    for _ in range(300):
        half_a, half_b = rng.uniform(0.05, 0.5, 3), rng.uniform(0.05, 0.5, 3)
        qa, qb = unit(rng.normal(size=4)), unit(rng.normal(size=4))
        xb = rng.uniform(-1.0, 1.0, 3)
        scene = rg.Scene()
        scene.add_body(rg.Box(half_a), mass=1.0, orientation=qa)
        scene.add_body(rg.Box(half_b), mass=1.0, position=xb, orientation=qb)
        world = rg.World(scene)
        listed = len(world.candidate_pairs(margin=margin)) == 1
        surface_a = (unit_surface * half_a) @ quat.to_matrix(qa).T
        in_b = (surface_a - xb) @ quat.to_matrix(qb)
        near = rg.Box(half_b).signed_distance(in_b).min() <= margin
        assert listed or not near, (half_a, half_b, qa, qb, xb)
        world_boxes = (np.abs(quat.to_matrix(qa)) @ half_a + np.abs(quat.to_matrix(qb)) @ half_b
                       + 2 * margin)
        dropped += bool(np.all(np.abs(xb) <= world_boxes) and not listed)
    assert dropped > 0


def test_deepest_contact_of_each_pair_comes_first():
    scene = rg.Scene()
    scene.add_ground()
    for k in range(3):
        q = axis_angle((1, 1 + k, 0), 0.2 + 0.1 * k)
        scene.add_body(rg.Box((0.3, 0.2, 0.1)), mass=1.0, position=(k, 0, 0.12), orientation=q)
    scene.add_body(rg.Box((0.5, 0.5, 0.5)), static=True, position=(5, 0, 0))
    scene.add_body(rg.Box((0.3, 0.3, 0.3)), mass=1.0, position=(5.1, 0, 0.78),
                   orientation=axis_angle((1, 0.5, 0), 0.1))
    c = contacts(scene)
    assert len({(a, b) for a, b in zip(c.body_a, c.body_b)}) >= 4
    assert_deepest_first(c)
    assert_unit_normals(c)


def test_margin_reports_near_contacts_with_negative_depth():
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Sphere(0.1), mass=1.0, position=(0, 0, 0.103))
    scene.add_body(rg.Box((0.1, 0.1, 0.1)), mass=1.0, position=(1, 0, 0.102))
    scene.add_body(box_mesh((0.1, 0.1, 0.1)), mass=1.0, position=(2, 0, 0.101))
    world = rg.World(scene)
    assert len(world.contacts().depth) == 0
    c = world.contacts(margin=0.005)
    assert len(c.depth) == 1 + 4 + 4
    expected = {1: -0.003, 2: -0.002, 3: -0.001}
    np.testing.assert_allclose(c.depth, [expected[a] for a in c.body_a], atol=1e-12)


SEPARATED = {
    "sphere": rg.Sphere(0.2),
    "box": rg.Box((0.2, 0.15, 0.1)),
    "capsule": rg.Capsule(0.1, 0.2),
    "mesh": box_mesh((0.2, 0.15, 0.1)),
    "L mesh": l_shape_mesh((0.5, 0.5), 0.15, 0.1),
    "compound": rg.Compound(((rg.Box((0.1, 0.1, 0.1)), ((0.1, 0, 0), (1, 0, 0, 0))),
                             (rg.Sphere(0.1), ((-0.1, 0, 0), (1, 0, 0, 0))))),
}


def support_point(shape, q, d):
    """The point of ``shape`` (shape frame at the origin, turned by q) furthest along d."""
    r = quat.to_matrix(q)
    d = np.asarray(d, dtype=float)
    if isinstance(shape, rg.Sphere):
        return shape.radius * d
    if isinstance(shape, rg.Box):
        return r @ (shape.half_extents * np.sign(r.T @ d))
    if isinstance(shape, rg.Capsule):
        return r @ (0, 0, shape.half_length * np.sign(r[:, 2] @ d)) + shape.radius * d
    if isinstance(shape, rg.Mesh):
        v = shape.vertices @ r.T
        return v[np.argmax(v @ d)]
    points = [r @ p.position + support_point(s, quat.multiply(q, p.orientation), d)
              for s, p in shape.parts]
    return max(points, key=lambda p: p @ d)


@pytest.mark.parametrize("lower", ["ground"] + sorted(SEPARATED))
@pytest.mark.parametrize("upper", sorted(SEPARATED))
def test_separated_pairs_report_nothing(lower, upper):
    """Every pair type, turned, the upper body's lowest point straight above the lower body's
    highest point (so the bodies are exactly ``gap`` apart, the plane between them separating
    them): 1e-4 m for exact types, plus the grid bound where a mesh is involved (its phi may
    be that much too small): no contacts. Pushed 2 mm (plus the bound) together, they touch."""
    qa, qb = unit([1, 0.2, 0.3, 0.1]), unit([1, -0.3, 0.1, 0.4])
    shapes = [SEPARATED.get(lower), SEPARATED[upper]]
    bound = max([grid_bound(s) for s in shapes if isinstance(s, rg.Mesh)] + [0.0])
    top = np.zeros(3) if lower == "ground" else support_point(SEPARATED[lower], qb, (0, 0, 1))
    bottom = support_point(SEPARATED[upper], qa, (0, 0, -1))
    for shift, expect in ((1e-4 + bound, False), (-0.002 - bound, True)):
        scene = rg.Scene()
        if lower == "ground":
            scene.add_ground()
        else:
            scene.add_body(SEPARATED[lower], static=True, orientation=qb)
        scene.add_body(SEPARATED[upper], mass=1.0, position=top - bottom + (0, 0, shift),
                       orientation=qa)
        c = contacts(scene)
        assert (len(c.depth) > 0) == expect, (lower, upper, shift)
        if expect:
            assert np.all(c.depth <= 0.002 + 2 * bound + 1e-9)


def test_batched_worlds_report_their_own_contacts():
    """Three worlds with different poses (set_pose per world): each world's contacts carry its
    index and equal those of a single world set up the same way."""
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Sphere(0.1), mass=1.0, position=(0, 0, 1.0))
    scene.add_body(rg.Box((0.1, 0.1, 0.1)), mass=1.0, position=(1, 0, 1.0))
    poses = [
        {},                                                     # world 0: nothing touches
        {1: ((0, 0, 0.09), None)},                              # world 1: sphere on the ground
        {2: ((1, 0, 0.095), axis_angle((0, 0, 1), 0.3)),        # world 2: box on the ground,
         1: ((1.0, 0, 0.295), None)},                           #   sphere on the box
    ]
    batched = rg.World(scene, num_worlds=3)
    for w, pose in enumerate(poses):
        for body, (x, q) in pose.items():
            batched.set_pose(body, x, q, world=w)
    c = batched.contacts()
    assert set(c.world) == {1, 2}
    for w, pose in enumerate(poses):
        single = rg.World(scene)
        for body, (x, q) in pose.items():
            single.set_pose(body, x, q)
        s = single.contacts()
        rows = c.world == w
        for name in ("body_a", "body_b", "point", "normal", "depth"):
            np.testing.assert_array_equal(getattr(c, name)[rows], getattr(s, name))
    rows = c.world == 2
    assert sorted({(a, b) for a, b in zip(c.body_a[rows], c.body_b[rows])}) == [(1, 2), (2, 0)]
    np.testing.assert_allclose(c.depth[rows & (c.body_b == 0)], 0.005, atol=1e-12)
    np.testing.assert_allclose(c.depth[rows & (c.body_b == 2)], 0.0, atol=1e-12)


@pytest.mark.parametrize("sweep", [True, False])
def test_many_boxes_on_the_ground_report_every_contact(sweep):
    """200 boxes resting on the ground: 800 corner contacts, far more than the initial buffers
    hold; they grow and nothing is lost."""
    scene = rg.Scene()
    scene.add_ground()
    for i in range(200):
        scene.add_body(rg.Box((0.1, 0.1, 0.1)), mass=1.0,
                       position=(0.3 * (i % 20), 0.3 * (i // 20), 0.099))
    world = rg.World(scene, config=rg.SolverConfig(sweep=sweep))
    c = world.contacts()
    assert len(c.depth) == 800
    assert np.array_equal(np.bincount(c.body_a, minlength=201)[1:], np.full(200, 4))
    np.testing.assert_allclose(c.depth, 0.001, atol=1e-12)


def test_dense_pile_grows_pair_and_contact_buffers_and_sweep_agrees():
    """A 4 x 4 x 3 block of cubes each 1 mm into its neighbours: more candidate pairs than the
    pair buffer first holds (2 n) and many contacts; sort-and-sweep and brute force agree."""
    scene = rg.Scene()
    scene.add_ground()
    for i in range(4):
        for j in range(4):
            for k in range(3):
                scene.add_body(rg.Box((0.1, 0.1, 0.1)), mass=1.0,
                               position=(0.199 * i, 0.199 * j, 0.099 + 0.199 * k))
    results = []
    for sweep in (True, False):
        world = rg.World(scene, config=rg.SolverConfig(sweep=sweep))
        results.append(world.contacts())
        assert len(world.candidate_pairs()) > 2 * len(scene)
    a, b = results
    for name in a._fields:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    # face neighbours: 3 * 4 * 4 * 2 along x and y ... each touching pair has 4 contacts
    pairs = {(p, q) for p, q in zip(a.body_a, a.body_b) if q != 0}
    face_pairs = 2 * 3 * 4 * 3 + 4 * 4 * 2
    assert len(pairs) >= face_pairs
    assert np.count_nonzero(a.body_b == 0) == 16 * 4


def test_pairs_of_a_pile_are_listed_once_each_in_body_order():
    """300 settling bodies: keys a n + b past two bytes, so the pair sort (a radix sort, a
    byte a pass) takes three passes. The listed pairs are strictly increasing in (a, b), and
    sort-and-sweep lists exactly the pairs brute force does, in the same order."""
    from rigid_gym.report.scenes import pile

    scene = pile(300)
    swept = rg.World(scene, dt=1 / 240)
    swept.step(120)
    brute = rg.World(scene, dt=1 / 240, config=dataclasses.replace(swept.config, sweep=False))
    for theirs, ours in zip(brute.state, swept.state):
        theirs[...] = ours
    pairs = swept.candidate_pairs()
    keys = pairs[:, 0].astype(np.int64) * len(scene.bodies) + pairs[:, 1]
    assert len(pairs) > 2 * len(scene.bodies)
    assert np.all(np.diff(keys) > 0)
    np.testing.assert_array_equal(brute.candidate_pairs(), pairs)
