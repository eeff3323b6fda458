"""Checks of numbers given by users: each returns the value in the form the code uses, or
raises a ValueError that names ``where`` it came from (a class and field, or a function and
argument), so that a bad value never reaches the compiled core.

One message format: ``"{where}: must be <what> <allowed range>, got <value>"``, e.g.
"World.set_pose: body: must be a name or an int in [0, 3], got 7" (``integer``) or
"body 0 ('ball'): restitution: must be finite and in [0, 1], got 1.5" (``in_range``)."""

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
    return in_range(value, 0.0, np.inf, where, open_low=True)


def allowed(low=None, high=None, open_low: bool = False) -> str:
    """The range [low, high] as the errors state it: "in [low, high]" ("(low, high]" with
    ``open_low``), ">= low" ("> low") without an upper bound (``high`` None or inf), "<= high"
    without a lower one (``low`` None), "" for neither."""
    text = lambda x: f"{x:g}" if isinstance(x, float) else str(x)
    if high is None or high == np.inf:
        return "" if low is None else f"{'>' if open_low else '>='} {text(low)}"
    if low is None:
        return f"<= {text(high)}"
    return f"in {'(' if open_low else '['}{text(low)}, {text(high)}]"


def integer(value, where: str, low: int | None = None, high: int | None = None, *,
            unit: str = "", other: str = "") -> int:
    """``value`` as an int: a Python or numpy integer (not a bool) in [low, high] (a bound of
    None: none on that side). The error names ``where``, the range with its ``unit`` and
    ``other`` values the caller accepts before this check (e.g. "None", "a name")."""
    if (isinstance(value, bool) or not isinstance(value, (int, np.integer))
            or (low is not None and value < low) or (high is not None and value > high)):
        what = " ".join(part for part in (f"{other} or an int" if other else "an int",
                                          allowed(low, high), unit) if part)
        raise ValueError(f"{where}: must be {what}, got {value!r}")
    return int(value)


def in_range(value, low: float, high: float, where: str, *, open_low: bool = False,
             unit: str = ""):
    """``value`` checked finite and in [low, high] ((low, high] with ``open_low``; ``high``
    may be inf): a number is returned as a float, an array (one value per world, say; 0-d
    too) or a sequence of numbers as a float64 array of its shape."""
    scalar = np.ndim(value) == 0 and not isinstance(value, np.ndarray)
    if scalar:
        arr = np.asarray(real(value, where))
    else:
        try:
            arr = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{where}: expected numbers, got {value!r}") from exc
    above = arr > low if open_low else arr >= low
    if not np.all(np.isfinite(arr) & above & (arr <= high)):
        what = " ".join(part for part in ("finite and", allowed(low, high, open_low), unit)
                        if part)
        raise ValueError(f"{where}: must be {what}, got {arr.tolist()!r}")
    return float(arr) if scalar else arr


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


class BadFile(RuntimeError):
    """A file a command reads is missing, cut short or not what it should be. The message
    names the file and says what to do; ``rigid-gym`` prints it without a traceback or its
    usage (the arguments were fine: the file is not)."""
