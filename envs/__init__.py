"""The Gymnasium tasks (imported as ``rigid_gym.envs``), registered on ``import rigid_gym``:

    import gymnasium as gym
    import rigid_gym
    env = gym.make("rigid_gym/Push-v0")          # or Stack, Throw, Reach, ...; ...Dense-v0 for -distance
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=256)   # natively batched (envs/vector.py)

``ENV_IDS`` lists every id. Entry points are strings, so registering imports no task module.
"""

import gymnasium as gym

TASKS = {"Push": 50, "Stack": 100, "Throw": 50}
"""Task name -> episode length in env steps of 0.04 s."""
TASKS.update({"Reach": 50, "PickAndPlace": 50, "Slide": 50, "Flip": 50})  # panda-gym's lengths
MODULES = {"PickAndPlace": "pick_and_place"}
"""Task name -> its module's name where that is not the name in lower case."""
TASKS["Tower"] = 150  # 50 per cube, for the default 3 (envs/tower.py)
TASKS["Insert"] = 50


def _register() -> list[str]:
    ids = []
    for task, steps in TASKS.items():
        for suffix, reward_type in (("", "sparse"), ("Dense", "dense")):
            env_id = f"rigid_gym/{task}{suffix}-v0"
            module = MODULES.get(task, task.lower())
            if env_id not in gym.registry:
                gym.register(env_id, entry_point=f"rigid_gym.envs.{module}:{task}Env",
                             vector_entry_point=f"rigid_gym.envs.vector:{module}",
                             max_episode_steps=steps, kwargs={"reward_type": reward_type})
            ids.append(env_id)
    return ids


ENV_IDS = _register()
