"""How deep must a box edge cross another edge before the sampled method sees it?

Box-box pairs are answered in closed form (boxbox.py), so the sampled method is measured on a
Box against a ``box_mesh`` of the same size (half extents 0.5 m, edge L = 1 m): the Box's
samples (corners plus ``box_edge_segments - 1`` points inside each edge) go into the mesh's
grid phi, the mesh's samples (vertices plus edge points at most one grid cell h apart) into
the Box's exact phi. The Box is turned 45 degrees about x (its lowest edge runs along x), the
mesh 45 degrees about y (its highest edge runs along y), so the two edges cross at right
angles and the Box's edge dips ``d`` below the mesh's ridge. Against the mesh's 90-degree
ridge the Box's edge is inside over a length 2 d around the crossing, so a sample is inside
once the crossing lies within d of one: with samples L / k apart, that is guaranteed for
d >= L / (2k), and happens by luck for smaller d.

For each k in 1, 2, 4, 8, 16 (``SolverConfig(box_edge_segments=k)``) and each of 48 crossing
places (random positions along both edges), the depth d is lowered through a log grid from
60% (beyond any realistic overlap, so that k = 1, 2, 4 show their rule too) to 0.1% of L in
steps of 15% (each value is the depth to within that step); the table gives the smallest d at
which the crossing is still seen at every place (the guaranteed depth) and at half of them
(the median), counting

  box samples   only contacts at the Box's samples (the part box_edge_segments controls);
  all           every contact (the mesh's own edge samples, h apart, catch what the Box's
                samples miss once d >~ h / 2, whatever k).

A second table does the same with meshes on both sides (two box_meshes; k plays no part):
the depth then follows the grid spacing, d ~ h / 2, for Mesh.sdf_resolution = 16, 32, 64.

Rule (measured below): the Box's samples alone see every crossing deeper than L / (2k)
(to the depth step; the mesh's trilinear phi is slightly too large near its ridge) and half
of them from about L / (4k) (k >= 2); but against a mesh the mesh's own edge samples
already see every crossing deeper than about h / 2, so box_edge_segments only matters where
L / (2k) < h / 2, i.e. for boxes whose edges are shorter than k of the mesh's grid cells
(L < k h): small boxes against coarse meshes.

    python benchmarks/box_edge_samples.py
"""

import numpy as np

import rigid_gym as rg
from rigid_gym.meshes import box_mesh

HALF = 0.5
EDGE = 2 * HALF
SEGMENTS = (1, 2, 4, 8, 16)
DEPTHS = EDGE * np.geomspace(0.6, 0.001, 47)  # 60% .. 0.1% of the edge, deepest first
PLACES = 48


def quat(axis, angle):
    a = np.asarray(axis, dtype=float)
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * a / np.linalg.norm(a)])


def crossing_world(upper, lower, segments: int) -> rg.World:
    """``upper`` (dynamic, lowest edge along x) over ``lower`` (static, ridge along y)."""
    scene = rg.Scene(gravity=(0, 0, 0))
    scene.add_body(lower, static=True, orientation=quat((0, 1, 0), np.pi / 4))
    scene.add_body(upper, mass=1.0, position=(0, 0, 10.0), orientation=quat((1, 0, 0), np.pi / 4))
    return rg.World(scene, config=rg.SolverConfig(box_edge_segments=segments))


def seen(world: rg.World, along_upper: float, along_lower: float, depth: float,
         box_samples_only: bool) -> bool:
    """Whether contacts are reported with the crossing ``along_upper`` (m from the middle of the
    upper body's edge) and ``along_lower`` (along the ridge) and ``depth`` deep."""
    ridge = HALF * np.sqrt(2.0)
    world.set_pose(1, position=(-along_upper, along_lower, 2 * ridge - depth))
    c = world.contacts()
    if not box_samples_only:
        return len(c.depth) > 0
    # the Box's edge samples lie on its lowest edge {y = along_lower, z = ridge - depth}
    on_edge = ((np.abs(c.point[:, 1] - along_lower) < 1e-9)
               & (np.abs(c.point[:, 2] - (ridge - depth)) < 1e-9))
    return bool(np.any(on_edge))


def smallest_seen(world, places, box_samples_only: bool) -> np.ndarray:
    """Per crossing place, the smallest depth of DEPTHS down to which it is still seen."""
    out = np.empty(len(places))
    for p, (u, v) in enumerate(places):
        smallest = np.inf
        for d in DEPTHS:
            if not seen(world, u, v, d, box_samples_only):
                break
            smallest = d
        out[p] = smallest
    return out


def percent(x: float) -> str:
    return "not seen" if not np.isfinite(x) else f"{100 * x / EDGE:.2f}%"


def main() -> None:
    rng = np.random.default_rng(0)
    places = rng.uniform(-0.45 * EDGE, 0.45 * EDGE, (PLACES, 2))
    mesh = box_mesh((HALF, HALF, HALF))
    h = EDGE / mesh.sdf_resolution

    print("## Box against a box_mesh of the same size (edge L = 1 m, mesh grid h = "
          f"{1000 * h:.1f} mm)\n")
    print("Smallest crossing depth seen, as % of the edge: guaranteed (all 48 places) / median.\n")
    print("| k | L / (2k) | box samples: guaranteed | box samples: median | all: guaranteed "
          "| all: median |")
    print("|---|---|---|---|---|---|")
    for k in SEGMENTS:
        world = crossing_world(rg.Box((HALF, HALF, HALF)), mesh, k)
        box_only = smallest_seen(world, places, True)
        every = smallest_seen(world, places, False)
        print(f"| {k} | {percent(EDGE / (2 * k))} | {percent(box_only.max())} "
              f"| {percent(np.median(box_only))} | {percent(every.max())} "
              f"| {percent(np.median(every))} |")

    print("\n## Meshes on both sides (two box_meshes; box_edge_segments plays no part)\n")
    print("| sdf_resolution | h | h / 2 | guaranteed | median |")
    print("|---|---|---|---|---|")
    for resolution in (16, 32, 64):
        m = box_mesh((HALF, HALF, HALF))
        m = rg.Mesh(m.vertices, m.triangles, sdf_resolution=resolution)
        world = crossing_world(m, rg.Mesh(m.vertices, m.triangles, sdf_resolution=resolution), 4)
        every = smallest_seen(world, places, False)
        print(f"| {resolution} | {percent(EDGE / resolution)} | {percent(EDGE / resolution / 2)} "
              f"| {percent(every.max())} | {percent(np.median(every))} |")


if __name__ == "__main__":
    main()
