"""Saved states by id: the store behind ``save_state`` / ``restore_state`` / ``remove_state``
of a World and of every env, the interface of PyBullet's ``saveState`` and panda-gym's
``sim.save_state``.

    state_id = env.unwrapped.save_state()   # an int
    ...                                     # step, reset, anything
    env.unwrapped.restore_state(state_id)   # back, bit for bit; the state stays saved
    env.unwrapped.remove_state(state_id)    # free it
"""

from __future__ import annotations

from typing import Generic, TypeVar

import numpy as np

T = TypeVar("T")


class SavedStates(Generic[T]):
    """Saved states of one object by id (0, 1, 2, ... in the order they are saved, never
    reused). ``owner``: the class name that errors start with."""

    def __init__(self, owner: str):
        self.owner = owner
        self.states: dict[int, T] = {}
        self.next_id = 0

    def save(self, state: T) -> int:
        """Keep ``state``; its new id."""
        state_id = self.next_id
        self.next_id += 1
        self.states[state_id] = state
        return state_id

    def get(self, state_id, method: str) -> T:
        """The state saved as ``state_id``, or a ValueError that names ``method``."""
        return self.states[self.checked(state_id, method)]

    def remove(self, state_id, method: str = "remove_state") -> None:
        del self.states[self.checked(state_id, method)]

    def checked(self, state_id, method: str) -> int:
        if isinstance(state_id, bool) or not isinstance(state_id, (int, np.integer)) \
                or int(state_id) not in self.states:
            raise ValueError(f"{self.owner}.{method}: no saved state {state_id!r}; saved: "
                             f"{sorted(self.states)} (ids from {self.owner}.save_state)")
        return int(state_id)
