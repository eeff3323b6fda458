"""Offline RL datasets of the tasks in Minari's format (Farama's standard, what
``minari.load_dataset`` reads), and the check that a dataset replays bit for bit.

    rigid-gym dataset rigid_gym/Push-v0 --policy scripted --episodes 100 --dataset-id rigid_gym/push/expert-v0
    rigid-gym dataset --verify rigid_gym/push/expert-v0
    rigid-gym dataset --recipes                       # the shipped datasets, RECIPES

    from .datasets import write_dataset, verify
    dataset = write_dataset("rigid_gym/push/expert-v0", "rigid_gym/Push-v0", "scripted", 100)
    assert all(result.ok for result in verify(dataset))

Datasets go where Minari keeps them: ``MINARI_DATASETS_PATH``, else ``~/.minari/datasets``.
An episode holds the Dict observations (each key ``(T + 1, size)`` float32, the reset's
first), the actions ``(T, action size)`` float32 exactly as the env was stepped with them,
rewards ``(T,)`` float64, terminations and truncations ``(T,)`` bool, and
``infos["is_success"]`` ``(T + 1,)`` bool; Minari keeps its reset seed in the episode's
metadata. The dataset's metadata holds the env spec (``dataset.recover_environment()`` makes
the env, the eval env spec the same), the policy, the action noise, the success rate, the
seeds, the rigid_gym version (also as a requirement, which ``recover_environment`` checks) and
the git commit of the code that wrote it.

The solver repeats a seeded episode bit for bit, so a dataset can be checked rather than
trusted: ``verify`` makes the env from the dataset, resets it with each episode's seed,
steps the episode's actions and compares every observation, reward, termination,
truncation and ``is_success`` with ``np.array_equal``. An episode stored without a seed was
reset without one, continuing the generator of the episode before it (how
``rigid_gym.agents.train`` lays out its demonstration streams), and is replayed so.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import shutil
import subprocess
import tempfile
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import gymnasium as gym
import minari
import numpy as np
from minari import MinariDataset
from minari.data_collector import EpisodeBuffer
from minari.dataset.minari_dataset import DATASET_ID_RE

import rigid_gym
from rigid_gym.checks import BadFile, in_range, integer

DATA_FORMAT = "arrow"
"""Minari's storage format for these datasets (pyarrow; its default, hdf5, needs h5py)."""
AUTHOR = "rigid_gym"
RECIPE_SEED = 3_000_000
"""The shipped datasets' first reset seeds start here, apart from the training seeds (small),
the evaluation seeds (1,000,000 on) and the training demonstrations' (2,000,000 on)."""
RECIPE_NOISE = 0.1
"""The noisy datasets' action noise: Gaussian, standard deviation in action units (the
action space is [-1, 1] per entry), added to the scripted action and clipped."""


@dataclasses.dataclass(frozen=True)
class Recipe:
    """One shipped dataset: ``dataset_id`` made from ``env_id`` by ``policy`` (random or
    scripted) with action noise ``noise``, episode k reset with seed ``seed + k``."""
    dataset_id: str
    env_id: str
    policy: str
    noise: float
    seed: int


RECIPE_TASKS: tuple[str, ...] = ("Push", "Stack", "Throw")
RECIPE_TASKS += ("Reach", "PickAndPlace", "Slide", "Flip")
RECIPE_TASKS += ("Tower", "Insert")
"""The tasks with shipped datasets; task t's recipes draw from seeds RECIPE_SEED +
100_000 x (3 t + k), so a task added at the end changes no other task's data."""


def _recipes() -> tuple[Recipe, ...]:
    recipes = []
    for t, task in enumerate(RECIPE_TASKS):
        for k, (name, policy, noise) in enumerate((("expert", "scripted", 0.0),
                                                   ("noisy", "scripted", RECIPE_NOISE),
                                                   ("random", "random", 0.0))):
            recipes.append(Recipe(f"rigid_gym/{task.lower()}/{name}-v0", f"rigid_gym/{task}-v0",
                                  policy, noise, RECIPE_SEED + 100_000 * (3 * t + k)))
    return tuple(recipes)


RECIPES = _recipes()
"""The shipped datasets: for each of RECIPE_TASKS (its name in lower case), ``expert-v0``
(the scripted policy), ``noisy-v0`` (it with ``RECIPE_NOISE``) and ``random-v0`` (uniform
random actions)."""
RECIPE_EPISODES = 200
"""Episodes per shipped dataset (``rigid-gym dataset --recipes``)."""


