"""The whole step in one kernel call: every phase of one world, for many steps.

``step_world`` runs the phases of ``rigid_gym.pipeline.step`` in the same order on one world
(broad phase, collision, velocity update, contact, shock propagation, position update), for
``steps`` steps, without returning to Python in between: no allocation (every work array is
given), and no per-phase call overhead. ``step_worlds`` does it for every world, in parallel
over worlds. A world's arithmetic is the same whichever way it is stepped, so the results are
bit-identical to the phase-by-phase pipeline and to stepping the worlds one by one.
"""

from collections import namedtuple

from rigid_gym.kernels.broadphase import find_world_pairs
from rigid_gym.kernels.integrate import (
    place_attached,
    update_world_positions,
    update_world_velocities,
)
from rigid_gym.kernels.jit import kernel, prange
from rigid_gym.kernels.solver import (
    COLLISION,
    CONTACT,
    propagate_world_shock,
    resolve_world_contacts,
)

Pairs = namedtuple("Pairs", "bounds order pair_a pair_b pair_count pair_impulse keys tmp")
"""The broad phase's buffers, leading world axis B (n bodies, P pair capacity): bounds
(B, n, 6) m; order (B, n) int64, sort-and-sweep's body order kept from step to step;
pair_a, pair_b (B, P) int32; pair_count (B,) int32 (may exceed P: buffers too small);
pair_impulse (B, P, 3) N s, each pair's impulse on its body a in the current step;
keys, tmp (B, P) int64 sorting scratch."""

Attachments = namedtuple("Attachments", "parent offset_position offset_orientation")
"""Bodies held rigidly by another (``World.attach``), leading world axis B: parent (B, n)
int32 (-1: free), offset_position (B, n, 3) m in the parent's frame, offset_orientation
(B, n, 4) relative to the parent's."""

Settings = namedtuple("Settings", "collision_passes contact_passes shock_sweeps rotation_order "
                                  "sweep broad_phase gravity up")
"""What ``SolverConfig`` decides, as the kernels take it: pass and sweep counts (0 = phase
off), the rotation order, sort and sweep on or off, whether the broad phase runs, |g| (m/s^2)
and the unit vector against gravity (3,)."""


@kernel
def step_world(w, steps, dt, state, model, geo, pairs, scratch, wide, graph, settings,
               attached):
    """Advance world w by up to ``steps`` steps of dt (s); returns how many were done. Fewer
    than ``steps`` means the pair buffers were too small for the next step (nothing of that
    step was applied; pairs.pair_count[w] says how many pairs it needs).

    state, model: ``rigid_gym.world`` State and Model; geo: compiled geometry; pairs: Pairs;
    scratch, wide: batched ``solver.Scratch`` (one pair's contacts; one body's contacts with
    all its supports); graph: batched ``solver.Graph``; settings: Settings; attached:
    Attachments, whose bodies are put at their place before every step and after the last.
    Forces and torques act during the first step and are then cleared.
    """
    s, m, c, a = state, model, settings, attached
    capacity = pairs.pair_a.shape[1]
    for done in range(steps):
        place_attached(w, s.position, s.orientation, s.velocity, s.angular_momentum,
                       s.angular_velocity, s.rotation, a.parent, a.offset_position,
                       a.offset_orientation)
        count = 0
        if c.broad_phase:
            count = find_world_pairs(s.position[w], s.rotation[w], s.velocity[w],
                                     s.angular_velocity[w], m.motion, geo, 0.0, dt, c.gravity,
                                     c.sweep, pairs.bounds[w], pairs.order[w], pairs.pair_a[w],
                                     pairs.pair_b[w], pairs.keys[w], pairs.tmp[w])
            pairs.pair_count[w] = count
            if count > capacity:
                return done
            pairs.pair_impulse[w, :count] = 0.0  # Coulomb's limit applies to the step's total
        pair_a, pair_b, impulse = pairs.pair_a[w], pairs.pair_b[w], pairs.pair_impulse[w]
        if c.collision_passes > 0 and count > 0:
            resolve_world_contacts(s, m, geo, w, pair_a, pair_b, count, impulse, dt, COLLISION,
                                   c.collision_passes, scratch)
        update_world_velocities(w, s.velocity, s.angular_momentum, s.angular_velocity,
                                s.rotation, s.force, s.torque, m.inverse_mass,
                                m.inverse_moments, m.motion, m.gravity, dt)
        if c.contact_passes > 0 and count > 0:
            resolve_world_contacts(s, m, geo, w, pair_a, pair_b, count, impulse, dt, CONTACT,
                                   c.contact_passes, scratch)
        if c.shock_sweeps > 0 and c.gravity > 0.0 and count > 0:
            propagate_world_shock(s, m, geo, w, pair_a, pair_b, count, impulse, dt, c.up,
                                  c.shock_sweeps, scratch, wide, graph)
        update_world_positions(w, s.position, s.orientation, s.velocity, s.angular_momentum,
                               s.angular_velocity, s.rotation, s.torque, m.inverse_moments,
                               m.motion, dt, c.rotation_order)
        s.force[w] = 0.0
        s.torque[w] = 0.0
    place_attached(w, s.position, s.orientation, s.velocity, s.angular_momentum,
                   s.angular_velocity, s.rotation, a.parent, a.offset_position,
                   a.offset_orientation)
    return steps


@kernel(parallel=True)
def step_worlds(steps, done, dt, state, model, geo, pairs, scratch, wide, graph, settings,
                attached):
    """``step_world`` for every world, in parallel: each world w advances from done[w] (B,)
    int64 steps to ``steps``, and done[w] is updated (short of ``steps`` when its pair buffers
    were too small)."""
    for w in prange(state.position.shape[0]):
        if done[w] < steps:
            done[w] += step_world(w, steps - done[w], dt, state, model, geo, pairs, scratch, wide,
                                  graph, settings, attached)
