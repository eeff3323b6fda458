"""What recording episodes with rerun costs: env steps/s with and without ``RecordRerun``.

For each task (through ``gym.make``, scripted policy, episodes of 50 steps, every episode
recorded: the worst case; training records a few), ``--repeats`` rounds each time
``--episodes`` seeded episodes bare and the same episodes recorded, in alternating order so
that load from other processes hits both alike. A recorded round ends when the writer process
has written all its files (``RecordRerun.sync``), and that wait is part of its time.
Reported: the median steps/s of each; the overhead, the median over rounds of bare /
recorded - 1 where each recorded round is paired with the bare round next to it in time (so
that the machine's drift between rounds cancels), and the spread of those ratios (first and
third quartiles); the recorder's
time per episode in the env's process measured directly (all time in the wrapper that is not
spent in the env: buffering, handing rows over, the final wait) and its share of a recorded
episode's time, the writer process's CPU time per episode (from /proc: what the files cost
where there is no idle core for the writer), and the size of a 50-step episode's file,
without and with contacts. On a loaded machine the steps/s ratio is noisier than the
recorder's own time.

``--training`` also times SAC + HER learning Push (PyTorch on one thread, as
``rigid-gym train`` runs it) for ``TRAINING_STEPS`` env steps, bare and with every episode
recorded, alternating, ``--repeats`` times each: what recording costs where it is used.

    python benchmarks/recording.py                  # about a minute on 2 cores
    python benchmarks/recording.py --training       # about 4 minutes
"""

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

import gymnasium as gym
from rigid_gym.envs.scripted import scripted_policy

import rigid_gym  # noqa: F401  (registers the ids)
from rigid_gym.recording import RecordRerun
from rigid_gym.recording_writer import writer

TASKS = ["rigid_gym/Push-v0", "rigid_gym/Stack-v0", "rigid_gym/Throw-v0"]
STEPS = 50
"""Env steps per episode (Stack's own limit is 100; 50 keeps the tasks comparable)."""
TRAINING_STEPS = 1500
"""Env steps of each ``--training`` run (learning starts after 100)."""


class EnvTime(gym.Wrapper):
    """Accumulates the wall time (s) spent in the wrapped env's reset and step."""

    def __init__(self, env):
        super().__init__(env)
        self.seconds = 0.0

    def _timed(self, call, *args, **kwargs):
        start = time.perf_counter()
        try:
            return call(*args, **kwargs)
        finally:
            self.seconds += time.perf_counter() - start

    def reset(self, **kwargs):
        return self._timed(self.env.reset, **kwargs)

    def step(self, action):
        return self._timed(self.env.step, action)


def make(env_id: str, folder: Path | None, contacts: bool = False):
    """(outer, inner): EnvTime wrappers around the recorder and around the env; when
    ``folder`` is None (not recorded), directly around each other, so that both kinds pay
    for the same two timing layers."""
    inner = EnvTime(gym.make(env_id, max_episode_steps=STEPS))
    if folder is None:
        return EnvTime(inner), inner
    return EnvTime(RecordRerun(inner, folder, episode_trigger=lambda k: True, run="bench",
                               contacts=contacts)), inner


def run_episodes(env, seeds) -> tuple[int, float]:
    """(steps, wall seconds) of the scripted policy's episodes, one per seed; a recorder's
    files are all written when it returns."""
    policy = scripted_policy(env)
    steps = 0
    start = time.perf_counter()
    for seed in seeds:
        observation, _ = env.reset(seed=seed)
        done = False
        while not done:
            observation, _, terminated, truncated, _ = env.step(policy(observation))
            steps, done = steps + 1, terminated or truncated
    if isinstance(env.env, RecordRerun):
        env.env.sync()
    return steps, time.perf_counter() - start