def make_actor(env: gym.Env, policy: str, seed: int) -> Callable[[dict], np.ndarray]:
    """observation -> action for ``env``: ``policy`` random, scripted or a model .zip, as
    ``rigid-gym record`` plays it (``rigid_gym.agents.policies.make_policy``; random actions
    seeded with ``seed``)."""
    from .policies import make_policy

    return make_policy(env, policy, None, seed)


def play(env: gym.Env, act: Callable[[dict], np.ndarray], seeds: list[int | None],
         noise: float = 0.0, rng: np.random.Generator | None = None,
         on_episode: Callable[[EpisodeBuffer], None] | None = None) -> list[EpisodeBuffer]:
    """Play ``len(seeds)`` episodes of ``env`` with ``act`` and return them as Minari's
    episode buffers (arrays as the module docstring says). Episode k is reset with
    ``seeds[k]``; None resets without a seed (the env's generator goes on from the episode
    before). noise: standard deviation of Gaussian noise (drawn from ``rng``) added to each
    action, which is then clipped to the action space; the stored action is the one stepped,
    in the action space's dtype. on_episode: called with each finished episode."""
    in_range(noise, 0.0, 10.0, "dataset: noise", unit="(action units)")
    space = env.action_space
    assert isinstance(space, gym.spaces.Box)  # every task acts in a box
    rng = rng if rng is not None else np.random.default_rng(0)
    episodes: list[EpisodeBuffer] = []
    for seed in seeds:
        obs, info = env.reset(seed=seed)
        observations, actions, rewards = [obs], [], []
        terminations, truncations, successes = [], [], [bool(info["is_success"])]
        done = False
        while not done:
            action = np.asarray(act(obs), dtype=np.float64)
            if noise:
                action = action + noise * rng.standard_normal(action.shape)
            action = np.clip(action, space.low, space.high).astype(space.dtype)
            obs, reward, terminated, truncated, info = env.step(action)
            observations.append(obs)
            actions.append(action)
            rewards.append(float(reward))
            terminations.append(bool(terminated))
            truncations.append(bool(truncated))
            successes.append(bool(info["is_success"]))
            done = terminated or truncated
        episode = EpisodeBuffer(
            id=len(episodes), seed=seed,
            observations={key: np.stack([o[key] for o in observations]) for key in obs},
            actions=np.stack(actions), rewards=np.array(rewards),
            terminations=np.array(terminations), truncations=np.array(truncations),
            # a list, as Minari's DataCollector passes infos: its arrow storage writes a 1-D
            # array's shape as "" and cannot read it back (minari 0.5.4)
            infos={"is_success": successes})
        episodes.append(episode)
        if on_episode is not None:
            on_episode(episode)
    return episodes


def success_rate(episodes: list) -> float:
    """The fraction of ``episodes`` (episode buffers or Minari's EpisodeData) whose last
    step reports ``is_success``."""
    return float(np.mean([bool(e.infos["is_success"][-1]) for e in episodes]))


def code_version() -> dict:
    """{"rigid_gym_version", "git_commit"}: the package version, and the commit of the git
    work tree the package runs from (with "-dirty" if it has changes; None outside one)."""
    root = Path(rigid_gym.__file__).resolve().parent.parent
    commit = None
    with contextlib.suppress(OSError, subprocess.SubprocessError):
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], check=False,
                              capture_output=True, text=True, timeout=10)
        if head.returncode == 0:
            status = subprocess.run(["git", "-C", str(root), "status", "--porcelain"],
                                    check=False, capture_output=True, text=True, timeout=10)
            commit = head.stdout.strip() + ("-dirty" if status.stdout.strip() else "")
    return {"rigid_gym_version": rigid_gym.__version__, "git_commit": commit}


