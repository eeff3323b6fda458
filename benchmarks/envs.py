"""The tasks as a user meets them: scripted success rates, env steps per second, frame times.

1. Scripted policies (``rigid_gym.envs.scripted``) over seeded episodes (seeds 0..N-1) of each
   task's sparse id: success rate at the episode's end, mean return, mean episode wall time.
2. Env steps per second through ``gym.make`` in one process (uniform random actions from a
   seeded generator, resets included), the median of ``--repeats`` timings of ``--steps``
   steps each after a warm-up; each task's panda-gym counterpart (``COUNTERPARTS``: PandaPush-v3
   for Push, Stack and Throw, PandaReach-v3, PandaPickAndPlace-v3, PandaSlide-v3 and
   PandaFlip-v3 for theirs, PandaStack-v3 for Tower, PandaPickAndPlace-v3 for Insert) timed the
   same way in the same run when panda-gym is installed (``pip install panda-gym``), and our
   rate as a ratio to it.
3. ``render_mode="rgb_array"`` frame time (480 x 480), the median over 20 frames of an
   episode, after the first frame (which builds the renderer); and a picture of every task at
   the start and at the end of a scripted episode (seed 1), written to ``--frames`` (default
   docs/images).
4. The two-finger gripper (``effector="gripper"``) on every task that grasps (``GRASPING``):
   its scripted policies' success rates, and its env steps/s against the same task with the
   pad, both timed in turn in each round of the same run (the ratio gripper / pad).

    python benchmarks/envs.py                    # all four tables, about 5 minutes on 2 cores
    python benchmarks/envs.py --only speed       # one table: success, speed, render or gripper
"""

import argparse
import functools
import statistics
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
from rigid_gym.envs.scripted import scripted_policy

import rigid_gym  # noqa: F401  (registers the ids)

TASKS = ["rigid_gym/Push-v0", "rigid_gym/Stack-v0", "rigid_gym/Throw-v0"]
TASKS += ["rigid_gym/Reach-v0", "rigid_gym/PickAndPlace-v0", "rigid_gym/Slide-v0",
          "rigid_gym/Flip-v0"]
PANDA_PUSH = "PandaPush-v3"
COUNTERPARTS = {"rigid_gym/Push-v0": PANDA_PUSH, "rigid_gym/Stack-v0": PANDA_PUSH,
                "rigid_gym/Throw-v0": PANDA_PUSH}
COUNTERPARTS.update({"rigid_gym/Reach-v0": "PandaReach-v3",
                     "rigid_gym/PickAndPlace-v0": "PandaPickAndPlace-v3",
                     "rigid_gym/Slide-v0": "PandaSlide-v3", "rigid_gym/Flip-v0": "PandaFlip-v3"})
TASKS += ["rigid_gym/Tower-v0", "rigid_gym/Insert-v0"]
COUNTERPARTS.update({"rigid_gym/Tower-v0": "PandaStack-v3",
                     "rigid_gym/Insert-v0": "PandaPickAndPlace-v3"})
"""Each task's panda-gym env for the speed ratio (Stack's and Throw's have none of the same
kind: PandaPush-v3, one cube; Tower's the nearest there, a tower of cubes: PandaStack-v3;
Insert's a peg carried and put down: PandaPickAndPlace-v3)."""
GRASPING = ["rigid_gym/Stack-v0", "rigid_gym/Throw-v0", "rigid_gym/PickAndPlace-v0",
            "rigid_gym/Tower-v0", "rigid_gym/Insert-v0"]
"""The tasks that take ``effector="gripper"``."""


def scripted_success(env_id: str, episodes: int, **kwargs) -> tuple[float, float, float]:
    """(success rate, mean return, mean seconds per episode) of the scripted policy of
    ``gym.make(env_id, **kwargs)``."""
    env = gym.make(env_id, **kwargs)
    policy = scripted_policy(env)
    successes, returns = [], []
    start = time.perf_counter()
    for seed in range(episodes):
        obs, info = env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            obs, reward, terminated, truncated, info = env.step(policy(obs))
            total += reward
            done = terminated or truncated
        successes.append(info["is_success"])
        returns.append(total)
    seconds = (time.perf_counter() - start) / episodes
    return float(np.mean(successes)), float(np.mean(returns)), seconds


