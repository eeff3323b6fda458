"""Ready-made closed triangle meshes for scenes and tests (all sizes in metres).

``box_mesh`` matches :class:`~rigid_gym.shapes.Box` exactly; ``l_shape_mesh`` is a nonconvex
extruded L whose exact answers are those of the two boxes it is made of; ``bowl_mesh`` is a
hemispherical shell open at the top, a concave container for contact tests; ``prism_mesh``
extrudes any polygon that is star-shaped from its first vertex.
"""

from __future__ import annotations

import numpy as np

from rigid_gym.checks import integer, positive
from rigid_gym.shapes import Box, Mesh


def prism_mesh(polygon, z_low: float, z_high: float) -> Mesh:
    """Extrude ``polygon`` (N, 2) in the xy-plane, m, between heights ``z_low`` < ``z_high`` (m).

    The polygon must be simple, counter-clockwise seen from +z, and star-shaped from its first
    vertex: each cap is the triangle fan from that vertex (so a wedge, a ramp or an L are fine).
    Vertices: bottom ring 0..N-1, top ring N..2N-1.
    """
    polygon = np.asarray(polygon, dtype=np.float64)
    if polygon.ndim != 2 or polygon.shape[1] != 2 or len(polygon) < 3:
        raise ValueError(f"prism_mesh.polygon: expected shape (N >= 3, 2), got {polygon.shape}")
    if not z_low < z_high:
        raise ValueError(f"prism_mesh: need z_low < z_high, got {z_low} and {z_high}")
    n = len(polygon)
    vertices = np.concatenate([
        np.column_stack([polygon, np.full(n, z_low)]),
        np.column_stack([polygon, np.full(n, z_high)]),
    ])
    k = np.arange(1, n - 1)
    bottom = np.column_stack([np.zeros(n - 2, dtype=int), k + 1, k])
    top = np.column_stack([np.full(n - 2, n), n + k, n + k + 1])
    s = np.arange(n)
    s1 = (s + 1) % n
    sides = np.concatenate([np.column_stack([s, s1, n + s1]), np.column_stack([s, n + s1, n + s])])
    return Mesh(vertices, np.concatenate([bottom, top, sides]))


def lathe(profile: np.ndarray, segments: int) -> Mesh:
    """Revolve ``profile`` (K, 2) of (radius, z), m, about the z axis in ``segments`` steps.

    The profile runs from a point on the axis (radius 0) to another one, through points of
    radius > 0, with the solid on its left in the (radius, z) plane (it traces the solid's
    cross-section counter-clockwise); the end points' radii are taken as exactly 0. Vertices:
    the first pole, ``segments`` per inner profile point, then the last pole.
    """
    rings = profile[1:-1]  # (K - 2, 2): (radius, z) of each ring of vertices
    theta = 2.0 * np.pi * np.arange(segments) / segments
    radius, height = rings[:, :1], rings[:, 1:]
    ring_vertices = np.stack([
        radius * np.cos(theta), radius * np.sin(theta), np.repeat(height, segments, axis=1),
    ], axis=-1).reshape(-1, 3)
    poles = np.column_stack([np.zeros((2, 2)), profile[[0, -1], 1]])
    vertices = np.concatenate([poles[:1], ring_vertices, poles[1:]])

    s = np.arange(segments)
    s1 = (s + 1) % segments
    ring = 1 + segments * np.arange(len(rings) - 1)[:, None]  # first vertex of rings 0..K-4
    following = ring + segments  # first vertex of the next ring along the profile
    quads_a = np.stack([ring + s, ring + s1, following + s1], axis=-1).reshape(-1, 3)
    quads_b = np.stack([ring + s, following + s1, following + s], axis=-1).reshape(-1, 3)
    bottom_fan = np.column_stack([np.zeros(segments, dtype=int), 1 + s1, 1 + s])
    last_ring = 1 + segments * (len(rings) - 1)
    top_fan = np.column_stack([last_ring + s, last_ring + s1, np.full(segments, len(vertices) - 1)])
    return Mesh(vertices, np.concatenate([bottom_fan, quads_a, quads_b, top_fan]))


def box_mesh(half_extents) -> Mesh:
    """The :class:`Box` with ``half_extents`` (3,), m, as 8 vertices and 12 triangles."""
    a, b, c = Box(half_extents).half_extents
    rectangle = np.array([[-a, -b], [a, -b], [a, b], [-a, b]])
    return prism_mesh(rectangle, -c, c)


def l_shape_mesh(outer=(1.0, 1.0), thickness: float = 0.25, half_depth: float = 0.25) -> Mesh:
    """An extruded L, the union of two boxes: ``[0, lx] x [0, t] x [-hz, hz]`` and
    ``[0, t] x [t, ly] x [-hz, hz]`` with ``outer = (lx, ly)``, ``t = thickness`` and
    ``hz = half_depth`` (m). Its notch is the region ``x > t, y > t``; 12 vertices, 20 triangles.
    """
    lx = positive(outer[0], "l_shape_mesh.outer[0]")
    ly = positive(outer[1], "l_shape_mesh.outer[1]")
    t = positive(thickness, "l_shape_mesh.thickness")
    hz = positive(half_depth, "l_shape_mesh.half_depth")
    if t >= min(lx, ly):
        raise ValueError(f"l_shape_mesh.thickness: must be < min(outer) = {min(lx, ly)}, got {t}")
    polygon = np.array([[0.0, 0.0], [lx, 0.0], [lx, t], [t, t], [t, ly], [0.0, ly]])
    return prism_mesh(polygon, -hz, hz)


def bowl_mesh(outer_radius: float = 0.5, inner_radius: float = 0.4, segments: int = 32,
              rings: int = 8) -> Mesh:
    """A hemispherical shell opening upwards: the lower half (z <= 0) of the ball of
    ``outer_radius`` minus the ball of ``inner_radius`` (m), its rim a flat annulus at z = 0.

    Each quarter-circle of the profile has ``rings`` straight pieces and the revolution has
    ``segments`` steps; both surfaces are inscribed in their spheres, so the wall is a little
    thinner outside and thicker inside than the exact shell's (volume 1.6% below it with the
    defaults).
    """
    big = positive(outer_radius, "bowl_mesh.outer_radius")
    small = positive(inner_radius, "bowl_mesh.inner_radius")
    if small >= big:
        raise ValueError(
            f"bowl_mesh.inner_radius: must be < outer_radius = {big}, got {small}"
        )
    integer(segments, "bowl_mesh.segments", 3)
    integer(rings, "bowl_mesh.rings", 1)
    up = np.linspace(-0.5 * np.pi, 0.0, int(rings) + 1)  # outer surface, pole to rim
    down = up[::-1]  # inner surface, rim to pole
    profile = np.concatenate([
        np.column_stack([big * np.cos(up), big * np.sin(up)]),
        np.column_stack([small * np.cos(down), small * np.sin(down)]),
    ])
    return lathe(profile, int(segments))
