"""The impulse phases of the step (Guendelman, Bridson & Fedkiw 2003).

All three work at *predicted* poses: each body is moved ahead by dt with its current velocity
(X + dt V, q turned by omega dt), contacts are found there, and impulses change velocities only.
The collision phase, which runs before gravity is added, also moves dynamic bodies by dt^2 g
when predicting (but still judges approach and sizes impulses with the old velocities): a
collision that gravity completes within the step then bounces instead of being caught by the
inelastic contact phase, and a body resting on an incline still sees no approach.

* ``resolve_contacts(..., mode=COLLISION)``: passes over every candidate pair with the pair's
  real restitution max(e_a, e_b), until a pass applies no impulse.
* ``resolve_contacts(..., mode=CONTACT)``: the same with restitution ramping from
  ``CONTACT_RESTITUTION_START`` (about -0.9: negative e only slows the approach) to 0 on the
  last pass, which stops rattling.
* ``propagate_shock``: builds the contact graph (an edge from each supporting body to the body
  it supports, judged by the contact normal against gravity; side contacts both ways), collapses
  its cycles (Tarjan's strongly connected components), orders it into levels from the ground
  up, and resolves level by level with everything below frozen (infinite mass). Leftover
  approach can then only push upper bodies: a stack cannot sink.

Within a pair, contacts are grouped into patches of similar normal, each resolved at once
(``resolve_patches``): against an immovable partner by the wrench of ``patch.resolve_patch``,
otherwise by one impulse at its centroid. Shock propagation combines a body's contacts with all
its frozen supports into such patches (``resolve_supported_body``). Coulomb's limit applies to
each pair's impulse over the whole step (``pair_impulse``).
"""

from collections import namedtuple

import math

import numpy as np

from rigid_gym.kernels.impulse import add_point_mass_matrix, contact_impulse
from rigid_gym.kernels.integrate import DYNAMIC, STATIC
from rigid_gym.kernels.jit import kernel
from rigid_gym.kernels.narrowphase import collide_bodies
from rigid_gym.kernels.patch import (
    APPLIED,
    REST_SPEED,
    SEPARATING,
    apply_pair,
    relative_point_velocity,
    resolve_patch,
    spin_friction,
)
from rigid_gym.kernels.quaternion import (
    cross,
    rotate_by_angular_velocity,
    rotation_from_quaternion,
)

COLLISION = 0
CONTACT = 1
SHOCK = 2
CONTACT_RESTITUTION_START = -0.9
SIDE_CONTACT = 0.1
"""Contacts whose normal is within this cosine of horizontal do not say which body is below:
the two bodies are put on the same level."""

GRAPH_MARGIN = 1e-4
"""Bodies closer than this (m) at the predicted poses count as touching in shock propagation:
in the contact graph (bodies falling together touch without overlapping, yet the upper one
rests on the lower) and in a body's patches against its frozen supports (a rocking box's
lifting corners belong to the face it rests on; the patch wrench decides whether the patch
holds, j_n > 0, or separates)."""
SAME_MOTION = 1e-9
"""Supports whose velocity fields differ by less than this (m/s, rad/s) move as one: their
contacts can share a patch (the seed partner's velocity field is used for all of them)."""
PATCH_COS = 0.95
"""Contacts of a pair whose normals agree within this cosine form one patch (one impulse)."""

Scratch = namedtuple("Scratch", "position quaternion rotation point normal depth group partner "
                                "source orient k box directions wrench system rhs solution work "
                                "lookahead pairs_of")
"""Work arrays of the impulse phases, each with a leading world axis B: predicted poses
(B, n, 3), (B, n, 4), (B, n, 3, 3); contacts (B, C, 3), (B, C, 3), (B, C) with their patch and
partner bookkeeping (B, C) int64 / float64; a 3x3 matrix; box-clipping space (B, 3, 16, 3);
the patch solve's directions, 6x6 systems and vectors; the prediction's extra shift (B, 3);
each body's number of listed pairs (B, n) int64.
C is the contact capacity the Scratch was made for. ``world_scratch`` takes one world's rows."""

