"""The layout of a task's ``observation`` vector: named fields in order, each a quantity of one
body with its size and unit, and the World state it reads.

A task owns its layout (``Task.observation_layout``, made by ``observation_layout`` from the
task's cubes, grip and effector). Everything that reads or writes the vector goes through it: the env's
index into the World's state (``gather_index``, for ``gather_observations``), the observation
space's size, the achieved goal's entries, the scripted policies and each env's documentation
table (``Layout.table``).

    layout = Stack().observation_layout
    layout.slice("cube1.position")         # slice(25, 28)
    fields = layout.split(obs["observation"])
    fields["holding"]                      # (1,): 1 while the pad holds a cube
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

QUANTITIES = {
    "position": (3, "m", "centre position"),
    "velocity": (3, "m/s", "velocity"),
    "offset": (3, "m", "position minus the pad's (the hand's, with effector=\"gripper\")"),
    "orientation": (6, "", ("rotation matrix, first two columns (continuous, unlike a "
                            "quaternion's sign or Euler angles)")),
    "angular_velocity": (3, "rad/s", "angular velocity"),
    "holding": (1, "", ("1 while the effector holds a cube (the pad's suction, or a cube "
                        "between the fingers with both pads on it), else 0")),
    "width": (1, "m", "opening between the pads"),
}
"""quantity -> (size, unit, what it is); positions and velocities in the world frame, of the
body's centre (a cube's centre is its centre of mass)."""
DERIVED = ("holding", "width")
"""The quantities that are no entry of the World's state: the env writes them
(``envs/core.py``)."""

PAD = "pad"
"""The body name of the suction gripper's pad in a layout."""
HAND = "hand"
"""The body name of the parallel gripper's hand in a layout (``effector="gripper"``)."""
FINGERS = "fingers"
"""The body name of the parallel gripper's fingers in a layout."""
EFFECTOR_BODIES = {"pad": PAD, "gripper": HAND}
"""Effector name -> the body name of its driven body in a layout."""


class Field(NamedTuple):
    """One named part of the observation vector: ``quantity`` (a key of QUANTITIES) of
    ``body`` ("pad", "cube0", ...; "" for the grip flag), ``size`` entries in ``unit``."""

    name: str
    body: str
    quantity: str
    size: int
    unit: str

    @property
    def content(self) -> str:
        """What the field holds, in words (the documentation's)."""
        what = QUANTITIES[self.quantity][2]
        subject = {"": "", PAD: "the pad's ", HAND: "the hand's ",
                   FINGERS: "the fingers' "}.get(self.body,
                                                 f"cube {self.body.removeprefix('cube')}'s ")
        return subject + what + (f", {self.unit}" if self.unit else "")


def field(body: str, quantity: str) -> Field:
    """The field of ``quantity`` of ``body``, named ``<body>.<quantity>`` (or the quantity
    alone for a field of no body)."""
    size, unit, _ = QUANTITIES[quantity]
    return Field(f"{body}.{quantity}" if body else quantity, body, quantity, size, unit)


