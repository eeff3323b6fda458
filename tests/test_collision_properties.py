"""Property tests of collision detection: random poses of random pairs of shapes.

A pair (sphere, box, capsule or mesh, each of random size) is placed near touching: B's shape
frame is put along a random unit direction u from A's, so that their extents along u (their
support functions) overlap by -g, with g drawn from [-0.1, 0.1] m. Then

* g > 0 means the plane between the two supports separates them by g: no contact may be
  reported once g exceeds the detection tolerance;
* every point of either shape that lies inside the other is within -g of its boundary (it
  lies in the slab between the supports), and for every contact type the reported depth is
  such a distance, so depth <= -g (times 1.05 + 1 um for box pairs, whose face axes are
  preferred over edge axes by that much, ``boxbox.FACE_PREFERENCE_*``);
* every contact point lies inside or on both shapes, by each shape's own exact signed
  distance (numpy, ``Shape.signed_distance``) evaluated in its frame: world -> body frame by
  the world's pose of the body -> shape frame by ``BodySpec.body_from_shape``;
* the normal points out of B or into A at the point (finite differences of the exact signed
  distances), i.e. from B towards A;
* if a dense sampling of one shape's surface finds points inside the other deeper than the
  method's resolution, at least one contact is reported.

Shapes are at least 0.2 m thick (half sizes >= 0.1 m; the meshes' walls >= 0.12 m), so the
overlap of at most 0.1 m cannot pass through either, which keeps "inside both" meaningful.

Tolerances (per shape): closed forms 1e-9 m (rounding); a mesh's phi is its exact signed
distance sampled on a grid of spacing h = longest side / sdf_resolution, trilinearly
interpolated: at most (sqrt(3) / 2) h from the exact value (the bound derived in
test_collision.py), which is the tolerance wherever a mesh's phi decides. Completeness for a
pair with a mesh: its vertices are samples and its edges carry samples at most h apart; as
signed distances are 1-Lipschitz, the sample nearest to an edge's deepest point is at most h / 2
less deep, and a sample reads inside the other shape's phi when it is deeper than that phi's
error (0 for closed forms, the grid bound for a mesh). So once the overlap exceeds
h / 2 + (grid bound) for each mesh involved, a contact is expected (an argument rather than a
proof: the corners of the overlap of two polyhedra are vertices of one inside the other or
edges of one crossing faces of the other, which is where the samples are; a sphere's or
capsule's core is answered exactly up to the grid bound).
"""

import numpy as np
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import rigid_gym as rg
from rigid_gym import quaternion as quat
from rigid_gym.collision import TOUCHING_GAP
from rigid_gym.meshes import bowl_mesh, box_mesh, l_shape_mesh, prism_mesh

EXACT = 1e-9


def _coarse_bowl():
    bowl = bowl_mesh(0.5, 0.38, segments=16, rings=4)
    return rg.Mesh(bowl.vertices, bowl.triangles, sdf_resolution=16)


MESHES = [
    box_mesh((0.3, 0.2, 0.15)),
    box_mesh((0.5, 0.12, 0.4)),
    l_shape_mesh((0.8, 0.6), 0.25, 0.2),
    prism_mesh([[0.0, 0.0], [0.6, 0.0], [0.0, 0.4]], -0.25, 0.25),  # a wedge
    _coarse_bowl(),                                                  # nonconvex, curved
]


def grid_spacing(mesh):
    lower, upper = mesh.bounds()
    return float(np.max(upper - lower)) / mesh.sdf_resolution


def grid_bound(shape):
    """How far a shape's phi may be from its exact signed distance, m."""
    if isinstance(shape, rg.Mesh):
        return np.sqrt(3.0) / 2.0 * grid_spacing(shape)
    return 0.0


half = st.floats(0.1, 0.5)
shapes = st.one_of(
    st.builds(rg.Sphere, half),
    st.builds(lambda x, y, z: rg.Box((x, y, z)), half, half, half),
    st.builds(rg.Capsule, st.floats(0.1, 0.3), st.floats(0.02, 1.2)),
    st.sampled_from(MESHES),
)
unit_quaternions = st.tuples(*[st.floats(-1, 1)] * 4).filter(
    lambda q: np.linalg.norm(q) > 0.2).map(lambda q: np.array(q) / np.linalg.norm(q))
directions = st.tuples(*[st.floats(-1, 1)] * 3).filter(
    lambda v: np.linalg.norm(v) > 0.2).map(lambda v: np.array(v) / np.linalg.norm(v))