SCRATCH_SHAPES = (("position", ("n", 3), np.float64), ("quaternion", ("n", 4), np.float64),
                  ("rotation", ("n", 3, 3), np.float64), ("point", ("c", 3), np.float64),
                  ("normal", ("c", 3), np.float64), ("depth", ("c",), np.float64),
                  ("group", ("c",), np.int64), ("partner", ("c",), np.int64),
                  ("source", ("c",), np.int64), ("orient", ("c",), np.float64),
                  ("k", (3, 3), np.float64), ("box", (3, 16, 3), np.float64),
                  ("directions", (3, 3), np.float64), ("wrench", (6, 6), np.float64),
                  ("system", (6, 6), np.float64), ("rhs", (6,), np.float64),
                  ("solution", (6,), np.float64), ("work", (2, 3, 3), np.float64),
                  ("lookahead", (3,), np.float64), ("pairs_of", ("n",), np.int64))
"""Per-world shape of each Scratch field ("n": bodies, "c": contact capacity) and dtype."""


@kernel(inline=True)  # returns views: must be inlined (kernels/jit.py)
def world_scratch(s, w):
    """The rows of world w of a batched Scratch."""
    return Scratch(s.position[w], s.quaternion[w], s.rotation[w], s.point[w], s.normal[w],
                   s.depth[w], s.group[w], s.partner[w], s.source[w], s.orient[w], s.k[w],
                   s.box[w], s.directions[w], s.wrench[w], s.system[w], s.rhs[w], s.solution[w],
                   s.work[w], s.lookahead[w], s.pairs_of[w])


@kernel(inline=True)
def predict_pose(state, model, w, i, dt, lookahead, scratch):
    """Body i's pose after dt at its current velocity, into the scratch rows of i. Dynamic
    bodies also move by ``lookahead`` (3,) m: the collision phase passes dt^2 g, so that a
    collision that gravity brings about within this step is seen (and bounced) there."""
    x = scratch.position[i]
    q = scratch.quaternion[i]
    for c in range(3):
        x[c] = state.position[w, i, c]
    for c in range(4):
        q[c] = state.orientation[w, i, c]
    if model.motion[i] == DYNAMIC:
        for c in range(3):
            x[c] += lookahead[c]
    if model.motion[i] != STATIC:
        for c in range(3):
            x[c] += dt * state.velocity[w, i, c]
        rotate_by_angular_velocity(q, state.angular_velocity[w, i, 0],
                                   state.angular_velocity[w, i, 1],
                                   state.angular_velocity[w, i, 2], dt)
    rotation_from_quaternion(q, scratch.rotation[i])


@kernel(inline=True)
def find_pair_contacts(state, model, geo, w, a, b, dt, lookahead, margin, scratch):
    """Contacts of bodies a, b at their predicted poses, deepest first (those deeper than
    -margin, m); returns the count."""
    predict_pose(state, model, w, a, dt, lookahead, scratch)
    predict_pose(state, model, w, b, dt, lookahead, scratch)
    return collide_bodies(geo, a, b, scratch.position[a], scratch.rotation[a],
                          scratch.position[b], scratch.rotation[b], margin, scratch.point,
                          scratch.normal, scratch.depth, 0, scratch.depth.shape[0], scratch.box)


@kernel(inline=True)
def relative_velocity(state, w, a, b, scratch, px, py, pz):
    """v_a - v_b at world point p, each body's lever arm taken from its predicted centre."""
    return relative_point_velocity(
        state, w, a, b, px - scratch.position[a, 0], py - scratch.position[a, 1],
        pz - scratch.position[a, 2], px - scratch.position[b, 0], py - scratch.position[b, 1],
        pz - scratch.position[b, 2])


