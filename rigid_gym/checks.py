"""Checks of numbers given by users: each returns the value in the form the code uses, or
raises a ValueError that names ``where`` it came from (a class and field, or a function and
argument), so that a bad value never reaches the compiled core."""

from __future__ import annotations

import numpy as np


def real(value, where: str) -> float:
    """``value`` as a float (inf and NaN too)."""
    try:
        return float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: expected a number, got {value!r}") from exc


def number(value, where: str) -> float:
    """``value`` as a finite float."""
    x = real(value, where)
    if not np.isfinite(x):
        raise ValueError(f"{where}: must be finite, got {value!r}")
    return x


def positive(value, where: str) -> float:
    """``value`` as a finite float > 0."""
    x = real(value, where)
    if not np.isfinite(x) or x <= 0.0:
        raise ValueError(f"{where}: must be finite and > 0, got {value!r}")
    return x


def vector(value, size: int, where: str) -> np.ndarray:
    """``value`` as a new, writable float64 array of shape (size,), every entry finite."""
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: expected {size} numbers, got {value!r}") from exc
    if arr.shape != (size,):
        raise ValueError(f"{where}: expected shape ({size},), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{where}: must be finite, got {arr.tolist()}")
    return arr


def finite_array(value, shape: tuple[int, ...], where: str) -> np.ndarray:
    """``value`` as a new, read-only float64 array of ``shape`` (an entry -1: any length),
    every entry finite."""
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: expected numbers, got {value!r}") from exc
    if arr.ndim != len(shape) or any(s != -1 and s != a for s, a in zip(shape, arr.shape)):
        raise ValueError(f"{where}: expected shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{where}: must be finite, got {value!r}")
    arr.setflags(write=False)
    return arr
