"""The whole step in one kernel call: every phase of a range of worlds, for many steps.

``step_world`` runs the phases (broad phase, collision, velocity update, contact, shock
propagation, position update) in that order on one world, for ``steps`` steps, without
returning to Python in between: no allocation (every work array is given), and no per-phase
call overhead. ``step_worlds`` does it for a range of worlds; it is the only compiled entry to
the solver, because numba optimises the whole solver again for every entry that calls it (and
for every type signature): the phase-by-phase pipeline selects phases with the ``phases``
bits, and batches run ranges of worlds on threads instead of a ``prange`` (a second entry).
A world's arithmetic is the same whichever way it is stepped, so the results are
bit-identical whether worlds run together or one by one, whole steps or phase by phase.
"""

from collections import namedtuple

from rigid_gym.kernels.broadphase import find_world_pairs, swept_margin
from rigid_gym.kernels.integrate import (
    place_attached,
    update_world_positions,
    update_world_velocities,
)
from rigid_gym.kernels.jit import kernel
from rigid_gym.kernels.rest import (
    keep_rest_impulses,
    mark_asleep,
    move_asleep_last,
    wake_world,
)
from rigid_gym.kernels.solver import (
    COLLISION,
    CONTACT,
    propagate_world_shock,
    resolve_world_contacts,
)

Pairs = namedtuple("Pairs", "bounds order pair_a pair_b pair_count pair_impulse keys tmp "
                             "reach start")
"""The broad phase's buffers, leading world axis B (n bodies, P pair capacity): bounds
(B, n, 6) m; order (B, n) int64, sort-and-sweep's body order kept from step to step;
pair_a, pair_b (B, P) int32, sorted by (a, b) but, with sleeping, the pairs of asleep bodies
moved last (``rest.move_asleep_last``); pair_count (B,) int32 (may exceed P: buffers too small);
pair_impulse (B, P, 3) N s, each pair's impulse on its body a in the current step;
keys, tmp (B, P) int64 sorting scratch; reach (B, n) m, how far each body's box was grown
in the current step; start (B, 3, n, 3): velocity, angular momentum and angular velocity
when the step's impulse phases began (restored to run them again with more pairs)."""

Attachments = namedtuple("Attachments", "parent offset_position offset_orientation")
"""Bodies held rigidly by another (``World.attach``), leading world axis B: parent (B, n)
int32 (-1: free), offset_position (B, n, 3) m in the parent's frame, offset_orientation
(B, n, 4) relative to the parent's."""

Settings = namedtuple("Settings", "collision_passes contact_passes shock_sweeps rotation_order "
                                  "sweep broad_phase sleep gravity up")
"""What ``SolverConfig`` decides, as the kernels take it: pass and sweep counts (0 = phase
off), the rotation order, sort and sweep on or off, whether the broad phase runs, sleeping
on or off (``kernels/rest.py``), |g| (m/s^2) and the unit vector against gravity (3,)."""


BROAD_PHASE, COLLISION_PHASE, VELOCITY_PHASE, CONTACT_PHASE, SHOCK_PHASE, POSITION_PHASE = (
    1, 2, 4, 8, 16, 32)
"""Bits of ``phases``: which of a step's phases a call runs, in this order (the step's)."""
EVERY_PHASE = 63
"""All six: whole steps."""
IMPULSE_PHASES = COLLISION_PHASE | VELOCITY_PHASE | CONTACT_PHASE | SHOCK_PHASE
MAX_RELISTS = 4
"""Times a step's impulse phases may run again with the pairs of the bodies' grown reach."""


