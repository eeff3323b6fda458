"""Z-buffer rasterisation for the software renderer :mod:`rigid_gym.render`.

Geometry is a triangle soup: triangle t has the corners 3t, 3t + 1, 3t + 2, wound
counter-clockwise seen from outside (outward normals).
    local, local_normal    (C, 3)     corners and unit shading normals in their owner's frame
    owner                  (C,) int32 the instance (a body or a marker) that moves each corner
    rotation, translation  (N, 3, 3), (N, 3) m: each instance's pose in the world
    world, world_normal    (C, 3)     the corners in the world (written by ``transform``)
Camera: ``eye`` (3,) m and ``axes`` (3, 3) whose rows are the unit right, up and forward
directions; ``focal`` is the focal length in pixels. Screen coordinates are pixels, x to the
right and y down, pixel (i, j) centred on (j + 0.5, i + 0.5).
Per-pixel buffers (H, W): ``nearness`` (larger = nearer; 1/depth with depth in m for the
camera, 0 = empty), ``ids`` (int32 triangle index, -1 = empty) and ``diffuse`` (the Lambert
factor max(0, n . light) in [0, 1], interpolated perspective-correctly).
The shadow map uses the same buffers and fill, seen orthographically along the light.
"""

import math

import numpy as np

from rigid_gym.kernels.jit import kernel


@kernel
def transform(local, local_normal, owner, rotation, translation, world, world_normal):
    """world = R p + x and world_normal = R n for every corner, with its owner's pose."""
    for c in range(local.shape[0]):
        r = rotation[owner[c]]
        x = translation[owner[c]]
        for k in range(3):
            world[c, k] = (r[k, 0] * local[c, 0] + r[k, 1] * local[c, 1]
                           + r[k, 2] * local[c, 2] + x[k])
            world_normal[c, k] = (r[k, 0] * local_normal[c, 0] + r[k, 1] * local_normal[c, 1]
                                  + r[k, 2] * local_normal[c, 2])


@kernel
def _face_normal(world, c):
    """(b - a) x (c - a) for the triangle with corners c, c + 1, c + 2 of ``world``: its
    outward normal, of length twice its area (m^2)."""
    ax, ay, az = world[c, 0], world[c, 1], world[c, 2]
    ex, ey, ez = world[c + 1, 0] - ax, world[c + 1, 1] - ay, world[c + 1, 2] - az
    fx, fy, fz = world[c + 2, 0] - ax, world[c + 2, 1] - ay, world[c + 2, 2] - az
    return ey * fz - ez * fy, ez * fx - ex * fz, ex * fy - ey * fx


@kernel
def _dot_row(matrix, row, x, y, z):
    """matrix[row] . (x, y, z)."""
    return matrix[row, 0] * x + matrix[row, 1] * y + matrix[row, 2] * z


@kernel
def _edge(ax, ay, bx, by, px, py):
    """Twice the signed area of (a, b, p), > 0 when p lies left of a -> b (x right, y up).

    Always evaluated from the lexicographically smaller end, so the two triangles that share
    an edge get exactly opposite values and no pixel centre falls through the crack.
    """
    if ax < bx or (ax == bx and ay < by):
        return (bx - ax) * (py - ay) - (by - ay) * (px - ax)
    return -((ax - bx) * (py - by) - (ay - by) * (px - bx))


@kernel
def _fill(ax, ay, az, ad, bx, by, bz, bd, cx, cy, cz, cd, triangle, nearness, ids, diffuse):
    """Write triangle ``triangle`` into the pixels whose centres it covers (edges included)
    where it is nearer than ``nearness`` holds.

    a, b, c: screen x, y (pixels), nearness z > 0 and attribute d of the corners, either
    winding. z is interpolated linearly on screen (exact for 1/depth under perspective and for
    depth under an orthographic view); d is interpolated so that d z is linear, which is
    perspective-correct when z = 1/depth.
    """
    area = _edge(ax, ay, bx, by, cx, cy)
    if not abs(area) > 0.0:
        return
    height, width = nearness.shape
    lo_x = max(min(ax, bx, cx), -1.0)
    hi_x = min(max(ax, bx, cx), width + 1.0)
    lo_y = max(min(ay, by, cy), -1.0)
    hi_y = min(max(ay, by, cy), height + 1.0)
    j0, j1 = max(int(math.ceil(lo_x - 0.5)), 0), min(int(math.floor(hi_x - 0.5)), width - 1)
    i0, i1 = max(int(math.ceil(lo_y - 0.5)), 0), min(int(math.floor(hi_y - 0.5)), height - 1)
    inverse_area = 1.0 / area
    for i in range(i0, i1 + 1):
        py = i + 0.5
        for j in range(j0, j1 + 1):
            px = j + 0.5
            wa = _edge(bx, by, cx, cy, px, py) * inverse_area
            wb = _edge(cx, cy, ax, ay, px, py) * inverse_area
            wc = _edge(ax, ay, bx, by, px, py) * inverse_area
            if wa < 0.0 or wb < 0.0 or wc < 0.0:
                continue
            z = wa * az + wb * bz + wc * cz
            if z > nearness[i, j]:
                nearness[i, j] = z
                ids[i, j] = triangle
                diffuse[i, j] = (wa * ad * az + wb * bd * bz + wc * cd * cz) / z


