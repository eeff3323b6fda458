"""Unit quaternions on the Python side (vectorised numpy), ordered (w, x, y, z).

The compiled core has its own scalar versions (``src/base/math.h``); tests check that both agree.
These are for building scenes, validating input and analysing results.
"""

from __future__ import annotations

import numpy as np

UNIT_TOLERANCE = 1e-6
"""How far |q| may be from 1 before input is rejected (it is then renormalised exactly)."""


def check_unit(q: np.ndarray, where: str) -> None:
    """Raise ValueError unless every quaternion in ``q`` (..., 4) has |q| within tolerance of 1."""
    norm = np.linalg.norm(q, axis=-1)
    if np.any(np.abs(norm - 1.0) > UNIT_TOLERANCE):
        raise ValueError(
            f"{where}: quaternion (w, x, y, z) must have unit norm (within {UNIT_TOLERANCE}), "
            f"got norm {np.atleast_1d(norm).tolist()}"
        )


def normalize(q: np.ndarray) -> np.ndarray:
    """(..., 4) -> (..., 4) divided by its norm."""
    q = np.asarray(q, dtype=np.float64)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a b of (..., 4) quaternions (apply b first, then a)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def conjugate(q: np.ndarray) -> np.ndarray:
    """(..., 4) -> (..., 4) conjugate, the inverse of a unit quaternion."""
    q = np.array(q, dtype=np.float64)
    q[..., 1:] *= -1.0
    return q


def to_matrix(q: np.ndarray) -> np.ndarray:
    """(..., 4) unit quaternions -> (..., 3, 3) rotation matrices (columns = rotated axes)."""
    w, x, y, z = np.moveaxis(np.asarray(q, dtype=np.float64), -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def from_matrix(r: np.ndarray) -> np.ndarray:
    """(3, 3) proper rotation matrix -> (4,) unit quaternion with w >= 0 (Shepperd's method)."""
    r = np.asarray(r, dtype=np.float64)
    trace = np.trace(r)
    diag = np.diag(r)
    k = int(np.argmax([trace, *diag]))
    if k == 0:
        s = 2.0 * np.sqrt(1.0 + trace)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif k == 1:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif k == 2:
        s = 2.0 * np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s]
    unit = normalize(np.array(q))
    return unit if unit[0] >= 0 else -unit


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors v (..., 3) by unit quaternions q (..., 4)."""
    return np.einsum("...ij,...j->...i", to_matrix(q), np.asarray(v, dtype=np.float64))