def random_stepper(env_id: str, steps: int, scripted: bool = False, **kwargs):
    """A function () -> env steps/s of ``steps`` steps of ``gym.make(env_id, **kwargs)`` with
    seeded uniform random actions (or, ``scripted``, its scripted policy's, the policy's own
    time included), resetting where an episode ends; warmed up by 100 steps."""
    if env_id == "PandaFlip-v3":
        without_missing_textures()
    env = gym.make(env_id, **kwargs)
    rng = np.random.default_rng(0)
    observation = env.reset(seed=0)[0]
    env.action_space.seed(0)
    policy = scripted_policy(env) if scripted else None

    def run(count) -> float:
        nonlocal observation
        start = time.perf_counter()
        for _ in range(count):
            action = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32) \
                if policy is None else policy(observation)
            observation, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                observation = env.reset()[0]
        return count / (time.perf_counter() - start)

    run(100)  # warm-up: first allocations and caches
    return functools.partial(run, steps)


def without_missing_textures() -> None:
    """panda-gym 3.0.7's wheel lacks the texture colored_cube.png (panda-gym #71), so
    PandaFlip-v3 fails at construction ("Error loading texture"): leave out a box's texture
    whose file is missing. A texture is a look, loaded once: no part of a step's cost."""
    import os

    import panda_gym.assets
    from panda_gym.pybullet import PyBullet

    original = PyBullet.create_box
    if getattr(original, "drops_missing_textures", False):
        return

    def create_box(self, *args, texture=None, **kwargs):
        if texture is not None and not os.path.exists(
                os.path.join(panda_gym.assets.get_data_path(), texture)):
            texture = None
        return original(self, *args, texture=texture, **kwargs)

    create_box.drops_missing_textures = True
    PyBullet.create_box = create_box


def rates_in_rounds(runs: dict, repeats: int) -> dict:
    """{key: [rate of each round]} for ``runs`` {key: () -> rate}: in each of ``repeats``
    rounds every run is timed once, in turn, so rates compared between keys were timed in the
    same stretch of the run, whatever the machine's drift in speed."""
    rates = {key: [] for key in runs}
    for _ in range(repeats):
        for key, run in runs.items():
            rates[key].append(run())
    return rates


def step_rates(env_ids: list[str], steps: int, repeats: int) -> dict[str, list[float]]:
    """{env id: env steps/s of each round} of ``steps`` random steps (resets included) of
    every env in turn in each of ``repeats`` rounds (rates_in_rounds)."""
    return rates_in_rounds({env_id: random_stepper(env_id, steps) for env_id in env_ids},
                           repeats)


def rate_and_ratio(rates: list[float], panda: list[float] | None) -> tuple[float, str]:
    """The median rate, and the median over rounds of rate / the counterpart's (or why
    none)."""
    if panda is None:
        return statistics.median(rates), "panda-gym not installed"
    return statistics.median(rates), f"{statistics.median(r / p for r, p in zip(rates, panda)):.2f}x"


def frame_milliseconds(env_id: str, frames: int = 20) -> float:
    env = gym.make(env_id, render_mode="rgb_array")
    env.reset(seed=0)
    env.render()  # first frame: tessellates the shapes
    times = []
    for _ in range(frames):
        env.step(env.action_space.sample())
        start = time.perf_counter()
        env.render()
        times.append(time.perf_counter() - start)
    return 1e3 * statistics.median(times)