@kernel(inline=True)
def same_motion(state, w, p, q):
    """Do bodies p and q move as one rigid body, to within SAME_MOTION (same omega and same
    V - omega x X)?"""
    if p == q:
        return True
    for c in range(3):
        if abs(state.angular_velocity[w, p, c] - state.angular_velocity[w, q, c]) > SAME_MOTION:
            return False
    wx, wy, wz = state.angular_velocity[w, p, 0], state.angular_velocity[w, p, 1], state.angular_velocity[w, p, 2]
    px, py, pz = cross(wx, wy, wz, state.position[w, p, 0], state.position[w, p, 1], state.position[w, p, 2])
    qx, qy, qz = cross(wx, wy, wz, state.position[w, q, 0], state.position[w, q, 1], state.position[w, q, 2])
    return (abs(state.velocity[w, p, 0] - px - state.velocity[w, q, 0] + qx) <= SAME_MOTION
            and abs(state.velocity[w, p, 1] - py - state.velocity[w, q, 1] + qy) <= SAME_MOTION
            and abs(state.velocity[w, p, 2] - pz - state.velocity[w, q, 2] + qz) <= SAME_MOTION)


@kernel(inline=True)
def gather_patch(state, w, scratch, seed, count):
    """Put every unassigned contact whose normal is within PATCH_COS of contact ``seed``'s,
    and whose partner body moves rigidly with the seed's, into the patch ``seed``
    (scratch.group). Returns how many of them approach (v_n < 0, kept in scratch.depth)."""
    seed_n = scratch.normal[seed]
    approaching = 0
    for i in range(seed, count):
        n = scratch.normal[i]
        if scratch.group[i] >= 0:
            continue
        if not same_motion(state, w, scratch.partner[seed], scratch.partner[i]):
            continue
        if n[0] * seed_n[0] + n[1] * seed_n[1] + n[2] * seed_n[2] < PATCH_COS:
            continue
        scratch.group[i] = seed
        if scratch.depth[i] < -REST_SPEED:
            approaching += 1
    return approaching


@kernel(inline=True)
def approach_weighted_centre(scratch, seed, count):
    """Centroid and mean normal of the patch's approaching contacts, each weighted by its
    approach speed -v_n, and their mean distance from that centroid (m)."""
    total = cx = cy = cz = nx = ny = nz = 0.0
    for i in range(seed, count):
        if scratch.group[i] == seed and scratch.depth[i] < -REST_SPEED:
            weight = -scratch.depth[i]
            total += weight
            cx += weight * scratch.point[i, 0]
            cy += weight * scratch.point[i, 1]
            cz += weight * scratch.point[i, 2]
            nx += weight * scratch.normal[i, 0]
            ny += weight * scratch.normal[i, 1]
            nz += weight * scratch.normal[i, 2]
    cx, cy, cz = cx / total, cy / total, cz / total
    # average before normalising: with approach speeds near 1e-160 m/s the weighted sum's
    # square underflows to 0 (it did: a cube at rest under a kinematic pad turned NaN)
    nx, ny, nz = nx / total, ny / total, nz / total
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    radius = 0.0
    for i in range(seed, count):
        if scratch.group[i] == seed and scratch.depth[i] < -REST_SPEED:
            dx, dy, dz = scratch.point[i, 0] - cx, scratch.point[i, 1] - cy, scratch.point[i, 2] - cz
            radius += -scratch.depth[i] * math.sqrt(dx * dx + dy * dy + dz * dz)
    return cx, cy, cz, nx / norm, ny / norm, nz / norm, radius / total


@kernel(inline=True)
def prior_impulse(scratch, seed, count, accumulated):
    """What the pairs behind patch ``seed`` already transmitted to its body this step (their
    contacts are contiguous, so each pair is counted once); a 3-tuple, N s."""
    px = py = pz = 0.0
    last = -1
    for i in range(seed, count):
        if scratch.group[i] == seed and scratch.source[i] != last:
            last = scratch.source[i]
            px += scratch.orient[i] * accumulated[last, 0]
            py += scratch.orient[i] * accumulated[last, 1]
            pz += scratch.orient[i] * accumulated[last, 2]
    return px, py, pz


@kernel(inline=True)
def record_impulse(scratch, seed, accumulated, jx, jy, jz):
    """Add impulse j (on the patch's body) to the step total of the seed contact's pair."""
    k = scratch.source[seed]
    o = scratch.orient[seed]
    accumulated[k, 0] += o * jx
    accumulated[k, 1] += o * jy
    accumulated[k, 2] += o * jz