def support(shape, r, u):
    """max over the shape (turned by r, shape origin at 0) of u . p, m."""
    if isinstance(shape, rg.Sphere):
        return shape.radius
    if isinstance(shape, rg.Box):
        return float(np.sum(shape.half_extents * np.abs(r.T @ u)))
    if isinstance(shape, rg.Capsule):
        return shape.radius + shape.half_length * abs(r[:, 2] @ u)
    return float(np.max(shape.vertices @ (r.T @ u)))


def surface_samples(shape, rng, count=3000):
    """Points on the shape's surface, shape frame: random ones plus, for boxes and meshes,
    the vertices and points along the edges (where the deepest points of polyhedra lie)."""
    if isinstance(shape, rg.Sphere):
        v = rng.normal(size=(count, 3))
        return shape.radius * v / np.linalg.norm(v, axis=1, keepdims=True)
    if isinstance(shape, rg.Capsule):
        v = rng.normal(size=(count, 3))
        v = shape.radius * v / np.linalg.norm(v, axis=1, keepdims=True)
        v[:, 2] += np.sign(v[:, 2]) * shape.half_length
        angle = rng.uniform(0, 2 * np.pi, count)
        side = np.column_stack([shape.radius * np.cos(angle), shape.radius * np.sin(angle),
                                rng.uniform(-1, 1, count) * shape.half_length])
        return np.concatenate([v, side])
    if isinstance(shape, rg.Box):
        shape = box_mesh(shape.half_extents)
    t = shape.vertices[shape.triangles]
    area = np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    k = rng.choice(len(t), count, p=area / area.sum())
    a, b = rng.random(count), rng.random(count)
    flip = a + b > 1
    a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
    faces = t[k, 0] + a[:, None] * (t[k, 1] - t[k, 0]) + b[:, None] * (t[k, 2] - t[k, 0])
    s = np.linspace(0, 1, 41)[:, None, None]
    edges = (t[:, 0] + s * (t[:, 1] - t[:, 0])).reshape(-1, 3)
    return np.concatenate([shape.vertices, edges, faces])


def shape_frame_distance(world, scene, body, points):
    """Exact signed distance of body ``body``'s shape at world points: world -> body frame by
    the world's pose, then -> shape frame by ``body_from_shape``."""
    spec = scene.bodies[body]
    local = (points - world.position[body]) @ world.rotation[body]
    return spec.shape.signed_distance(spec.body_from_shape.apply_inverse(local))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow],
          derandomize=True)
@given(shape_a=shapes, shape_b=shapes, qa=unit_quaternions, qb=unit_quaternions, u=directions,
       gap=st.floats(-0.1, 0.1), origin=st.tuples(*[st.floats(-2, 2)] * 3))
@example(shape_a=MESHES[0], shape_b=MESHES[4], qa=np.array([0.0, 0.0, 0.0, 1.0]),
         qb=np.array([0.0, 0.0, 0.0, 1.0]), u=np.array([np.sqrt(0.5), 0.0, np.sqrt(0.5)]),
         gap=-0.09375, origin=(0.0, 0.0, 0.0))  # a random search found it: a box deep in the bowl
def test_contacts_of_random_pairs(shape_a, shape_b, qa, qb, u, gap, origin):
    """derandomize: the same examples every run, so CI is reproducible."""
    check_contacts(shape_a, shape_b, qa, qb, u, gap, origin)


