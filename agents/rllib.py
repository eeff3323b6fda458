"""Ray RLlib on the rigid_gym tasks: importing this module registers every id with RLlib.

    from ray.rllib.algorithms.ppo import PPOConfig
    import rigid_gym.agents.rllib             # registers rigid_gym/Push-v0 ... with RLlib

    config = PPOConfig().environment("rigid_gym/PushDense-v0").env_runners(num_env_runners=2)
    algo = config.build_algo()
    result = algo.train()                     # result["env_runners"]["episode_return_mean"]

RLlib's env runners are other processes, often on other machines, that never import
rigid_gym, so a plain Gymnasium id is unknown there; an id registered with RLlib
(``ray.tune.register_env``) reaches every runner through the cluster, and its creator,
``make_env``, imports rigid_gym where it runs. RLlib's default encoders take flat (Box)
observations, not the tasks' Dict, so ``make_env`` flattens them with Gymnasium's
``FlattenObservation``: one float32 vector, the keys in sorted order (achieved_goal,
desired_goal, observation). ``config.environment(id, env_config={...})`` passes the env's
arguments (``reward_type``, ``randomize``, ...).
"""

from __future__ import annotations

import functools

import gymnasium as gym
from ray.tune.registry import register_env

from ..envs import ENV_IDS


def make_env(env_id: str, env_config: dict) -> gym.Env:
    """``gym.make(env_id, **env_config)`` with its Dict observation flattened to one float32
    vector (``FlattenObservation``: shape (goal + goal + observation,)). ``env_config``: the
    task's arguments (RLlib passes an ``EnvContext``, a dict)."""
    import rigid_gym  # noqa: F401  (registers the ids in the process the env is made in)

    return gym.wrappers.FlattenObservation(gym.make(env_id, **env_config))


def register() -> None:
    """Register every rigid_gym id with RLlib (``ray.tune.register_env``), each made by
    ``make_env``: done on import."""
    for env_id in ENV_IDS:
        register_env(env_id, functools.partial(make_env, env_id))


register()
