"""Sleeping: a body whose last step changed nothing is not stepped again, exactly.

The step is a deterministic function of the state. A dynamic body whose only listed pair is
with one static or kinematic body (a cube resting on the table) is solved by that pair
alone: the pair shares no movable body with any other, so the contact phase resolves it at
e = 0 on its own (``solver.resolve_world_contacts``), and shock propagation puts the body on
level 1 against its one frozen support; extra passes or sweeps that other bodies need find
the same state again and apply nothing. So if, at the start of a step, such a body, its
partner and its pair are exactly (bit for bit) as they were at the start of the last step,
and no force, torque or attachment acts on it, this step would leave it exactly where the
last one did: where it is. The body is then ``asleep`` for the step: its pair is moved behind
the awake pairs, which are all the impulse phases see (their order kept, and what the
phases do with a pair depends only on the pairs sharing a movable body with it); its
velocities are put back before the position update (which then moves it by the same
velocity as the last step's, i.e. nowhere: it is a fixed point); and its pair reports the
impulse it transmitted in the last step, as stepping it would.

What the comparison cannot see wakes a world from Python (``World`` calls
``Workspace.forget``): new masses, friction or restitution, a reset or load, attaching and
detaching. A relist in a step (``kernels/step.py``) wakes its world too. The test of
exactness is stepping with sleeping on and off and comparing every state and impulse bit
for bit (tests/test_solver.py).
"""

import math
from collections import namedtuple

import numpy as np

from rigid_gym.kernels.integrate import DYNAMIC
from rigid_gym.kernels.jit import kernel

Rest = namedtuple("Rest", "asleep awake_pairs partner previous_partner snapshot impulse")
"""Sleeping's bookkeeping, leading world axis B (n bodies): asleep (B, n) bool, skipped by
the current step; awake_pairs (B,) int64, how many of the step's listed pairs (the first
ones) are awake; partner (B, n) int64, for a dynamic body whose one listed pair is with a
static or kinematic body, that body (else SEVERAL, or NONE without pairs), in the current
step and (previous_partner) the last; snapshot (B, n, SNAPSHOT) float64, every body's
state at the start of the last step; impulse (B, n, 3) N s, the impulse on each such body
through its one pair in the last step."""

SNAPSHOT = 25
"""Floats of a body's state compared: position 3, orientation 4, velocity 3, angular
momentum 3, angular velocity 3, rotation 9."""
NONE = -2
SEVERAL = -1
"""``partner`` values: no pair; more than one, or one with a dynamic body (also: forgotten)."""

REST_SHAPES = (("asleep", ("n",), np.bool_), ("awake_pairs", (), np.int64),
               ("partner", ("n",), np.int64),
               ("previous_partner", ("n",), np.int64), ("snapshot", ("n", SNAPSHOT), np.float64),
               ("impulse", ("n", 3), np.float64))
"""Per-world shape of each Rest field ("n": bodies) and dtype."""


