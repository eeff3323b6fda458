"""The policies that drive an env outside training: random actions, the scripted policy, or a
trained stable-baselines3 model. ``rigid-gym record`` and ``rigid-gym dataset`` play them
(``rigid_gym.cli``, ``rigid_gym.agents.datasets``)."""

from __future__ import annotations


def make_policy(env, policy: str, algo: str | None, seed: int):
    """observation -> action for ``env``: random (the action space sampled, seeded with
    ``seed``), scripted (``rigid_gym.envs.scripted``) or a stable-baselines3 model .zip (its
    algorithm ``algo``, else its settings file's, else the zip's)."""
    if policy == "random":
        env.action_space.seed(seed)
        return lambda observation: env.action_space.sample()
    if policy == "scripted":
        from ..envs.scripted import scripted_policy

        return scripted_policy(env)
    from .evaluate import load_model, run_metadata

    model = load_model(policy, env, algo or run_metadata(policy).get("algo"))
    return lambda observation: model.predict(observation, deterministic=True)[0]
