"""Shapes a body can have: Sphere, Box, Capsule, Plane, Mesh and Compound.

A shape is an immutable description in its own *shape frame* (metres). It knows its geometry
only; mass properties live in :mod:`rigid_gym.inertia`, collision data in later modules.
Every shape answers a signed distance ``signed_distance(points)``: negative inside, zero on the
surface, positive outside (for a Mesh the magnitude is the distance to the nearest triangle).

Construction validates the numbers and raises ``ValueError`` naming the shape and field, so a
bad size never reaches the compiled core (``rigid_gym._core``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from rigid_gym import _core
from rigid_gym import quaternion as quat
from rigid_gym.checks import finite_array, integer, positive


@dataclass(frozen=True)
class Sphere:
    """A ball of ``radius`` (m) centred on the shape frame's origin."""

    radius: float

    def __post_init__(self):
        object.__setattr__(self, "radius", positive(self.radius, "Sphere.radius"))

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """(P, 3) points in the shape frame -> (P,) signed distances, m."""
        return np.linalg.norm(np.asarray(points, dtype=np.float64), axis=-1) - self.radius

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned bounding box in the shape frame: (lower (3,), upper (3,)), m."""
        r = np.full(3, self.radius)
        return -r, r


@dataclass(frozen=True, init=False)
class Box:
    """A box with ``half_extents`` (3,) in m along the shape frame's axes, centred on its origin
    (given as any 3 numbers, held as a read-only float64 array)."""

    half_extents: np.ndarray

    def __init__(self, half_extents: ArrayLike):
        h = finite_array(half_extents, (3,), "Box.half_extents")
        if np.any(h <= 0.0):
            raise ValueError(f"Box.half_extents: every entry must be > 0, got {h.tolist()}")
        object.__setattr__(self, "half_extents", h)

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """(P, 3) points in the shape frame -> (P,) exact signed distances, m."""
        q = np.abs(np.asarray(points, dtype=np.float64)) - self.half_extents
        outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
        inside = np.minimum(np.max(q, axis=-1), 0.0)
        return outside + inside

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return -self.half_extents.copy(), self.half_extents.copy()


@dataclass(frozen=True)
class Capsule:
    """Points within ``radius`` (m) of the segment from ``(0, 0, -half_length)`` to
    ``(0, 0, +half_length)`` (m): a cylinder along z capped by two hemispheres."""

    radius: float
    half_length: float

    def __post_init__(self):
        object.__setattr__(self, "radius", positive(self.radius, "Capsule.radius"))
        object.__setattr__(
            self, "half_length", positive(self.half_length, "Capsule.half_length")
        )

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """(P, 3) points in the shape frame -> (P,) exact signed distances, m."""
        p = np.asarray(points, dtype=np.float64)
        z = np.clip(p[..., 2], -self.half_length, self.half_length)
        d = p.copy()
        d[..., 2] -= z
        return np.linalg.norm(d, axis=-1) - self.radius

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        h = np.array([self.radius, self.radius, self.radius + self.half_length])
        return -h, h


@dataclass(frozen=True)
class Plane:
    """The half-space ``z <= 0`` of the shape frame; only static bodies (the ground) use it."""

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """(P, 3) points in the shape frame -> (P,) signed distances (the height z), m."""
        return np.asarray(points, dtype=np.float64)[..., 2].copy()

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array([-np.inf, -np.inf, -np.inf]), np.array([np.inf, np.inf, 0.0])


@dataclass(frozen=True, eq=False)
class Mesh:
    """A closed triangle mesh (a triangle soup that bounds a volume; may be nonconvex).

    ``vertices``: (V, 3) float positions in the shape frame, m.
    ``triangles``: (T, 3) int vertex indices, counter-clockwise seen from outside (outward
    normals). The mesh must be closed: every edge is used by exactly two triangles, once in
    each direction. Its enclosed volume must be positive (an inside-out mesh is rejected).
    ``sdf_resolution``: cells along the longest side of the grid on which collision samples
    the signed distance (contacts with a mesh are accurate to about one cell).
    """

    vertices: np.ndarray
    triangles: np.ndarray
    sdf_resolution: int = 32

    def __post_init__(self):
        integer(self.sdf_resolution, "Mesh.sdf_resolution", 4, 512)
        v = finite_array(self.vertices, (-1, 3), "Mesh.vertices")
        try:
            t = np.array(self.triangles, dtype=np.int64)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"Mesh.triangles: expected integers, got {self.triangles!r}") from exc
        if t.ndim != 2 or t.shape[1] != 3 or len(t) < 4:
            raise ValueError(f"Mesh.triangles: expected shape (T >= 4, 3), got {t.shape}")
        if t.min() < 0 or t.max() >= len(v):
            raise ValueError(
                f"Mesh.triangles: indices must lie in [0, {len(v) - 1}], "
                f"got range [{t.min()}, {t.max()}]"
            )
        if np.any((t[:, 0] == t[:, 1]) | (t[:, 1] == t[:, 2]) | (t[:, 0] == t[:, 2])):
            raise ValueError("Mesh.triangles: a triangle repeats a vertex index")
        _check_closed(t)
        t = t.astype(np.int32)
        t.setflags(write=False)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "triangles", t)
        volume = self.volume()
        if not volume > 0.0:
            raise ValueError(
                f"Mesh: enclosed volume must be > 0, got {volume:.6g} m^3 "
                "(triangles wound clockwise seen from outside, i.e. an inside-out mesh?)"
            )

    def volume(self) -> float:
        """Enclosed volume, m^3 (divergence theorem: sum of signed tetrahedra from the origin)."""
        a, b, c = (self.vertices[self.triangles[:, k]] for k in range(3))
        return float(np.einsum("ij,ij->", a, np.cross(b, c)) / 6.0)

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """(P, 3) points in the shape frame -> (P,) signed distances, m.

        Magnitude: exact distance to the nearest triangle. Sign: inside where the generalised
        winding number exceeds 1/2, so it is right for nonconvex meshes too.
        """
        p = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
        out = np.empty(len(p))
        _core.signed_distance(p, self.vertices, self.triangles, out)
        return out.reshape(np.shape(points)[:-1])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.vertices.min(axis=0), self.vertices.max(axis=0)


def _check_closed(triangles: np.ndarray) -> None:
    """Raise ValueError unless every directed edge (a, b) appears once and (b, a) once."""
    directed = np.concatenate(
        [triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]], axis=0
    )
    edges, counts = np.unique(directed, axis=0, return_counts=True)
    if np.any(counts > 1):
        bad = edges[counts > 1][0]
        raise ValueError(
            f"Mesh.triangles: directed edge {bad.tolist()} is used {counts.max()} times "
            "(inconsistent winding or a non-manifold edge)"
        )
    reverse = {tuple(e) for e in edges}
    for a, b in edges:
        if (b, a) not in reverse:
            raise ValueError(
                f"Mesh.triangles: edge ({a}, {b}) has no matching edge ({b}, {a}); "
                "the mesh is open (it must be closed to have a volume)"
            )


@dataclass(frozen=True, init=False)
class Pose:
    """A rigid placement: ``position`` (3,) m and unit ``orientation`` quaternion (w, x, y, z)
    (given as any 3 and 4 numbers, held as read-only float64 arrays)."""

    position: np.ndarray
    orientation: np.ndarray

    def __init__(self, position: ArrayLike = (0.0, 0.0, 0.0),
                 orientation: ArrayLike = (1.0, 0.0, 0.0, 0.0)):
        object.__setattr__(self, "position", finite_array(position, (3,), "Pose.position"))
        q = finite_array(orientation, (4,), "Pose.orientation")
        quat.check_unit(q, "Pose.orientation")
        object.__setattr__(self, "orientation", q)

    def rotation(self) -> np.ndarray:
        """(3, 3) rotation matrix of ``orientation``."""
        return quat.to_matrix(self.orientation)

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) points in this pose's local frame -> the parent frame."""
        return np.asarray(points) @ self.rotation().T + self.position

    def apply_inverse(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) points in the parent frame -> this pose's local frame."""
        return (np.asarray(points) - self.position) @ self.rotation()


