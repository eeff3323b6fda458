"""Mass properties of solid shapes: mass, centre of mass and inertia tensor.

For a body of uniform ``density`` rho (kg/m^3) occupying the region Omega of its shape frame:

* mass ``M = int rho dV`` (kg);
* centre of mass ``X = int rho x dV / M`` (m, shape frame);
* inertia tensor about the centre of mass, shape-frame axes,
  ``I = int rho ((p . p) 1 - p p^T) dV`` with ``p = x - X`` (kg m^2).

:func:`mass_properties` is exact: closed forms for the primitives, polyhedral integrals for
meshes, and :func:`combine` (the shifted-origin formula) for compounds. The grid and Monte
Carlo estimators approximate the same integrals by sums over sample points inside the shape
(found by its signed distance); they cross-check the exact answers and serve shapes with no
closed form. :func:`principal_axes` and :func:`inverse_moments` prepare a tensor for the solver:
a diagonal body-frame tensor whose inverse ignores zero moments (a rod, a point).
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from rigid_gym.shapes import Box, Capsule, Compound, Mesh, Plane, Pose, Sphere

CHUNK_POINTS = 1 << 18
"""Sample points handled at once by the grid and Monte Carlo estimators (about 6 MiB each)."""

DIAGONAL_TOLERANCE = 1e-14
""":func:`principal_axes` keeps a tensor's own axes when every off-diagonal entry is at most
this fraction of its largest entry."""

ZERO_MOMENT_TOLERANCE = 1e-12
""":func:`inverse_moments` treats moments at most this fraction of the largest one as zero."""


def _readonly(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class MassProperties:
    """Mass properties of a rigid body in its shape frame.

    ``mass``: kg, > 0. ``center``: (3,) centre of mass, m. ``inertia``: (3, 3) symmetric
    inertia tensor about ``center`` along the shape frame's axes, kg m^2. Arrays are float64
    copies made read-only.
    """

    mass: float
    center: np.ndarray
    inertia: np.ndarray

    def __post_init__(self):
        mass = float(self.mass)
        center = np.array(self.center, dtype=np.float64)
        inertia = np.array(self.inertia, dtype=np.float64)
        if not (math.isfinite(mass) and mass > 0.0):
            raise ValueError(f"MassProperties.mass: must be finite and > 0 kg, got {self.mass!r}")
        if center.shape != (3,) or not np.all(np.isfinite(center)):
            raise ValueError(
                f"MassProperties.center: expected 3 finite numbers, got {self.center!r}"
            )
        if inertia.shape != (3, 3) or not np.all(np.isfinite(inertia)):
            raise ValueError(
                f"MassProperties.inertia: expected a finite (3, 3) array, got {self.inertia!r}"
            )
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "center", _readonly(center))
        object.__setattr__(self, "inertia", _readonly(inertia))


# --- validation ---------------------------------------------------------------------------


def _check_density(density) -> float:
    """``density`` as a finite float > 0 (kg/m^3), or a ValueError naming it."""
    try:
        value = float(density)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"density: expected a number in kg/m^3, got {density!r}") from exc
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"density: must be finite and > 0 kg/m^3, got {density!r}")
    return value


def _check_count(count, name: str) -> int:
    """``count`` as a positive int, or a ValueError naming ``name``."""
    try:
        if isinstance(count, bool):
            raise TypeError
        value = operator.index(count)
    except TypeError as exc:
        raise ValueError(f"{name}: expected a positive integer, got {count!r}") from exc
    if value <= 0:
        raise ValueError(f"{name}: must be a positive integer, got {value}")
    return value


def _check_solid(shape) -> None:
    """Raise ValueError for a Plane (no volume) and TypeError for anything that is not a shape."""
    if isinstance(shape, Plane):
        raise ValueError(
            "Plane has no volume and so no mass properties; use it only for static bodies"
        )
    if not isinstance(shape, (Sphere, Box, Capsule, Mesh, Compound)):
        raise TypeError(
            f"expected a Sphere, Box, Capsule, Mesh or Compound, got {type(shape).__name__}"
        )


# --- exact mass properties ----------------------------------------------------------------


def _symmetric(tensor: np.ndarray) -> np.ndarray:
    """(3, 3) -> its symmetric part: sums taken in different orders differ in the last bit."""
    return 0.5 * (tensor + tensor.T)


def _from_moments(mass: float, first: np.ndarray, second: np.ndarray,
                  origin: np.ndarray) -> MassProperties:
    """Mass properties from the moments of a body about a reference point.

    ``mass`` kg; ``first`` (3,) = int rho x dV, kg m; ``second`` (3, 3) = int rho x x^T dV,
    kg m^2, both with x measured from ``origin`` (3,), m. Shifts the second moment to the
    centre of mass (C = second - M c c^T) and returns I = tr(C) 1 - C there.
    """
    offset = first / mass
    covariance = second - mass * np.outer(offset, offset)
    inertia = np.trace(covariance) * np.eye(3) - covariance
    return MassProperties(mass, origin + offset, _symmetric(inertia))


def _sphere(sphere: Sphere, density: float) -> MassProperties:
    """Ball: M = rho 4/3 pi r^3, I = 2/5 M r^2 on every axis."""
    r = sphere.radius
    mass = density * 4.0 / 3.0 * math.pi * r**3
    return MassProperties(mass, np.zeros(3), 0.4 * mass * r**2 * np.eye(3))


def _box(box: Box, density: float) -> MassProperties:
    """Box of half extents (a, b, c): M = 8 rho a b c, I_xx = M/12 ((2b)^2 + (2c)^2) etc."""
    a, b, c = box.half_extents
    mass = density * 8.0 * a * b * c
    moments = mass / 3.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    return MassProperties(mass, np.zeros(3), np.diag(moments))


def _capsule(capsule: Capsule, density: float) -> MassProperties:
    """Capsule = cylinder (radius r, length 2h along z) + two hemispheres (radius r).

    Cylinder: M_c = rho pi r^2 2h, I_zz = M_c r^2 / 2, I_xx = M_c (3 r^2 + (2h)^2) / 12.
    Hemisphere: M_h = rho 2/3 pi r^3; about the centre of its flat face I = 2/5 M_h r^2 on every
    axis. Its centre of mass lies 3r/8 from that face, so about its own centre of mass
    I_xx = (2/5 - (3/8)^2) M_h r^2, and about the capsule's centre, at distance h + 3r/8,
    I_xx = (2/5 - (3/8)^2) M_h r^2 + M_h (h + 3r/8)^2 (I_zz stays 2/5 M_h r^2: the axis is z).
    """
    r, h = capsule.radius, capsule.half_length
    m_cyl = density * math.pi * r**2 * 2.0 * h
    m_hemi = density * 2.0 / 3.0 * math.pi * r**3
    i_zz = 0.5 * m_cyl * r**2 + 2.0 * 0.4 * m_hemi * r**2
    hemi_xx = (0.4 - (3.0 / 8.0) ** 2) * m_hemi * r**2 + m_hemi * (h + 3.0 * r / 8.0) ** 2
    i_xx = m_cyl * (3.0 * r**2 + (2.0 * h) ** 2) / 12.0 + 2.0 * hemi_xx
    return MassProperties(m_cyl + 2.0 * m_hemi, np.zeros(3), np.diag([i_xx, i_xx, i_zz]))


def _mesh(mesh: Mesh, density: float) -> MassProperties:
    """Closed mesh, by the divergence theorem: a sum over triangles (a, b, c) of the signed
    tetrahedra (o, a, b, c), with o the bounding-box centre (limits cancellation) and
    a, b, c measured from o. With D = det[a b c] = a . (b x c) and s = a + b + c, a tetrahedron
    has volume D/6, first moment D/24 s and second moment
    int x x^T dV = D/120 (a a^T + b b^T + c c^T + s s^T).
    """
    lower, upper = mesh.bounds()
    origin = 0.5 * (lower + upper)
    a, b, c = (mesh.vertices[mesh.triangles[:, k]] - origin for k in range(3))
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    s = a + b + c
    second = sum(np.einsum("t,ti,tj->ij", det, x, x) for x in (a, b, c, s))
    return _from_moments(
        density * det.sum() / 6.0, density * det @ s / 24.0, density * second / 120.0, origin
    )


def _compound(compound: Compound, density: float) -> MassProperties:
    """Compound: its parts' exact properties combined by :func:`combine` (overlaps count twice)."""
    return combine([(mass_properties(shape, density), pose) for shape, pose in compound.parts])