@kernel
def _clip_near(corners, near, out):
    """Sutherland-Hodgman: the part of the triangle ``corners`` (3, 4) (view x, y, z in m and
    an attribute) with z >= ``near`` (m), as a convex polygon written into ``out`` (4, 4).
    Returns its vertex count: 0, 3 or 4."""
    count = 0
    for k in range(3):
        n = (k + 1) % 3
        inside, next_inside = corners[k, 2] >= near, corners[n, 2] >= near
        if inside:
            for m in range(4):
                out[count, m] = corners[k, m]
            count += 1
        if inside != next_inside:
            s = (near - corners[k, 2]) / (corners[n, 2] - corners[k, 2])
            for m in range(4):
                out[count, m] = corners[k, m] + s * (corners[n, m] - corners[k, m])
            count += 1
    return count


@kernel(allocates=True)
def rasterize(world, world_normal, first, last, eye, axes, focal, near, light,
              nearness, ids, diffuse):
    """Draw triangles ``first`` to ``last - 1`` with a perspective camera into the buffers.

    Back faces (seen from behind, by their geometric normal) are skipped; the rest are clipped
    at the plane ``near`` m in front of the eye. Each corner carries the Lambert factor
    max(0, n . light) of its shading normal; light: (3,) unit vector towards the light.
    """
    height, width = nearness.shape
    cx, cy = 0.5 * width, 0.5 * height
    corners = np.empty((3, 4))
    polygon = np.empty((4, 4))
    screen = np.empty((4, 4))
    for t in range(first, last):
        c = 3 * t
        nx, ny, nz = _face_normal(world, c)
        if _dot_row(world, c, nx, ny, nz) >= nx * eye[0] + ny * eye[1] + nz * eye[2]:
            continue  # the eye is not on the outer side of the face's plane
        for k in range(3):
            x, y, z = world[c + k, 0] - eye[0], world[c + k, 1] - eye[1], world[c + k, 2] - eye[2]
            for m in range(3):
                corners[k, m] = _dot_row(axes, m, x, y, z)
            corners[k, 3] = max(_dot_row(world_normal, c + k, light[0], light[1], light[2]), 0.0)
        count = _clip_near(corners, near, polygon)
        for k in range(count):
            inverse_depth = 1.0 / polygon[k, 2]
            screen[k, 0] = cx + focal * polygon[k, 0] * inverse_depth
            screen[k, 1] = cy - focal * polygon[k, 1] * inverse_depth
            screen[k, 2] = inverse_depth
            screen[k, 3] = polygon[k, 3]
        for k in range(1, count - 1):
            _fill(screen[0, 0], screen[0, 1], screen[0, 2], screen[0, 3],
                  screen[k, 0], screen[k, 1], screen[k, 2], screen[k, 3],
                  screen[k + 1, 0], screen[k + 1, 1], screen[k + 1, 2], screen[k + 1, 3],
                  t, nearness, ids, diffuse)


@kernel(allocates=True)
def shadow_map(world, count, light_axes, origin, texel, nearness, ids, diffuse):
    """Draw the faces of triangles 0 to ``count - 1`` that face away from the light into an
    orthographic shadow map.

    light_axes: (3, 3) rows u, v (the map's x and y) and the unit vector towards the light;
    origin: (3,) m, the map's corner in (u, v) and the light coordinate at which nearness is 0;
    texel: m per texel. Nearness is the height along the light above ``origin[2]``.
    Using only the faces turned away from the light (the far side of each closed body) keeps
    lit surfaces from shadowing themselves.
    """
    sx, sy, sz = np.empty(3), np.empty(3), np.empty(3)
    for t in range(count):
        c = 3 * t
        nx, ny, nz = _face_normal(world, c)
        if _dot_row(light_axes, 2, nx, ny, nz) > 0.0:
            continue
        for k in range(3):
            x, y, z = world[c + k, 0], world[c + k, 1], world[c + k, 2]
            sx[k] = (_dot_row(light_axes, 0, x, y, z) - origin[0]) / texel
            sy[k] = (_dot_row(light_axes, 1, x, y, z) - origin[1]) / texel
            sz[k] = _dot_row(light_axes, 2, x, y, z) - origin[2]
        _fill(sx[0], sy[0], sz[0], 0.0, sx[1], sy[1], sz[1], 0.0, sx[2], sy[2], sz[2], 0.0,
              t, nearness, ids, diffuse)


