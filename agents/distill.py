"""A pixel policy distilled from a state policy on its own visited states (teacher-student,
Chen et al. 2019, "Learning by Cheating"; DAgger, Ross et al. 2011).

    rigid-gym train rigid_gym/Push-v0 --obs-mode pixels --seed 0   # hyperparams.yml's distill
    rigid-gym train rigid_gym/Push-v0 --obs-mode pixels --seed 0 --resume

The student sees what a robot with a camera has: the frame (``size`` x ``size`` uint8 RGB
from the batched renderer), the goal (``desired_goal``) and the pad's own state (its position
and velocity, and whether it holds a cube in the tasks with a grip: ``PROPRIOCEPTION``), never
the cubes' (``student_inputs`` picks these out of a ``state+pixels`` observation and nothing
else). The teacher is a committed state policy (Push: agents/models/push_sac_seed0.zip, SAC +
HER; Stack: stack_bcsac_seed0.zip, BC-SAC; Throw: throw_sac_seed0.zip); its training wall and
CPU time (its result file in agents/results/) count in the pixel run's.

Each iteration i plays ``episodes`` episodes in ``n_envs`` batched envs; at every step each
env follows the teacher with probability beta_i = max(0, 1 - i / beta_iterations), else the
student's own action (so the data is more and more the student's own states), every visited
state is labelled with the teacher's deterministic action, added to the data set (frames kept
as uint8), and the student is regressed on all of it (``updates`` Adam steps of mean squared
action error on batches of ``batch_size``, every frame shifted by up to ``shift`` pixels at
random, as DrQ, plus ``locate_weight`` times the error of the encoder's read-out of the achieved goal, the
cubes' positions: privileged state that trains the encoder and never reaches the acting
policy). After each iteration the deterministic student plays ``eval_episodes``
episodes on seeds from VALIDATION_SEED (the curve); at the end 100 from EVAL_SEED (the result).

A run folder holds run.json (settings, seconds), evaluations.csv, model.zip (``save_policy``:
the student's weights and what it takes, which ``rigid-gym evaluate`` and ``record`` load
through ``DistilledPolicy``), and checkpoints/ (``latest.pt``: the student, its optimizer,
the random state, the iterations done; ``data_<i>.npz``: iteration i's labelled states), from
which ``--resume`` goes on.
"""

from __future__ import annotations

import csv
import io
import json
import shutil
import sys
import zipfile
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from .evaluate import EVAL_SEED, VALIDATION_SEED, load_model, success_rate
from .progress import note
from .results import RESULTS, method

PROPRIOCEPTION = ("pad.position", "pad.velocity", "holding")
"""The fields of the state ``observation`` that the student sees, those that the task has: the
pad's own state (position, velocity, and the grip's holding flag)."""
ALGO = "distill"
CUBE_SCALE = 0.15
"""m: the cube positions that the encoder's auxiliary read-out learns are divided by this
(the half width of where Push's cubes start and goals lie), so that they span about [-1, 1]
(Throw's bin, 0.5-0.65 m out, reads about 4)."""


def observation_kwargs(size: int) -> dict:
    """The env arguments of the student's envs: state+pixels (the teacher labels from the
    state; ``student_inputs`` keeps only the frame, the goal and the pad's state)."""
    return {"obs_mode": "state+pixels", "width": size, "height": size}


def proprioception_fields(env_id: str) -> list[str]:
    """The fields of PROPRIOCEPTION that ``env_id``'s observation has, in that order."""
    env: Any = gym.make(env_id).unwrapped
    return [name for name in PROPRIOCEPTION if name in env.task.observation_layout.slices]


def proprioception_index(env_id: str) -> np.ndarray:
    """The entries of ``env_id``'s ``observation`` vector that hold PROPRIOCEPTION, (k,) int
    (Push: 6, the pad's position and velocity; Stack, Throw: 7, and the holding flag)."""
    env: Any = gym.make(env_id).unwrapped
    return env.task.observation_layout.entries(proprioception_fields(env_id))


