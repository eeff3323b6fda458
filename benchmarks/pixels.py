"""Pixel observations' speed: env steps/s with an 84 x 84 frame per step, beside panda-gym.

Every env steps with seeded uniform random actions, resets included (a vector env resets its
copies itself); in each of ``--repeats`` rounds every env is timed once, in turn
(``rates_in_rounds`` of benchmarks/envs.py), after a warm-up. A rate is the median over the
rounds, a ratio to PandaPush-v3 the median of the rounds' ratios, so the machine's drift in
speed moves both sides of a comparison.

1. ``gym.make(id, obs_mode="pixels", width=84, height=84)``, one env, Push, Stack and Throw;
   Push in state mode beside them, for what the frame costs.
2. ``gym.make_vec(id, num_envs=B, obs_mode="pixels", width=84, height=84)`` at B = 16 and 64:
   B x vector steps per second, the frames of a step drawn in one call over the core's
   threads (``rigid_gym._core.num_threads``, at most ``RIGID_GYM_NUM_THREADS``).
3. panda-gym's PandaPush-v3 with ``render_mode="rgb_array"``, ``render_width=84``,
   ``render_height=84`` and ``env.render()`` after every step and reset: the frame per step
   that a pixel agent needs (PyBullet's CPU renderer), when panda-gym is installed
   (``pip install -e ".[compare]"``).

4. CPU time of one 84 x 84 frame (``time.process_time``, the median of ``--repeats``
   timings of 1,000 frames of a state after a few random steps): what a frame costs whatever
   else the machine runs.
5. With ``--frames FOLDER``: each task's 84 x 84 ``pixels`` observation (front camera) after
   FRAME_STEPS steps of its scripted policy from reset(seed=1), as FOLDER/pixels_<task>.png.

    python benchmarks/pixels.py                  # about 2 minutes on 2 cores
    python benchmarks/pixels.py --repeats 9      # more rounds per median (default 5)
    python benchmarks/pixels.py --frames docs/images --repeats 0   # the pictures only
"""

import argparse
import functools
import importlib.util
import statistics
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import rigid_gym  # noqa: F401  (registers the ids)

SIZE = 84
TASKS = ["rigid_gym/Push-v0", "rigid_gym/Stack-v0", "rigid_gym/Throw-v0"]
BATCH_SIZES = (16, 64)
PANDA_PUSH = "PandaPush-v3"
FRAME_STEPS = {"rigid_gym/Push-v0": 12, "rigid_gym/Stack-v0": 25, "rigid_gym/Throw-v0": 8}
"""Scripted steps before each task's picture: the pad at work on a cube."""


