"""What a recorder or a renderer needs from an env, and nothing more: the protocol that
``rigid_gym.recording.RecordRerun`` records through (it knows no env class).

An env is recordable when its ``unwrapped`` has these members (every rigid_gym task has):

    world            a rigid_gym World: the bodies to draw (their scene) and their poses; of a
                     batched World, world 0
    camera_view      (eye (3,) m, target (3,) m, vertical field of view (deg)): the camera of
                     the env's own rgb_array frames, which the recording's 3D view copies
    scalar_series    the plots, a tuple of Series, in the order of ``scalars``' values
    markers()        the current episode's goal markers (Marker each): what frames and
                     recordings draw beside the bodies
    scalars(action, reward, info)   the plotted values of one env step, one float per label
                     of ``scalar_series``, in order

Shapes are ``rigid_gym.shapes`` shapes; colours are (r, g, b) in [0, 1].
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    from rigid_gym.world import World


@dataclass(frozen=True)
class Marker:
    """Geometry drawn that is not a body (a goal): ``shape`` (a solid shape) placed by its
    shape frame at ``position`` (3,) m with ``orientation`` (4,) unit quaternion (w, x, y, z),
    in ``color`` (r, g, b) with opacity ``alpha`` in (0, 1]; ``face_colors``: None, or six
    (r, g, b) for its faces towards +x, -x, +y, -y, +z, -z (an orientation to be seen; the
    Renderer draws them, recordings the one ``color``)."""

    shape: object
    position: tuple
    color: tuple
    alpha: float = 1.0
    orientation: tuple = (1.0, 0.0, 0.0, 0.0)
    face_colors: tuple | None = None


@dataclass(frozen=True)
class Series:
    """One plot of scalars over the steps, at entity path ``/<name>``: one line per label,
    each drawn in its colour of ``colors`` ((r, g, b) in [0, 1], one per label)."""

    name: str
    labels: tuple[str, ...]
    colors: tuple[tuple[float, float, float], ...]

    def __post_init__(self):
        if len(self.labels) != len(self.colors):
            raise ValueError(f"Series {self.name!r}: {len(self.labels)} labels but "
                             f"{len(self.colors)} colours; give one colour per label")

    def rgb255(self) -> np.ndarray:
        """The colours as (lines, 3) uint8."""
        return np.round(255 * np.asarray(self.colors, dtype=np.float64)).astype(np.uint8)


@runtime_checkable
class Recordable(Protocol):
    """The members an env has for ``RecordRerun`` to record it (see the module docstring)."""

    world: World
    camera_view: tuple
    scalar_series: tuple

    def markers(self) -> list[Marker]:
        ...

    def scalars(self, action, reward, info) -> list[float]:
        ...
