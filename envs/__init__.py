"""The Gymnasium tasks (imported as ``rigid_gym.envs``): Push, Stack and Throw are built here."""