def scripted_frames(env_id: str, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """rgb_array frames at the start and at the end of a scripted episode."""
    env = gym.make(env_id, render_mode="rgb_array")
    policy = scripted_policy(env)
    obs, _ = env.reset(seed=seed)
    start = env.render()
    done = False
    while not done:
        obs, _, terminated, truncated, _ = env.step(policy(obs))
        done = terminated or truncated
    return start, env.render()


PICTURE_COLUMNS = 5
"""Tasks per row of the task picture."""


def save_task_picture(path: Path) -> None:
    """One PNG: a cell per task, its start above its end, PICTURE_COLUMNS cells a row (the
    last row filled with white), at half the frames' resolution (2 x 2 means)."""
    import matplotlib.pyplot as plt

    cells = [np.concatenate(scripted_frames(env_id), axis=0) for env_id in TASKS]
    cells += [np.full_like(cells[0], 255)] * (-len(cells) % PICTURE_COLUMNS)
    rows = [np.concatenate(cells[i:i + PICTURE_COLUMNS], axis=1)
            for i in range(0, len(cells), PICTURE_COLUMNS)]
    picture = np.concatenate(rows, axis=0).astype(np.float64)
    h, w = picture.shape[0] // 2 * 2, picture.shape[1] // 2 * 2
    half = picture[:h, :w].reshape(h // 2, 2, w // 2, 2, 3).mean(axis=(1, 3))
    path.parent.mkdir(parents=True, exist_ok=True)
    plt.imsave(path, half.round().astype(np.uint8))
    print(f"\nwrote {path}: {', '.join(TASKS)}, {PICTURE_COLUMNS} a row, left to right; start "
          "above, end of a scripted episode (seed 1) below")


def panda_available() -> bool:
    try:
        import panda_gym  # noqa: F401
    except ImportError:
        return False
    return True


def print_speed_table(steps: int, repeats: int) -> None:
    """Env steps/s of every task and of its panda-gym counterpart (``COUNTERPARTS``, when
    installed), timed in turn in each of ``repeats`` rounds of ``steps`` steps; ratios are the
    medians of the rounds'."""
    print(f"\nEnv steps/s, gym.make, one env, random actions, resets included (median of "
          f"{repeats} rounds of {steps} steps, every env timed in turn in each round)\n")
    pandas = sorted(set(COUNTERPARTS.values())) if panda_available() else []
    rates = step_rates(TASKS + pandas, steps, repeats)
    print("| env | steps/s | panda-gym counterpart | ours / counterpart |")
    print("|---|---|---|---|")
    for env_id in TASKS:
        counterpart = COUNTERPARTS[env_id]
        rate, ratio = rate_and_ratio(rates[env_id], rates.get(counterpart))
        print(f"| {env_id} | {rate:,.0f} | {counterpart} | {ratio} |")
    for panda in pandas:
        print(f"| {panda} (panda-gym, PyBullet) | {statistics.median(rates[panda]):,.0f} | | |")


def print_gripper_tables(episodes: int, steps: int, repeats: int) -> None:
    """The gripper's scripted success rates on every task of GRASPING, and its env steps/s
    (random actions, as ``print_speed_table``) against the pad's, both envs of a task timed
    in turn in each of ``repeats`` rounds: the ratio is the median of the rounds'."""
    print(f"\nThe two-finger gripper (effector=\"gripper\"): scripted policies, {episodes} "
          "seeded episodes each\n")
    print("| task | success rate | mean return | s per episode |")
    print("|---|---|---|---|")
    for env_id in GRASPING:
        rate, mean_return, seconds = scripted_success(env_id, episodes, effector="gripper")
        print(f"| {env_id} | {rate:.0%} | {mean_return:.1f} | {seconds:.3f} |", flush=True)
    print(f"\nEnv steps/s, gripper against pad, gym.make, one env, resets included (median "
          f"of {repeats} rounds of {steps} steps, every env timed in turn in each round), with "
          "random actions and with the scripted policies (which grasp, carry and place)\n")
    runs = {(env_id, effector, scripted): random_stepper(env_id, steps, scripted,
                                                         effector=effector)
            for env_id in GRASPING for scripted in (False, True)
            for effector in ("pad", "gripper")}
    rates = rates_in_rounds(runs, repeats)
    print("| env | actions | pad steps/s | gripper steps/s | gripper / pad |")
    print("|---|---|---|---|---|")
    for env_id in GRASPING:
        for scripted in (False, True):
            pad, gripper = rates[env_id, "pad", scripted], rates[env_id, "gripper", scripted]
            ratio = statistics.median(g / p for g, p in zip(gripper, pad))
            print(f"| {env_id} | {'scripted' if scripted else 'random'} | "
                  f"{statistics.median(pad):,.0f} | {statistics.median(gripper):,.0f} | "
                  f"{ratio:.2f}x |", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--only", choices=["success", "speed", "render", "gripper"])
    parser.add_argument("--frames", type=Path, default=Path("docs/images"),
                        help="folder for the task picture (tasks.png)")
    args = parser.parse_args()

    if args.only in (None, "success"):
        print(f"\nScripted policies, {args.episodes} seeded episodes each\n")
        print("| task | success rate | mean return | s per episode |")
        print("|---|---|---|---|")
        for env_id in TASKS:
            rate, mean_return, seconds = scripted_success(env_id, args.episodes)
            print(f"| {env_id} | {rate:.0%} | {mean_return:.1f} | {seconds:.3f} |", flush=True)

    if args.only in (None, "speed"):
        print_speed_table(args.steps, args.repeats)

    if args.only in (None, "render"):
        print("\nrgb_array frames, 480 x 480 (median of 20 after the first)\n")
        print("| env | ms per frame |")
        print("|---|---|")
        for env_id in TASKS:
            print(f"| {env_id} | {frame_milliseconds(env_id):.1f} |", flush=True)
        save_task_picture(args.frames / "tasks.png")

    if args.only in (None, "gripper"):
        print_gripper_tables(args.episodes, args.steps, args.repeats)


if __name__ == "__main__":
    main()