@kernel(inline=True)
def step_world(w, steps, phases, dt, state, model, geo, pairs, scratch, wide, graph, settings,
               attached, rest):
    """Advance world w by up to ``steps`` steps of dt (s), running the phases whose bits are
    set in ``phases`` (EVERY_PHASE: whole steps); returns how many were done. Fewer than
    ``steps`` means the pair buffers were too small for the next step (nothing of that step
    was applied; pairs.pair_count[w] says how many pairs it needs).

    state, model: ``rigid_gym.world`` State and Model; geo: compiled geometry; pairs: Pairs;
    scratch, wide: batched ``solver.Scratch`` (one pair's contacts; one body's contacts with
    all its supports); graph: batched ``solver.Graph``; settings: Settings; attached:
    Attachments, whose bodies are put at their place before every step (with the broad phase)
    and after the last (with the position update); rest: ``rest.Rest``, which bodies sleep
    through the step (with ``settings.sleep``). Forces and torques act during the first step
    and are cleared by its position update.

    The broad phase lists the pairs that can touch if every body keeps its speed through the
    step (``swept_margin``), but the impulse phases may speed a body up: a resting box struck
    by another. Before the position update, a body whose new velocity reaches past its box
    grows its box; if that lists more pairs, the velocities are put back as they were when
    the impulse phases began and the phases run again with every pair (up to MAX_RELISTS
    times), so a body is not moved into a neighbour whose pair was never listed. Nothing
    sleeps then.
    """
    s, m, c, a = state, model, settings, attached
    capacity = pairs.pair_a.shape[1]
    for done in range(steps):
        if phases & BROAD_PHASE:
            place_attached(w, s.position, s.orientation, s.velocity, s.angular_momentum,
                           s.angular_velocity, s.rotation, a.parent, a.offset_position,
                           a.offset_orientation)
            count = 0
            pairs.reach[w] = 0.0
            if c.broad_phase:
                count = list_pairs(w, dt, c.gravity, s, m, geo, pairs, c)
            pairs.pair_count[w] = count
            if count > capacity:
                return done
            pairs.pair_impulse[w, :count] = 0.0  # Coulomb's limit applies to the step's total
            keep_velocities(s.velocity[w], s.angular_momentum[w], s.angular_velocity[w],
                            pairs.start[w], True)
            rest.awake_pairs[w] = count
            if c.sleep:
                mark_asleep(w, s, m.motion, pairs.pair_a[w], pairs.pair_b[w], count,
                            pairs.pair_impulse[w], a.parent[w], rest, pairs.keys[w])
        impulse_phases(w, phases, dt, s, m, geo, pairs, scratch, wide, graph, c,
                       rest.awake_pairs[w])
        if phases & POSITION_PHASE:
            if c.sleep:  # the velocity update gave the asleep bodies gravity's share
                for i in range(rest.asleep.shape[1]):
                    if rest.asleep[w, i]:
                        keep_body_velocities(s.velocity[w], s.angular_momentum[w],
                                             s.angular_velocity[w], pairs.start[w], False, i)
            if c.broad_phase:
                for _ in range(MAX_RELISTS):
                    if not outgrown(w, dt, s, geo, pairs.reach[w]):
                        break
                    count = pairs.pair_count[w]
                    more = list_pairs(w, dt, 0.0, s, m, geo, pairs, c)  # the final velocities
                    if more == count:  # boxes only grow: the same count is the same pairs
                        if c.sleep:  # in the order the impulses were recorded in
                            move_asleep_last(pairs.pair_a[w], pairs.pair_b[w], count,
                                             rest.asleep[w], pairs.keys[w])
                        break
                    pairs.pair_count[w] = more
                    keep_velocities(s.velocity[w], s.angular_momentum[w],
                                    s.angular_velocity[w], pairs.start[w], False)
                    wake_world(w, rest, more)
                    if more > capacity:
                        return done
                    pairs.pair_impulse[w, :more] = 0.0
                    impulse_phases(w, IMPULSE_PHASES, dt, s, m, geo, pairs, scratch, wide,
                                   graph, c, more)
            if c.sleep:
                keep_rest_impulses(w, pairs.pair_a[w], pairs.pair_b[w], pairs.pair_count[w],
                                   pairs.pair_impulse[w], rest)
            update_world_positions(w, s.position, s.orientation, s.velocity, s.angular_momentum,
                                   s.angular_velocity, s.rotation, s.torque, m.inverse_moments,
                                   m.motion, dt, c.rotation_order)
            s.force[w] = 0.0
            s.torque[w] = 0.0
    if phases & POSITION_PHASE:
        place_attached(w, s.position, s.orientation, s.velocity, s.angular_momentum,
                       s.angular_velocity, s.rotation, a.parent, a.offset_position,
                       a.offset_orientation)
    return steps


