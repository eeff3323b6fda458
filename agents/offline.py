"""Behaviour cloning from a Minari dataset: the offline baseline.

    python -m rigid_gym.agents.offline rigid_gym/push/expert-v0 rigid_gym/stack/expert-v0 \\
        --episodes 100

A small MLP maps (observation, desired_goal) to the action, trained by mean squared error on
every (observation, action) pair of the dataset (Pomerleau 1991; the goal-conditioned
form of the Minari and D4RL baselines), then evaluated deterministically on the evaluation
seeds that the online baselines use (``rigid_gym.agents.evaluate.success_rate``).
"""

from __future__ import annotations

import argparse

import numpy as np
import torch as th
from torch import nn

from .datasets import load
from .evaluate import success_rate

INPUTS = ("observation", "desired_goal")
"""The observation entries the policy reads (achieved_goal is inside ``observation``)."""


class ClonedPolicy:
    """An MLP policy, obs dict -> action, with stable-baselines3's ``predict`` (so
    ``success_rate`` evaluates it). ``net``: the torch module; ``mean``, ``scale``: the input
    normalisation, ``(inputs,)`` each."""

    def __init__(self, net: nn.Module, mean: np.ndarray, scale: np.ndarray):
        self.net, self.mean, self.scale = net, mean, scale

    def predict(self, observation: dict, deterministic: bool = True):
        x = np.concatenate([np.asarray(observation[key], np.float32) for key in INPUTS], -1)
        with th.no_grad():
            action = self.net(th.as_tensor((x - self.mean) / self.scale)).numpy()
        return action, None


def clone(dataset_id: str, hidden: tuple[int, ...] = (256, 256), epochs: int = 50,
          batch_size: int = 256, learning_rate: float = 1e-3, seed: int = 0) -> ClonedPolicy:
    """Fit an MLP (``hidden`` widths, ReLU, tanh output: the action space is [-1, 1]) to the
    actions of every step of ``dataset_id`` for ``epochs`` passes of Adam; seeded with
    ``seed`` (torch's generator and the batch order)."""
    dataset = load(dataset_id)
    episodes = list(dataset.iterate_episodes())
    x = np.concatenate([np.concatenate([e.observations[key][:-1] for key in INPUTS], -1)
                        for e in episodes]).astype(np.float32)
    y = np.concatenate([e.actions for e in episodes]).astype(np.float32)
    mean, scale = x.mean(0), x.std(0) + 1e-6
    th.manual_seed(seed)
    layers, width = [], x.shape[1]
    for size in hidden:
        layers += [nn.Linear(width, size), nn.ReLU()]
        width = size
    net = nn.Sequential(*layers, nn.Linear(width, y.shape[1]), nn.Tanh())
    optimizer = th.optim.Adam(net.parameters(), lr=learning_rate)
    inputs, targets = th.as_tensor((x - mean) / scale), th.as_tensor(y)
    order = np.random.default_rng(seed)
    for _ in range(epochs):
        for batch in np.array_split(order.permutation(len(x)), max(1, len(x) // batch_size)):
            loss = ((net(inputs[batch]) - targets[batch]) ** 2).sum(1).mean()
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
    return ClonedPolicy(net.eval(), mean, scale)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Behaviour cloning from Minari datasets: "
                                     "train on each, print its success rate")
    parser.add_argument("datasets", nargs="+", metavar="ID")
    parser.add_argument("--episodes", type=int, default=100, help="evaluation episodes")
    parser.add_argument("--epochs", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    th.set_num_threads(1)
    print("| dataset | transitions | behaviour cloning, success |")
    print("|---|---|---|")
    for dataset_id in args.datasets:
        dataset = load(dataset_id)
        policy = clone(dataset_id, epochs=args.epochs, seed=args.seed)
        result = success_rate(policy, dataset.recover_environment(eval_env=True), args.episodes)
        print(f"| {dataset_id} | {dataset.total_steps:,} | {result['success_rate']:.0%} over "
              f"{args.episodes} episodes |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
