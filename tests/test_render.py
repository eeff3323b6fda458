"""Software renderer: projection, z-buffer, culling, shadows, markers, tessellation, validation."""

import numpy as np
import pytest

import rigid_gym as rg
from rigid_gym.meshes import bowl_mesh, l_shape_mesh
from rigid_gym.render import (
    AMBIENT,
    BACKGROUND,
    GROUND_COLOR,
    Camera,
    Renderer,
    corner_normals,
    tessellate,
)

IDENTITY = (1.0, 0.0, 0.0, 0.0)
RED, BLUE = (0.9, 0.1, 0.1), (0.1, 0.2, 0.9)


def byte(rgb):
    """What the renderer writes for a colour in [0, 1]: the nearest of 0..255."""
    return (np.clip(np.asarray(rgb), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def draw(scene, renderer=None, **kwargs):
    """Render ``scene`` at its initial poses."""
    world = rg.World(scene)
    renderer = renderer or Renderer(scene, **kwargs)
    return renderer.render(world.position, world.orientation)


def box_scene(half=0.1, position=(0.0, 0.0, 0.0), orientation=IDENTITY):
    scene = rg.Scene()
    scene.add_body(rg.Box((half, half, half)), mass=1.0, position=position, orientation=orientation)
    return scene


def is_background(image):
    return np.all(image == byte(BACKGROUND), axis=-1)


def inside_convex_hull(points, pixels, margin):
    """(P,) whether pixel centres ``pixels`` (P, 2) lie inside the convex hull of ``points``
    (K, 2) by more than ``margin`` pixels (margin < 0: within -margin outside it)."""
    pts = sorted(map(tuple, points))
    hull = []
    for sequence in (pts, pts[::-1]):  # monotone chain: lower then upper half
        half = []
        for p in sequence:
            while len(half) >= 2 and turn(half[-2], half[-1], p) <= 0:
                half.pop()
            half.append(p)
        hull.extend(half[:-1])
    hull = np.array(hull)
    edges = np.roll(hull, -1, axis=0) - hull
    normals = np.column_stack([edges[:, 1], -edges[:, 0]]) / np.linalg.norm(edges, axis=1)[:, None]
    # counter-clockwise hull in (x, y): the inside is to the left of each edge
    distance = np.einsum("ek,pek->pe", -normals, pixels[:, None, :] - hull[None])
    return np.all(distance > margin, axis=1)


def turn(a, b, c):
    """> 0 when a -> b -> c turns counter-clockwise."""
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


def pixel_centres(height, width):
    i, j = np.mgrid[0:height, 0:width]
    return np.column_stack([j.ravel() + 0.5, i.ravel() + 0.5])


def test_output_shape_dtype_and_determinism():
    """A (height, width, 3) uint8 picture; the same input gives the same bytes, also from a
    second renderer."""
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0, 0, 0.05))
    scene.add_body(rg.Sphere(0.04), mass=1.0, position=(0.12, 0.05, 0.04))
    first = draw(scene, width=64, height=48)
    assert first.shape == (48, 64, 3) and first.dtype == np.uint8
    renderer = Renderer(scene, width=64, height=48)
    assert draw(scene, renderer).tobytes() == first.tobytes()
    assert draw(scene, renderer).tobytes() == first.tobytes()


def test_ground_only_shows_background_and_the_two_lit_tiles():
    """With nothing but a ground plane every pixel is the background or a lit ground tile
    (ambient + diffuse with the light's height as Lambert factor): no shadows, no stray
    triangles. The default camera sees the sky above the table's far edge. A scene without
    bodies is all background."""
    scene = rg.Scene()
    scene.add_ground()
    renderer = Renderer(scene, width=96, height=96)
    image = renderer.render(np.zeros((1, 3)), [IDENTITY])
    lit = AMBIENT + (1.0 - AMBIENT) * renderer.light[2]
    allowed = [byte(BACKGROUND), byte(np.array(GROUND_COLOR) * lit),
               byte(np.array(GROUND_COLOR) * 0.94 * lit)]
    matches = [np.all(image == c, axis=-1) for c in allowed]
    assert np.all(np.any(matches, axis=0))
    assert all(m.sum() > 100 for m in matches)
    assert matches[0][0, 0] and not matches[0][48, 48]
    nothing = Renderer(rg.Scene(), width=32, height=32).render(np.zeros((0, 3)), np.zeros((0, 4)))
    assert np.all(is_background(nothing))