def create(dataset_id: str, env: gym.Env, episodes: list[EpisodeBuffer], policy: str,
           noise: float, description: str, extra: dict | None = None) -> MinariDataset:
    """Write ``episodes`` of ``env`` as the Minari dataset ``dataset_id`` (under
    MINARI_DATASETS_PATH), as its episodes 0, 1, ... in that order, with the metadata of the
    module docstring, and return it. extra: more metadata entries (JSON values)."""
    checked_dataset_id(dataset_id)
    episodes = [dataclasses.replace(episode, id=k) for k, episode in enumerate(episodes)]
    version = code_version()
    with removed_on_failure(dataset_id), warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*author_email.*")  # the project has none
        dataset = minari.create_dataset_from_buffers(
            dataset_id, episodes, env=env.spec, eval_env=env.spec,
            algorithm_name=Path(policy).name if policy.endswith(".zip") else policy,
            author=AUTHOR, code_permalink=f"rigid_gym {version['rigid_gym_version']}, git "
            f"commit {version['git_commit'] or 'unknown'}: agents/datasets.py",
            description=description, data_format=DATA_FORMAT,
            requirements=[f"rigid_gym=={version['rigid_gym_version']}"])
        dataset.storage.update_metadata({"policy": policy, "action_noise": float(noise),
                                         "success_rate": success_rate(episodes),
                                         **version, **(extra or {})})
    return dataset


def checked_dataset_id(dataset_id: str) -> str:
    """``dataset_id`` if Minari takes it as a new dataset's id, ``[namespace/]name-v<k>``
    (e.g. rigid_gym/push/expert-v0); else a ValueError saying the form, raised before
    anything is played or written."""
    match = DATASET_ID_RE.fullmatch(dataset_id) if isinstance(dataset_id, str) else None
    if match is None or match.group("version") is None:
        raise ValueError(f"dataset: {dataset_id!r} is not a dataset id; Minari's ids are "
                         "[namespace/]name-v<version>, the namespace's parts of 2 or more "
                         "letters, digits, - or _ (e.g. rigid_gym/push/expert-v0, "
                         "my-push-v0)")
    return dataset_id


@contextlib.contextmanager
def removed_on_failure(dataset_id: str) -> Iterator[None]:
    """Where the ``with`` block (writing ``dataset_id``) fails, delete what it made under
    the datasets' folder: the dataset's folder and the namespace folders that did not exist
    before, so that a failed write leaves nothing that a later one trips over."""
    root = datasets_root()
    made = [root / dataset_id] + [root / p for p in Path(dataset_id).parents if str(p) != "."]
    new = [folder for folder in made if not folder.exists()]
    try:
        yield
    except BaseException:
        for folder in new:  # the dataset's folder first, then its namespaces inside out
            shutil.rmtree(folder, ignore_errors=True)
        raise


def write_dataset(dataset_id: str, env_id: str, policy: str, episodes: int, noise: float = 0.0,
                  seed: int = 0, progress: bool = False) -> MinariDataset:
    """Play ``episodes`` episodes of ``env_id`` with ``policy`` (random, scripted or a
    stable-baselines3 model .zip), episode k reset with seed ``seed + k``, and write them as
    the Minari dataset ``dataset_id``; returns it. noise: Gaussian action noise (``play``),
    drawn from a generator seeded with ``seed``; progress: a bar of the episodes on stderr."""
    if env_id not in rigid_gym.ENV_IDS:
        raise ValueError(f"dataset: unknown env id {env_id!r}; choose from "
                         f"{', '.join(rigid_gym.ENV_IDS)}")
    checked_dataset_id(dataset_id)
    integer(episodes, "dataset: episodes", 1, 2 ** 32)
    integer(seed, f"dataset: seed (with {episodes} episodes, seeded seed + k)", 0,
            2 ** 32 - episodes)
    if minari.list_local_datasets(prefix=dataset_id).get(dataset_id) is not None:
        raise ValueError(f"dataset: {dataset_id} already exists in {datasets_root()}; "
                         f"delete it first (minari delete {dataset_id}) or pick a new id")
    env = gym.make(env_id)
    shown = _bar(episodes, f"{dataset_id}: {policy} episodes", progress)
    try:
        buffers = play(env, make_actor(env, policy, seed), [seed + k for k in range(episodes)],
                       noise, np.random.default_rng(seed), lambda e: shown.update(1))
    finally:
        shown.close()
        env.close()
    description = (f"{episodes} episodes of {env_id} played by the {policy} policy"
                   + (f" with Gaussian action noise of standard deviation {noise:g}"
                      if noise else "")
                   + f"; episode k reset with seed {seed} + k.")
    return create(dataset_id, env, buffers, policy, noise, description, {"first_seed": seed})


