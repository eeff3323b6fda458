"""The learning algorithms the baselines use, by name, and how a saved model names its own."""

from __future__ import annotations

import importlib
import json
import zipfile
from pathlib import Path

ALGORITHMS = ("sac", "tqc", "ppo", "bc_sac")
"""What ``rigid-gym train`` trains (hyperparams.yml's ``algo``)."""
SB3_PACKAGES = ("stable_baselines3", "sb3_contrib")
"""Where other algorithm classes (A2C, DDPG, ...) are looked up, by class name."""


def algorithm_class(name: str):
    """The SB3 class for ``name`` (sac, tqc, ppo, or bc_sac: SAC with a behaviour-cloning loss
    on the demonstrations, ``rigid_gym.agents.bc_sac``)."""
    if name == "bc_sac":
        from rigid_gym.agents.bc_sac import BCSAC
        return BCSAC
    if name == "sac":
        from stable_baselines3 import SAC
        return SAC
    if name == "ppo":
        from stable_baselines3 import PPO
        return PPO
    if name == "tqc":
        try:
            from sb3_contrib import TQC
        except ImportError as exc:
            raise ValueError("train: algo 'tqc' needs sb3-contrib (pip install -e '.[train]')"
                             ) from exc
        return TQC
    raise ValueError(f"train: algo must be one of {ALGORITHMS}, got {name!r}")


def find_algorithm(name: str):
    """The class for ``name``: one of ALGORITHMS (any case), else the class of that name
    (any case) in SB3_PACKAGES; a ValueError when there is none."""
    if name.lower() in ALGORITHMS:
        return algorithm_class(name.lower())
    for package in SB3_PACKAGES:
        try:
            module = importlib.import_module(package)
        except ImportError:
            continue
        found = [attr for attr in dir(module) if attr.lower() == name.lower()]
        if found:
            return getattr(module, found[0])
    raise ValueError(f"load_model: no algorithm {name!r} in {' or '.join(SB3_PACKAGES)} (pip "
                     "install stable-baselines3 sb3-contrib); pass a class name such as SAC")


def algorithm_of(path: str | Path) -> str:
    """The algorithm of a stable-baselines3 zip, from its policy class's module
    (``stable_baselines3.sac.policies`` -> ``sac``); PPO and A2C share
    ``stable_baselines3.common.policies`` and only PPO saves a ``clip_range``."""
    try:
        with zipfile.ZipFile(path) as archive:
            data = json.loads(archive.read("data"))
        module = data["policy_class"]["__module__"].split(".")
        if module[1] == "common":
            return "PPO" if "clip_range" in data else "A2C"
        return module[1]
    except (zipfile.BadZipFile, KeyError, ValueError, IndexError) as exc:
        raise ValueError(f"load_model: {path} is not a stable-baselines3 model zip whose "
                         f"algorithm can be read ({exc}); pass the algorithm") from None
