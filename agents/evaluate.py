"""Evaluate a trained baseline: success rate and returns over seeded episodes.

    from .evaluate import evaluate
    evaluate("runs/Push-sac-seed0/model.zip", episodes=100)

    rigid-gym evaluate runs/Push-sac-seed0/model.zip --episodes 100
    rigid-gym evaluate agents/models/stack_bcsac_seed0.zip --episodes 100
    python -m rigid_gym.agents.evaluate      # re-evaluate the committed models, write their figures
    python -m rigid_gym.agents.evaluate --commit runs/Stack-bc_sac-seed0 stack_bcsac_seed0

The env id and algorithm come from the model's settings file, or are given: ``run.json`` in
the folder of a run's ``model.zip`` (``rigid-gym train`` writes it), or ``<name>.json``
beside ``<name>.zip`` (the committed models in agents/models/).
"""

from __future__ import annotations

import json
import shutil
import zipfile
from pathlib import Path

import gymnasium as gym
import numpy as np

import rigid_gym  # noqa: F401  (registers the env ids)
from rigid_gym.checks import BadFile

from .algorithms import PIXEL_ALGORITHMS, algorithm_of, find_algorithm
from .progress import bar

EVAL_SEED = 1_000_000
"""Evaluation episodes use seeds EVAL_SEED, EVAL_SEED + 1, ...; training uses small seeds."""
VALIDATION_SEED = 3_000_000
"""Episodes that choose among a run's checkpoints (``train.finish``) use seeds from here: apart
from training's, the demonstrations' (2,000,000 on) and the evaluation's."""
OBSERVATION_OPTIONS = ("obs_mode", "width", "height", "camera", "goal_marker", "effector")
"""The env arguments that shape what a policy observes or what its actions do: a pixel
model's env, or a gripper model's (``effector``), is made with its settings' values of these
(``observation_kwargs``)."""
MODELS = Path(__file__).with_name("models")
"""The committed models: NAME.zip, with NAME.json (settings and ``evaluation``) beside each."""


def success_rate(model, env: gym.Env, episodes: int, seed: int = EVAL_SEED,
                 deterministic: bool = True, progress: bool = False) -> dict:
    """Run ``model`` for ``episodes`` episodes of ``env`` on seeds ``seed``, ``seed + 1``, ...
    Success is ``info["is_success"]`` at an episode's end. Returns episodes, success_rate,
    mean_return and std_return. ``progress``: draw a bar of the episodes (with the success
    rate so far) on standard error."""
    successes, returns = [], []
    shown = bar(episodes, f"evaluating on {env.spec.id if env.spec else 'the env'}", progress)
    for k in range(episodes):
        obs, info = env.reset(seed=seed + k)
        total, done = 0.0, False
        while not done:
            action, _ = model.predict(obs, deterministic=deterministic)
            obs, reward, terminated, truncated, info = env.step(action)
            total += float(reward)
            done = terminated or truncated
        successes.append(float(info["is_success"]))
        returns.append(total)
        shown.update(1)
        shown.set_postfix_str(f"success {np.mean(successes):.0%}")
    shown.close()
    return {"episodes": episodes, "success_rate": float(np.mean(successes)),
            "mean_return": float(np.mean(returns)), "std_return": float(np.std(returns))}


def load_model(path: str | Path, env: gym.Env, algo: str | None = None):
    """Load a stable-baselines3 model zip for ``env`` (HER models need their env to load).
    ``algo``: sac, tqc, ppo, bc_sac or an SB3 class name (A2C, ...), default read from the
    zip (:func:`algorithm_of`); a zip that SBX saved loads into SBX's class whatever
    ``algo`` says."""
    if not Path(path).is_file():
        raise BadFile(f"model file {path} not found")
    try:
        found = algorithm_of(path)
    except BadFile:
        if algo is None:
            raise
        found = None
    if found is not None and found.startswith("sbx:"):  # SBX's zips load only into SBX's classes
        algo = found
    name = algo or found
    assert name is not None  # found is None only where algo was given
    cls = find_algorithm(name)
    try:
        return cls.load(path, env=env, device="cpu")
    except zipfile.BadZipFile as exc:
        raise BadFile(f"{path} is not a model zip ({exc})") from None
    except ValueError as exc:  # spaces that differ from the env's
        name = env.spec.id if env.spec is not None else type(env.unwrapped).__name__
        raise ValueError(f"load_model: {path} does not fit {name}: {exc}") from None


def run_metadata(path: str | Path) -> dict:
    """The settings of the model at ``path``: ``run.json`` in its folder (a run of
    ``rigid-gym train``), else ``<name>.json`` beside ``<name>.zip`` (agents/models/), else
    {}."""
    path = Path(path)
    for meta in (path.with_name("run.json"), path.with_suffix(".json")):
        if meta.is_file():
            return json.loads(meta.read_text())
    return {}