def student_inputs(obs: dict, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """What the student sees of a (batched or single) state+pixels observation: the frames
    (..., H, W, 3) uint8 and the vector (..., g + k) float32, the desired goal (g) then the
    observation's entries ``index`` (the pad's state, ``proprioception_index``). Nothing of
    the cubes."""
    vector = np.concatenate([obs["desired_goal"], obs["observation"][..., index]], axis=-1)
    return np.asarray(obs["pixels"], dtype=np.uint8), vector.astype(np.float32)


def encoder_layers(size: int, channels: int, features: int):
    """(conv, project): four 3x3 convolutions of ``channels`` (strides 2, 2, 2, 1; a 64 x 64
    frame leaves 5 x 5, a 48 x 48 one 3 x 3) and a linear layer to ``features`` with LayerNorm
    and tanh (DrQ's encoder, strided). ``encode`` applies them to frames (B, H, W, 3)."""
    import torch
    from torch import nn

    conv = nn.Sequential(
        nn.Conv2d(3, channels, 3, stride=2), nn.ReLU(),
        nn.Conv2d(channels, channels, 3, stride=2), nn.ReLU(),
        nn.Conv2d(channels, channels, 3, stride=2), nn.ReLU(),
        nn.Conv2d(channels, channels, 3, stride=1), nn.ReLU(), nn.Flatten())
    with torch.no_grad():
        flat = conv(torch.zeros(1, 3, size, size)).shape[1]
    return conv, nn.Sequential(nn.Linear(flat, features), nn.LayerNorm(features), nn.Tanh())


def encode(conv, project, frames):
    """Features (B, features) of frames (B, H, W, 3) uint8 values as float: scaled to
    [-0.5, 0.5], then ``encoder_layers``' conv and project."""
    return project(conv(frames.permute(0, 3, 1, 2) / 255.0 - 0.5))


def make_network(size: int, vector_size: int, action_size: int, channels: int = 32,
                 features: int = 64, hidden: int = 256, located: int = 3):
    """The student: ``encoder_layers`` on the frame, its features concatenated with the
    vector, then an MLP of two ``hidden`` ReLU layers to tanh actions. Input: frames
    (B, H, W, 3) uint8 as float, vector (B, vector_size); output (B, action_size) in [-1, 1].
    ``locator``: a linear read-out of the features to ``located`` numbers (the cubes'
    positions, scaled), trained beside the actions so that the encoder learns where the cube
    is (an auxiliary loss on privileged state, training only; acting never calls it);
    ``located`` 0: none (a policy trained without it, ``pixel_sac``)."""
    import torch
    from torch import nn

    class Student(nn.Module):
        def __init__(self):
            super().__init__()
            self.conv, self.project = encoder_layers(size, channels, features)
            self.head = nn.Sequential(nn.Linear(features + vector_size, hidden), nn.ReLU(),
                                      nn.Linear(hidden, hidden), nn.ReLU(),
                                      nn.Linear(hidden, action_size), nn.Tanh())
            if located:
                self.locator = nn.Linear(features, located)

        def encode(self, frames):
            return encode(self.conv, self.project, frames)

        def forward(self, frames, vector):
            return self.head(torch.cat([self.encode(frames), vector], dim=1))

        def both(self, frames, vector):
            """(actions, located) of one encoding."""
            z = self.encode(frames)
            return self.head(torch.cat([z, vector], dim=1)), self.locator(z)

    return Student()


def random_shift(frames, shift: int, generator):
    """Each frame (B, H, W, 3) float shifted by up to ``shift`` pixels each way (edge pixels
    repeated, then a random H x W crop; DrQ's augmentation)."""
    import torch
    import torch.nn.functional as F

    b, h, w, _ = frames.shape
    padded = F.pad(frames.permute(0, 3, 1, 2), (shift,) * 4, mode="replicate")
    dx, dy = torch.randint(0, 2 * shift + 1, (2, b), generator=generator).tolist()
    return torch.stack([padded[k, :, dy[k]:dy[k] + h, dx[k]:dx[k] + w] for k in range(b)]
                       ).permute(0, 2, 3, 1)


class DistilledPolicy:
    """A saved student (or pixel SAC policy, ``pixel_sac``, saved in the student's form) as
    ``rigid-gym evaluate`` and ``record`` use a model: ``load(path, env)`` and
    ``predict(obs, deterministic)`` on a state+pixels observation of the size it was trained
    on (``student_inputs`` keeps the frame, goal and pad state)."""

    def __init__(self, network, config: dict):
        self.network, self.config = network, config
        self.index = np.asarray(config["proprioception_index"], dtype=np.int64)

    @classmethod
    def load(cls, path: str | Path, env: gym.Env | None = None, device: str = "cpu"):
        import torch

        with zipfile.ZipFile(path) as archive:
            config = json.loads(archive.read("data"))
            weights = torch.load(io.BytesIO(archive.read("policy.pth")), map_location=device)
        network = make_network(config["size"], config["vector_size"], config["action_size"],
                               **config["network"])
        network.load_state_dict(weights)
        network.eval()
        if env is not None:
            parts = getattr(env.observation_space, "spaces", {})
            found = parts.get("pixels")
            wanted = (config["size"], config["size"], 3)
            if found is None or found.shape != wanted or "observation" not in parts:
                raise ValueError(f"{path} takes state+pixels observations of {wanted} frames; "
                                 f"the env gives {env.observation_space}")
        return cls(network, config)

    def predict(self, obs: dict, deterministic: bool = True):
        """(action, None): the student's action for ``obs`` (one observation or a batch)."""
        import torch

        frames, vector = student_inputs(obs, self.index)
        single = frames.ndim == 3
        if single:
            frames, vector = frames[None], vector[None]
        with torch.no_grad():
            action = self.network(torch.from_numpy(frames).float(),
                                  torch.from_numpy(vector)).numpy()
        return (action[0] if single else action), None


def save_policy(path: Path, network, config: dict, algo: str = ALGO) -> None:
    """model.zip: ``data`` (the config and ``algo``, "distill" or the pixel SAC's "drq") and
    ``policy.pth`` (the weights of a ``make_network``)."""
    import torch

    buffer = io.BytesIO()
    torch.save(network.state_dict(), buffer)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("data", json.dumps({"algo": algo, **config}))
        archive.writestr("policy.pth", buffer.getvalue())


def vector_success(policy, env_id: str, size: int, episodes: int, seed: int) -> float:
    """Success rate of ``policy`` (deterministic) over ``episodes`` episodes on seeds
    ``seed``, ``seed + 1``, ..., played side by side in one batched env (every episode runs
    the time limit: success is the last step's)."""
    envs = gym.make_vec(env_id, num_envs=episodes, **observation_kwargs(size))
    obs, _ = envs.reset(seed=[seed + k for k in range(episodes)])  # type: ignore[arg-type]
    done = np.zeros(episodes, bool)
    success = np.zeros(episodes)
    while not done.all():
        obs, _, terminated, truncated, info = envs.step(policy.predict(obs)[0])
        ended = (terminated | truncated) & ~done
        success[ended] = np.asarray(info["final_info"]["is_success"], float)[ended] \
            if "final_info" in info else np.asarray(info["is_success"], float)[ended]
        done |= ended
    envs.close()
    return float(success.mean())


def validate(policy, env_id: str, size: int, episodes: int, clock, env_steps: int,
             curve: list[dict], folder: Path) -> tuple[float, dict]:
    """Score ``policy`` on ``episodes`` validation episodes (NaN for none), add the point to
    ``curve`` and to ``folder``/evaluations.csv -> (its success rate, ``clock.seconds()``)."""
    rate = vector_success(policy, env_id, size, episodes, VALIDATION_SEED) \
        if episodes else float("nan")
    seconds = clock.seconds()
    curve.append({"env_steps": env_steps, "wall_s": round(seconds["wall_seconds"], 1),
                  "success": rate})
    with open(folder / "evaluations.csv", "a", newline="") as f:
        csv.writer(f).writerow([env_steps, rate, "", seconds["wall_seconds"]])
    return rate, seconds


def select_student(folder: Path, curve: list[dict], iterations: int):
    """The run's student, as ``train.finish`` chooses a checkpoint: among the students of the
    iterations of the run's second half (``checkpoints/student_<i>.zip``, i >= SELECT_FROM *
    iterations), the one of best validation success on the curve, the latest among equals,
    copied to ``selected_model.zip``; without any, the last. Returns (DistilledPolicy, its
    env steps)."""
    from .train import SELECT_FROM

    best, chosen = -1.0, None
    for k, point in enumerate(curve[:iterations], start=1):
        path = folder / "checkpoints" / f"student_{k}.zip"
        if k >= SELECT_FROM * iterations and path.is_file() and point["success"] >= best:
            best, chosen = point["success"], (path, point["env_steps"])
    if chosen is None:
        return DistilledPolicy.load(folder / "model.zip"), curve[-1]["env_steps"]
    shutil.copy2(chosen[0], folder / "selected_model.zip")
    return DistilledPolicy.load(chosen[0]), chosen[1]


def teacher_seconds(teacher: Path) -> tuple[float, float]:
    """(wall, CPU) seconds of the teacher's training: its result file in agents/results
    (``<run_name>.json`` of the run named by the model's settings), else its json's."""
    from .train import run_name

    meta = json.loads(teacher.with_suffix(".json").read_text())
    result = RESULTS / f"{run_name(meta['env_id'], meta['algo'], meta['seed'])}.json"
    if result.is_file():
        found = json.loads(result.read_text())
        return float(found["wall_s"]), float(found["cpu_s"])
    return float(meta["wall_seconds"]), float(meta["cpu_seconds"])


def train_distill(env_id: str, settings: dict, *, seed: int, folder: Path, resume: bool, teacher: str | None, iterations: int | None,
                  eval_episodes: int, final_episodes: int, results: str | Path | None,
                  progress: bool) -> Path:
    """The DAgger loop of the module docstring, into ``folder``; ``settings``: hyperparams.yml's
    distill recipe (teacher, size, n_envs, iterations, episodes, beta_iterations, updates,
    batch_size, learning_rate, shift, locate_weight, network). ``teacher``, ``iterations``: override
    it. The run's clock starts at the teacher's training seconds. Returns ``folder``."""
    import torch

    from .train import Clock

    recipe = dict(settings["distill"])
    teacher_path = Path(teacher or recipe["teacher"])
    if not teacher_path.is_absolute() and not teacher_path.is_file():
        teacher_path = Path(__file__).parent / teacher_path
    if not teacher_path.is_file():
        raise ValueError(f"train: no teacher model at {teacher_path}")
    iterations = iterations if iterations is not None else recipe["iterations"]
    size, n_envs = recipe["size"], recipe["n_envs"]
    per_iteration = -(-recipe["episodes"] // n_envs)  # episodes per env per iteration
    checkpoints = folder / "checkpoints"
    state_path = checkpoints / "latest.pt"
    index = proprioception_index(env_id)
    probe = gym.make(env_id)
    goal_size = probe.observation_space["desired_goal"].shape[0]  # type: ignore[index]
    # the read-out learns the achieved goal (the cubes' positions); Push's 3 is the default
    network_kwargs = {**recipe.get("network", {}),
                      **({"located": goal_size} if goal_size != 3 else {})}
    config = {"env_id": env_id, "size": size, "vector_size": goal_size + len(index),
              "action_size": int(np.prod(probe.action_space.shape or (1,))),
              "proprioception_index": index.tolist(), "network": network_kwargs}
    network = make_network(config["size"], config["vector_size"], config["action_size"],
                           **config["network"])
    optimizer = torch.optim.Adam(network.parameters(), lr=recipe["learning_rate"])
    generator = torch.Generator().manual_seed(seed)
    rng = np.random.default_rng(seed)
    torch.manual_seed(seed)
    done_iterations, env_steps, curve = 0, 0, []
    if resume:
        if not state_path.is_file():
            raise ValueError(f"--resume: no checkpoint at {state_path}")
        state = torch.load(state_path, weights_only=False)
        network.load_state_dict(state["network"])
        optimizer.load_state_dict(state["optimizer"])
        generator.set_state(state["generator"])
        rng.bit_generator.state = state["rng"]
        done_iterations, env_steps, curve = state["iterations"], state["env_steps"], state["curve"]
        clock = Clock(state["wall_seconds"], state["cpu_seconds"])
        record = json.loads((folder / "run.json").read_text())
        record["resumed_at"] = record.get("resumed_at", []) + [env_steps]
        record["iterations"] = record["recipe"]["iterations"] = iterations
        (folder / "run.json").write_text(json.dumps(record, indent=2))
        with open(folder / "evaluations.csv", "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(["timesteps", "success_rate", "mean_return", "wall_seconds"])
            writer.writerows([p["env_steps"], p["success"], "", p["wall_s"]] for p in curve)
    else:
        shutil.rmtree(checkpoints, ignore_errors=True)
        checkpoints.mkdir(parents=True)
        wall, cpu = teacher_seconds(teacher_path)
        clock = Clock(wall, cpu)
        record = {"env_id": env_id, "algo": ALGO, "learner": "torch", "seed": seed,
                  "obs_mode": "pixels", "env_kwargs": observation_kwargs(size),
                  "teacher": str(teacher or recipe["teacher"]), "teacher_wall_seconds": wall,
                  "teacher_cpu_seconds": cpu, "iterations": iterations, "n_envs": n_envs,
                  "recipe": recipe, "command": " ".join(sys.argv),
                  "student_inputs": {"pixels": [size, size, 3],
                                     "vector": ["desired_goal",
                                                *proprioception_fields(env_id)]}}
        (folder / "run.json").write_text(json.dumps(record, indent=2))
        with open(folder / "evaluations.csv", "w", newline="") as f:
            csv.writer(f).writerow(["timesteps", "success_rate", "mean_return", "wall_seconds"])
    teacher_model = load_model(teacher_path, probe)
    teacher_method = method(json.loads(teacher_path.with_suffix(".json").read_text()))
    student = DistilledPolicy(network, config)

    # the iterations that latest.pt counts (a data file of a later one, written before a stop
    # cut its checkpoint short, is played again)
    chunks = [np.load(checkpoints / f"data_{i}.npz") for i in range(done_iterations)]
    frames = [c["frames"] for c in chunks]
    vectors = [c["vectors"] for c in chunks]
    labels = [c["labels"] for c in chunks]
    cubes = [c["cubes"] for c in chunks]
    envs = gym.make_vec(env_id, num_envs=n_envs, **observation_kwargs(size))
    seeds = [1000 * seed + done_iterations * n_envs + r for r in range(n_envs)]
    obs, _ = envs.reset(seed=seeds)  # type: ignore[arg-type]
    for iteration in range(done_iterations, iterations):
        beta = max(0.0, 1.0 - iteration / recipe["beta_iterations"])
        steps = per_iteration * gym.spec(env_id).max_episode_steps
        note(f"{env_id}: iteration {iteration + 1}/{iterations}, beta {beta:.2f}, "
             f"{steps * n_envs:,} env steps", progress)
        new_f = np.empty((steps, n_envs, size, size, 3), np.uint8)
        new_v = np.empty((steps, n_envs, config["vector_size"]), np.float32)
        new_l = np.empty((steps, n_envs, config["action_size"]), np.float32)
        new_c = np.empty((steps, n_envs, goal_size), np.float32)
        network.eval()
        for t in range(steps):
            new_f[t], new_v[t] = student_inputs(obs, index)
            state_obs = {k: obs[k] for k in ("observation", "achieved_goal", "desired_goal")}
            new_l[t] = teacher_model.predict(state_obs, deterministic=True)[0]
            new_c[t] = obs["achieved_goal"] / CUBE_SCALE
            action = new_l[t].copy()
            own = rng.random(n_envs) >= beta
            if own.any():
                action[own] = student.predict(obs)[0][own]
            obs, *_ = envs.step(action)
        env_steps += steps * n_envs
        chunk = {"frames": new_f.reshape(-1, size, size, 3),
                 "vectors": new_v.reshape(-1, config["vector_size"]),
                 "labels": new_l.reshape(-1, config["action_size"]),
                 "cubes": new_c.reshape(-1, goal_size)}
        frames.append(chunk["frames"])
        vectors.append(chunk["vectors"])
        labels.append(chunk["labels"])
        cubes.append(chunk["cubes"])
        all_f = np.concatenate(frames) if len(frames) > 1 else frames[0]
        all_v, all_l, all_c = (np.concatenate(vectors), np.concatenate(labels),
                               np.concatenate(cubes))
        if len(frames) > 1:
            frames, vectors, labels, cubes = [all_f], [all_v], [all_l], [all_c]
        network.train()
        loss_sum = 0.0
        for _ in range(recipe["updates"]):
            rows = torch.from_numpy(rng.integers(0, len(all_l), recipe["batch_size"]))
            batch = random_shift(torch.from_numpy(all_f[rows.numpy()]).float(),
                                 recipe["shift"], generator)
            actions, located = network.both(batch, torch.from_numpy(all_v[rows.numpy()]))
            loss = ((actions - torch.from_numpy(all_l[rows.numpy()])) ** 2).mean() + \
                recipe["locate_weight"] * ((located - torch.from_numpy(all_c[rows.numpy()]))
                                           ** 2).mean()
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            loss_sum += loss.item()
        network.eval()
        rate, seconds = validate(student, env_id, size, eval_episodes, clock, env_steps, curve,
                                 folder)
        note(f"{env_id}: iteration {iteration + 1}: {len(all_l):,} labelled states, loss "
             f"{loss_sum / recipe['updates']:.4f}, validation success {rate:.0%}, "
             f"{seconds['wall_seconds'] / 60:.1f} min", progress)
        np.savez(checkpoints / f"data_{iteration}.npz", frames=chunk["frames"],
                 vectors=chunk["vectors"], labels=chunk["labels"], cubes=chunk["cubes"])
        save_policy(folder / "model.zip", network, config)
        shutil.copy2(folder / "model.zip", checkpoints / f"student_{iteration + 1}.zip")
        torch.save({"network": network.state_dict(), "optimizer": optimizer.state_dict(),
                    "generator": generator.get_state(), "rng": rng.bit_generator.state,
                    "iterations": iteration + 1, "env_steps": env_steps, "curve": curve,
                    **clock.seconds()}, state_path.with_suffix(".partial"))
        state_path.with_suffix(".partial").replace(state_path)
    envs.close()
    save_policy(folder / "model.zip", network, config)
    record = json.loads((folder / "run.json").read_text())
    record.update(clock.seconds())
    (folder / "run.json").write_text(json.dumps(record, indent=2))
    if final_episodes:
        finish_pixels(folder, curve, clock, final_episodes, results, progress, {
            "algo": ALGO, "seed": seed, "env_steps": env_steps,
            "method": f"pixels {size}x{size}: DAgger student of the {teacher_method} state "
                      "policy",
            "teacher_wall_s": record["teacher_wall_seconds"],
            "teacher_cpu_s": record["teacher_cpu_seconds"]})
    return folder


def finish_pixels(folder: Path, curve: list[dict], clock, episodes: int,
                  results: str | Path | None, progress: bool, fields: dict) -> dict:
    """A pixel run's result: its policy chosen on validation (``select_student`` among the
    ``checkpoints/student_<k>.zip`` of its curve's points), ``episodes`` episodes from
    EVAL_SEED, the result (train.RESULT_KEYS, "obs_mode": "pixels", ``fields``: algo, seed,
    env_steps, method and any others) written to ``result.json`` and into ``results``.
    ``clock``: the run's (train.Clock); the evaluation counts in its seconds."""
    from .train import machine

    record = json.loads((folder / "run.json").read_text())
    env_id, size = record["env_id"], record["env_kwargs"]["width"]
    chosen, selected = select_student(folder, curve, len(curve))
    note(f"{env_id}: final evaluation, {episodes} episodes (the policy of {selected:,} env "
         "steps)", progress)
    final = success_rate(chosen, gym.make(env_id, **observation_kwargs(size)), episodes,
                         EVAL_SEED, progress=progress)
    seconds = clock.seconds()
    result = {
        "env_id": env_id, **fields, "wall_s": seconds["wall_seconds"],
        "cpu_s": seconds["cpu_seconds"], "episodes": episodes,
        "success": final["success_rate"], "selected_env_steps": selected,
        "curve": curve + [{"env_steps": fields["env_steps"],
                           "wall_s": round(seconds["wall_seconds"], 1),
                           "success": final["success_rate"]}],
        "learner": "torch", "demo_env_steps": 0, "machine": machine(), "obs_mode": "pixels"}
    text = json.dumps(result, indent=1) + "\n"
    (folder / "result.json").write_text(text)
    if results is not None:
        Path(results).mkdir(parents=True, exist_ok=True)
        (Path(results) / f"{folder.name}.json").write_text(text)
    return result
