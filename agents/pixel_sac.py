"""Pixel SAC + HER with no privileged state: DrQ-style soft actor-critic (Kostrikov et al.
2020) on the frame, the goal and the pad's own state, no teacher and no state critic.

    rigid-gym train rigid_gym/Push-v0 --obs-mode pixels --algo drq --seed 0
    rigid-gym train rigid_gym/Push-v0 --obs-mode pixels --algo drq --seed 0 --resume

Actor and critic see what the distilled student sees (``distill.student_inputs``: the
``size`` x ``size`` uint8 frame from the batched renderer, ``desired_goal`` and the pad's
state), never the cubes' state. The achieved goal (the cubes' positions) is read only where
the env's reward is: hindsight relabelling (HER, ``future`` goals, ``her_k`` relabelled per
original) recomputes the sparse reward of a replayed step with ``compute_reward``, as the
env itself would have given it for that goal.

The critic owns the encoder (``distill.encoder_layers``: strided 3x3 convolutions, a linear
layer with LayerNorm and tanh) and two Q heads on its features, the vector and the action;
the actor is an MLP on the encoder's features with the gradient stopped (DrQ: only the
critic's loss trains the encoder). Every sampled frame, and its successor, is shifted by up
to ``shift`` pixels (``distill.random_shift``). The next action of the target is taken on
the target encoder's features (one encoder pass less per update than DrQ's, which encodes the
next frame with both). The temperature is learned towards an entropy of -action size.

The replay buffer holds whole episodes (every env's episodes have ``max_episode_steps``
steps: Push neither terminates nor stops early), each frame stored once as uint8 (the next
observation of step t is the episode's frame t + 1): ``buffer_episodes`` x (T + 1) frames. At
48 x 48 that is 7 kB a frame, 1.4 GB for 4,000 Push episodes (200k steps); SB3's buffer keeps
two float copies per transition by default (``optimize_memory_usage`` is refused with HER),
~42 GB for 1M transitions of uint8 84 x 84 frames, which is why its default does not fit.

Every ``eval_every`` env steps (whole episodes of the ``n_envs`` envs) the deterministic
policy plays ``eval_episodes`` episodes on seeds from VALIDATION_SEED (the curve), is saved
in the distilled student's form (``distill.save_policy``: ``rigid-gym evaluate`` and
``record`` load it as ``DistilledPolicy``) to ``checkpoints/student_<k>.zip``, and the run
checkpoints: ``latest.pt`` (networks, optimizers, temperature, random states, counters) and
``buffer_<k>.npz`` (the episodes since the last one), from which ``--resume`` goes on (the
envs start afresh). At the end, as the distilled runs: the best of the second half's
policies on validation, 100 episodes from EVAL_SEED (``distill.finish_pixels``).
"""

from __future__ import annotations

import copy
import csv
import json
import math
import shutil
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from .distill import (
    DistilledPolicy,
    encode,
    encoder_layers,
    finish_pixels,
    make_network,
    observation_kwargs,
    proprioception_fields,
    proprioception_index,
    random_shift,
    save_policy,
    student_inputs,
    validate,
)
from .progress import note

ALGO = "drq"
LOG_STD = (-5.0, 2.0)
"""The actor's log standard deviation, squashed into this range (DrQ's)."""