def check_contacts(shape_a, shape_b, qa, qb, u, gap, origin):
    ra, rb = quat.to_matrix(qa), quat.to_matrix(qb)
    xa = np.array(origin)
    xb = xa + (support(shape_a, ra, u) + support(shape_b, rb, -u) + gap) * u
    scene = rg.Scene()
    scene.add_body(shape_a, mass=1.0, position=xa, orientation=qa)
    scene.add_body(shape_b, mass=1.0, position=xb, orientation=qb)
    world = rg.World(scene)
    c = world.contacts()

    # the frames used below are the ones we placed (a check of the body/shape bookkeeping)
    for body, (x, r) in enumerate(((xa, ra), (xb, rb))):
        pose = scene.bodies[body].body_from_shape
        np.testing.assert_allclose(world.rotation[body] @ pose.rotation(), r, atol=1e-9)
        np.testing.assert_allclose(world.position[body] + world.rotation[body] @ pose.position,
                                   x, atol=1e-9)

    tol_a, tol_b = EXACT + grid_bound(shape_a), EXACT + grid_bound(shape_b)
    meshes = [s for s in (shape_a, shape_b) if isinstance(s, rg.Mesh)]
    if gap > tol_a + tol_b + TOUCHING_GAP:
        assert len(c.depth) == 0, f"{len(c.depth)} contacts {gap:.4f} m apart"
    if len(c.depth) == 0:
        # completeness: a clear overlap found by dense sampling must be reported
        rng = np.random.default_rng(0)
        pa = surface_samples(shape_a, rng) @ ra.T + xa
        pb = surface_samples(shape_b, rng) @ rb.T + xb
        overlap = max(-np.min(shape_frame_distance(world, scene, 1, pa)),
                      -np.min(shape_frame_distance(world, scene, 0, pb)))
        resolution = 1e-6 + sum(grid_spacing(m) / 2 + grid_bound(m) for m in meshes)
        assert overlap <= resolution, f"missed an overlap of {overlap:.4g} m"
        return

    assert np.all(np.isfinite(c.point)) and np.all(np.isfinite(c.normal))
    np.testing.assert_allclose(np.linalg.norm(c.normal, axis=1), 1.0, atol=1e-9)
    assert np.all(c.depth > -TOUCHING_GAP)  # overlapping, or touching as the solver counts it
    assert np.all((c.body_a == 0) & (c.body_b == 1))
    assert c.depth[0] == c.depth.max()
    boxes = isinstance(shape_a, rg.Box) and isinstance(shape_b, rg.Box)
    limit = (1.05 * -gap + 1e-6 if boxes else -gap) + tol_a + tol_b
    assert np.all(c.depth <= limit), f"depth {c.depth.max():.4g} > {limit:.4g}"

    # every point inside or on both shapes (a touching contact's point, depth < 0, lies on A
    # and at most its separation outside B)
    sd_a = shape_frame_distance(world, scene, 0, c.point)
    sd_b = shape_frame_distance(world, scene, 1, c.point)
    apart = np.maximum(0.0, -c.depth)
    assert np.all(sd_a <= tol_a + apart), f"a point is {sd_a.max():.3g} m outside A"
    assert np.all(sd_b <= tol_b + apart), f"a point is {sd_b.max():.3g} m outside B"

    # the normal leaves B or enters A at the point (from B towards A); a contact no deeper
    # than the shapes' phi tolerance (faces exactly touching) has no direction to check
    eps = 1e-6
    deep = c.depth > tol_a + tol_b
    ahead, behind = c.point[deep] + eps * c.normal[deep], c.point[deep] - eps * c.normal[deep]
    leaves_b = (shape_frame_distance(world, scene, 1, ahead)
                - shape_frame_distance(world, scene, 1, behind)) > 0.0
    enters_a = (shape_frame_distance(world, scene, 0, ahead)
                - shape_frame_distance(world, scene, 0, behind)) < 0.0
    assert np.all(leaves_b | enters_a), "a normal points from A towards B"


@settings(max_examples=60, deadline=None)
@given(shape=shapes, q=unit_quaternions, sink=st.floats(-0.05, 0.1),
       origin=st.tuples(st.floats(-2, 2), st.floats(-2, 2)))
@example(shape=rg.Sphere(0.5), q=np.array([1.0, 0.0, 0.0, 0.0]), sink=-1.19e-7,
         origin=(0.0, 0.0))  # within the touching gap
@example(shape=rg.Box((0.1, 0.2, 0.3)), q=np.array([1.0, 0.0, 0.0, 0.0]), sink=-2e-6,
         origin=(0.0, 0.0))  # just beyond it
def test_random_shapes_on_the_ground(shape, q, sink, origin):
    """A shape turned at random, its lowest point ``sink`` m below the ground (above it when
    negative): the deepest contact is exactly that deep (every type is exact against a plane:
    vertices and core ends are its extremes), normals are +z, points are the shape's points
    below the ground, and nothing is reported further above it than TOUCHING_GAP, within
    which a resting body counts as touching."""
    r = quat.to_matrix(q)
    z = support(shape, r, np.array([0.0, 0.0, -1.0])) - sink
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(shape, mass=1.0, position=(origin[0], origin[1], z), orientation=q)
    world = rg.World(scene)
    c = world.contacts()
    if sink < -TOUCHING_GAP - 1e-9:  # apart by more than the touching gap
        assert len(c.depth) == 0
        return
    if sink <= 1e-9:  # touching within the gap (or rounding): reported, then as deep as it is
        assert len(c.depth) == 0 or abs(c.depth.max() - sink) <= 1e-9
        return
    assert len(c.depth) >= 1
    np.testing.assert_allclose(c.depth[0], sink, atol=1e-9)
    np.testing.assert_allclose(c.normal, np.tile([0, 0, 1.0], (len(c.depth), 1)), atol=1e-12)
    np.testing.assert_allclose(c.point[:, 2], -c.depth, atol=1e-9)
    assert np.all(shape_frame_distance(world, scene, 1, c.point) <= EXACT)