@kernel(inline=True)
def body_state(state, w, i, k):
    """Float k of body i's state, in SNAPSHOT order."""
    if k < 3:
        return state.position[w, i, k]
    if k < 7:
        return state.orientation[w, i, k - 3]
    if k < 10:
        return state.velocity[w, i, k - 7]
    if k < 13:
        return state.angular_momentum[w, i, k - 10]
    if k < 16:
        return state.angular_velocity[w, i, k - 13]
    return state.rotation[w, i, (k - 16) // 3, (k - 16) % 3]


@kernel(inline=True)
def unchanged(state, w, i, snapshot):
    """Is body i's state bit for bit its snapshot (SNAPSHOT,)? (The sign of a zero counts;
    a NaN is never unchanged.)"""
    for k in range(SNAPSHOT):
        x = body_state(state, w, i, k)
        if x != snapshot[k] or math.copysign(1.0, x) != math.copysign(1.0, snapshot[k]):
            return False
    return True


@kernel(inline=True)
def note_partner(partner, motion, i, j):
    """Body i is listed with body j."""
    if partner[i] == NONE and motion[j] != DYNAMIC:
        partner[i] = j
    else:
        partner[i] = SEVERAL


@kernel(inline=True)
def mark_asleep(w, state, motion, pair_a, pair_b, count, pair_impulse, parent, rest, spare):
    """At the start of world w's step, after the broad phase (its ``count`` pairs pair_a,
    pair_b (P,) int32; pair_impulse (P, 3) zeroed): decide which bodies are asleep (module
    docstring), move their pairs behind the awake ones (rest.awake_pairs says how many
    those are) with the last step's impulses, and keep this step's partners and states for
    the next. parent (n,) int32: attachments (-1: free); rest: ``Rest``; spare (P,) int64:
    scratch."""
    n = state.position.shape[1]
    partner, asleep = rest.partner[w], rest.asleep[w]
    for i in range(n):
        partner[i] = NONE
    for k in range(count):
        note_partner(partner, motion, pair_a[k], pair_b[k])
        note_partner(partner, motion, pair_b[k], pair_a[k])
    for i in range(n):
        p = partner[i]
        asleep[i] = False
        if motion[i] != DYNAMIC or p < 0 or p != rest.previous_partner[w, i] or parent[i] >= 0:
            continue
        pushed = False
        for c in range(3):
            pushed = pushed or state.force[w, i, c] != 0.0 or state.torque[w, i, c] != 0.0
        asleep[i] = (not pushed and unchanged(state, w, i, rest.snapshot[w, i])
                     and unchanged(state, w, p, rest.snapshot[w, p]))
    for i in range(n):
        for k in range(SNAPSHOT):
            rest.snapshot[w, i, k] = body_state(state, w, i, k)
        rest.previous_partner[w, i] = partner[i]
    awake = move_asleep_last(pair_a, pair_b, count, asleep, spare)
    for k in range(awake, count):
        a, b = pair_a[k], pair_b[k]
        for c in range(3):
            pair_impulse[k, c] = rest.impulse[w, a, c] if asleep[a] else -rest.impulse[w, b, c]
    rest.awake_pairs[w] = awake


@kernel(inline=True)
def move_asleep_last(pair_a, pair_b, count, asleep, spare):
    """Reorder the ``count`` pairs (pair_a, pair_b (P,) int32): those without an asleep ((n,)
    bool) body first, then those with one, each in their order; returns how many are awake.
    spare (P,) int64: scratch."""
    n = asleep.shape[0]
    awake = sleeping = 0
    for k in range(count):
        a, b = pair_a[k], pair_b[k]
        if asleep[a] or asleep[b]:
            spare[sleeping] = a * n + b
            sleeping += 1
        else:
            pair_a[awake], pair_b[awake] = a, b
            awake += 1
    for k in range(sleeping):
        pair_a[awake + k], pair_b[awake + k] = spare[k] // n, spare[k] % n
    return awake


@kernel(inline=True)
def keep_rest_impulses(w, pair_a, pair_b, count, pair_impulse, rest):
    """At the end of world w's impulse phases: the impulse each body with one static or
    kinematic partner took through its pair (for the next step, should it sleep)."""
    partner = rest.partner[w]
    for k in range(count):
        a, b = pair_a[k], pair_b[k]
        for c in range(3):
            if partner[a] == b:
                rest.impulse[w, a, c] = pair_impulse[k, c]
            if partner[b] == a:
                rest.impulse[w, b, c] = -pair_impulse[k, c]


@kernel(inline=True)
def wake_world(w, rest, count):
    """No body of world w sleeps in the rest of this step (all its ``count`` pairs are awake)
    or in the next."""
    for i in range(rest.asleep.shape[1]):
        rest.asleep[w, i] = False
        rest.previous_partner[w, i] = SEVERAL
    rest.awake_pairs[w] = count