@kernel(inline=True)
def restitution_for(model, w, a, b, mode, ramp_e):
    """COLLISION: the pair's max(e_a, e_b); CONTACT: the ramp value; SHOCK: 0."""
    if mode == COLLISION:
        return max(model.restitution[w, a], model.restitution[w, b])
    if mode == CONTACT:
        return ramp_e
    return 0.0


@kernel(inline=True)
def resolve_pair(state, model, geo, w, k, a, b, dt, lookahead, mode, ramp_e, movable_a,
                 movable_b, scratch, accumulated):
    """Resolve the contacts of the pair (a, b) at their predicted poses (``resolve_patches``);
    returns the number of impulses applied. mode COLLISION uses the pair's restitution,
    CONTACT uses ``ramp_e``, SHOCK uses 0. movable_a/b: False treats the body as infinite
    mass (kinematic, static, or frozen). k: the pair's index; accumulated (P, 3): each pair's
    impulse on its body a so far in this step (read for Coulomb's limit, then added to)."""
    count = find_pair_contacts(state, model, geo, w, a, b, dt, lookahead, 0.0, scratch)
    for i in range(count):
        scratch.partner[i] = b
        scratch.source[i] = k
        scratch.orient[i] = 1.0
    return resolve_patches(state, model, w, a, movable_a, movable_b, scratch, count, mode, ramp_e,
                           accumulated)


@kernel(inline=True)
def resolve_patches(state, model, w, a, movable_a, movable_b, scratch, count, mode, ramp_e,
                    accumulated):
    """Resolve body a's contacts in scratch (normals towards a; each against the body
    scratch.partner[i]) in phase ``mode``; returns the number of impulses applied.

    The contacts are grouped into patches of similar normal and rigidly co-moving partners (a
    face resting on a face is one patch). Against an immovable partner (static, kinematic, or
    frozen by shock propagation) in the contact and shock phases, a face or edge patch gets
    the wrench of ``patch.resolve_patch`` over all its touching points: it
    brings the patch exactly to rest or to sliding without rocking, or does nothing when the
    patch is separating. Otherwise (collisions, two movable bodies, single points, a body
    tipping over an edge) the patch's approaching points get one impulse (``impulse.contact_impulse``) at their
    centroid, weighted by approach speed, along their mean normal, plus torsional friction
    about the normal bounded by mu j_n r (r: the points' mean distance from the centroid).
    One impulse per patch, not one per point, is what lets a box come exactly to rest:
    sequential point impulses leave it rocking, and their order biases it sideways.
    Coulomb's limit applies to the pair's impulse over the whole step: the patch wrench is
    checked with what its pairs already transmitted this step (``accumulated``, through
    scratch.source/orient) added, and every impulse applied is added there.
    """
    if count == 0:
        return 0
    # approach speed of every contact, kept in scratch.depth (negative: approaching)
    for i in range(count):
        p = scratch.point[i]
        n = scratch.normal[i]
        vx, vy, vz = relative_velocity(state, w, a, scratch.partner[i], scratch, p[0], p[1], p[2])
        scratch.depth[i] = vx * n[0] + vy * n[1] + vz * n[2]
        scratch.group[i] = -1
    applied = 0
    k = scratch.k
    for seed in range(count):
        if scratch.group[seed] >= 0:
            continue
        b = scratch.partner[seed]
        e = restitution_for(model, w, a, b, mode, ramp_e)
        mu = math.sqrt(model.friction[w, a] * model.friction[w, b])
        approaching = gather_patch(state, w, scratch, seed, count)
        if mode != COLLISION and not movable_b:
            px, py, pz = prior_impulse(scratch, seed, count, accumulated)
            outcome, jx, jy, jz = resolve_patch(state, model, w, a, b, movable_a, movable_b,
                                                scratch, seed, count, e, mu, px, py, pz)
            if outcome == APPLIED:
                record_impulse(scratch, seed, accumulated, jx, jy, jz)
                applied += 1
                continue
            if outcome == SEPARATING:
                continue
        if approaching == 0:
            continue
        cx, cy, cz, nx, ny, nz, radius = approach_weighted_centre(scratch, seed, count)
        vx, vy, vz = relative_velocity(state, w, a, b, scratch, cx, cy, cz)
        if vx * nx + vy * ny + vz * nz >= -REST_SPEED:
            continue
        rax, ray, raz = cx - scratch.position[a, 0], cy - scratch.position[a, 1], cz - scratch.position[a, 2]
        rbx, rby, rbz = cx - scratch.position[b, 0], cy - scratch.position[b, 1], cz - scratch.position[b, 2]
        k[:, :] = 0.0
        if movable_a:
            add_point_mass_matrix(model.inverse_mass[w, a], state.rotation[w, a],
                                  model.inverse_moments[w, a], rax, ray, raz, k)
        if movable_b:
            add_point_mass_matrix(model.inverse_mass[w, b], state.rotation[w, b],
                                  model.inverse_moments[w, b], rbx, rby, rbz, k)
        jx, jy, jz = contact_impulse(k, vx, vy, vz, nx, ny, nz, e, mu)
        apply_pair(state, model, w, a, b, movable_a, movable_b, jx, jy, jz, 0.0, 0.0, 0.0,
                   rax, ray, raz, rbx, rby, rbz)
        record_impulse(scratch, seed, accumulated, jx, jy, jz)
        if mu > 0.0 and radius > 0.0:
            limit = mu * (jx * nx + jy * ny + jz * nz) * radius
            spin_friction(state, model, w, a, b, movable_a, movable_b, nx, ny, nz, limit)
        applied += 1
    return applied