def make_networks(size: int, vector_size: int, action_size: int, channels: int = 16,
                  features: int = 50, hidden: int = 256):
    """(critic, actor). critic: ``encoder_layers`` (``critic.encode(frames)``: (B, features))
    and ``critic.q(z, vector, action)``: two Q values (B,), (B,), each an MLP of two ``hidden``
    ReLU layers. actor: ``actor(z, vector)``: (mean, log_std) (B, action_size) each, an MLP of
    two ``hidden`` ReLU layers (``trunk``) then the linear ``mean`` and ``log_std``."""
    import torch
    from torch import nn

    def mlp(inputs: int, outputs: int):
        return nn.Sequential(nn.Linear(inputs, hidden), nn.ReLU(), nn.Linear(hidden, hidden),
                             nn.ReLU(), nn.Linear(hidden, outputs))

    class Critic(nn.Module):
        def __init__(self):
            super().__init__()
            self.conv, self.project = encoder_layers(size, channels, features)
            self.q1 = mlp(features + vector_size + action_size, 1)
            self.q2 = mlp(features + vector_size + action_size, 1)

        def encode(self, frames):
            return encode(self.conv, self.project, frames)

        def q(self, z, vector, action):
            x = torch.cat([z, vector, action], dim=1)
            return self.q1(x).squeeze(1), self.q2(x).squeeze(1)

    class Actor(nn.Module):
        def __init__(self):
            super().__init__()
            self.trunk = mlp(features + vector_size, hidden)[:-1]  # up to the last ReLU
            self.mean = nn.Linear(hidden, action_size)
            self.log_std = nn.Linear(hidden, action_size)

        def forward(self, z, vector):
            h = self.trunk(torch.cat([z, vector], dim=1))
            low, high = LOG_STD
            return self.mean(h), low + 0.5 * (high - low) * (torch.tanh(self.log_std(h)) + 1)

    return Critic(), Actor()


def sample(actor, z, vector):
    """(action, log_prob): a tanh-squashed Gaussian sample of ``actor`` and its log density
    (B, action_size), (B,)."""
    import torch

    mean, log_std = actor(z, vector)
    std = log_std.exp()
    u = mean + std * torch.randn_like(mean)
    action = torch.tanh(u)
    log_prob = (-0.5 * ((u - mean) / std) ** 2 - log_std - 0.5 * math.log(2 * math.pi)).sum(1)
    return action, log_prob - torch.log(1 - action ** 2 + 1e-6).sum(1)


def acting_policy(critic, actor, config: dict) -> DistilledPolicy:
    """The deterministic policy tanh(mean) on the critic's encoder, as a distilled student
    (``make_network`` with ``located`` 0): conv and project from the critic, the head from the
    actor's trunk and mean, copies of the weights."""
    network = make_network(config["size"], config["vector_size"], config["action_size"],
                           **config["network"])
    weights = {f"{part}.{key}": value for part in ("conv", "project")
               for key, value in getattr(critic, part).state_dict().items()}
    for k, layer in ((0, actor.trunk[0]), (2, actor.trunk[2]), (4, actor.mean)):
        weights[f"head.{k}.weight"], weights[f"head.{k}.bias"] = layer.weight, layer.bias
    network.load_state_dict({key: value.detach().clone() for key, value in weights.items()})
    network.eval()
    return DistilledPolicy(network, config)


class EpisodeBuffer:
    """Whole episodes of T steps, a ring of ``capacity`` episodes: frames (E, T + 1, H, W, 3)
    uint8, proprioception (E, T + 1, k), achieved goals (E, T + 1, g), the desired goal
    (E, g) and actions (E, T, a), float32. ``add`` takes a batch of episodes; ``sample``
    draws steps with HER's future goals."""

    def __init__(self, capacity: int, steps: int, size: int, proprio: int, goal: int,
                 action: int):
        self.capacity, self.steps, self.count, self.next = capacity, steps, 0, 0
        # zeros: pages are mapped as the ring fills, not at once
        self.frames = np.zeros((capacity, steps + 1, size, size, 3), np.uint8)
        self.proprio = np.zeros((capacity, steps + 1, proprio), np.float32)
        self.achieved = np.zeros((capacity, steps + 1, goal), np.float32)
        self.goal = np.zeros((capacity, goal), np.float32)
        self.actions = np.zeros((capacity, steps, action), np.float32)

    def add(self, episodes: dict) -> None:
        """Episodes {"frames" (n, T + 1, H, W, 3), "proprio", "achieved", "goal",
        "actions"}, over the oldest once full."""
        for k in range(len(episodes["goal"])):
            for name in ("frames", "proprio", "achieved", "goal", "actions"):
                getattr(self, name)[self.next] = episodes[name][k]
            self.next = (self.next + 1) % self.capacity
            self.count = min(self.count + 1, self.capacity)

    def sample(self, batch: int, her_k: int, rng: np.random.Generator, compute_reward):
        """A batch of steps: (frames, next frames (B, H, W, 3) uint8, vectors, next vectors
        (B, g + k): goal then proprioception, actions (B, a), rewards (B,)). A step's goal
        is, with probability her_k / (her_k + 1), the achieved goal of a later step of its
        episode (HER's ``future``), its reward ``compute_reward(achieved', goal)`` of the
        step's outcome."""
        e = rng.integers(0, self.count, batch)
        t = rng.integers(0, self.steps, batch)
        goal = self.goal[e].copy()
        relabel = rng.random(batch) < her_k / (her_k + 1)
        future = rng.integers(t + 1, self.steps + 1)
        goal[relabel] = self.achieved[e[relabel], future[relabel]]
        rewards = np.asarray(compute_reward(self.achieved[e, t + 1], goal, None), np.float32)
        vectors = np.concatenate([goal, self.proprio[e, t]], axis=1)
        next_vectors = np.concatenate([goal, self.proprio[e, t + 1]], axis=1)
        return (self.frames[e, t], self.frames[e, t + 1], vectors, next_vectors,
                self.actions[e, t], rewards)