def test_box_fills_exactly_its_projected_silhouette():
    """A red cube right (+x) of and above (+z) the view axis lands in the top right quarter:
    the non-background pixels are exactly those whose centres lie inside the projected hull of
    its corners (its front face and, seen in perspective, its left side; pixels within 0.01 px
    of the border may go either way). So the image is neither mirrored nor flipped."""
    scene = box_scene(half=0.1, position=(0.15, 0.0, 0.1))
    camera = Camera(eye=(0.0, -1.5, 0.0), target=(0.0, 0.0, 0.0), fov_deg=40.0)
    image = draw(scene, width=80, height=80, camera=camera, colors={0: RED})
    box = np.array([[x, y, z] for x in (0.05, 0.25) for y in (-0.1, 0.1) for z in (0.0, 0.2)])
    corners, _ = camera.project(box, 80, 80)
    assert corners[:, 0].min() > 40 and corners[:, 1].max() <= 40  # right half, top half
    centres = pixel_centres(80, 80)
    inside = inside_convex_hull(corners, centres, 0.01).reshape(80, 80)
    outside = ~inside_convex_hull(corners, centres, -0.01).reshape(80, 80)
    covered = ~is_background(image)
    assert inside.sum() > 200
    assert np.all(covered[inside]) and not np.any(covered[outside])
    red = image[inside].astype(int)
    assert np.all(red[:, 0] > 2 * red[:, 1]) and np.all(red[:, 0] > 2 * red[:, 2])


def test_near_box_occludes_far_box_whatever_the_body_order():
    """A small red cube between the camera and a large blue one: red at the centre, blue
    around it, the same picture whichever body comes first."""
    camera = Camera(eye=(1.0, -1.0, 0.8), target=(0.0, 0.0, 0.0))
    images = []
    for order in ((0, 1), (1, 0)):
        scene = rg.Scene()
        bodies = [(0.05, (0.5, -0.5, 0.4), RED), (0.2, (0.0, 0.0, 0.0), BLUE)]
        colors = {}
        for k, index in enumerate(order):
            half, position, color = bodies[index]
            scene.add_body(rg.Box((half, half, half)), mass=1.0, position=position)
            colors[k] = color
        images.append(draw(scene, width=64, height=64, camera=camera, colors=colors))
    assert images[0].tobytes() == images[1].tobytes()
    (centre,), _ = camera.project([(0.5, -0.5, 0.4)], 64, 64)
    i, j = int(centre[1]), int(centre[0])
    r, _, b = images[0][i, j].astype(int)
    assert r > 2 * b
    r, _, b = images[0][i, j + 8].astype(int)
    assert b > 2 * r


def test_rotated_boxes_cover_their_whole_silhouette():
    """Back-face culling and shared-edge rasterisation leave no holes: for 20 random
    orientations every pixel inside the projected hull of the cube's corners (by more than
    one pixel) is covered, and nothing is drawn more than 0.01 px outside it."""
    rng = np.random.default_rng(3)
    camera = Camera(eye=(0.3, -0.5, 0.25), target=(0.0, 0.0, 0.0))
    centres = pixel_centres(64, 64)
    for q in rng.normal(size=(20, 4)):
        q /= np.linalg.norm(q)
        scene = box_scene(half=0.08, orientation=q)
        image = draw(scene, width=64, height=64, camera=camera)
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        corners = rg.Pose((0, 0, 0), q).apply(0.08 * signs)
        projected, _ = camera.project(corners, 64, 64)
        covered = ~is_background(image).ravel()
        assert np.all(covered[inside_convex_hull(projected, centres, 1.0)])
        assert not np.any(covered[~inside_convex_hull(projected, centres, -0.01)])


def test_shadow_darkens_the_ground_under_a_body():
    """Light straight down on a cube floating above the ground: the ground point under its
    centre (seen from the side) gets only ambient light; without shadows it is fully lit."""
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0.0, 0.0, 0.3))
    camera = Camera(eye=(0.0, -0.8, 0.5), target=(0.0, 0.0, 0.0))
    (point,), _ = camera.project([(0.02, 0.02, 0.0)], 64, 64)  # inside a tile, not on a seam
    i, j = int(point[1]), int(point[0])
    tile = np.array(GROUND_COLOR)
    shaded = draw(scene, width=64, height=64, camera=camera, light_direction=(0, 0, 1))
    assert np.array_equal(shaded[i, j], byte(tile * AMBIENT))
    plain = draw(scene, width=64, height=64, camera=camera, light_direction=(0, 0, 1),
                 shadows=False)
    assert np.array_equal(plain[i, j], byte(tile))


