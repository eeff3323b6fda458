"""stable-baselines3 on a natively batched env: ``SB3VecEnv`` wraps a Gymnasium vector env.

    envs = SB3VecEnv(gym.make_vec("rigid_gym/Push-v0", num_envs=16))
    model = SAC("MultiInputPolicy", envs, replay_buffer_class=HerReplayBuffer, ...)

SB3 expects same-step autoreset with the episode's last observation in
``info["terminal_observation"]`` and ``info["TimeLimit.truncated"]``: the rigid_gym vector envs
reset the same way (``AutoresetMode.SAME_STEP``), and this adapter only reshapes their results
into SB3's per-env info dicts. HER's ``env_method("compute_reward", ...)`` calls the task's
vectorised ``compute_reward``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv as GymVectorEnv
from stable_baselines3.common.vec_env import VecEnv


class SB3VecEnv(VecEnv):
    """SB3's VecEnv over a Gymnasium vector env whose autoreset mode is SAME_STEP."""

    def __init__(self, venv: GymVectorEnv):
        mode = venv.metadata.get("autoreset_mode")
        if mode != AutoresetMode.SAME_STEP:
            raise ValueError(f"SB3VecEnv: the vector env must autoreset in the same step "
                             f"(AutoresetMode.SAME_STEP), got {mode!r}")
        self.venv = venv
        super().__init__(venv.num_envs, venv.single_observation_space,
                         venv.single_action_space)
        self._actions: np.ndarray | None = None

    def reset(self):
        seeds = self._seeds if any(s is not None for s in self._seeds) else None
        observation, infos = self.venv.reset(seed=seeds)
        self.reset_infos = self._split(infos)
        self._reset_seeds()
        self._reset_options()
        return observation

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        observation, rewards, terminated, truncated, infos = self.venv.step(self._actions)
        per_env = self._split(infos)
        dones = terminated | truncated
        if dones.any():  # the ended episodes' last infos, as SB3 expects
            final = self._split(infos["final_info"])
            for i in np.flatnonzero(dones):
                per_env[i] = {**final[i], "terminal_observation": infos["final_obs"][i]}
        for i, info in enumerate(per_env):
            info["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return observation, rewards.astype(np.float32), dones, per_env

    def close(self) -> None:
        self.venv.close()

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        return [getattr(self.venv.envs[i], attr_name) for i in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        for i in self._get_indices(indices):
            setattr(self.venv.envs[i], attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list[Any]:
        return [getattr(self.venv.envs[i], method_name)(*method_args, **method_kwargs)
                for i in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def _split(self, infos: dict) -> list[dict]:
        """Gymnasium's batched info dict (arrays with "_key" masks) -> one dict per env."""
        per_env = [{} for _ in range(self.num_envs)]
        for key, values in infos.items():
            if key.startswith("_") or key in ("final_obs", "final_info"):
                continue
            mask = infos.get(f"_{key}", np.ones(self.num_envs, dtype=bool))
            for i in np.flatnonzero(mask):
                per_env[i][key] = values[i]
        return per_env
