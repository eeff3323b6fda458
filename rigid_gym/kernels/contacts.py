"""Contact detection for every world: the narrow phase over the broad phase's pairs."""

import numpy as np

from rigid_gym.kernels.jit import kernel
from rigid_gym.kernels.narrowphase import collide_bodies


@kernel(allocates=True)
def detect_contacts(position, rotation, geo, pair_a, pair_b, pair_count, margin,
                    body_a, body_b, point, normal, depth, contact_count):
    """Contacts of every candidate pair of every world at the given poses.

    position (B, n, 3), rotation (B, n, 3, 3); pairs from ``broadphase.find_pairs``;
    margin: m, report contacts deeper than -margin. Out, per world w: body_a, body_b (B, C)
    int32, point (B, C, 3) m, normal (B, C, 3) from body_b to body_a, depth (B, C) m and
    contact_count (B,) int32 (contacts found; more than C means the buffers were too small
    and only C were written).
    """
    num_worlds = position.shape[0]
    capacity = depth.shape[1]
    for w in range(num_worlds):
        scratch = np.empty((3, 16, 3))
        count = 0
        for p in range(pair_count[w]):
            a, b = pair_a[w, p], pair_b[w, p]
            found = collide_bodies(geo, a, b, position[w, a], rotation[w, a], position[w, b],
                                   rotation[w, b], margin, point[w], normal[w], depth[w], count,
                                   capacity, scratch)
            for k in range(count, min(count + found, capacity)):
                body_a[w, k] = a
                body_b[w, k] = b
            count += found
        contact_count[w] = count
