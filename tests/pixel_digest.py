"""frame_digest, for tests/test_pixels.py and the fresh processes it starts (which import this
small module rather than the test module and its SB3)."""

import hashlib

import gymnasium as gym
import numpy as np

import rigid_gym  # noqa: F401  (registers the ids)


def frame_digest(env_id: str, num_envs: int, steps: int) -> str:
    """sha256 of every frame of make_vec(env_id, num_envs, obs_mode="pixels") from
    reset(seed=7) over ``steps`` seeded random steps."""
    envs = gym.make_vec(env_id, num_envs=num_envs, obs_mode="pixels")
    digest = hashlib.sha256(envs.reset(seed=7)[0]["pixels"].tobytes())
    actions = np.random.default_rng(1).uniform(-1, 1, (steps,) + envs.action_space.shape)
    for a in actions:
        digest.update(envs.step(a)[0]["pixels"].tobytes())
    return digest.hexdigest()