@kernel(inline=True)
def list_pairs(w, dt, acceleration, s, m, geo, pairs, c):
    """World w's pairs for its current poses and velocities (``find_world_pairs``), boxes
    grown by at least pairs.reach[w]; returns how many."""
    return find_world_pairs(s.position[w], s.rotation[w], s.velocity[w], s.angular_velocity[w],
                            m.motion, geo, 0.0, dt, acceleration, c.sweep, pairs.bounds[w],
                            pairs.order[w], pairs.pair_a[w], pairs.pair_b[w], pairs.keys[w],
                            pairs.tmp[w], pairs.reach[w])


@kernel(inline=True)
def impulse_phases(w, phases, dt, s, m, geo, pairs, scratch, wide, graph, c, count):
    """World w's collision, velocity update, contact and shock phases (those whose bits are
    set in ``phases``) over its first ``count`` listed pairs (the awake ones, with sleeping);
    arguments as ``step_world``'s."""
    pair_a, pair_b, impulse = pairs.pair_a[w], pairs.pair_b[w], pairs.pair_impulse[w]
    if phases & COLLISION_PHASE and c.collision_passes > 0 and count > 0:
        resolve_world_contacts(s, m, geo, w, pair_a, pair_b, count, impulse, dt, COLLISION,
                               c.collision_passes, scratch)
    if phases & VELOCITY_PHASE:
        update_world_velocities(w, s.velocity, s.angular_momentum, s.angular_velocity,
                                s.rotation, s.force, s.torque, m.inverse_mass,
                                m.inverse_moments, m.motion, m.gravity, dt)
    if phases & CONTACT_PHASE and c.contact_passes > 0 and count > 0:
        resolve_world_contacts(s, m, geo, w, pair_a, pair_b, count, impulse, dt, CONTACT,
                               c.contact_passes, scratch)
    if phases & SHOCK_PHASE and c.shock_sweeps > 0 and c.gravity > 0.0 and count > 0:
        propagate_world_shock(s, m, geo, w, pair_a, pair_b, count, impulse, dt, c.up,
                              c.shock_sweeps, scratch, wide, graph)


@kernel
def keep_velocities(velocity, angular_momentum, angular_velocity, kept, keep):
    """Copy one world's velocity, angular momentum and angular velocity (n, 3) each into
    kept (3, n, 3) when ``keep``, else back from it."""
    for i in range(velocity.shape[0]):
        keep_body_velocities(velocity, angular_momentum, angular_velocity, kept, keep, i)


@kernel(inline=True)
def keep_body_velocities(velocity, angular_momentum, angular_velocity, kept, keep, i):
    """``keep_velocities`` for body i alone."""
    for k in range(3):
        if keep:
            kept[0, i, k] = velocity[i, k]
            kept[1, i, k] = angular_momentum[i, k]
            kept[2, i, k] = angular_velocity[i, k]
        else:
            velocity[i, k] = kept[0, i, k]
            angular_momentum[i, k] = kept[1, i, k]
            angular_velocity[i, k] = kept[2, i, k]


@kernel(inline=True)
def outgrown(w, dt, s, geo, reach):
    """True when some body of world w, at its current velocity, moves further in dt than its
    box was grown (reach (n,) m). Called before the position update, which moves a body by
    its current velocities: no acceleration term (the broad phase's bounds the velocity
    update's gravity)."""
    for i in range(reach.shape[0]):
        if geo.body_unbounded[i] == 0 and swept_margin(
                s.velocity[w, i], s.angular_velocity[w, i], geo, i, 0.0, dt, 0.0) > reach[i]:
            return True
    return False


@kernel
def step_worlds(first, last, steps, phases, done, dt, state, model, geo, pairs, scratch, wide,
                graph, settings, attached, rest):
    """``step_world`` for worlds first, ..., last - 1, one after the other: each world w
    advances from done[w] ((B,) int64) steps to ``steps``, and done[w] is updated (short of
    ``steps`` when its pair buffers were too small). The one compiled entry to the step:
    batches are shared out over threads by calling it on ranges of worlds
    (``rigid_gym.pipeline.advance``), and the phase-by-phase pipeline calls it with one phase
    bit at a time."""
    for w in range(first, last):
        if done[w] < steps:
            done[w] += step_world(w, steps - done[w], phases, dt, state, model, geo, pairs,
                                  scratch, wide, graph, settings, attached, rest)