def train_pixel_sac(env_id: str, settings: dict, *, seed: int, folder: Path, resume: bool,
                    timesteps: int | None, eval_episodes: int, final_episodes: int,
                    results: str | Path | None, progress: bool) -> Path:
    """The loop of the module docstring, into ``folder``; ``settings[ALGO]``: hyperparams.yml's
    recipe (size, n_envs, n_timesteps, buffer_episodes, batch_size, gradient_steps,
    learning_rate, gamma, tau, learning_starts, her_k, shift, init_alpha, eval_every,
    network). ``timesteps``: overrides n_timesteps (rounded up to whole episodes of the
    envs). Returns ``folder``."""
    import torch
    import torch.nn.functional as F

    from .train import Clock

    recipe = dict(settings[ALGO])
    size, n_envs = recipe["size"], recipe["n_envs"]
    steps = int(gym.spec(env_id).max_episode_steps or 0)
    round_size = n_envs * steps  # env steps of one episode of every env
    total = -(-(timesteps if timesteps is not None else recipe["n_timesteps"]) // round_size)
    every = max(1, recipe["eval_every"] // round_size)  # rounds between evaluations
    index = proprioception_index(env_id)
    probe: gym.Env = gym.make(env_id)
    goal_size = probe.observation_space["desired_goal"].shape[0]  # type: ignore[index]
    action_size = int(np.prod(probe.action_space.shape or (1,)))
    network = {"channels": 16, "features": 50, "hidden": 256, **recipe.get("network", {})}
    config = {"env_id": env_id, "size": size, "vector_size": goal_size + len(index),
              "action_size": action_size, "proprioception_index": index.tolist(),
              "network": {**network, "located": 0}}
    torch.manual_seed(seed)
    critic, actor = make_networks(size, config["vector_size"], action_size, **network)
    target = copy.deepcopy(critic)
    log_alpha = torch.tensor(math.log(recipe["init_alpha"]), requires_grad=True)
    critic_opt = torch.optim.Adam(critic.parameters(), lr=recipe["learning_rate"])
    actor_opt = torch.optim.Adam(actor.parameters(), lr=recipe["learning_rate"])
    alpha_opt = torch.optim.Adam([log_alpha], lr=recipe["learning_rate"])
    generator = torch.Generator().manual_seed(seed)
    rng = np.random.default_rng(seed)
    buffer = EpisodeBuffer(recipe["buffer_episodes"], steps, size, len(index), goal_size,
                           action_size)
    checkpoints = folder / "checkpoints"
    state_path = checkpoints / "latest.pt"
    rounds, curve = 0, []
    if resume:
        if not state_path.is_file():
            raise ValueError(f"--resume: no checkpoint at {state_path}")
        state = torch.load(state_path, weights_only=False)
        for part, module in (("critic", critic), ("target", target), ("actor", actor),
                             ("critic_opt", critic_opt), ("actor_opt", actor_opt),
                             ("alpha_opt", alpha_opt)):
            module.load_state_dict(state[part])
        with torch.no_grad():
            log_alpha.copy_(state["log_alpha"])
        generator.set_state(state["generator"])
        rng.bit_generator.state = state["rng"]
        torch.set_rng_state(state["torch_rng"])
        rounds, curve = state["rounds"], state["curve"]
        clock = Clock(state["wall_seconds"], state["cpu_seconds"])
        starts = sorted(int(p.stem.split("_")[1]) for p in checkpoints.glob("buffer_*.npz"))
        for start in starts:  # (one of rounds past latest.pt's, cut short by a stop: played again)
            if start < rounds:
                buffer.add(dict(np.load(checkpoints / f"buffer_{start}.npz")))
        record = json.loads((folder / "run.json").read_text())
        record["resumed_at"] = record.get("resumed_at", []) + [rounds * round_size]
        record["timesteps"] = total * round_size
        (folder / "run.json").write_text(json.dumps(record, indent=2))
    else:
        shutil.rmtree(checkpoints, ignore_errors=True)
        checkpoints.mkdir(parents=True)
        clock = Clock()
        record = {"env_id": env_id, "algo": ALGO, "learner": "torch", "seed": seed,
                  "obs_mode": "pixels", "env_kwargs": observation_kwargs(size),
                  "timesteps": total * round_size, "n_envs": n_envs, "recipe": recipe,
                  "command": " ".join(sys.argv),
                  "inputs": {"pixels": [size, size, 3],
                             "vector": ["desired_goal", *proprioception_fields(env_id)]}}
        (folder / "run.json").write_text(json.dumps(record, indent=2))
    with open(folder / "evaluations.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["timesteps", "success_rate", "mean_return", "wall_seconds"])
        writer.writerows([p["env_steps"], p["success"], "", p["wall_s"]] for p in curve)

    envs = gym.make_vec(env_id, num_envs=n_envs, **observation_kwargs(size))
    compute_reward = envs.unwrapped.compute_reward  # type: ignore[attr-defined]
    obs, _ = envs.reset(seed=[1000 * seed + (rounds + r) * n_envs  # type: ignore[arg-type]
                              for r in range(n_envs)])
    target_entropy = -float(action_size)
    gamma, tau, shift = recipe["gamma"], recipe["tau"], recipe["shift"]
    saved_from = rounds  # the episodes of rounds from here go into the next buffer_<k>.npz
    new_episodes: list[dict] = []

    def update():
        frames, next_frames, vectors, next_vectors, actions, rewards = (
            torch.from_numpy(x) for x in buffer.sample(recipe["batch_size"], recipe["her_k"],
                                                       rng, compute_reward))
        frames = random_shift(frames.float(), shift, generator)
        next_frames = random_shift(next_frames.float(), shift, generator)
        alpha = log_alpha.exp().detach()
        with torch.no_grad():
            z_next = target.encode(next_frames)
            next_actions, next_log_prob = sample(actor, z_next, next_vectors)
            q1, q2 = target.q(z_next, next_vectors, next_actions)
            y = rewards + gamma * (torch.min(q1, q2) - alpha * next_log_prob)
        z = critic.encode(frames)
        q1, q2 = critic.q(z, vectors, actions)
        critic_loss = F.mse_loss(q1, y) + F.mse_loss(q2, y)
        critic_opt.zero_grad()
        critic_loss.backward()
        critic_opt.step()
        z = z.detach()
        new_actions, log_prob = sample(actor, z, vectors)
        actor_loss = (alpha * log_prob - torch.min(*critic.q(z, vectors, new_actions))).mean()
        actor_opt.zero_grad()
        actor_loss.backward()
        actor_opt.step()
        alpha_loss = -(log_alpha * (log_prob.detach() + target_entropy)).mean()
        alpha_opt.zero_grad()
        alpha_loss.backward()
        alpha_opt.step()
        with torch.no_grad():
            for p, q in zip(target.parameters(), critic.parameters()):
                p.mul_(1 - tau).add_(q, alpha=tau)
        return critic_loss.item()

    while rounds < total:
        episode = {"frames": np.empty((n_envs, steps + 1, size, size, 3), np.uint8),
                   "proprio": np.empty((n_envs, steps + 1, len(index)), np.float32),
                   "achieved": np.empty((n_envs, steps + 1, goal_size), np.float32),
                   "goal": obs["desired_goal"].astype(np.float32),
                   "actions": np.empty((n_envs, steps, action_size), np.float32)}
        losses = []
        for t in range(steps):
            frames, vectors = student_inputs(obs, index)
            episode["frames"][:, t], episode["proprio"][:, t] = frames, obs["observation"][
                :, index]
            episode["achieved"][:, t] = obs["achieved_goal"]
            env_steps = (rounds * steps + t) * n_envs
            if env_steps < recipe["learning_starts"]:
                action = rng.uniform(-1, 1, (n_envs, action_size)).astype(np.float32)
            else:
                with torch.no_grad():
                    z = critic.encode(torch.from_numpy(frames).float())
                    action = sample(actor, z, torch.from_numpy(vectors))[0].numpy()
            episode["actions"][:, t] = action
            obs, _, terminated, truncated, info = envs.step(action)
            ended = terminated | truncated
            if ended.any() != (t == steps - 1) or ended.any() != ended.all():
                raise ValueError(f"train: {ALGO} takes episodes that all run the time limit "
                                 f"({steps} steps); {env_id}'s ended at step {t + 1}")
            if buffer.count and env_steps + n_envs > recipe["learning_starts"]:
                losses += [update() for _ in range(recipe["gradient_steps"])]
        last = info["final_obs"]
        episode["frames"][:, steps] = np.stack([o["pixels"] for o in last])
        episode["proprio"][:, steps] = np.stack([o["observation"][index] for o in last])
        episode["achieved"][:, steps] = np.stack([o["achieved_goal"] for o in last])
        buffer.add(episode)
        new_episodes.append(episode)
        rounds += 1
        if rounds % every and rounds != total:
            continue
        policy = acting_policy(critic, actor, config)
        env_steps = rounds * round_size
        rate, seconds = validate(policy, env_id, size, eval_episodes, clock, env_steps, curve,
                                 folder)
        note(f"{env_id}: {env_steps:,} env steps, critic loss "
             f"{np.mean(losses) if losses else float('nan'):.4f}, alpha "
             f"{log_alpha.exp().item():.3f}, validation success {rate:.0%}, "
             f"{seconds['wall_seconds'] / 60:.1f} min", progress)
        chunk: dict[str, Any] = {name: np.concatenate([e[name] for e in new_episodes])
                                 for name in new_episodes[0]}
        np.savez(checkpoints / f"buffer_{saved_from}.npz", **chunk)
        saved_from, new_episodes = rounds, []
        save_policy(folder / "model.zip", policy.network, config, ALGO)
        shutil.copy2(folder / "model.zip", checkpoints / f"student_{len(curve)}.zip")
        torch.save({"critic": critic.state_dict(), "target": target.state_dict(),
                    "actor": actor.state_dict(), "critic_opt": critic_opt.state_dict(),
                    "actor_opt": actor_opt.state_dict(), "alpha_opt": alpha_opt.state_dict(),
                    "log_alpha": log_alpha.detach(), "generator": generator.get_state(),
                    "rng": rng.bit_generator.state, "torch_rng": torch.get_rng_state(),
                    "rounds": rounds, "curve": curve, **seconds},
                   state_path.with_suffix(".partial"))
        state_path.with_suffix(".partial").replace(state_path)
    envs.close()
    record = json.loads((folder / "run.json").read_text())
    record.update(clock.seconds())
    (folder / "run.json").write_text(json.dumps(record, indent=2))
    if final_episodes:
        finish_pixels(folder, curve, clock, final_episodes, results, progress, {
            "algo": ALGO, "seed": seed, "env_steps": rounds * round_size,
            "method": f"pixels {size}x{size}: SAC + HER, random shifts (DrQ), no privileged "
                      "state"})
    return folder