@dataclass(frozen=True, eq=False)
class Compound:
    """A rigid union of parts: ``parts`` is a sequence of ``(shape, Pose)`` (or
    ``(shape, (position, orientation))``) giving each part's placement in the compound's frame.
    Parts share the body's density; overlapping parts count their overlap twice."""

    parts: tuple

    def __post_init__(self):
        parts = []
        if len(self.parts) == 0:
            raise ValueError("Compound.parts: needs at least one (shape, pose) part")
        for k, part in enumerate(self.parts):
            try:
                shape, pose = part
            except (TypeError, ValueError) as exc:
                raise ValueError(f"Compound.parts[{k}]: expected (shape, pose), got {part!r}") from exc
            if not isinstance(shape, (Sphere, Box, Capsule, Mesh, Compound)):
                raise ValueError(
                    f"Compound.parts[{k}]: shape must be Sphere, Box, Capsule, Mesh or Compound, "
                    f"got {type(shape).__name__}"
                )
            if not isinstance(pose, Pose):
                pose = Pose(*pose)
            parts.append((shape, pose))
        object.__setattr__(self, "parts", tuple(parts))

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """(P, 3) points -> (P,) the minimum of the parts' signed distances (exact outside the
        union only where the nearest part decides; the sign is always right)."""
        p = np.asarray(points, dtype=np.float64)
        return np.min([s.signed_distance(pose.apply_inverse(p)) for s, pose in self.parts], axis=0)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        corners = []
        for shape, pose in self.parts:
            lo, hi = shape.bounds()
            box = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                            for z in (lo[2], hi[2])])
            corners.append(pose.apply(box))
        points = np.concatenate(corners)
        return points.min(axis=0), points.max(axis=0)


SOLID_SHAPES = (Sphere, Box, Capsule, Mesh, Compound)
"""Shapes with a volume (and so a mass); Plane is for static bodies only."""

Shape = Sphere | Box | Capsule | Plane | Mesh | Compound
"""Any shape (for annotations)."""