def test_markers_opaque_translucent_and_moved():
    """An opaque marker shows its own colour, a translucent one blends with what is behind,
    and set_marker moves it: markers are drawn without being bodies."""
    scene = box_scene(half=0.05, position=(0.0, 0.5, 0.0))  # behind the markers' spot
    camera = Camera(eye=(0.0, -1.0, 0.0), target=(0.0, 0.0, 0.0))
    renderer = Renderer(scene, width=48, height=48, camera=camera, colors={0: BLUE})
    behind = draw(scene, renderer)[24, 24].astype(int)
    marker = renderer.add_marker(rg.Sphere(0.05), position=(0, 0, 0), color=RED, alpha=0.5)
    blended = draw(scene, renderer)[24, 24].astype(int)
    assert blended[0] > behind[0] + 40 and blended[2] < behind[2] - 40 and blended[2] > 40
    renderer.set_marker(marker, position=(0.0, 0.0, 5.0))
    assert np.array_equal(draw(scene, renderer)[24, 24], behind)
    renderer.add_marker(rg.Box((0.02, 0.02, 0.02)), position=(0, 0, 0), color=(0.0, 1.0, 0.0))
    g = draw(scene, renderer)[24, 24].astype(int)
    assert g[1] > 100 and g[0] == 0 and g[2] == 0


SOLIDS = {
    "box": (rg.Box((0.1, 0.2, 0.3)), 0.0),
    "mesh": (bowl_mesh(0.1, 0.08), 0.0),
    "compound": (rg.Compound([(l_shape_mesh(), ((0, 0, 0), IDENTITY)),
                              (rg.Box((0.1, 0.1, 0.1)), ((3, 0, 0), (0.6, 0.8, 0.0, 0.0)))]), 0.0),
    "sphere": (rg.Sphere(0.1), 0.0),
    "capsule": (rg.Capsule(0.05, 0.2), 0.2),
}


def exact_volume(shape):
    if isinstance(shape, rg.Box):
        return float(np.prod(2 * shape.half_extents))
    if isinstance(shape, rg.Mesh):
        return shape.volume()
    if isinstance(shape, rg.Compound):
        return sum(exact_volume(part) for part, _ in shape.parts)
    return rounded_volume(shape.radius, getattr(shape, "half_length", 0.0))


def rounded_volume(radius, half_length):
    """Volume of the points within ``radius`` of the segment z in [-half_length, half_length]."""
    return 4.0 / 3.0 * np.pi * radius**3 + 2.0 * half_length * np.pi * radius**2


@pytest.mark.parametrize("name", SOLIDS)
def test_tessellation_is_closed_and_has_the_shape_volume(name):
    """Every solid tessellates into a closed, outward-wound mesh (rg.Mesh checks both).

    Box, Mesh and Compound (disjoint parts) are exact: volume to 1e-12. Sphere and capsule are
    inscribed (vertices on the surface of a convex shape), so their volume V_t <= V; and each
    face plane lies at least rho from the core (the centre or segment), so the polyhedron
    contains the shape of radius rho: V(rho) <= V_t. With 24 x 12 steps rho / r = 0.983, so the
    error is at most 5.0% (sphere) and 3.6% (this capsule); measured 2.8% and 1.4%.
    """
    shape, half_length = SOLIDS[name]
    vertices, triangles = tessellate(shape)
    assert vertices.dtype == np.float64 and triangles.dtype == np.int32
    volume = rg.Mesh(vertices, triangles).volume()
    exact = exact_volume(shape)
    if name in ("box", "mesh", "compound"):
        assert volume == pytest.approx(exact, rel=1e-12)
        return
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    rho = np.min(np.einsum("ij,ij->i", n, a) - np.abs(n[:, 2]) * half_length)
    assert rounded_volume(rho, half_length) <= volume <= exact
    assert volume > 0.97 * exact


def test_plane_patch_and_shading_normals():
    """A Plane gives a flat square facing +z of the asked size; shading normals are smooth
    on a sphere (within 5 degrees of the radial direction, a third of the 15 degree facet
    step) and sharp on a box (its face normals)."""
    vertices, triangles = tessellate(rg.Plane(), plane_half_size=0.5)
    assert np.all(vertices[:, 2] == 0.0) and np.allclose(np.abs(vertices[:, :2]).max(axis=0), 0.5)
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    assert np.all(n[:, 2] > 0) and 0.5 * n[:, 2].sum() == pytest.approx(1.0)
    v, t = tessellate(rg.Sphere(1.0))
    radial = v[t].reshape(-1, 3)
    assert np.einsum("ij,ij->i", corner_normals(v, t), radial).min() > np.cos(np.radians(5.0))
    v, t = tessellate(rg.Box((1.0, 2.0, 3.0)))
    normals = corner_normals(v, t)
    assert np.all(np.sort(np.abs(normals), axis=1) == [0.0, 0.0, 1.0])


