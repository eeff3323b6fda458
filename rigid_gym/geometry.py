"""Compile a scene's shapes into the flat arrays the core's collision detection reads.

Every body becomes one or more *geoms* (a Compound contributes one per part), each a primitive
placed in the body's principal frame. Following Guendelman, Bridson & Fedkiw 2003, a geom
answers a signed distance phi (``src/collision/geometry.h``) and carries *surface samples*:

    Box    its 8 corners plus ``edge_segments - 1`` points inside each edge, so that edge-edge
           crossings are seen (measured in benchmarks/box_edge_samples.py)
    Mesh   its vertices plus points on each edge at most one grid spacing apart
    Sphere, Capsule: none; they are a core (a point, a segment) plus a radius, and the narrow
           phase treats them exactly against any signed distance
    Plane  none (it is only ever the static ground)

A Mesh's phi is its exact signed distance sampled on a grid with ``Mesh.sdf_resolution`` cells
along its longest side and two cells of padding; outside the grid, where a sphere's or capsule's
core (its radius beyond the padding) can still be within reach, the narrow phase measures the
exact distance to the mesh's triangles, which are kept for that. A mesh's samples that lie
inside another part of the same Compound are dropped (they are not on the body's surface); a
box keeps its fixed layout (corners, then the 12 edges' samples), which the narrow phase
relies on.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

from rigid_gym import _core
from rigid_gym import quaternion as quat
from rigid_gym._core import BOX_CORNERS, BOX_EDGES, CAPSULE_CORE_SAMPLES
from rigid_gym.shapes import Box, Capsule, Compound, Mesh, Plane, Pose, Shape, Sphere

GRID_PADDING_CELLS = 2
INSIDE_OTHER_PART = 1e-9
"""A compound's sample counts as inside another of its parts below this distance, m."""


class Geometry(NamedTuple):
    """Collision geometry of n bodies as G geoms, S surface samples and M distance grids.

    geom_body (G,) int32; geom_type (G,) int32 (SPHERE, CAPSULE, BOX, MESH, PLANE);
    geom_size (G, 3) m: sphere (r, 0, 0), capsule (r, half_length, 0), box half extents;
    geom_position (G, 3) m and geom_rotation (G, 3, 3): the geom frame in the body frame;
    geom_grid (G,) int32: the mesh's grid, -1 for other types;
    body_geom_start (n + 1,) int32: body i owns geoms body_geom_start[i] : body_geom_start[i+1];
    sample_start (G + 1,) int32 and sample_points (S, 3) m: each geom's surface samples, body
        frame, its corners or vertices first (sample_vertex_count (G,) int32 of them);
    body_bound_center (n, 3) m and body_bound_half (n, 3) m: a box in the body frame holding
        the body; body_unbounded (n,) int32: 1 for bodies with no bounds (planes);
    grid_offset (M,) int32, grid_shape (M, 3) int32 (nodes per axis), grid_origin (M, 3) m,
        grid_spacing (M,) m, grid_values (sum of nodes,) m: the meshes' sampled phi;
    mesh_triangle_start (M + 1,) int32, mesh_triangles (T, 3) int32 and mesh_vertices (V, 3) m:
        mesh m's triangles are mesh_triangles[mesh_triangle_start[m] : mesh_triangle_start[m+1]],
        indices into mesh_vertices (the mesh's frame), for exact distances outside its grid.
    """

    geom_body: np.ndarray
    geom_type: np.ndarray
    geom_size: np.ndarray
    geom_position: np.ndarray
    geom_rotation: np.ndarray
    geom_grid: np.ndarray
    body_geom_start: np.ndarray
    sample_start: np.ndarray
    sample_vertex_count: np.ndarray
    sample_points: np.ndarray
    body_bound_center: np.ndarray
    body_bound_half: np.ndarray
    body_unbounded: np.ndarray
    grid_offset: np.ndarray
    grid_shape: np.ndarray
    grid_origin: np.ndarray
    grid_spacing: np.ndarray
    grid_values: np.ndarray
    mesh_triangle_start: np.ndarray
    mesh_triangles: np.ndarray
    mesh_vertices: np.ndarray


class _Grid(NamedTuple):
    shape: np.ndarray
    origin: np.ndarray
    spacing: float
    values: np.ndarray