def cpu_seconds(pid: int) -> float:
    """User + system CPU time (s) of process ``pid`` so far (Linux's /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def measure(env_id: str, repeats: int, episodes: int, folder: Path) -> dict:
    """Median steps/s bare and recorded, the recorder's median ms per episode, the writer's
    CPU ms per episode, file sizes. Each kind keeps one env for all its rounds, as training
    does (the recorder sends what its files share at its first episode)."""
    bare_rates, recorded_rates, recorder_ms, ratios = [], [], [], []
    seeds = range(episodes)
    envs = {"bare": make(env_id, None), "recorded": make(env_id, folder)}
    for env, _ in envs.values():
        run_episodes(env, [0])  # warm-up: first allocations, the shared layout
    writer_start = cpu_seconds(writer().process.pid)
    for repeat in range(repeats):
        order = ("bare", "recorded") if repeat % 2 == 0 else ("recorded", "bare")
        for kind in order:
            env, inner = envs[kind]
            env.seconds = inner.seconds = 0.0
            steps, seconds = run_episodes(env, seeds)
            if kind == "bare":
                bare_rates.append(steps / seconds)
            else:
                recorded_rates.append(steps / seconds)
                recorder_ms.append(1e3 * (env.seconds - inner.seconds) / episodes)
        ratios.append(bare_rates[-1] / recorded_rates[-1])
    writer_ms = 1e3 * (cpu_seconds(writer().process.pid) - writer_start) / (repeats * episodes)
    for env, _ in envs.values():
        env.close()
    sizes = {}
    for contacts in (False, True):
        env, _ = make(env_id, folder / f"contacts-{contacts}", contacts)
        run_episodes(env, [0])
        env.close()
        sizes[contacts] = env.env.paths[0].stat().st_size / 1024
    bare, recorded = statistics.median(bare_rates), statistics.median(recorded_rates)
    quartiles = statistics.quantiles(ratios, n=4) if len(ratios) > 1 else ratios * 3
    return {"bare": bare, "recorded": recorded, "overhead": statistics.median(ratios) - 1.0,
            "spread": (quartiles[0] - 1.0, quartiles[2] - 1.0),
            "recorder_ms": statistics.median(recorder_ms), "writer_ms": writer_ms,
            "episode_ms": 1e3 * STEPS / recorded, "kib": sizes[False],
            "kib_contacts": sizes[True]}


def training_rates(repeats: int, folder: Path) -> tuple[float, float]:
    """Median env steps/s of SAC + HER on Push, bare and recording every episode."""
    import torch
    from stable_baselines3 import SAC, HerReplayBuffer

    torch.set_num_threads(1)
    rates = {"bare": [], "recorded": []}
    for repeat in range(repeats):
        for kind in ("bare", "recorded") if repeat % 2 == 0 else ("recorded", "bare"):
            env = gym.make("rigid_gym/Push-v0")
            if kind == "recorded":
                env = RecordRerun(env, folder / "training", episode_trigger=lambda k: True,
                                  run=f"r{repeat}")
            model = SAC("MultiInputPolicy", env, replay_buffer_class=HerReplayBuffer,
                        learning_starts=100, policy_kwargs={"net_arch": [64, 64]}, seed=0)
            start = time.perf_counter()
            model.learn(TRAINING_STEPS)
            env.close()  # a recorder's last file is written before the clock stops
            rates[kind].append(TRAINING_STEPS / (time.perf_counter() - start))
    return statistics.median(rates["bare"]), statistics.median(rates["recorded"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=9, help="rounds per task (default 9)")
    parser.add_argument("--episodes", type=int, default=60,
                        help="episodes per round and kind (default 60: the wait for the "
                             "writer's last file at a round's end, counted as recording, is "
                             "then ~0.5%% of the round)")
    parser.add_argument("--training", action="store_true",
                        help="also time SAC + HER training on Push, bare and recorded")
    args = parser.parse_args()
    if args.repeats < 1 or args.episodes < 1:
        parser.error(f"--repeats and --episodes must be >= 1, got {args.repeats}, "
                     f"{args.episodes}")
    print(f"{STEPS}-step scripted episodes, every one recorded; medians of {args.repeats} "
          f"rounds of {args.episodes} episodes\n")
    print("| task | steps/s bare | steps/s recorded | overhead (quartiles) | recorder, ms per "
          "episode (share) | writer CPU, ms per episode | file per episode | with contacts |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for env_id in TASKS:
            r = measure(env_id, args.repeats, args.episodes, Path(folder))
            share = r["recorder_ms"] / r["episode_ms"]
            low, high = (100 * x for x in r["spread"])
            print(f"| {env_id.split('/')[1]} | {r['bare']:,.0f} | {r['recorded']:,.0f} | "
                  f"{100 * r['overhead']:+.1f}% ({low:+.1f}..{high:+.1f}) | "
                  f"{r['recorder_ms']:.2f} ({100 * share:.1f}%) | {r['writer_ms']:.1f} | "
                  f"{r['kib']:.0f} KiB | {r['kib_contacts']:.0f} KiB |", flush=True)
        if args.training:
            bare, recorded = training_rates(args.repeats, Path(folder))
            print(f"\nSAC + HER on Push, {TRAINING_STEPS} env steps, medians of "
                  f"{args.repeats}: {bare:,.0f} env steps/s bare, {recorded:,.0f} recording "
                  f"every episode ({100 * (bare / recorded - 1):+.1f}%)")


if __name__ == "__main__":
    main()