_EXACT: dict[type, Callable[..., MassProperties]] = {
    Sphere: _sphere, Box: _box, Capsule: _capsule, Mesh: _mesh, Compound: _compound}


def mass_properties(shape, density: float) -> MassProperties:
    """Exact mass properties of ``shape`` (Sphere, Box, Capsule, Mesh or Compound) at uniform
    ``density`` (kg/m^3), in the shape frame.

    Raises ValueError for a bad density or a Plane (no volume), TypeError for a non-shape.
    """
    density = _check_density(density)
    _check_solid(shape)
    return _EXACT[type(shape)](shape, density)


def combine(parts: Sequence[tuple[MassProperties, Pose]]) -> MassProperties:
    """Mass properties of a rigid union of parts (the shifted-origin formula).

    ``parts``: (MassProperties, Pose) pairs, each part's properties in its own frame and the
    Pose placing that frame in the combined frame. M = sum M_k; X = sum M_k X_k / M with
    X_k = pose_k.apply(center_k); I = sum [R_k I_k R_k^T + M_k ((d . d) 1 - d d^T)] with
    d = X_k - X: every tensor is moved to the common centre before adding.
    """
    if len(parts) == 0:
        raise ValueError("combine: needs at least one (MassProperties, Pose) part")
    masses = np.array([props.mass for props, _ in parts])
    centers = np.array([pose.apply(props.center) for props, pose in parts])
    mass = masses.sum()
    center = masses @ centers / mass
    inertia = np.zeros((3, 3))
    for (props, pose), m, x in zip(parts, masses, centers):
        rotation = pose.rotation()
        d = x - center
        inertia += rotation @ props.inertia @ rotation.T + m * (d @ d * np.eye(3) - np.outer(d, d))
    return MassProperties(mass, center, _symmetric(inertia))


