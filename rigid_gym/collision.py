"""Contacts as a World reports them, and the choice of broad phase.

The detection itself is in the compiled core (``src/collision/broad_phase.cpp``, ``src/collision/narrow_phase.cpp``,
``src/solver/queries.cpp``): ``World.contacts`` asks it for the contacts at the current poses with
buffers of its own, so asking never disturbs what the last step listed.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

# the solver's touching tolerance, m (src/solver/patch.h CLOSED_GAP): contacts() reports contacts
# this close as touching
from rigid_gym._core import TOUCHING_GAP as TOUCHING_GAP  # noqa: PLC0414 - explicit re-export

SWEEP_MIN_BODIES = 64
"""Bounded bodies from which sort-and-sweep beats brute force (benchmarks/collision.py)."""


class Contacts(NamedTuple):
    """Contacts as flat arrays over all worlds, k rows.

    world (k,) int32; body_a, body_b (k,) int32; point (k, 3) m (the deepest point of one body
    inside the other); normal (k, 3) unit, from body_b towards body_a; depth (k,) m,
    > 0 when overlapping, > -TOUCHING_GAP (1e-6 m: touching, as the solver counts it; about
    +-1e-16 for bodies resting on each other) when no margin is asked for. Within a pair
    the deepest contact comes first. pair_impulse (k, 3) N s: the impulse the row's pair
    transmitted to body_a during the last step (the solver resolves a pair's touching points
    as patches, one impulse each, so there is no impulse per point; zero for a pair the last
    step did not list, or before the first step), the same on every row of a pair. It is
    what the solver applied, not a contact force: shock propagation stops a body against its
    frozen supports without their reaction, so the pairs of a resting stack do not carry its
    weight.
    """

    world: np.ndarray
    body_a: np.ndarray
    body_b: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    depth: np.ndarray
    pair_impulse: np.ndarray


def uses_sweep(body_unbounded: np.ndarray, sweep: bool | None) -> bool:
    """Whether the broad phase sorts and sweeps (True) or pairs by brute force: ``sweep`` if
    given, else sort and sweep from ``SWEEP_MIN_BODIES`` bounded bodies (body_unbounded (n,)
    int32, 1 for planes)."""
    if sweep is not None:
        return bool(sweep)
    return int(np.count_nonzero(body_unbounded == 0)) >= SWEEP_MIN_BODIES
