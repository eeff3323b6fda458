"""SHA-256 of the v0 tasks' trajectories under their scripted policies, to check that a solver
change leaves them bit-identical:

    python benchmarks/task_hashes.py > before.txt   # on the old build
    python benchmarks/task_hashes.py > after.txt    # on the new build
    diff before.txt after.txt

For every task (Push, Stack, Throw, Tower, Insert), ``--episodes`` episodes reset with seeds 0, 1, ... are
played with ``rigid_gym.envs.scripted``; each episode's hash covers every env step's
observation, reward and flags, and the world's full state (positions, orientations,
velocities, angular momenta and velocities) after each step. One line per task and
episode, then one per task.
"""

from __future__ import annotations

import argparse
import hashlib

import gymnasium as gym
import numpy as np
from rigid_gym.envs.scripted import scripted_policy

import rigid_gym  # noqa: F401  (registers the envs)

TASKS = ("Push", "Stack", "Throw", "Tower", "Insert")


def episode_hash(env: gym.Env, policy, seed: int) -> str:
    """Hex SHA-256 of one scripted episode of ``env`` reset with ``seed``."""
    digest = hashlib.sha256()
    obs, _ = env.reset(seed=seed)
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        world = env.unwrapped.world
        for key in sorted(obs):
            digest.update(np.ascontiguousarray(obs[key]).tobytes())
        for name in ("position", "orientation", "velocity", "angular_momentum",
                     "angular_velocity"):
            digest.update(np.ascontiguousarray(getattr(world.state, name)).tobytes())
        digest.update(np.array([reward, terminated, truncated, info["is_success"]],
                               dtype=np.float64).tobytes())
        done = terminated or truncated
    return digest.hexdigest()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=10)
    args = parser.parse_args()
    for task in TASKS:
        env = gym.make(f"rigid_gym/{task}-v0")
        policy = scripted_policy(env)
        total = hashlib.sha256()
        for seed in range(args.episodes):
            h = episode_hash(env, policy, seed)
            total.update(h.encode())
            print(f"{task} seed {seed}: {h}")
        print(f"{task} all: {total.hexdigest()}")
        env.close()


if __name__ == "__main__":
    main()