# --- sampled mass properties --------------------------------------------------------------


def _solid_bounds(shape) -> tuple[np.ndarray, np.ndarray]:
    """(lower (3,), upper (3,)) bounding box of a solid shape, m."""
    _check_solid(shape)
    return shape.bounds()


def _sampled(shape, count: int, sample: Callable[[int], np.ndarray], point_mass: float,
             origin: np.ndarray, method: str) -> MassProperties:
    """Mass properties estimated from ``count`` sample points, each inside point weighing
    ``point_mass`` (kg): sums of m, m x and m x x^T (x from ``origin`` (3,), m).

    ``sample(n)`` returns the next ``n`` points (n, 3), m; it is called in order, at most
    :data:`CHUNK_POINTS` at a time, so memory stays bounded. A point is inside where the
    shape's signed distance is <= 0.
    """
    inside_count = 0
    first = np.zeros(3)
    second = np.zeros((3, 3))
    for start in range(0, count, CHUNK_POINTS):
        points = sample(min(CHUNK_POINTS, count - start))
        x = points[shape.signed_distance(points) <= 0.0] - origin
        inside_count += len(x)
        first += x.sum(axis=0)
        second += x.T @ x
    if inside_count == 0:
        raise ValueError(f"{method}: no sample point fell inside the shape; use more points")
    return _from_moments(point_mass * inside_count, point_mass * first, point_mass * second, origin)


