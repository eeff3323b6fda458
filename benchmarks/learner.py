"""The learner's pace: env steps per wall second of SAC + HER training on rigid_gym/Push-v0.

Each setting trains in this process with one thread (PyTorch's ``set_num_threads(1)``, JAX
with ``XLA_FLAGS`` set to one thread before it is imported), at Push's shipped settings (lr
1e-3, batch 256, gamma 0.95, tau 0.05, HER future k = 4), from a fresh model: ``--warmup``
env steps past learning_starts (which compile JAX's update), then ``--steps`` timed env
steps. Collection goes through the batched env (``SB3VecEnv`` over ``gym.make_vec``). The
first row is PyTorch SB3 SAC [64, 64], 1 env, 1 gradient step per env step (stable-baselines3's
defaults, the baseline); every other row is also given as a ratio to it, measured in the same
run. Settings run in turn for ``--rounds`` rounds and each figure is the median of its rounds,
so a machine shared with others drifts both sides of a ratio alike.

    python benchmarks/learner.py                        # the default table, ~6 min on 2 cores
    python benchmarks/learner.py --settings sb3:64:1:1 sbx:64:1:1 sbx:256:8:2 --steps 3000
    python benchmarks/learner.py --recipes           # each recipe of the results table instead

A setting is ``learner:width:n_envs:gradient_steps`` (gradient steps per vector step, so per
``n_envs`` env steps). It measures pace only, not what is learned (``rigid_gym.agents.table``
runs the learning). ``--recipes`` times each (env id, algo) of the results table
(``rigid_gym.agents.table.RECIPES``) at its hyperparams.yml settings instead (without its
demonstrations and evaluations: the table's ``PACE`` is whole runs' pace, those included).
"""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false "
                                   "intra_op_parallelism_threads=1")

import argparse
import statistics
import time

from rigid_gym.agents.algorithms import learner_available, learner_for
from rigid_gym.agents.train import build_model, load_hyperparams

DEFAULT = ["sb3:64:1:1", "sbx:64:1:1", "sbx:256:1:1", "sbx:64:4:4", "sbx:64:8:8",
           "sbx:64:8:4", "sbx:256:8:2", "sbx:256:8:8"]


def pace(learner: str, width: int, n_envs: int, gradient_steps: int, steps: int,
         warmup: int) -> float:
    """Env steps per wall second of ``steps`` training steps of a fresh Push model, after
    ``warmup`` steps past learning_starts."""
    settings = load_hyperparams("rigid_gym/Push-v0")
    overrides = {"policy_kwargs": {"net_arch": [width, width]}, "train_freq": 1,
                 "gradient_steps": gradient_steps}
    return timed(build_model("rigid_gym/Push-v0", settings, "sac", learner, n_envs, seed=0,
                             overrides=overrides), settings, steps, warmup)


def recipe_pace(env_id: str, algo: str, steps: int, warmup: int) -> float:
    """Env steps per wall second of ``steps`` training steps of ``env_id``'s ``algo`` recipe
    (hyperparams.yml), on the default learner, after ``warmup`` steps past learning_starts."""
    settings = load_hyperparams(env_id, algo)
    learner = learner_for(algo, None)
    return timed(build_model(env_id, settings, algo, learner, settings.get("n_envs", 1), seed=0),
                 settings, steps, warmup)


def timed(made, settings: dict, steps: int, warmup: int) -> float:
    """Env steps per wall second of ``steps`` more steps of ``made`` (model, env) after
    learning_starts + ``warmup`` steps."""
    model, env = made
    model.learn(settings["kwargs"].get("learning_starts", 0) + warmup)
    start = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    seconds = time.perf_counter() - start
    env.close()
    return steps / seconds


def processor() -> str:
    """The machine as the tables name it (``train.machine``)."""
    from rigid_gym.agents.train import machine
    return machine()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--settings", nargs="+", default=DEFAULT,
                        help="learner:width:n_envs:gradient_steps each (the first is the "
                             "baseline of the ratios)")
    parser.add_argument("--steps", type=int, default=2000, help="timed env steps per setting")
    parser.add_argument("--warmup", type=int, default=400)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--recipes", action="store_true",
                        help="time the results table's recipes instead of --settings")
    args = parser.parse_args()
    if args.recipes:
        from rigid_gym.agents.table import RECIPES

        print(f"the results table's recipes, 1 thread, {processor()}, {args.steps} env steps "
              "after the warm-up")
        print("| env id | algo | env steps/s |\n|---|---|---|")
        for recipes in RECIPES.values():
            for env_id, algo in recipes:
                rate = recipe_pace(env_id, algo, args.steps, args.warmup)
                print(f"| {env_id} | {algo} | {rate:,.0f} |", flush=True)
        return
    settings = []
    for text in args.settings:
        learner, width, n_envs, gradient_steps = text.split(":")
        if not learner_available(learner):
            print(f"skipping {text}: {learner} is not installed")
            continue
        settings.append((learner, int(width), int(n_envs), int(gradient_steps)))
    rates = {s: [] for s in settings}
    for _ in range(args.rounds):
        for s in settings:
            rates[s].append(pace(*s, args.steps, args.warmup))
    base = statistics.median(rates[settings[0]])
    print(f"SAC + HER on rigid_gym/Push-v0, 1 thread, {processor()}, median of {args.rounds} "
          f"rounds of {args.steps} env steps")
    print("| learner | net | n_envs | gradient steps per vector step | env steps/s | ratio |")
    print("|---|---|---|---|---|---|")
    for s in settings:
        rate = statistics.median(rates[s])
        learner, width, n_envs, gradient_steps = s
        print(f"| {learner} | [{width}, {width}] | {n_envs} | {gradient_steps} | {rate:,.0f} | "
              f"{rate / base:.2f}x |")


if __name__ == "__main__":
    main()
