"""Stable-baselines3 baselines (imported as ``rigid_gym.agents``)."""