def two_bodies():
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Sphere(0.1), mass=1.0, position=(0, 0, 0.1))
    return scene


def render_with(position, orientation):
    return Renderer(two_bodies()).render(position, orientation)


def add_marker(shape, **kwargs):
    return Renderer(two_bodies()).add_marker(shape, **kwargs)


@pytest.mark.parametrize("make, message", [
    (lambda: Renderer(two_bodies(), width=15), r"Renderer.width: must be an int in \[16, 4096\]"),
    (lambda: Renderer(two_bodies(), height=4097),
     r"Renderer.height: must be an int in \[16, 4096\]"),
    (lambda: Renderer(two_bodies(), width=64.0), r"Renderer.width"),
    (lambda: Camera(fov_deg=180.0), r"Camera.fov_deg: must be in \(0, 180\)"),
    (lambda: Camera(fov_deg=0.0), r"Camera.fov_deg"),
    (lambda: Camera(eye=(1, 2, 3), target=(1, 2, 3)), r"Camera.eye: must differ from target"),
    (lambda: Camera(eye=(0, 0, 1), target=(0, 0, 0)), r"Camera.up: must be nonzero and not par"),
    (lambda: Camera(eye=(0, 0, np.nan)), r"Camera.eye: must be finite"),
    (lambda: Renderer(two_bodies(), colors={0: (1.2, 0, 0)}),
     r"Renderer.colors\[0\] \(RGB channels\): must be finite and in \[0, 1\], got \[1.2, 0.0"),
    (lambda: Renderer(two_bodies(), colors={5: (1, 0, 0)}),
     r"Renderer.colors key \(one of 2 bodies\): must be an int in \[0, 1\], got 5"),
    (lambda: Renderer(two_bodies(), light_direction=(0, 0, 0)),
     r"Renderer.light_direction: must be nonzero"),
    (lambda: render_with(np.zeros((1, 3)), np.tile(IDENTITY, (2, 1))),
     r"Renderer.render.position: expected shape \(2, 3\)"),
    (lambda: render_with(np.zeros((2, 3)), np.zeros((2, 4))),
     r"Renderer.render.orientation: quaternion"),
    (lambda: add_marker(rg.Sphere(0.1), alpha=0.0),
     r"alpha: must be finite and in \(0, 1\], got 0.0"),
    (lambda: add_marker(rg.Plane()), r"shape must be Sphere, Box, Capsule, Mesh or Compound"),
    (lambda: add_marker(rg.Sphere(0.1), color=(0, 0, -1)),
     r"color \(RGB channels\): must be finite and in \[0, 1\], got \[0.0, 0.0, -1.0\]"),
    (lambda: Renderer(two_bodies()).set_marker(0, (0, 0, 0)),
     r"Renderer.set_marker.index: there are no markers to index, got 0"),
    (lambda: tessellate("sphere"), r"tessellate.shape: expected Sphere"),
    (lambda: tessellate(rg.Plane(), plane_half_size=-1.0),
     r"tessellate.plane_half_size: must be finite and > 0"),
])
def test_bad_input_is_rejected_naming_the_argument(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_face_colors_paint_each_face_by_its_direction_and_are_checked():
    """Seen from straight above, a box with face colours shows its +z colour; turned upside
    down (a half turn about x), its -z colour; six colours are required."""
    faces = [(0.9, 0.1, 0.1), (0.1, 0.9, 0.1), (0.9, 0.9, 0.1), (0.6, 0.2, 0.8), BLUE, RED]
    above = Camera(eye=(0.0, 0.0, 1.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0))

    def hue_at_centre(orientation):
        scene = box_scene(orientation=orientation)
        picture = draw(scene, camera=above, width=32, height=32, face_colors={0: faces})
        pixel = picture[16, 16].astype(float)
        return pixel / pixel.sum()

    for orientation, rgb in ((IDENTITY, BLUE), ((0.0, 1.0, 0.0, 0.0), RED)):
        np.testing.assert_allclose(hue_at_centre(orientation), np.array(rgb) / sum(rgb),
                                   atol=0.02)
    with pytest.raises(ValueError, match="six"):
        Renderer(box_scene(), face_colors={0: faces[:5]})