def write_streams(dataset_id: str, env_id: str, policy: str, seeds: list[int], episodes: int,
                  progress: bool = False) -> MinariDataset:
    """Play one stream of ``episodes`` episodes of ``env_id`` per seed in ``seeds``, each in an
    env of its own whose first reset takes the seed and whose later resets take none (as a
    stable-baselines3 VecEnv seeds its envs), and write them, stream after stream, as the
    Minari dataset ``dataset_id``; returns it. Only the first episode of a stream has a seed,
    and ``verify`` replays the others after it."""
    shown = _bar(episodes * len(seeds), f"{env_id}: {policy} episodes", progress)
    buffers = []
    try:
        for seed in seeds:
            env = gym.make(env_id)
            buffers += play(env, make_actor(env, policy, seed), [seed] + [None] * (episodes - 1),
                            on_episode=lambda e: shown.update(1))
            env.close()
    finally:
        shown.close()
    description = (f"{len(seeds)} stream(s) of {episodes} episodes of {env_id} played by the "
                   f"{policy} policy; a stream's first episode reset with its seed "
                   f"({', '.join(map(str, seeds))}), the others without one.")
    return create(dataset_id, env, buffers, policy, 0.0, description,
                  {"stream_seeds": list(seeds), "stream_episodes": episodes})


def _bar(total: int, description: str, shown: bool):
    from .progress import bar

    return bar(total, description, shown)


def datasets_root() -> Path:
    """Where Minari keeps datasets now: MINARI_DATASETS_PATH, else ~/.minari/datasets."""
    from minari.storage import get_dataset_path

    return Path(get_dataset_path())


@contextlib.contextmanager
def temporary_datasets_root() -> Iterator[Path]:
    """Point MINARI_DATASETS_PATH at a new temporary folder for the ``with`` block (the
    datasets written there are deleted after it), then back to what it was. Minari reads the
    folder from the process's environment, so other threads see it too while it is set."""
    before = os.environ.get("MINARI_DATASETS_PATH")
    with tempfile.TemporaryDirectory(prefix="rigid_gym-datasets-") as folder:
        os.environ["MINARI_DATASETS_PATH"] = folder
        try:
            yield Path(folder)
        finally:
            if before is None:
                del os.environ["MINARI_DATASETS_PATH"]
            else:
                os.environ["MINARI_DATASETS_PATH"] = before


def load(dataset_id: str) -> MinariDataset:
    """``minari.load_dataset(dataset_id)`` once its files are checked (``check_files``),
    with an error naming the folder searched where there is no such dataset."""
    folder = datasets_root() / dataset_id
    if not isinstance(dataset_id, str) or not (folder / "data").is_dir():
        raise ValueError(f"dataset: no dataset {dataset_id} in {datasets_root()} "
                         "(MINARI_DATASETS_PATH)")
    check_files(dataset_id, folder / "data")
    try:
        return minari.load_dataset(dataset_id)
    except (OSError, ValueError, KeyError) as exc:  # what check_files does not look at
        raise BadFile(f"dataset {dataset_id}: Minari cannot load {folder}: {exc}") from None


def check_files(dataset_id: str, folder: Path) -> None:
    """Check that dataset ``dataset_id``'s ``folder`` (its ``data`` folder, in Minari's arrow
    layout) holds its metadata.json and, per episode k < total_episodes, a folder ``k`` with
    a metadata.json and whole .arrow files; else a BadFile naming the file. Reads every
    file once (what a replay reads anyway)."""
    import pyarrow as pa

    damaged = f"; the dataset {dataset_id} is damaged: write it again, or delete it " \
              f"(minari delete {dataset_id})"

    def json_file(path: Path) -> dict:
        try:
            value = json.loads(path.read_text())
        except FileNotFoundError:
            raise BadFile(f"dataset: {path} is missing{damaged}") from None
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise BadFile(f"dataset: {path} is not readable JSON ({exc}){damaged}") from None
        if not isinstance(value, dict):
            raise BadFile(f"dataset: {path} holds no JSON object{damaged}")
        return value

    total = json_file(folder / "metadata.json").get("total_episodes")
    if isinstance(total, bool) or not isinstance(total, int) or total < 0:
        raise BadFile(f"dataset: {folder / 'metadata.json'} has no total_episodes{damaged}")
    for k in range(total):
        episode = folder / str(k)
        if not episode.is_dir():
            raise BadFile(f"dataset: episode {k}'s folder {episode} is missing{damaged}")
        json_file(episode / "metadata.json")
        parts = sorted(episode.glob("*.arrow"))
        if not parts:
            raise BadFile(f"dataset: episode {k}'s folder {episode} holds no .arrow file"
                          f"{damaged}")
        for part in parts:
            try:
                with pa.memory_map(str(part)) as source:
                    pa.ipc.open_file(source).read_all()
            except (OSError, pa.ArrowException) as exc:
                raise BadFile(f"dataset: {part} is not a whole Arrow file ({exc}){damaged}") \
                    from None