def compose(parent: Pose, child: Pose) -> Pose:
    """The pose of ``child``'s frame in ``parent``'s parent frame."""
    return Pose(parent.apply(child.position),
                quat.normalize(quat.multiply(parent.orientation, child.orientation)))


def primitives(shape: Shape, pose: Pose) -> list[tuple[Shape, Pose]]:
    """A shape flattened to (primitive, pose) pairs; Compounds are opened recursively."""
    if isinstance(shape, Compound):
        return [p for part, part_pose in shape.parts for p in primitives(part, compose(pose, part_pose))]
    return [(shape, pose)]


@functools.lru_cache(maxsize=64)
def mesh_grid(mesh: Mesh) -> _Grid:
    """Sample a mesh's exact signed distance on a padded grid of cubic cells. Meshes are
    immutable, so the grid is computed once per mesh and reused by every World built with it."""
    lower, upper = mesh.bounds()
    spacing = float(np.max(upper - lower)) / mesh.sdf_resolution
    origin = lower - GRID_PADDING_CELLS * spacing
    shape = np.ceil((upper + GRID_PADDING_CELLS * spacing - origin) / spacing).astype(np.int32) + 1
    axes = [origin[k] + spacing * np.arange(shape[k]) for k in range(3)]
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    values = np.empty(len(nodes))
    _core.signed_distance(np.ascontiguousarray(nodes), mesh.vertices, mesh.triangles, values)
    for shared in (shape, origin, values):
        shared.setflags(write=False)
    return _Grid(shape, origin, spacing, values)


def surface_samples(shape, edge_segments: int, grid_spacing: float = 0.0) -> np.ndarray:
    """(S, 3) surface samples of a primitive in its own frame, m (see the module docstring)."""
    if isinstance(shape, Box):
        corners = BOX_CORNERS * shape.half_extents
        return np.concatenate([corners, _edge_points(corners, BOX_EDGES, edge_segments)])
    if isinstance(shape, Mesh):
        t = shape.triangles
        pairs = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
        edges = np.unique(np.sort(pairs, axis=1), axis=0)
        points = [shape.vertices]
        for a, b in edges:
            length = np.linalg.norm(shape.vertices[b] - shape.vertices[a])
            points.append(_edge_points(shape.vertices, [(a, b)], int(np.ceil(length / grid_spacing))))
        return np.concatenate(points)
    return np.zeros((0, 3))


def _vertex_count(shape) -> int:
    if isinstance(shape, Box):
        return 8
    if isinstance(shape, Mesh):
        return len(shape.vertices)
    return 0


def _edge_points(vertices: np.ndarray, edges, segments: int) -> np.ndarray:
    """The ``segments - 1`` interior points that cut each edge (a, b) into equal segments."""
    t = np.arange(1, segments)[:, None] / segments
    if len(t) == 0:
        return np.zeros((0, 3))
    return np.concatenate([vertices[a] + t * (vertices[b] - vertices[a]) for a, b in edges])


GEOM_TYPES = {Sphere: _core.SPHERE, Capsule: _core.CAPSULE, Box: _core.BOX, Mesh: _core.MESH,
              Plane: _core.PLANE}


def _size(shape) -> list[float]:
    if isinstance(shape, Sphere):
        return [shape.radius, 0.0, 0.0]
    if isinstance(shape, Capsule):
        return [shape.radius, shape.half_length, 0.0]
    if isinstance(shape, Box):
        return list(shape.half_extents)
    return [0.0, 0.0, 0.0]