@kernel(inline=True)
def resolve_supported_body(state, model, geo, w, body, current, pair_a, pair_b, dt, scratch,
                           wide, graph, accumulated):
    """Shock propagation for one body of the level being processed against all its frozen
    supports at once: their contacts (deepest first per pair, normals turned towards ``body``)
    go into ``wide`` and are resolved as patches, so a box straddling two frozen boxes is held
    by both (one support alone could hold it only with its centre of pressure on an edge)."""
    count = 0
    capacity = wide.depth.shape[0]
    applied = 0
    lookahead = scratch.lookahead
    for s in range(graph.body_pair_start[body], graph.body_pair_start[body + 1]):
        k = graph.body_pairs[s]
        a, b = pair_a[k], pair_b[k]
        other = b if a == body else a
        if model.motion[other] == DYNAMIC and graph.level[other] >= current:
            continue  # not frozen: resolved pair by pair
        found = find_pair_contacts(state, model, geo, w, a, b, dt, lookahead, GRAPH_MARGIN,
                                   scratch)
        if count + found > capacity:
            # no room to combine it: resolve this support on its own rather than drop it
            applied += resolve_pair(state, model, geo, w, k, a, b, dt, lookahead, SHOCK, 0.0,
                                    a == body, b == body, scratch, accumulated)
            continue
        sign = 1.0 if a == body else -1.0
        for i in range(found):
            for c in range(3):
                wide.point[count, c] = scratch.point[i, c]
                wide.normal[count, c] = sign * scratch.normal[i, c]
            wide.partner[count] = other
            wide.source[count] = k
            wide.orient[count] = sign
            count += 1
        for c in range(3):
            wide.position[other, c] = scratch.position[other, c]
            wide.position[body, c] = scratch.position[body, c]
    return applied + resolve_patches(state, model, w, body, True, False, wide, count, SHOCK, 0.0,
                                     accumulated)