@kernel
def _lit_fraction(u, v, height, shadow):
    """Fraction in [0, 1] of a point that the light reaches. u, v: its shadow-map position,
    texels; height: its nearness to the light in the map's units (m), bias included.

    The point is hidden by a texel that holds a surface nearer the light; the four texels
    around it are weighted bilinearly, so shadow edges blend over one texel.
    """
    u, v = u - 0.5, v - 0.5  # texel (r, c) is centred on (c + 0.5, r + 0.5)
    rows, columns = shadow.shape
    ku, kv = int(math.floor(u)), int(math.floor(v))
    fu, fv = u - ku, v - kv
    lit = 0.0
    for i in range(2):
        for j in range(2):
            r, c = kv + i, ku + j
            if not (0 <= r < rows and 0 <= c < columns and shadow[r, c] > height):
                lit += (fv if i == 1 else 1.0 - fv) * (fu if j == 1 else 1.0 - fu)
    return lit


@kernel
def _byte(value):
    """A colour channel in [0, 1] (clamped) as the nearest of 0..255."""
    return np.uint8(int(min(max(value, 0.0), 1.0) * 255.0 + 0.5))


@kernel
def shade(nearness, ids, diffuse, layer_ids, layer_diffuse, color, alpha, focal,
          to_light, light_offset, texel, shadow, ambient, background, image):
    """Colour every pixel into ``image`` (H, W, 3) uint8.

    A surface pixel of triangle t is color[t] (T, 3) in [0, 1] times
    ambient + (1 - ambient) * diffuse * lit, where lit is its unshadowed fraction (1 when
    ``shadow`` is empty); an empty pixel is ``background`` (3,). Where ``layer_ids`` holds a
    translucent triangle f in front, its colour (unshadowed) is blended over with alpha[f].

    The surface point's shadow-map coordinates are light_offset (3,) + depth * to_light (3, 3)
    @ (x, y, 1), with (x, y) the pixel centre on the view plane at unit depth and depth =
    1 / nearness, m: rows 0 and 1 give texels, row 2 the nearness to the light, m. A surface
    must be one ``texel`` (m) nearer the light than the point to shadow it. The map holds only
    the far sides of bodies, which lie behind any lit surface of the same body, so this small
    bias suffices: a body shadows its own lit side only near its terminator, where the diffuse
    light is weak anyway.
    """
    height, width = ids.shape
    cx, cy = 0.5 * width, 0.5 * height
    for i in range(height):
        y = (cy - i - 0.5) / focal
        for j in range(width):
            t = ids[i, j]
            r, g, b = background[0], background[1], background[2]
            if t >= 0:
                lit = diffuse[i, j]
                if lit > 0.0 and shadow.shape[0] > 0:
                    x = (j + 0.5 - cx) / focal
                    depth = 1.0 / nearness[i, j]
                    u = light_offset[0] + depth * _dot_row(to_light, 0, x, y, 1.0)
                    v = light_offset[1] + depth * _dot_row(to_light, 1, x, y, 1.0)
                    h = light_offset[2] + depth * _dot_row(to_light, 2, x, y, 1.0)
                    lit *= _lit_fraction(u, v, h + texel, shadow)
                s = ambient + (1.0 - ambient) * lit
                r, g, b = color[t, 0] * s, color[t, 1] * s, color[t, 2] * s
            f = layer_ids[i, j]
            if f >= 0:
                s = alpha[f] * (ambient + (1.0 - ambient) * layer_diffuse[i, j])
                keep = 1.0 - alpha[f]
                r = keep * r + s * color[f, 0]
                g = keep * g + s * color[f, 1]
                b = keep * b + s * color[f, 2]
            image[i, j, 0] = _byte(r)
            image[i, j, 1] = _byte(g)
            image[i, j, 2] = _byte(b)