class Layout:
    """The fields of an observation vector, in order; a field's entries follow from the sizes
    of those before it.

    size: the vector's length. slice(name): a field's entries. split(vector): every field of
    ``vector`` (..., size) by name, views (..., field size). effector: the body name of the
    first field, the driven body (``PAD`` or ``HAND``), whose position offsets subtract.
    """

    def __init__(self, fields: tuple[Field, ...]):
        names = [f.name for f in fields]
        if len(set(names)) != len(names):
            raise ValueError(f"Layout: field names must be distinct, got {names}")
        self.fields = tuple(fields)
        ends = np.cumsum([f.size for f in self.fields]).tolist()
        self.slices = {f.name: slice(end - f.size, end) for f, end in zip(self.fields, ends)}
        self.size = ends[-1] if ends else 0
        self.effector = self.fields[0].body if self.fields else PAD

    def slice(self, name: str) -> slice:
        """The entries of field ``name``."""
        if name not in self.slices:
            raise ValueError(f"Layout.slice: no field {name!r}; the fields are "
                             f"{', '.join(self.slices)}")
        return self.slices[name]

    def entries(self, names) -> np.ndarray:
        """The (m,) int64 entries of the fields ``names``, in that order."""
        return np.array([i for name in names for i in range(self.size)[self.slice(name)]],
                        dtype=np.int64)

    def split(self, vector: np.ndarray) -> dict[str, np.ndarray]:
        """Every field of ``vector`` (..., size) by name: views (..., field size)."""
        if np.shape(vector)[-1:] != (self.size,):
            raise ValueError(f"Layout.split: expected a vector (..., {self.size}), got shape "
                             f"{np.shape(vector)}")
        return {name: vector[..., s] for name, s in self.slices.items()}

    def table(self) -> str:
        """The fields as a Markdown table: entries, name, content and unit."""
        rows = [f"| {s.start}:{s.stop} | {f.name} | {f.content} |"
                for f, s in zip(self.fields, self.slices.values())]
        return "\n".join(["| entries | field | content |", "|---|---|---|", *rows])


def observation_layout(num_cubes: int, has_grip: bool, effector: str = "pad") -> Layout:
    """The layout of a task with ``num_cubes`` cubes, with or without a grip, driven by
    ``effector`` ("pad" or "gripper"): the pad's (or the hand's) position and velocity,
    whether it holds a cube (tasks with a grip), the fingers' opening (the gripper's, as
    panda-gym observes it), then per cube its position, its position minus the pad's (the
    hand's), orientation, velocity and angular velocity."""
    body = EFFECTOR_BODIES[effector]
    pad = [field(body, "position"), field(body, "velocity")] + (
        [field("", "holding")] if has_grip else []) + (
        [field(FINGERS, "width")] if effector == "gripper" else [])
    cubes = [field(f"cube{k}", quantity) for k in range(num_cubes)
             for quantity in ("position", "offset", "orientation", "velocity",
                              "angular_velocity")]
    return Layout(tuple(pad + cubes))


def gather_index(layout: Layout, num_bodies: int,
                 bodies: dict[str, int]) -> tuple[np.ndarray, np.ndarray]:
    """Where ``gather_observations`` (src/envs/observation.h) finds each entry of ``layout`` in a
    world's state laid side by side: positions (num_bodies x 3), velocities (x 3), rotations
    (x 9, row-major), angular velocities (x 3). ``bodies`` maps a layout's body names to body
    indices (the layout's ``effector`` among them). Returns the (size,) int64 index and the
    (size,) entries subtracted (-1: none; an offset subtracts the effector's position). The
    DERIVED quantities (the holding flag, the fingers' opening) are no state entries: their
    places read entry 0 and the env writes them over it."""
    n = num_bodies

    def entries(body: int, quantity: str) -> list[int]:
        if quantity in ("position", "offset"):
            return [3 * body + i for i in range(3)]
        if quantity == "velocity":
            return [3 * n + 3 * body + i for i in range(3)]
        if quantity == "orientation":  # column by column
            return [6 * n + 9 * body + 3 * row + column
                    for column in range(QUANTITIES["orientation"][0] // 3) for row in range(3)]
        if quantity == "angular_velocity":
            return [15 * n + 3 * body + i for i in range(3)]
        raise ValueError(f"gather_index: {quantity!r} is no state quantity")

    index: list[int] = []
    minus: list[int] = []
    for f in layout.fields:
        if f.quantity in DERIVED:
            index += [0] * f.size
            minus += [-1] * f.size
            continue
        index += entries(bodies[f.body], f.quantity)
        minus += entries(bodies[layout.effector], "position") if f.quantity == "offset" \
            else [-1] * f.size
    return np.array(index, dtype=np.int64), np.array(minus, dtype=np.int64)