@kernel
def resolve_world_contacts(state, model, geo, w, pair_a, pair_b, pairs, accumulated, dt, mode,
                           passes, scratch):
    """The collision (mode COLLISION) or contact (mode CONTACT) phase for world w: up to
    ``passes`` sweeps over its ``pairs`` candidate pairs (pair_a, pair_b (P,) int32), stopping
    early when a sweep applies no impulse. accumulated (P, 3): each pair's impulse on its body
    a in this step, N s (added to here); scratch: the batched Scratch.

    In the contact phase, a pair whose movable bodies are in no other pair (``alone``: a cube
    on the table, two boxes meeting in the air) skips the restitution ramp: the ramp shares
    impulses out among contacts that disturb each other, and such a pair disturbs nothing, so
    its early passes would only scale its own approach down before the last pass (e = 0)
    stops it. Its passes run at e = 0 once the other pairs' passes are done (they share no
    movable body, so the order between the two does not matter), until one applies nothing.
    """
    scratch = world_scratch(scratch, w)
    for c in range(3):
        scratch.lookahead[c] = dt * dt * model.gravity[c] if mode == COLLISION else 0.0
    ramp = mode == CONTACT
    if ramp:
        count_pairs_of_bodies(pair_a, pair_b, pairs, scratch.pairs_of)
    for group in range(2 if ramp else 1):  # with the ramp: the other pairs, then those alone
        for p in range(passes):
            ramp_e = CONTACT_RESTITUTION_START * (1.0 - (p + 1.0) / passes) if group == 0 else 0.0
            applied = 0
            for k in range(pairs):
                a, b = pair_a[k], pair_b[k]
                if ramp and alone(model, a, b, scratch.pairs_of) != (group == 1):
                    continue
                applied += resolve_pair(state, model, geo, w, k, a, b, dt, scratch.lookahead,
                                        mode, ramp_e, model.motion[a] == DYNAMIC,
                                        model.motion[b] == DYNAMIC, scratch, accumulated)
            if applied == 0:
                break


@kernel
def count_pairs_of_bodies(pair_a, pair_b, pairs, pairs_of):
    """pairs_of (n,) int64: in how many of the ``pairs`` listed pairs each body is."""
    for i in range(pairs_of.shape[0]):
        pairs_of[i] = 0
    for k in range(pairs):
        pairs_of[pair_a[k]] += 1
        pairs_of[pair_b[k]] += 1


@kernel(inline=True)
def alone(model, a, b, pairs_of):
    """Is the pair (a, b) the only pair of each of its dynamic bodies? (pairs_of: see
    ``count_pairs_of_bodies``; static and kinematic bodies take no impulse, so the pairs
    they share carry nothing from one to another.)"""
    return ((model.motion[a] != DYNAMIC or pairs_of[a] == 1)
            and (model.motion[b] != DYNAMIC or pairs_of[b] == 1))


Graph = namedtuple("Graph", "touching edge_from edge_to edge_start targets component "
                            "component_level by_component index low on_stack stack calls "
                            "next_edge level by_level counts body_pair_start body_pairs")
"""Work arrays of shock propagation, each with a leading world axis B (n bodies, P pair
capacity): touching (P,) bool; the contact graph's edges edge_from, edge_to (2P,) int64 and
their CSR form edge_start (n + 1,), targets (2P,); Tarjan's component (n,), index, low,
on_stack (bool), stack, calls, next_edge (n,); component_level, by_component (n,); each body's
level and the bodies by level (n,); counts (n + 2,) for counting sorts; each body's touching
pairs body_pair_start (n + 1,), body_pairs (2P,). ``world_graph`` takes one world's rows."""

GRAPH_SHAPES = (("touching", ("p",), np.bool_), ("edge_from", ("2p",), np.int64),
                ("edge_to", ("2p",), np.int64), ("edge_start", ("n+1",), np.int64),
                ("targets", ("2p",), np.int64), ("component", ("n",), np.int64),
                ("component_level", ("n",), np.int64), ("by_component", ("n",), np.int64),
                ("index", ("n",), np.int64), ("low", ("n",), np.int64),
                ("on_stack", ("n",), np.bool_), ("stack", ("n",), np.int64),
                ("calls", ("n",), np.int64), ("next_edge", ("n",), np.int64),
                ("level", ("n",), np.int64), ("by_level", ("n",), np.int64),
                ("counts", ("n+2",), np.int64), ("body_pair_start", ("n+1",), np.int64),
                ("body_pairs", ("2p",), np.int64))
"""Per-world shape of each Graph field ("n": bodies, "p": pair capacity) and dtype."""


