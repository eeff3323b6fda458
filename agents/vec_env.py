"""stable-baselines3 on a natively batched env: ``SB3VecEnv`` wraps a Gymnasium vector env.

    envs = SB3VecEnv(gym.make_vec("rigid_gym/Push-v0", num_envs=16))
    model = SAC("MultiInputPolicy", envs, replay_buffer_class=HerReplayBuffer, ...)

SB3 expects same-step autoreset with the episode's last observation in
``info["terminal_observation"]`` and ``info["TimeLimit.truncated"]``: the rigid_gym vector envs
reset the same way (``AutoresetMode.SAME_STEP``), and this adapter only reshapes their results
into SB3's per-env info dicts. HER's ``env_method("compute_reward", ...)`` calls the task's
vectorised ``compute_reward``. The copies of a rigid_gym vector env are one batch, not env
objects: ``get_attr``, ``set_attr`` and ``env_method`` reach the vector env itself (the same
for every index), whose ``compute_reward`` takes any batch of goals.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector import VectorEnv as GymVectorEnv
from stable_baselines3.common.vec_env import VecEnv


class SB3VecEnv(VecEnv):
    """SB3's VecEnv over a Gymnasium vector env whose autoreset mode is SAME_STEP."""

    def __init__(self, venv: GymVectorEnv):
        mode = venv.metadata.get("autoreset_mode")
        if mode != AutoresetMode.SAME_STEP:
            raise ValueError(f"SB3VecEnv: the vector env must autoreset in the same step "
                             f"(AutoresetMode.SAME_STEP), got {mode!r}")
        self.venv = venv
        self.next_seeds: list | None = None
        """The seeds of the next reset (``seed``), one per env, or None."""
        super().__init__(venv.num_envs, venv.single_observation_space,
                         venv.single_action_space)
        self.actions: np.ndarray | None = None

    def seed(self, seed: int | None = None) -> list:
        """As SB3's: env i gets ``seed + i`` (a random seed when None) at the next reset."""
        self.next_seeds = list(super().seed(seed))
        return self.next_seeds

    def reset(self):
        # Gymnasium's vector envs take one seed per env, though VectorEnv.reset's annotation
        # names only an int
        observation, infos = self.venv.reset(seed=self.next_seeds)  # type: ignore[arg-type]
        self.reset_infos = self.split(infos)
        self.next_seeds = None
        return observation

    def step_async(self, actions: np.ndarray) -> None:
        self.actions = actions

    def step_wait(self):
        observation, rewards, terminated, truncated, infos = self.venv.step(self.actions)
        per_env = self.split(infos)
        dones = terminated | truncated
        if dones.any():  # the ended episodes' last infos, as SB3 expects
            final = self.split(infos["final_info"])
            for ended in np.flatnonzero(dones):
                per_env[ended] = {**final[ended],
                                  "terminal_observation": infos["final_obs"][ended]}
        for i, info in enumerate(per_env):
            info["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return observation, rewards.astype(np.float32), dones, per_env

    def close(self) -> None:
        self.venv.close()

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        return [getattr(self.venv.unwrapped, attr_name) for _ in self.indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        setattr(self.venv.unwrapped, attr_name, value)  # one batch: every index at once

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list[Any]:
        method = getattr(self.venv.unwrapped, method_name)
        return [method(*method_args, **method_kwargs) for _ in self.indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self.indices(indices)]

    def indices(self, indices) -> list[int]:
        """SB3's ``indices`` (None: every env, an int, or a sequence) as a list."""
        if indices is None:
            return list(range(self.num_envs))
        return [indices] if isinstance(indices, int) else list(indices)

    def split(self, infos: dict) -> list[dict]:
        """Gymnasium's batched info dict (arrays with "_key" masks) -> one dict per env."""
        per_env: list[dict] = [{} for _ in range(self.num_envs)]
        for key, values in infos.items():
            if key.startswith("_") or key in ("final_obs", "final_info"):
                continue
            mask = infos.get(f"_{key}", np.ones(self.num_envs, dtype=bool))
            for i in np.flatnonzero(mask):
                per_env[i][key] = values[i]
        return per_env
