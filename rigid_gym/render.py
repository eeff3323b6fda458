"""Headless software renderer: RGB pictures of a world, no GPU or display needed.

    renderer = Renderer(world.scene, width=480, height=480)
    goal = renderer.add_marker(Sphere(0.02), position=(0.1, 0.0, 0.1), alpha=0.5)
    image = renderer.render(world.position, world.orientation)  # (480, 480, 3) uint8

Every shape is tessellated once into a closed triangle mesh in its shape frame (a Plane into a
finite, tiled square patch: a table top); each frame moves the triangles with the body poses
and draws them with a z-buffer (the core's ``src/render/frames.h`` over ``src/render/raster.cpp``): a
perspective camera, back-face culling, Gouraud-interpolated Lambert shading from one
directional light plus ambient, and the bodies' shadows from an orthographic shadow map.
Translucent markers (alpha < 1) are blended over the opaque scene, nearest one per pixel.
``render_batch`` draws many worlds of the scene (a batched World's copies) in one call on the
core's threads. Output is deterministic: the same input gives the same bytes, on any thread.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from rigid_gym import _core
from rigid_gym import quaternion as quat
from rigid_gym._core import DYNAMIC, KINEMATIC
from rigid_gym.checks import finite_array, in_range, integer, number, positive, vector
from rigid_gym.meshes import box_mesh, lathe
from rigid_gym.scene import Scene
from rigid_gym.shapes import SOLID_SHAPES, Box, Capsule, Compound, Mesh, Plane, Sphere

SPHERE_SEGMENTS = 24
"""Steps around the axis of a tessellated sphere or capsule (its rings have 24 vertices)."""
SPHERE_RINGS = 12
"""Steps from pole to pole of a tessellated sphere (a capsule has one more, its cylinder)."""
PLANE_TILE = 0.1
"""Side of the checker tiles of a Plane's patch, m."""
CREASE_DEG = 40.0
"""Faces meeting at less than this angle share smoothed shading normals; sharper edges (a
box's) stay sharp."""

DEFAULT_LIGHT = (0.5, -0.15, 0.85)
"""Direction towards the light (normalised on use): high and to the right of the default
camera, so that the three faces of a box it sees differ and shadows fall to the left."""
AMBIENT = 0.4
"""Brightness of a surface turned away from the light (or in shadow), as a fraction of lit."""
BACKGROUND = (0.93, 0.95, 0.98)
GROUND_COLOR = (0.90, 0.86, 0.79)
"""Plane bodies (light wood); their patch alternates it with a 6% darker tile."""
STATIC_COLOR = (0.62, 0.62, 0.60)
KINEMATIC_COLOR = (0.30, 0.30, 0.33)
DRIVEN_COLOR = (0.58, 0.58, 0.62)
"""Dynamic bodies jointed to a kinematic one (a gripper's fingers): parts of the driven
mechanism, not objects, so drawn in a lighter shade of its grey rather than the palette's."""
DYNAMIC_PALETTE = (
    (0.22, 0.47, 0.80), (0.93, 0.55, 0.16), (0.30, 0.66, 0.30), (0.84, 0.24, 0.22),
    (0.58, 0.42, 0.76), (0.16, 0.65, 0.66), (0.92, 0.78, 0.25), (0.88, 0.50, 0.68),
    (0.58, 0.42, 0.30),
)
"""Dynamic bodies, in order of appearance, cycled."""
MARKER_COLOR = (0.20, 0.85, 0.35)
SHADOW_RESOLUTION = 512
"""Most texels along each side of the shadow map, which spans the bodies (not the planes). A
frame's map has twice the frame's larger side, up to this (168 at 84 x 84): its texels stay
finer than the frame's pixels wherever the bodies fill less than the whole view, and a small
frame does not pay for a large map."""
NEAR = 1e-3
"""Distance from the eye to the near clipping plane, m."""