def load_benchmark(name: str):
    """``benchmarks/<name>.py`` as a module, loaded by path (``import envs`` could find the
    repository's ``envs/`` package)."""
    spec = importlib.util.spec_from_file_location(f"benchmark_{name}",
                                                  Path(__file__).with_name(f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


SPEED = load_benchmark("speed")
ENVS = SPEED.ENV_BENCHMARK


def single_stepper(make, steps: int, render: bool = False):
    """() -> env steps/s of ``steps`` steps of the env ``make()`` gives, random actions from a
    seeded generator, resetting where an episode ends, ``render()`` after every step and reset
    when ``render``; warmed up by 20 steps."""
    env = make()
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    if render:
        env.render()

    def run(count) -> float:
        start = time.perf_counter()
        for _ in range(count):
            action = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
            _, _, terminated, truncated, _ = env.step(action)
            if render:
                env.render()
            if terminated or truncated:
                env.reset()
                if render:
                    env.render()
        return count / (time.perf_counter() - start)

    run(20)
    return functools.partial(run, steps)


def vector_stepper(env_id: str, num_envs: int, steps: int):
    """() -> env steps/s (B x vector steps/s) of ``steps`` vector steps of the batched pixel
    env, seeded random actions of shape (B, action size); warmed up by 5 steps."""
    envs = gym.make_vec(env_id, num_envs=num_envs, obs_mode="pixels", width=SIZE, height=SIZE)
    rng = np.random.default_rng(0)
    envs.reset(seed=0)

    def run(count) -> float:
        start = time.perf_counter()
        for _ in range(count):
            envs.step(rng.uniform(-1, 1, envs.action_space.shape).astype(np.float32))
        return num_envs * count / (time.perf_counter() - start)

    run(5)
    return functools.partial(run, steps)


def panda_maker():
    """A function that makes PandaPush-v3 with an 84 x 84 rgb_array frame, or None when
    panda-gym is not installed."""
    try:
        import panda_gym  # noqa: F401
    except ImportError:
        return None
    return lambda: gym.make(PANDA_PUSH, render_mode="rgb_array", render_width=SIZE,
                            render_height=SIZE)


def frame_cpu_microseconds(env_id: str, repeats: int, frames: int = 1000) -> float:
    """Median over ``repeats`` timings of the CPU time of one pixels frame, us."""
    env = gym.make(env_id, obs_mode="pixels", width=SIZE, height=SIZE)
    env.reset(seed=0)
    for _ in range(5):
        env.step(env.action_space.sample())
    core = env.unwrapped.core
    state, world = core.world.state, np.zeros(1, dtype=np.int64)
    times = []
    for _ in range(repeats):
        start = time.process_time()
        for _ in range(frames):
            core.frames.draw(state, world)
        times.append((time.process_time() - start) / frames)
    return 1e6 * statistics.median(times)


def save_frames(folder: Path) -> None:
    """Write each task's pixels observation after FRAME_STEPS scripted steps (seed 1)."""
    import matplotlib.pyplot as plt
    from rigid_gym.envs.scripted import scripted_policy

    folder.mkdir(parents=True, exist_ok=True)
    for env_id in TASKS:
        env = gym.make(env_id, obs_mode="state+pixels", width=SIZE, height=SIZE)
        policy = scripted_policy(env)
        obs, _ = env.reset(seed=1)
        for _ in range(FRAME_STEPS[env_id]):
            obs = env.step(policy(obs))[0]
        path = folder / f"pixels_{env_id.split('/')[1].split('-')[0].lower()}.png"
        plt.imsave(path, obs["pixels"])
        print(f"wrote {path}")


def print_speed_tables(repeats: int, steps: int = 1000, env_steps: int = 1280,
                       panda_steps: int = 30) -> None:
    """Print the env steps/s table (single envs, batches, PandaPush-v3) and the CPU time per
    frame: sections 1-4 above. ``steps``: steps of each single env per round; ``env_steps``:
    env steps of each vector env per round; ``panda_steps``: steps of PandaPush-v3 per round.
    ``benchmarks/speed.py`` prints these too, into docs/benchmarks.md."""
    runs = {}
    for env_id in TASKS:
        runs[("pixels", env_id, 1)] = single_stepper(
            lambda env_id=env_id: gym.make(env_id, obs_mode="pixels", width=SIZE, height=SIZE),
            steps)
    runs[("state", TASKS[0], 1)] = single_stepper(lambda: gym.make(TASKS[0]), steps)
    for b in BATCH_SIZES:
        for env_id in TASKS:
            runs[("pixels", env_id, b)] = vector_stepper(env_id, b, max(env_steps // b, 1))
    panda = panda_maker()
    if panda is not None:
        runs[PANDA_PUSH] = single_stepper(panda, panda_steps, render=True)
    rates = ENVS.rates_in_rounds(runs, repeats)
    panda_rates = rates.pop(PANDA_PUSH, None)

    print(f"\nEnv steps/s with an {SIZE} x {SIZE} frame per step, random actions, resets "
          f"included (median of {repeats} rounds, every env timed in turn in each "
          "round)\n")
    print(f"| env | obs_mode | envs | env steps/s | ours/{PANDA_PUSH} |")
    print("|---|---|---|---|---|")
    for (mode, env_id, b), values in rates.items():
        rate, ratio = ENVS.rate_and_ratio(values, panda_rates)
        how = "gym.make" if b == 1 else f"make_vec, B = {b}"
        print(f"| {env_id} | {mode} | {how} | {rate:,.0f} | {ratio} |")
    if panda_rates:
        print(f"| {PANDA_PUSH} (panda-gym, PyBullet), render() {SIZE} x {SIZE} | | gym.make | "
              f"{statistics.median(panda_rates):,.1f} | 1.00x |")

    print(f"\nCPU time of one {SIZE} x {SIZE} frame (median of {repeats} timings of "
          "1,000 frames)\n")
    print("| env | us per frame |")
    print("|---|---|")
    for env_id in TASKS:
        print(f"| {env_id} | {frame_cpu_microseconds(env_id, repeats):.0f} |", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--steps", type=int, default=1000,
                        help="steps of each single env per round")
    parser.add_argument("--env-steps", type=int, default=1280,
                        help="env steps of each vector env per round (B x vector steps)")
    parser.add_argument("--panda-steps", type=int, default=30,
                        help="steps of PandaPush-v3 per round")
    parser.add_argument("--frames", type=Path, help="folder for each task's picture")
    args = parser.parse_args()
    if args.frames is not None:
        save_frames(args.frames)
    if args.repeats < 1:
        return
    print(SPEED.machine_line())
    print_speed_tables(args.repeats, args.steps, args.env_steps, args.panda_steps)


if __name__ == "__main__":
    main()