@kernel(inline=True)  # returns views: must be inlined (kernels/jit.py)
def world_graph(g, w):
    """The rows of world w of a batched Graph."""
    return Graph(g.touching[w], g.edge_from[w], g.edge_to[w], g.edge_start[w], g.targets[w],
                 g.component[w], g.component_level[w], g.by_component[w], g.index[w], g.low[w],
                 g.on_stack[w], g.stack[w], g.calls[w], g.next_edge[w], g.level[w],
                 g.by_level[w], g.counts[w], g.body_pair_start[w], g.body_pairs[w])


@kernel
def strongly_connected_components(n, graph):
    """Tarjan's algorithm without recursion over the graph with node v's successors
    graph.targets[edge_start[v]:edge_start[v + 1]]. Writes graph.component[v] and returns the
    count. Components come out in reverse topological order: an edge between components
    always goes from a higher number to a lower one."""
    edge_start, edge_to, component = graph.edge_start, graph.targets, graph.component
    index, low, on_stack = graph.index, graph.low, graph.on_stack
    stack, calls, next_edge = graph.stack, graph.calls, graph.next_edge
    for v in range(n):
        index[v] = -1
        low[v] = 0
        on_stack[v] = False
    counter = 0
    count = 0
    top = 0
    for root in range(n):
        if index[root] >= 0:
            continue
        depth = 0
        v = root
        while True:
            if index[v] < 0:  # first visit
                index[v] = low[v] = counter
                counter += 1
                stack[top] = v
                top += 1
                on_stack[v] = True
                next_edge[v] = edge_start[v]
                calls[depth] = v
                depth += 1
            v = calls[depth - 1]
            if next_edge[v] < edge_start[v + 1]:
                u = edge_to[next_edge[v]]
                next_edge[v] += 1
                if index[u] < 0:
                    v = u
                    continue
                if on_stack[u]:
                    low[v] = min(low[v], index[u])
                continue
            if low[v] == index[v]:
                while True:
                    top -= 1
                    x = stack[top]
                    on_stack[x] = False
                    component[x] = count
                    if x == v:
                        break
                count += 1
            depth -= 1
            if depth == 0:
                break
            parent = calls[depth - 1]
            low[parent] = min(low[parent], low[v])
            v = parent
    return count


@kernel
def counting_sort(keys, n, num_keys, counts, out):
    """out[:n] = the indices 0..n-1 ordered by keys[:n] (ints in [0, num_keys)), ties by
    index (a stable sort); counts: (>= num_keys + 1,) scratch."""
    for k in range(num_keys + 1):
        counts[k] = 0
    for v in range(n):
        counts[keys[v] + 1] += 1
    for k in range(num_keys):
        counts[k + 1] += counts[k]
    for v in range(n):
        out[counts[keys[v]]] = v
        counts[keys[v]] += 1


@kernel
def contact_levels(n, motion, num_edges, graph):
    """graph.level[v] for every body: 0 for static and kinematic bodies; for dynamic ones
    1 + the highest level among the bodies supporting it (cycles share one level); the
    edges are graph.edge_from/edge_to[:num_edges]."""
    edge_start, targets, counts = graph.edge_start, graph.targets, graph.counts
    # CSR form of the edges, each node's successors in edge order
    for v in range(n + 1):
        edge_start[v] = 0
    for k in range(num_edges):
        edge_start[graph.edge_from[k] + 1] += 1
    for v in range(n):
        edge_start[v + 1] += edge_start[v]
        counts[v] = edge_start[v]
    for k in range(num_edges):
        v = graph.edge_from[k]
        targets[counts[v]] = graph.edge_to[k]
        counts[v] += 1
    component = graph.component
    count = strongly_connected_components(n, graph)
    component_level = graph.component_level
    for c in range(count):
        component_level[c] = 1
    # topological order: components from the highest number down
    for v in range(n):
        graph.level[v] = count - 1 - component[v]  # reused as the sort key
    counting_sort(graph.level, n, count, counts, graph.by_component)
    for m in range(n):
        v = graph.by_component[m]
        c = component[v]
        for k in range(edge_start[v], edge_start[v + 1]):
            u = targets[k]
            if component[u] != c:
                component_level[component[u]] = max(component_level[component[u]],
                                                     component_level[c] + 1)
    for v in range(n):
        graph.level[v] = component_level[component[v]] if motion[v] == DYNAMIC else 0