@dataclass(frozen=True, eq=False, init=False)
class Camera:
    """A perspective camera looking from ``eye`` (3,) m at ``target`` (3,) m, with ``up`` (3,)
    pointing up on screen (any vector not parallel to the view direction) and a vertical field
    of view of ``fov_deg`` degrees in (0, 180). Pixels are square. The default views a table
    top about 0.6 m across from the front right, above. The vectors are given as any 3 numbers
    and held as read-only float64 arrays."""

    eye: np.ndarray
    target: np.ndarray
    up: np.ndarray
    fov_deg: float

    def __init__(self, eye: ArrayLike = (0.45, -0.7, 0.6), target: ArrayLike = (0.0, 0.0, 0.05),
                 up: ArrayLike = (0.0, 0.0, 1.0), fov_deg: float = 45.0):
        for field, given in (("eye", eye), ("target", target), ("up", up)):
            value = vector(given, 3, f"Camera.{field}")
            value.setflags(write=False)
            object.__setattr__(self, field, value)
        fov = number(fov_deg, "Camera.fov_deg")
        if not 0.0 < fov < 180.0:
            raise ValueError(f"Camera.fov_deg: must be in (0, 180) degrees, got {fov_deg!r}")
        object.__setattr__(self, "fov_deg", fov)
        forward = self.target - self.eye
        if not np.linalg.norm(forward) > 0.0:
            raise ValueError(
                f"Camera.eye: must differ from target, got {self.eye.tolist()} for both")
        right = np.cross(forward, self.up)
        if not np.linalg.norm(right) > 1e-9 * np.linalg.norm(forward) * np.linalg.norm(self.up):
            raise ValueError(f"Camera.up: must be nonzero and not parallel to target - eye, got "
                             f"{self.up.tolist()} for target - eye = {forward.tolist()}")

    def axes(self) -> np.ndarray:
        """(3, 3) rows: the unit right, up and forward directions of the view, world frame."""
        forward = self.target - self.eye
        forward = forward / np.linalg.norm(forward)
        right = np.cross(forward, self.up)
        right /= np.linalg.norm(right)
        return np.array([right, np.cross(right, forward), forward])

    def focal(self, height: int) -> float:
        """Focal length in pixels for an image ``height`` pixels tall."""
        return 0.5 * height / np.tan(np.radians(0.5 * self.fov_deg))

    def project(self, points, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """Screen positions of world ``points`` (P, 3), m, in a ``width`` x ``height`` image.

        Returns (P, 2) pixel coordinates (x to the right, y down; pixel (i, j) is centred on
        (j + 0.5, i + 0.5)) and (P,) depths along the view direction, m (> 0 in front).
        """
        axes = self.axes()
        view = (np.asarray(points, dtype=np.float64) - self.eye) @ axes.T
        focal = self.focal(height)
        depth = view[:, 2]
        screen = np.column_stack([0.5 * width + focal * view[:, 0] / depth,
                                  0.5 * height - focal * view[:, 1] / depth])
        return screen, depth


def tessellate(shape, plane_half_size: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A triangle mesh of ``shape`` in its shape frame.

    Returns vertices (V, 3) float64, m, and triangles (T, 3) int32, counter-clockwise seen from
    outside. Solid shapes give closed meshes: a Box its 12 triangles, a Mesh its own, a Sphere
    a UV sphere (SPHERE_SEGMENTS x SPHERE_RINGS steps, 528 triangles; vertices on the surface,
    so its volume is 2.8% smaller), a Capsule a cylinder between two such hemispheres, a
    Compound its parts placed by their poses. A Plane gives the square |x|, |y| <= ``plane_half_size`` (m) of its
    surface z = 0, facing +z, cut into PLANE_TILE tiles (2 triangles each).
    """
    if isinstance(shape, Box):
        mesh = box_mesh(shape.half_extents)
        return mesh.vertices.copy(), mesh.triangles.copy()
    if isinstance(shape, Sphere):
        return _revolve(shape.radius, 0.0)
    if isinstance(shape, Capsule):
        return _revolve(shape.radius, shape.half_length)
    if isinstance(shape, Mesh):
        return shape.vertices.copy(), shape.triangles.copy()
    if isinstance(shape, Compound):
        return _tessellate_compound(shape, plane_half_size)
    if isinstance(shape, Plane):
        return _tiled_square(positive(plane_half_size, "tessellate.plane_half_size"))
    raise ValueError(f"tessellate.shape: expected Sphere, Box, Capsule, Mesh, Compound or Plane, "
                     f"got {type(shape).__name__}")


class Renderer:
    """Draws one world of ``scene`` into ``width`` x ``height`` RGB pictures (16 to 4096 px).

    camera: a Camera (default ``Camera()``); may be replaced between frames.
    colors: optional {body index: (r, g, b) in [0, 1]} overriding the default palette (planes
        light wood, static bodies grey, kinematic bodies dark grey, dynamic bodies distinct
        colours from DYNAMIC_PALETTE).
    face_colors: optional {body index: six (r, g, b)}: the colours of the body's triangles
        facing +x, -x, +y, -y, +z, -z of its frame (by their normals' largest component), for
        a body whose orientation must be seen (a die's faces); overrides ``colors``.
    light_direction: (3,) direction towards the light, world frame (normalised here).
    shadows: draw the bodies' shadows (on everything, planes included).
    plane_half_size: half the side of the square drawn for each Plane, m.
    """

    def __init__(self, scene: Scene, width: int = 480, height: int = 480,
                 camera: Camera | None = None, colors: dict | None = None,
                 light_direction=DEFAULT_LIGHT, shadows: bool = True,
                 plane_half_size: float = 1.0, face_colors: dict | None = None):
        if not isinstance(scene, Scene):
            raise ValueError(
                f"Renderer.scene: expected a rigid_gym.Scene, got {type(scene).__name__}")
        self.width = _size(width, "Renderer.width")
        self.height = _size(height, "Renderer.height")
        self._camera = _camera(Camera() if camera is None else camera)
        light = vector(light_direction, 3, "Renderer.light_direction")
        if not np.linalg.norm(light) > 0.0:
            raise ValueError("Renderer.light_direction: must be nonzero, got [0, 0, 0]")
        self.light = light / np.linalg.norm(light)  # (3,) unit vector towards the light
        self.num_bodies = len(scene)
        colours = body_colors(scene, colors)
        half = positive(plane_half_size, "Renderer.plane_half_size")
        self._parts = [_body_part(b, colours[b.index], half) for b in scene.bodies]
        for index, faces in (face_colors or {}).items():
            body = _index(index, len(scene), "Renderer.face_colors key", "bodies")
            part = self._parts[body]
            tinted = by_face(part.corners, faces, f"Renderer.face_colors[{index}]")
            self._parts[body] = _Part(part.corners, part.normals, tinted, part.alpha, part.kind)
        self._marker_rotation = np.zeros((0, 3, 3))  # (m, 3, 3) each marker's orientation
        self._marker_position = np.zeros((0, 3))  # (m, 3) m
        self.shadow_side = shadow_side(self.width, self.height) if shadows else 0
        """Texels along each side of the shadow map (0: no shadows)."""
        self._pack()

    @property
    def camera(self) -> Camera:
        return self._camera

    @camera.setter
    def camera(self, camera: Camera) -> None:
        self._camera = _camera(camera)
        self._set_view()

    @property
    def num_markers(self) -> int:
        return len(self._marker_position)

    # -- markers -------------------------------------------------------------------------------

    def add_marker(self, shape, position=(0.0, 0.0, 0.0), color=MARKER_COLOR, alpha: float = 1.0,
                   orientation=(1.0, 0.0, 0.0, 0.0), face_colors=None) -> int:
        """Add extra geometry that is not a body (a goal, a target), drawn until the renderer
        is dropped. Returns its marker index.

        shape: Sphere, Box, Capsule, Mesh or Compound, placed by its shape frame at
            ``position`` (3,) m with ``orientation`` (4,) unit quaternion (w, x, y, z).
        color: (r, g, b) in [0, 1]; alpha in (0, 1]: below 1 it is blended over what lies
            behind it (markers cast no shadows). face_colors: None, or six (r, g, b) for the
            triangles facing +x, -x, +y, -y, +z, -z of the shape frame (as the Renderer's).
        """
        index = len(self._parts) - self.num_bodies
        where = f"Renderer.add_marker (marker {index})"
        if not isinstance(shape, SOLID_SHAPES):
            raise ValueError(f"{where}: shape must be Sphere, Box, Capsule, Mesh or Compound, "
                             f"got {type(shape).__name__}")
        rgb = _color(color, f"{where}: color")
        alpha = in_range(alpha, 0.0, 1.0, f"{where}: alpha", open_low=True)
        vertices, triangles = tessellate(shape)
        corners, normals = vertices[triangles].reshape(-1, 3), corner_normals(vertices, triangles)
        kind = _OPAQUE if alpha == 1.0 else _TRANSLUCENT
        colors = np.tile(rgb, (len(triangles), 1)) if face_colors is None else by_face(
            corners, face_colors, f"{where}: face_colors")
        self._parts.append(_Part(corners, normals, colors, alpha, kind))
        self._marker_rotation = np.concatenate([self._marker_rotation, np.eye(3)[None]])
        self._marker_position = np.concatenate([self._marker_position, np.zeros((1, 3))])
        self._pack()
        self.set_marker(index, position, orientation)
        return index

    def set_marker(self, index: int, position, orientation=None) -> None:
        """Move marker ``index``: ``position`` (3,) m, optional ``orientation`` (4,) unit
        quaternion (w, x, y, z) of its shape frame (kept when None)."""
        marker = _index(index, self.num_markers, "Renderer.set_marker.index", "markers")
        self._marker_position[marker] = vector(position, 3, "Renderer.set_marker.position")
        if orientation is not None:
            q = vector(orientation, 4, "Renderer.set_marker.orientation")
            quat.check_unit(q, "Renderer.set_marker.orientation")
            self._marker_rotation[marker] = quat.to_matrix(quat.normalize(q))

    # -- drawing -------------------------------------------------------------------------------

    def render(self, position, orientation) -> np.ndarray:
        """The picture of one world whose body frames are ``position`` (n, 3), m (centres of
        mass, as ``World.position``) and ``orientation`` (n, 4) unit quaternions (w, x, y, z)
        (as ``World.orientation``). Returns a new (height, width, 3) uint8 RGB array."""
        n = self.num_bodies
        x = finite_array(position, (n, 3), "Renderer.render.position")
        q = finite_array(orientation, (n, 4), "Renderer.render.orientation")
        quat.check_unit(q, "Renderer.render.orientation")
        rotation = np.ascontiguousarray(quat.to_matrix(q), dtype=np.float64)
        image = np.empty((1, self.height, self.width, 3), np.uint8)
        self._frames.render(rotation[None], np.ascontiguousarray(x)[None], self._marker_rotation,
                            self._marker_position[None], _FIRST_WORLD, image)
        return image[0]

    def render_batch(self, rotation: np.ndarray, position: np.ndarray,
                     marker_position: np.ndarray, worlds: np.ndarray,
                     out: np.ndarray | None = None) -> np.ndarray:
        """The pictures of copies ``worlds`` (k,) int64 of B worlds of this scene, in one call
        shared out over the core's threads (``rigid_gym._core.num_threads``).

        rotation (B, n, 3, 3) and position (B, n, 3), m: the copies' body frames (as
        ``World.state.rotation`` and ``World.state.position``); marker_position (B, m, 3), m:
        each copy's markers (their orientations are the renderer's, ``set_marker``). Returns
        ``out`` (k, height, width, 3) uint8 (a new array when None), image k of copy
        ``worlds[k]``, whose bytes depend on nothing else: not on the other copies, nor on the
        thread that drew it. Every argument must
        be a C-contiguous float64 (int64 for worlds, uint8 for out) array of these shapes: the
        core checks shapes, types and indices (TypeError, ValueError), not finiteness (a
        non-finite pose draws garbage, never out of bounds).
        """
        if out is None:
            out = np.empty((len(worlds), self.height, self.width, 3), np.uint8)
        self._frames.render(rotation, position, self._marker_rotation, marker_position, worlds,
                            out)
        return out

    def _set_view(self) -> None:
        """Hand the camera and the light to the core."""
        camera = self._camera
        self._frames.set_view(camera.eye, camera.axes(), camera.focal(self.height), NEAR,
                              self.light, _light_axes(self.light), AMBIENT,
                              np.array(BACKGROUND))

    def _pack(self) -> None:
        """The core's renderer of the parts' triangles in drawing order: the background
        (planes) first, then shadow casters (solid bodies), then the other opaque parts (opaque
        markers), then translucent markers."""
        order = sorted(range(len(self._parts)), key=lambda k: self._parts[k].kind)
        parts = [self._parts[k] for k in order]
        none = np.empty((0, 3))  # so that a scene without bodies or markers packs too
        counts = np.array([len(part.colors) for part in parts], dtype=np.int64)
        kinds = np.array([part.kind for part in parts], dtype=np.int64)
        self._frames = _core.FrameRenderer(
            np.concatenate([none] + [part.corners for part in parts]),
            np.concatenate([none] + [part.normals for part in parts]),
            np.repeat(np.array(order, np.int32), 3 * counts),
            np.concatenate([none] + [part.colors for part in parts]),
            np.repeat(np.array([part.alpha for part in parts], dtype=np.float64), counts),
            int(counts[kinds == _BACKGROUND].sum()), int(counts[kinds == _CASTER].sum()),
            int(counts[kinds != _TRANSLUCENT].sum()),
            self.num_bodies, self.num_markers, self.width, self.height, self.shadow_side)
        self._set_view()


# -- parts: tessellated bodies and markers -----------------------------------------------------

_BACKGROUND, _CASTER, _OPAQUE, _TRANSLUCENT = 0, 1, 2, 3
_FIRST_WORLD = np.zeros(1, dtype=np.int64)
_FIRST_WORLD.setflags(write=False)
"""The copy that ``Renderer.render`` draws: its one world."""
"""Kinds of part: a plane (the background), a solid body (casts a shadow), other opaque
geometry, translucent markers."""


@dataclass(frozen=True)
class _Part:
    """One body's or marker's triangles as a soup, in its instance's frame: corners and unit
    shading normals (3T, 3), colors (T, 3) in [0, 1], alpha in (0, 1] and its kind."""

    corners: np.ndarray
    normals: np.ndarray
    colors: np.ndarray
    alpha: float
    kind: int


def _body_part(body, rgb: np.ndarray, plane_half_size: float) -> _Part:
    """The triangles of ``body`` in its body frame (the shape frame placed at
    ``body_from_shape``); a Plane's patch gets a checker of ``rgb`` and a darker tone."""
    vertices, triangles = tessellate(body.shape, plane_half_size)
    pose = body.body_from_shape
    corners = pose.apply(vertices[triangles].reshape(-1, 3))
    normals = corner_normals(vertices, triangles) @ pose.rotation().T
    colors = np.tile(rgb, (len(triangles), 1))
    if isinstance(body.shape, Plane):
        centre = vertices[triangles].mean(axis=1)
        odd = np.floor(centre[:, 0] / PLANE_TILE) + np.floor(centre[:, 1] / PLANE_TILE)
        colors[odd % 2 == 1] *= 0.94
        return _Part(corners, normals, colors, 1.0, _BACKGROUND)
    return _Part(corners, normals, colors, 1.0, _CASTER)


def by_face(corners: np.ndarray, faces, where: str) -> np.ndarray:
    """(T, 3) RGB of triangles with ``corners`` (3T, 3): ``faces`` (six (r, g, b), for the
    directions +x, -x, +y, -y, +z, -z) chosen by each triangle's normal's largest component."""
    rgb = np.array([_color(c, f"{where}[{k}]") for k, c in enumerate(faces)]) \
        if len(faces) == 6 else None
    if rgb is None:
        raise ValueError(f"{where}: expected six (r, g, b), one per face direction "
                         f"(+x, -x, +y, -y, +z, -z), got {len(faces)}")
    triangles = corners.reshape(-1, 3, 3)
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    axis = np.argmax(np.abs(normals), axis=1)
    negative = normals[np.arange(len(normals)), axis] < 0.0
    return rgb[2 * axis + negative]


def body_colors(scene: Scene, colors: dict | None = None) -> np.ndarray:
    """(n, 3) RGB of every body: the defaults by motion (a dynamic body jointed to a kinematic
    one in DRIVEN_COLOR, the others from DYNAMIC_PALETTE in order), then the overrides in
    ``colors``."""
    out, dynamic = np.empty((len(scene), 3)), 0
    driven = {j.body_a for j in scene.joints
              if j.body_b >= 0 and scene.bodies[j.body_b].motion == KINEMATIC}
    for body in scene.bodies:
        if isinstance(body.shape, Plane):
            out[body.index] = GROUND_COLOR
        elif body.index in driven:
            out[body.index] = DRIVEN_COLOR
        elif body.motion == DYNAMIC:
            out[body.index] = DYNAMIC_PALETTE[dynamic % len(DYNAMIC_PALETTE)]
            dynamic += 1
        else:
            out[body.index] = KINEMATIC_COLOR if body.motion == KINEMATIC else STATIC_COLOR
    for index, rgb in (colors or {}).items():
        out[_index(index, len(scene), "Renderer.colors key", "bodies")] = _color(
            rgb, f"Renderer.colors[{index}]")
    return out


# -- tessellation ------------------------------------------------------------------------------

def _revolve(radius: float, half_length: float) -> tuple[np.ndarray, np.ndarray]:
    """A UV sphere of ``radius`` (m) whose two hemispheres are moved apart to z = -+half_length
    (m) and joined by a cylinder: a capsule, or a sphere when half_length is 0."""
    half_rings = SPHERE_RINGS // 2
    lower = np.linspace(-0.5 * np.pi, 0.0, half_rings + 1)
    upper = lower + 0.5 * np.pi
    arcs = [np.column_stack([radius * np.cos(a), radius * np.sin(a) + dz])
            for a, dz in ((lower, -half_length), (upper, half_length))]
    profile = np.concatenate([arcs[0], arcs[1][1:]]) if half_length == 0.0 else np.concatenate(arcs)
    mesh = lathe(profile, SPHERE_SEGMENTS)
    return mesh.vertices.copy(), mesh.triangles.copy()


def _tessellate_compound(shape: Compound, plane_half_size: float) -> tuple[np.ndarray, np.ndarray]:
    """The parts' meshes placed by their poses, concatenated."""
    vertices, triangles, offset = [], [], 0
    for part, pose in shape.parts:
        v, t = tessellate(part, plane_half_size)
        vertices.append(pose.apply(v))
        triangles.append(t + offset)
        offset += len(v)
    return np.concatenate(vertices), np.concatenate(triangles).astype(np.int32)


def _tiled_square(half: float) -> tuple[np.ndarray, np.ndarray]:
    """The square |x|, |y| <= ``half`` (m) at z = 0 as a grid of about PLANE_TILE tiles."""
    tiles = max(round(2.0 * half / PLANE_TILE), 1)
    ticks = np.linspace(-half, half, tiles + 1)
    x, y = np.meshgrid(ticks, ticks, indexing="ij")
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    corner = (np.arange(tiles)[:, None] * (tiles + 1) + np.arange(tiles)[None, :]).ravel()
    a, b, c, d = corner, corner + tiles + 1, corner + tiles + 2, corner + 1  # (+x then +y)
    triangles = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return vertices, triangles.astype(np.int32)


def corner_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(3T, 3) unit shading normals at the triangles' corners, in the mesh's frame.

    A corner's normal is the area-weighted mean of the normals of the faces around its vertex
    that turn less than CREASE_DEG from its own face: smooth across the gentle edges of a
    tessellated curve, sharp across a box's edges.
    """
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    face = np.cross(b - a, c - a)  # (T, 3), length twice the area
    length = np.linalg.norm(face, axis=1, keepdims=True)
    unit = np.divide(face, length, out=np.zeros_like(face), where=length > 0.0)
    vertex = triangles.ravel()  # (3T,) the vertex of each corner
    order = np.argsort(vertex, kind="stable")  # corners grouped by vertex
    counts = np.bincount(vertex)  # corners per vertex
    size = counts[vertex[order]]  # for each sorted corner, its group's size and first entry
    first = (np.cumsum(counts) - counts)[vertex[order]]
    offsets = np.arange(size.sum()) - np.repeat(np.cumsum(size) - size, size)
    corner = np.repeat(order, size)  # every (corner, corner at the same vertex) pair
    other = order[np.repeat(first, size) + offsets]
    cosine = np.einsum("ij,ij->i", unit[corner // 3], unit[other // 3])
    keep = cosine >= np.cos(np.radians(CREASE_DEG))
    normals = np.column_stack([
        np.bincount(corner[keep], weights=face[other[keep] // 3, k], minlength=len(vertex))
        for k in range(3)
    ])
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return np.divide(normals, length, out=np.tile([0.0, 0.0, 1.0], (len(vertex), 1)),
                     where=length > 0.0)


# -- small helpers -----------------------------------------------------------------------------

def _light_axes(light: np.ndarray) -> np.ndarray:
    """(3, 3) orthonormal rows u, v, light: the shadow map's axes and the light direction."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(light[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(helper, light)
    u /= np.linalg.norm(u)
    return np.array([u, np.cross(light, u), light])


def shadow_side(width: int, height: int) -> int:
    """Texels along each side of the shadow map of a ``width`` x ``height`` frame."""
    return min(SHADOW_RESOLUTION, 2 * max(width, height))


def _camera(value) -> Camera:
    if not isinstance(value, Camera):
        raise ValueError(f"Renderer.camera: expected a Camera, got {type(value).__name__}")
    return value


def _size(value, where: str) -> int:
    """An image side in pixels: an int in [16, 4096]."""
    return integer(value, where, 16, 4096, unit="pixels")


def _index(value, count: int, where: str, what: str) -> int:
    """An index into ``count`` ``what`` (bodies, markers): an int in [0, count - 1]."""
    if count == 0:
        raise ValueError(f"{where}: there are no {what} to index, got {value!r}")
    return integer(value, f"{where} (one of {count} {what})", 0, count - 1)


def _color(value, where: str) -> np.ndarray:
    """(3,) RGB with every channel in [0, 1]."""
    return in_range(vector(value, 3, where), 0.0, 1.0, f"{where} (RGB channels)")
