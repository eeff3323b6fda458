"""SolverConfig: which phases of the step run and how.

``SolverConfig.for_scene(scene)`` derives the cheapest configuration that cannot change a
scene's result (DESIGN.md §5); every field can be overridden with ``dataclasses.replace``.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rigid_gym.scene import Scene

ROTATION_ORDERS = (1, 2, 3)


@dataclass(frozen=True)
class SolverConfig:
    """Switches and counts for :func:`rigid_gym.pipeline.step`.

    rotation_order: 1 = the exact-rotation update of the course notes with omega at the start
        of the step (first order); 2 = Buss's second-order update (omega + h/2 alpha);
        3 = Buss's third-order update. Cost grows slightly with the order.
    box_edge_segments: each box edge carries this many - 1 surface samples between its
        corners, so that edge-edge crossings are detected once they are deeper than about
        edge length / (2 box_edge_segments) (benchmarks/box_edge_samples.py).
    sweep: broad phase by sort-and-sweep (True) or brute force (False); None chooses
        sort-and-sweep from ``collision.SWEEP_MIN_BODIES`` bounded bodies.
    """

    rotation_order: int = 2
    box_edge_segments: int = 4
    sweep: bool | None = None

    def __post_init__(self):
        if self.rotation_order not in ROTATION_ORDERS:
            raise ValueError(
                f"SolverConfig.rotation_order must be one of {ROTATION_ORDERS}, "
                f"got {self.rotation_order!r}"
            )
        if (isinstance(self.box_edge_segments, bool) or not isinstance(self.box_edge_segments, int)
                or not 1 <= self.box_edge_segments <= 64):
            raise ValueError("SolverConfig.box_edge_segments must be an int in [1, 64], "
                             f"got {self.box_edge_segments!r}")
        if self.sweep not in (None, True, False):
            raise ValueError(f"SolverConfig.sweep must be None, True or False, got {self.sweep!r}")

    @classmethod
    def for_scene(cls, scene: Scene, **overrides) -> SolverConfig:
        """The default configuration for ``scene`` with what it cannot need switched off."""
        known = {f.name for f in fields(cls)}
        unknown = set(overrides) - known
        if unknown:
            raise ValueError(
                f"SolverConfig.for_scene: unknown option(s) {sorted(unknown)}; "
                f"allowed: {sorted(known)}"
            )
        return cls(**overrides)

    def phases(self) -> dict[str, bool]:
        """Which phases of the step run, by name, in step order."""
        return {"update_velocities": True, "update_positions": True}
