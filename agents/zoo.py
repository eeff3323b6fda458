"""The baselines' settings in RL Baselines3 Zoo's format, for every rigid_gym id.

    python -m rl_zoo3.train --algo sac --env rigid_gym/Push-v0 --gym-packages rigid_gym \\
        --conf-file rigid_gym.agents.zoo
    python -m rl_zoo3.enjoy --algo sac --env rigid_gym/Push-v0 --gym-packages rigid_gym \\
        -f logs --no-render

``hyperparams`` (env id -> Zoo settings) is made from ``agents/hyperparams.yml`` at import, so
the Zoo runs the numbers ``rigid-gym train`` runs: budget, n_envs, HER settings and the
algorithm's arguments, Dict observations through ``MultiInputPolicy``, ``is_success`` in the
monitor files, and the scripted demonstrations put in the replay buffer when training starts
(``Demonstrations``). ``ZOO_ALGOS`` says which ``--algo`` each id's settings are for: the
sparse ids' are off-policy (``sac``, or ``tqc``, which takes the same arguments), the dense
ids' are ``ppo``'s. The Zoo has no ``bc_sac``: Stack's entry is that baseline without its
behaviour-cloning loss (SAC + HER + the demonstrations), which learns far less than
``rigid-gym train`` (agents/hyperparams.yml says how much).
"""

from __future__ import annotations

import inspect

from stable_baselines3 import SAC
from stable_baselines3.common.callbacks import BaseCallback

from .bc_sac import BCSAC
from .train import add_demonstrations, hyperparams_table

ZOO_ALGOS = {"sac": ("sac", "tqc"), "tqc": ("tqc", "sac"), "bc_sac": ("sac", "tqc"),
             "ppo": ("ppo",)}
"""hyperparams.yml's algo -> the Zoo's ``--algo`` values its arguments suit, the first one
the one to use."""


def named_arguments(cls) -> set[str]:
    """The names of the arguments of ``cls``'s constructor (not ``*args``, ``**kwargs``)."""
    return {name for name, p in inspect.signature(cls.__init__).parameters.items()
            if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)}


BC_ONLY = tuple(sorted(named_arguments(BCSAC) - named_arguments(SAC)))
"""bc_sac's own arguments (bc_weight, ...), left out of the Zoo's settings."""


class Demonstrations(BaseCallback):
    """When training starts, put ``episodes`` episodes of the scripted policy into the replay
    buffer (``rigid_gym.agents.train.add_demonstrations``, seeded by the model's seed), as
    ``rigid-gym train`` does before it trains."""

    def __init__(self, episodes: int):
        super().__init__()
        self.episodes = episodes

    def _on_training_start(self) -> None:
        env_id = self.training_env.get_attr("spec")[0].id
        add_demonstrations(self.model, env_id, self.episodes, self.model.seed or 0)

    def _on_step(self) -> bool:
        return True


def zoo_settings(settings: dict) -> dict:
    """One id's hyperparams.yml entry as the Zoo's settings for that id."""
    entry = {"policy": "MultiInputPolicy", "n_timesteps": settings["n_timesteps"],
             "n_envs": settings.get("n_envs", 1),
             # Python text, as the Zoo's own files write it (it evaluates it)
             "monitor_kwargs": "dict(info_keywords=('is_success',))"}
    entry.update({key: value for key, value in settings.get("kwargs", {}).items()
                  if key not in BC_ONLY})
    if settings["algo"] != "ppo" and "her" in settings:
        entry["replay_buffer_class"] = "HerReplayBuffer"  # a name, as the Zoo's own files
        entry["replay_buffer_kwargs"] = dict(settings["her"])
    if settings.get("demonstrations"):
        entry["callback"] = [{f"{__name__}.Demonstrations":
                              {"episodes": settings["demonstrations"]}}]
    return entry


hyperparams = {env_id: zoo_settings(settings) for env_id, settings in hyperparams_table().items()}
"""env id -> the Zoo's settings (``--conf-file rigid_gym.agents.zoo``)."""