def compile_geometry(bodies, edge_segments: int) -> Geometry:
    """Geometry arrays for a list of ``BodySpec`` (see :class:`Geometry`)."""
    geom_body, geom_type, geom_size, geom_position, geom_rotation, geom_grid = [], [], [], [], [], []
    body_geom_start, sample_start, samples, vertex_count = [0], [0], [], []
    bound_center, bound_half, unbounded = [], [], []
    grids: list[_Grid] = []
    grid_meshes: list[Mesh] = []
    grid_of_mesh: dict[int, int] = {}
    for body in bodies:
        parts = primitives(body.shape, body.body_from_shape)
        body_points = []
        for shape, pose in parts:
            grid_spacing = 0.0
            if isinstance(shape, Mesh):
                if id(shape) not in grid_of_mesh:
                    grid_of_mesh[id(shape)] = len(grids)
                    grids.append(mesh_grid(shape))
                    grid_meshes.append(shape)
                grid_spacing = grids[grid_of_mesh[id(shape)]].spacing
            local = surface_samples(shape, edge_segments, grid_spacing)
            points = pose.apply(local) if len(local) else local
            vertices = _vertex_count(shape)
            others = [(s, p) for s, p in parts if not (s is shape and p is pose)]
            if others and len(points) and isinstance(shape, Mesh):
                # a box keeps its full layout (corners, then 12 equal edges); a mesh's
                # samples buried in another part of the compound are dropped
                inside = np.min([s.signed_distance(p.apply_inverse(points)) for s, p in others], axis=0)
                keep = inside > -INSIDE_OTHER_PART
                vertices = int(np.count_nonzero(keep[:vertices]))
                points = points[keep]
            samples.append(points)
            vertex_count.append(vertices)
            sample_start.append(sample_start[-1] + len(points))
            body_points.append(_extent_points(shape, pose))
            geom_body.append(body.index)
            geom_type.append(GEOM_TYPES[type(shape)])
            geom_size.append(_size(shape))
            geom_position.append(pose.position)
            geom_rotation.append(pose.rotation())
            geom_grid.append(grid_of_mesh[id(shape)] if isinstance(shape, Mesh) else -1)
        body_geom_start.append(len(geom_body))
        is_plane = any(isinstance(s, Plane) for s, _ in parts)
        unbounded.append(int(is_plane))
        if is_plane:
            bound_center.append(np.zeros(3))
            bound_half.append(np.zeros(3))
        else:
            pts = np.concatenate(body_points)
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            bound_center.append(0.5 * (lo + hi))
            bound_half.append(0.5 * (hi - lo))
    offsets = np.cumsum([0] + [len(g.values) for g in grids])[:-1]
    vertex_offsets = np.cumsum([0] + [len(m.vertices) for m in grid_meshes])
    triangles = [m.triangles + o for m, o in zip(grid_meshes, vertex_offsets)]
    f64 = lambda a, shape: np.ascontiguousarray(np.array(a, dtype=np.float64).reshape(shape))
    i32 = lambda a: np.ascontiguousarray(np.array(a, dtype=np.int32))
    return Geometry(
        geom_body=i32(geom_body), geom_type=i32(geom_type), geom_size=f64(geom_size, (-1, 3)),
        geom_position=f64(geom_position, (-1, 3)), geom_rotation=f64(geom_rotation, (-1, 3, 3)),
        geom_grid=i32(geom_grid), body_geom_start=i32(body_geom_start),
        sample_start=i32(sample_start), sample_vertex_count=i32(vertex_count),
        sample_points=f64(np.concatenate(samples), (-1, 3)),
        body_bound_center=f64(bound_center, (-1, 3)), body_bound_half=f64(bound_half, (-1, 3)),
        body_unbounded=i32(unbounded),
        grid_offset=i32(offsets), grid_shape=i32([g.shape for g in grids]).reshape(-1, 3),
        grid_origin=f64([g.origin for g in grids], (-1, 3)),
        grid_spacing=f64([g.spacing for g in grids], (-1,)),
        grid_values=f64(np.concatenate([g.values for g in grids]) if grids else [], (-1,)),
        mesh_triangle_start=i32(np.cumsum([0] + [len(m.triangles) for m in grid_meshes])),
        mesh_triangles=i32(np.concatenate(triangles) if triangles else np.zeros((0, 3))),
        mesh_vertices=f64([v for m in grid_meshes for v in m.vertices], (-1, 3)),
    )


def _extent_points(shape, pose: Pose) -> np.ndarray:
    """Points whose bounding box holds the primitive, in the body frame."""
    if isinstance(shape, Plane):
        return np.zeros((0, 3))
    lo, hi = shape.bounds()
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    if isinstance(shape, Mesh):
        corners = shape.vertices
    return pose.apply(corners)


def max_pair_contacts(geometry: Geometry) -> int:
    """An upper bound on the contacts ``collide_bodies`` can return for any pair of bodies, so
    solver buffers sized by it never overflow: per geom pair at most the samples of both geoms
    plus 8 (box-box clipping) plus the capsule core samples."""
    per_geom = np.diff(geometry.sample_start) + 8 + CAPSULE_CORE_SAMPLES
    per_body = np.add.reduceat(per_geom, geometry.body_geom_start[:-1]) if len(per_geom) else per_geom
    geoms = np.diff(geometry.body_geom_start)
    return int(2 * geoms.max() * per_body.max())