def episode_seeds(dataset: MinariDataset) -> list[int | None]:
    """Each episode's reset seed as Minari keeps it (None: reset without a seed)."""
    return [meta.get("seed") for meta in dataset.storage.get_episode_metadata(
        dataset.episode_indices)]


@dataclasses.dataclass(frozen=True)
class Replay:
    """One episode's replay: ``ok`` when every observation, reward, termination, truncation
    and is_success matched bit for bit; otherwise ``mismatch`` names the first difference
    (what and at which step)."""
    episode: int
    seed: int | None
    steps: int
    ok: bool
    mismatch: str = ""


def verify(dataset: MinariDataset | str,
           on_episode: Callable[[Replay], None] | None = None) -> list[Replay]:
    """Replay every episode of ``dataset`` (a MinariDataset or a dataset id) in the env that
    ``recover_environment()`` makes, reset with the episode's seed, and compare what the env
    returns with what the dataset holds; returns one ``Replay`` per episode (and calls
    ``on_episode`` with each)."""
    if isinstance(dataset, str):
        dataset = load(dataset)
    env = dataset.recover_environment()
    results: list[Replay] = []
    for seed, episode in zip(episode_seeds(dataset), dataset.iterate_episodes()):
        if seed is None and not results:
            result = Replay(int(episode.id), seed, len(episode), False,
                            "the first episode has no reset seed: it cannot be replayed")
        elif seed is None and not results[-1].ok:
            result = Replay(int(episode.id), seed, len(episode), False,
                            f"reset without a seed after episode {results[-1].episode}, "
                            "which did not replay")
        else:
            result = replay_episode(env, episode, seed)
        results.append(result)
        if on_episode is not None:
            on_episode(result)
    env.close()
    return results


def replay_episode(env: gym.Env, episode, seed: int | None) -> Replay:
    """Reset ``env`` with ``seed`` (None: without one), step ``episode``'s actions (a
    Minari EpisodeData) and compare what the env returns with what the episode holds."""
    def differs(t: int, obs: dict, info: dict) -> str:
        for key, value in obs.items():
            if not np.array_equal(value, episode.observations[key][t]):
                return f"observation {key!r} at step {t}"
        if bool(info["is_success"]) != bool(episode.infos["is_success"][t]):
            return f"is_success at step {t}"
        return ""

    obs, info = env.reset(seed=seed)
    mismatch = differs(0, obs, info)
    for t, action in enumerate(episode.actions):
        if mismatch:
            break
        obs, reward, terminated, truncated, info = env.step(action)
        stored = (episode.rewards[t], episode.terminations[t], episode.truncations[t])
        for name, value, expected in zip(("reward", "termination", "truncation"),
                                         (reward, terminated, truncated), stored):
            if not np.array_equal(np.asarray(value), expected):
                mismatch = f"{name} at step {t + 1}: {value!r}, stored {expected!r}"
                break
        mismatch = mismatch or differs(t + 1, obs, info)
        if not mismatch and (terminated or truncated) and t + 1 < len(episode):
            mismatch = f"the env ended the episode at step {t + 1} of {len(episode)}"
    return Replay(int(episode.id), seed, len(episode), not mismatch, mismatch)


def write_recipes(episodes: int = RECIPE_EPISODES, progress: bool = False,
                  recipes: tuple[Recipe, ...] = RECIPES) -> list[MinariDataset]:
    """Regenerate the shipped datasets (``RECIPES``), ``episodes`` each, replacing any of
    those ids already there; returns them."""
    datasets = []
    for recipe in recipes:
        if minari.list_local_datasets(prefix=recipe.dataset_id).get(recipe.dataset_id):
            minari.delete_dataset(recipe.dataset_id)
        datasets.append(write_dataset(recipe.dataset_id, recipe.env_id, recipe.policy, episodes,
                                      recipe.noise, recipe.seed, progress))
    return datasets