def observation_kwargs(meta: dict) -> dict:
    """The OBSERVATION_OPTIONS of a model's settings (``run_metadata``) ``env_kwargs``: what
    its env must be made with for the model to see what it was trained on ({} for a state
    model)."""
    return {k: v for k, v in (meta.get("env_kwargs") or {}).items() if k in OBSERVATION_OPTIONS}


def evaluate(model_path: str | Path, env_id: str | None = None, episodes: int = 100,
             seed: int = EVAL_SEED, algo: str | None = None, deterministic: bool = True,
             progress: bool = False) -> dict:
    """Success rate and returns of a saved model over ``episodes`` seeded episodes; the env
    id and the algorithm default to the model's settings file (``run_metadata``).
    ``progress``: draw a bar of the episodes on standard error."""
    if not Path(model_path).is_file():
        raise BadFile(f"model file {model_path} not found")
    meta = run_metadata(model_path)
    env_id = env_id or meta.get("env_id")
    if env_id is None:
        raise ValueError(f"evaluate: no settings beside {model_path} (run.json in its folder, "
                         f"or {Path(model_path).with_suffix('.json').name}); pass the env id")
    env = gym.make(env_id, **observation_kwargs(meta))
    model = load_model(model_path, env, algo or meta.get("algo"))
    result = success_rate(model, env, episodes, seed, deterministic, progress)
    return {"env_id": env_id, **result}


def record_evaluation(model_path: str | Path, episodes: int = 100) -> dict:
    """Evaluate a committed model (``<name>.zip`` with ``<name>.json``) over ``episodes``
    episodes from EVAL_SEED and write the figures into its json as ``evaluation``
    ({"episodes", "seed", "success_rate", "mean_return"}); returns them."""
    meta_path = Path(model_path).with_suffix(".json")
    meta = json.loads(meta_path.read_text())
    result = evaluate(model_path, episodes=episodes)
    meta["evaluation"] = {"episodes": episodes, "seed": EVAL_SEED,
                          "success_rate": result["success_rate"],
                          "mean_return": round(result["mean_return"], 3)}
    meta_path.write_text(json.dumps(meta, indent=2) + "\n")
    return meta["evaluation"]


def commit_model(run: str | Path, name: str, episodes: int = 100) -> dict:
    """Put a finished run's policy into agents/models as ``name``.zip with ``name``.json: its
    ``selected_model.zip`` (``train.finish``'s choice, else ``model.zip``) saved without what
    only training needs (the optimizers' state, and SBX's module objects, which its loading
    rebuilds from the policy: a BC-SAC model goes from 3.8 to 0.8 MB, acting the same), its
    run.json with the command that made it, then ``record_evaluation`` over ``episodes``
    episodes. Returns the evaluation."""
    run = Path(run)
    meta = json.loads((run / "run.json").read_text())
    source = run / "selected_model.zip"
    source = source if source.is_file() else run / "model.zip"
    if meta.get("algo") in PIXEL_ALGORITHMS:  # a pixel policy's zip holds its weights alone
        shutil.copy2(source, MODELS / f"{name}.zip")
        return finish_commit(run, name, meta, source, episodes)
    model = load_model(source, gym.make(meta["env_id"], **observation_kwargs(meta)),
                       meta.get("algo"))
    for part in ("actor_state", "qf_state"):  # SBX: flax train states
        state = getattr(model.policy, part, None)
        if state is not None:
            setattr(model.policy, part, state.replace(opt_state=None))
    optimizers = [getattr(model.policy, part, None) for part in ("actor", "critic")]
    for optimizer in (getattr(o, "optimizer", None) for o in optimizers):  # PyTorch SB3
        if optimizer is not None:
            optimizer.state.clear()
    model.save(MODELS / f"{name}.zip", exclude=["actor", "qf"] if meta.get("learner") == "sbx"
               else None)
    return finish_commit(run, name, meta, source, episodes)


def finish_commit(run: Path, name: str, meta: dict, source: Path, episodes: int) -> dict:
    """``commit_model``'s end, once ``name``.zip is in place: its json from the run's
    settings ``meta``, then ``record_evaluation``."""
    result = run / "result.json"
    if result.is_file():
        meta["selected_env_steps"] = json.loads(result.read_text())["selected_env_steps"]
    meta["source"] = str(source)
    (MODELS / f"{name}.json").write_text(json.dumps(meta, indent=2) + "\n")
    return record_evaluation(MODELS / f"{name}.zip", episodes)


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description="Re-evaluate the committed models and write "
                                     "their figures, or commit a run's policy as one")
    parser.add_argument("--commit", nargs=2, metavar=("RUN_FOLDER", "NAME"),
                        help="put RUN_FOLDER's policy into agents/models as NAME (commit_model)")
    args = parser.parse_args()
    paths = [MODELS / f"{args.commit[1]}.zip"] if args.commit else sorted(MODELS.glob("*.zip"))
    for path in paths:
        figures = commit_model(args.commit[0], args.commit[1]) if args.commit else \
            record_evaluation(path)
        print(f"{path.name}: success {figures['success_rate']:.0%} over {figures['episodes']} "
              "episodes", flush=True)