def mass_properties_grid(shape, density: float, resolution: int) -> MassProperties:
    """Mass properties estimated on a grid (the notes' "grid approach").

    The shape's bounding box is cut into ``resolution``^3 equal cells; a cell whose centre is
    inside the shape (signed distance <= 0) counts with mass ``density`` (kg/m^3) x its volume,
    concentrated at the centre. A Compound counts overlaps once here (unlike the exact answer).
    """
    density = _check_density(density)
    n = _check_count(resolution, "resolution")
    lower, upper = _solid_bounds(shape)
    cell = (upper - lower) / n
    next_index = 0

    def sample(count: int) -> np.ndarray:
        nonlocal next_index
        k = np.arange(next_index, next_index + count)
        next_index += count
        index = np.column_stack([k // (n * n), (k // n) % n, k % n])
        return lower + (index + 0.5) * cell

    origin = 0.5 * (lower + upper)
    return _sampled(shape, n**3, sample, density * np.prod(cell), origin, "mass_properties_grid")


def mass_properties_monte_carlo(shape, density: float, samples: int,
                                seed: int = 0) -> MassProperties:
    """Mass properties estimated from random points (the notes' "Monte Carlo approach").

    ``samples`` points uniform in the shape's bounding box, drawn from
    ``np.random.default_rng(seed)`` (the same seed gives the same answer); each inside point
    (signed distance <= 0) weighs ``density`` (kg/m^3) x box volume / ``samples``. The error
    shrinks like samples^-1/2. A Compound counts overlaps once here (unlike the exact answer).
    """
    density = _check_density(density)
    count = _check_count(samples, "samples")
    lower, upper = _solid_bounds(shape)
    rng = np.random.default_rng(seed)

    def sample(n: int) -> np.ndarray:
        return rng.uniform(lower, upper, size=(n, 3))

    point_mass = density * np.prod(upper - lower) / count
    origin = 0.5 * (lower + upper)
    return _sampled(shape, count, sample, point_mass, origin, "mass_properties_monte_carlo")


# --- body frame ---------------------------------------------------------------------------


def principal_axes(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Diagonalise a symmetric (3, 3) inertia tensor, kg m^2.

    Returns ``(moments (3,) kg m^2, rotation (3, 3))`` with ``inertia = rotation @
    diag(moments) @ rotation.T``; the columns of ``rotation`` are the principal axes and
    det(rotation) = +1. A tensor that is already diagonal (off-diagonal entries at most
    :data:`DIAGONAL_TOLERANCE` of its largest entry) keeps its own axes: the identity and its
    diagonal in order. Otherwise the moments come ascending from ``np.linalg.eigh``.
    """
    tensor = np.asarray(inertia, dtype=np.float64)
    if tensor.shape != (3, 3) or not np.all(np.isfinite(tensor)):
        raise ValueError(f"principal_axes: expected a finite (3, 3) tensor, got {inertia!r}")
    scale = np.abs(tensor).max()
    if np.abs(tensor - tensor.T).max() > 1e-12 * scale:
        raise ValueError(f"principal_axes: the tensor must be symmetric, got {tensor.tolist()}")
    off_diagonal = tensor - np.diag(np.diag(tensor))
    if np.abs(off_diagonal).max() <= DIAGONAL_TOLERANCE * scale:
        return np.diag(tensor).copy(), np.eye(3)
    moments, rotation = np.linalg.eigh(tensor)
    if np.linalg.det(rotation) < 0.0:
        rotation[:, 2] *= -1.0
    return moments, rotation


def inverse_moments(moments: np.ndarray) -> np.ndarray:
    """(3,) principal moments, kg m^2 -> (3,) their inverses, 1/(kg m^2), with zero for every
    moment at most :data:`ZERO_MOMENT_TOLERANCE` of the largest one (a rod cannot be spun about
    its axis, a point mass about any). All zero gives all zero.
    """
    m = np.asarray(moments, dtype=np.float64)
    if m.shape != (3,) or not np.all(np.isfinite(m)):
        raise ValueError(f"inverse_moments: expected 3 finite moments, got {moments!r}")
    nonzero = m > ZERO_MOMENT_TOLERANCE * m.max()
    return np.divide(1.0, m, out=np.zeros(3), where=nonzero)