@kernel
def pairs_by_body(n, pair_a, pair_b, pairs, graph):
    """CSR adjacency of the touching pairs: body v's pairs are
    graph.body_pairs[body_pair_start[v]:body_pair_start[v + 1]], in pair order."""
    start, fill = graph.body_pair_start, graph.counts
    for v in range(n + 1):
        start[v] = 0
    for k in range(pairs):
        if graph.touching[k]:
            start[pair_a[k] + 1] += 1
            start[pair_b[k] + 1] += 1
    for v in range(n):
        start[v + 1] += start[v]
        fill[v] = start[v]
    for k in range(pairs):
        if graph.touching[k]:
            graph.body_pairs[fill[pair_a[k]]] = k
            fill[pair_a[k]] += 1
            graph.body_pairs[fill[pair_b[k]]] = k
            fill[pair_b[k]] += 1


@kernel
def build_contact_graph(state, model, geo, w, pair_a, pair_b, pairs, dt, up, scratch, graph):
    """Which pairs touch at the predicted poses (graph.touching) and the support edges between
    their bodies (graph.edge_from -> edge_to, lower to upper, both ways for side contacts);
    returns the number of edges."""
    edges = 0
    for k in range(pairs):
        a, b = pair_a[k], pair_b[k]
        graph.touching[k] = find_pair_contacts(state, model, geo, w, a, b, dt, scratch.lookahead,
                                               GRAPH_MARGIN, scratch) > 0
        if not graph.touching[k] or model.motion[b] != DYNAMIC:
            continue  # b is the ground or a gripper: a rests on level 0
        rise = (scratch.normal[0, 0] * up[0] + scratch.normal[0, 1] * up[1]
                + scratch.normal[0, 2] * up[2])
        if rise > -SIDE_CONTACT:  # b below a (or beside it)
            graph.edge_from[edges], graph.edge_to[edges] = b, a
            edges += 1
        if rise < SIDE_CONTACT:  # a below b (or beside it)
            graph.edge_from[edges], graph.edge_to[edges] = a, b
            edges += 1
    return edges


@kernel
def propagate_world_shock(state, model, geo, w, pair_a, pair_b, pairs, accumulated, dt, up,
                          sweeps, scratch, wide, graph):
    """The shock-propagation phase for world w (see the module docstring).

    up: (3,) unit vector against gravity; sweeps: passes over each level; batched work arrays:
    scratch, a Scratch for one pair's contacts, wide, one with room for a body's contacts with
    all its supports, and graph, a Graph."""
    n = state.position.shape[1]
    scratch, wide, graph = world_scratch(scratch, w), world_scratch(wide, w), world_graph(graph, w)
    for c in range(3):
        scratch.lookahead[c] = 0.0
    edges = build_contact_graph(state, model, geo, w, pair_a, pair_b, pairs, dt, up, scratch,
                                graph)
    contact_levels(n, model.motion, edges, graph)
    pairs_by_body(n, pair_a, pair_b, pairs, graph)
    level, by_level = graph.level, graph.by_level
    counting_sort(level, n, n + 1, graph.counts, by_level)
    start = 0
    while start < n:
        current = level[by_level[start]]
        end = start
        while end < n and level[by_level[end]] == current:
            end += 1
        if current > 0:
            for _ in range(sweeps):
                applied = 0
                # each body of the level against all its frozen supports at once
                for s in range(start, end):
                    applied += resolve_supported_body(state, model, geo, w, by_level[s], current,
                                                      pair_a, pair_b, dt, scratch, wide, graph,
                                                      accumulated)
                # then the pairs inside the level, both bodies movable
                for k in range(pairs):
                    a, b = pair_a[k], pair_b[k]
                    if graph.touching[k] and level[a] == current and level[b] == current:
                        applied += resolve_pair(state, model, geo, w, k, a, b, dt,
                                                scratch.lookahead, SHOCK, 0.0, True, True,
                                                scratch, accumulated)
                if applied == 0:
                    break  # another sweep would find the same state and do nothing too
        start = end
