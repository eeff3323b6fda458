"""The learning algorithms the baselines use, by name, on which learner, and how a saved model
names its own.

Two learners run the same algorithms behind stable-baselines3's interfaces (``learn``,
callbacks, VecEnv, ``HerReplayBuffer``, ``.zip`` models):

- ``sbx``: SBX (``sbx-rl``, the SB3 maintainers' JAX port, the ``fast`` extra): the off-policy
  update is one jitted call per vector step (all its gradient steps in a ``fori_loop``),
  faster than PyTorch's on one core once several envs share a vector step
  (``benchmarks/learner.py`` times the settings).
- ``sb3``: stable-baselines3 on PyTorch, what the ``train`` extra installs.
- ``batch``: PPO only, ``rigid_gym.agents.batch_ppo``: JAX, reading the batched env's arrays
  directly and updating in one jitted call per rollout, for hundreds of copies; it saves
  stable-baselines3 PPO zips, which load as any SB3 PPO.

``default_learner()`` is sbx where it imports, else sb3. PPO trains on batch where JAX and
optax import (SBX's PPO takes no Dict observations), else on sb3.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import zipfile
from pathlib import Path

from rigid_gym.checks import BadFile

ALGORITHMS = ("sac", "tqc", "ppo", "bc_sac", "distill", "drq")
"""What ``rigid-gym train`` trains (hyperparams.yml's ``algo``; distill and drq are the pixel
recipes, ``rigid_gym.agents.distill`` and ``rigid_gym.agents.pixel_sac``)."""
PIXEL_ALGORITHMS = ("distill", "drq")
"""The pixel recipes (``--obs-mode pixels``): their zips hold a ``distill.make_network``'s
weights and load as ``distill.DistilledPolicy``."""
LEARNERS = ("sbx", "sb3", "batch")
"""The learners, fastest first (see the module docstring)."""
SB3_PACKAGES = ("stable_baselines3", "sb3_contrib")
"""Where other algorithm classes (A2C, DDPG, ...) are looked up, by class name."""


def learner_available(name: str) -> bool:
    """Whether learner ``name`` (one of LEARNERS) can be imported here."""
    if name not in LEARNERS:
        raise ValueError(f"train: learner must be one of {LEARNERS}, got {name!r}")
    if name == "sb3":
        return importlib.util.find_spec("stable_baselines3") is not None
    if name == "batch":
        return all(importlib.util.find_spec(m) is not None for m in ("jax", "optax"))
    return all(importlib.util.find_spec(m) is not None for m in ("sbx", "jax", "flax"))


def default_learner() -> str:
    """sbx where SBX and JAX import, else sb3."""
    return "sbx" if learner_available("sbx") else "sb3"


def learner_for(algo: str, learner: str | None) -> str:
    """The learner ``algo`` trains on: ``learner`` (None: ``default_learner()``, and for ppo
    batch where it imports); ppo trains on batch or sb3 (sbx asked for: sb3), the others on
    sbx or sb3. A ValueError if the one asked for is not installed or cannot train ``algo``."""
    if learner is None and algo == "ppo" and learner_available("batch"):
        return "batch"
    learner = learner or default_learner()
    if not learner_available(learner):
        raise ValueError(f"train: learner {learner!r} is not installed (pip install -e "
                         "'.[fast]' for sbx and batch); use --learner sb3")
    if learner == "batch" and algo != "ppo":
        raise ValueError(f"train: the batch learner trains ppo only, not {algo!r}")
    return "sb3" if algo == "ppo" and learner == "sbx" else learner


def algorithm_class(name: str, learner: str = "sb3"):
    """The class for ``name`` on ``learner``: sac, tqc, ppo, or bc_sac (SAC with a
    behaviour-cloning loss on the demonstrations, ``rigid_gym.agents.bc_sac``); on sbx, SBX's
    SAC and TQC and ``bc_sac.BCSACJax`` (ppo is SB3's, see ``learner_for``); on batch,
    ``batch_ppo.BatchPPO``; distill, drq: the pixel policies' loader
    (``distill.DistilledPolicy``, PyTorch whatever the learner)."""
    if name in PIXEL_ALGORITHMS:
        from .distill import DistilledPolicy
        return DistilledPolicy
    if learner == "batch" and name == "ppo":
        from .batch_ppo import BatchPPO
        return BatchPPO
    if learner == "sbx" and name != "ppo":
        if name == "bc_sac":
            from .bc_sac import BCSACJax
            return BCSACJax
        if name in ("sac", "tqc"):
            import sbx
            return {"sac": sbx.SAC, "tqc": sbx.TQC}[name]
    if name == "bc_sac":
        from .bc_sac import BCSAC
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
    """The class for ``name``: ``sbx:<algo>`` (a model SBX saved, ``algorithm_of``), one of
    ALGORITHMS (any case, SB3's), else the class of that name (any case) in SB3_PACKAGES; a
    ValueError when there is none."""
    if name.lower().startswith("sbx:"):
        if not learner_available("sbx"):
            raise ValueError("load_model: this model was trained with SBX (JAX): pip install "
                             "-e '.[fast]'")
        return algorithm_class(name.lower()[4:], "sbx")
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
    """The algorithm of a stable-baselines3 zip (a BadFile where it is not one), from its policy class's module
    (``stable_baselines3.sac.policies`` -> ``sac``, SBX's ``sbx.sac.policies`` -> ``sbx:sac``);
    PPO and A2C share ``stable_baselines3.common.policies`` and only PPO saves a
    ``clip_range``."""
    try:
        with zipfile.ZipFile(path) as archive:
            data = json.loads(archive.read("data"))
        if data.get("algo") in PIXEL_ALGORITHMS:  # a pixel policy (distill.save_policy)
            return data["algo"]
        module = data["policy_class"]["__module__"].split(".")
        if module[0] == "sbx":
            return f"sbx:{module[1]}"
        if module[1] == "common":
            return "PPO" if "clip_range" in data else "A2C"
        return module[1]
    except (zipfile.BadZipFile, KeyError, ValueError, IndexError) as exc:
        raise BadFile(f"{path} is not a stable-baselines3 model zip whose algorithm can be "
                      f"read ({type(exc).__name__}: {exc})") from None
