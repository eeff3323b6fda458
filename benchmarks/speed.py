"""Speed: solver steps/s, env steps/s, batched env steps/s, pixel env steps/s.

1. Solver (``--only solver``): steps/s at dt = 1/240, one world, for the scenes of
   ``rigid_gym.report.scenes``: settled, the 10-cube stack, the 55-box pyramid (alone, and
   beside a ball rolling away from it) and piles of 10, 100 and 1000 mixed bodies; falling, the piles of 10 and 100 in the first second after
   their drop. Every engine (ours, and ours stopping slow islands (``--sleep-speed``,
   SolverConfig.sleep_speed), MuJoCo without and with its island sleeping, and PyBullet
   through ``rigid_gym.report.peers`` when the ``compare`` extra is installed: ``pip
   install -e ".[compare]"``) builds every scene and runs a settled scene's ``settle`` steps;
   then each of ``--repeats`` rounds times ``step(steps)`` of every scene and engine in turn,
   a falling scene's after a reset to its start. A rate is the median over
   the rounds, a ratio the median of the rounds' ratios, k the median of the rounds' k: what
   is compared was timed within one round, so the VM's drift in speed moves both sides.
   Every engine gets the same step counts, so all are timed over the same stretch of
   simulated time. Then the stack runs 10 s more and the table gives how far its top cube
   moved (bar: < 1 mm for ours); for the piles, the microseconds per step and per body-step
   and the exponent k of cost ~ N^k between the two largest piles (100 and 1000). A peer that
   cannot build a scene says why in the table.
2. Envs (``--only envs``): env steps/s through ``gym.make`` for Push, Stack and Throw, one
   env, seeded random actions, resets included (the helper of ``benchmarks/envs.py``), and
   panda-gym's PandaPush-v3 timed the same way in the same run when installed, with our rate
   as a ratio to it.
3. Batched (``--only batched``): env steps/s (B x vector steps per second) through
   ``gym.make_vec(env_id, num_envs=B, vectorization_mode="vector_entry_point")`` at B = 1,
   16, 256 and 1024, actions from a seeded generator of shape (B, action size), resets left to
   the vector env and included (each timing is a whole number of episodes, so every copy
   resets in it); then Push under its scripted policy, the policy's time left out (it
   pushes the cube most of the time, which random actions rarely touch); "not available"
   where a task registers no vector entry point.
4. Pixels (``--only pixels``): benchmarks/pixels.py's tables: Push, Stack and Throw with an
   84 x 84 frame per step through ``gym.make`` and ``gym.make_vec`` (B = 16 and 64), Push in
   state mode and panda-gym's PandaPush-v3 rendering 84 x 84 after every step beside them,
   and the CPU time of one frame.

The header line names the machine and the versions. One world runs on the calling thread
only; a batch runs there too or is shared out over the core's threads
(``rigid_gym._core.num_threads``, at most ``RIGID_GYM_NUM_THREADS``), whichever its own
timings found faster (src/solver/sharing.h).

    python benchmarks/speed.py                   # all four sections, minutes on 2 cores
                                                 # (MuJoCo's 1000-body pile the longest part)
    python benchmarks/speed.py --only solver     # one section: solver, envs, batched, pixels
    python benchmarks/speed.py --quick           # smoke run with small counts, about 15 s
    python benchmarks/speed.py --repeats 9       # more timings per median (default 5)
    python benchmarks/speed.py --sleep-speed 0.05  # the threshold of ours, sleeping
"""

import argparse
import functools
import importlib.metadata
import importlib.util
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
from rigid_gym._core import DYNAMIC
from rigid_gym.envs.scripted import scripted_policy

import rigid_gym as rg
from rigid_gym import _core
from rigid_gym.report import peers
from rigid_gym.report.scenes import cube_stack, pile, pyramid, pyramid_and_ball

DT = 1 / 240
STACK_SECONDS = 10.0
"""Simulated time over which the stack's top cube is watched, s."""
STACK_BAR_MM = 1.0
OURS, OURS_SLEEPING = "ours", "ours, sleeping"
"""Ours by default (exact sleeping only), and with slow islands stopped and put to sleep
(SolverConfig.sleep_speed = ``--sleep-speed``): both opt-in choices of speed over exactness
side by side, as MuJoCo's with its sleep flag on."""
PEERS = {"MuJoCo": ("mujoco", peers.MuJoCoWorld, OURS),
         "MuJoCo, sleep on": ("mujoco", functools.partial(peers.MuJoCoWorld, sleep=True),
                              OURS_SLEEPING),
         "PyBullet": ("pybullet", peers.PyBulletWorld, OURS)}
"""Peer label -> (module name as in ``peers.available``, world class (scene, dt), the ours it
is compared with). MuJoCo sleeps resting islands only with ``mjENBL_SLEEP`` on, which a user
turns on for speed; ours stops slow islands only with SolverConfig.sleep_speed above 0."""
ENGINES = (OURS, OURS_SLEEPING, *PEERS)
SLEEP_SPEED = 0.01
"""m/s: ``--sleep-speed``'s default, the SolverConfig.sleep_speed of ours, sleeping."""
BATCH_SIZES = (1, 16, 256, 1024)
QUICK_BATCH_SIZES = (1, 16)
SCRIPTED_BATCHED = "rigid_gym/Push-v0"
"""The task timed batched under its scripted policy too."""
BATCH_WARMUP = 5
"""Untimed vector steps before the timings (first allocations, caches)."""


def load_env_benchmark():
    """``benchmarks/envs.py`` as a module, loaded by path (``import envs`` could find the
    repository's ``envs/`` package, which is rigid_gym.envs)."""
    spec = importlib.util.spec_from_file_location("benchmark_envs",
                                                  Path(__file__).with_name("envs.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


ENV_BENCHMARK = load_env_benchmark()


# -- header ----------------------------------------------------------------------------------

def cpu_model() -> str:
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or "unknown CPU"


def version(package: str) -> str:
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def machine_line() -> str:
    return (f"Machine: {cpu_model()}, {os.cpu_count()} cores, {_core.num_threads()} solver "
            f"threads; Python {platform.python_version()}, rigid_gym {version('rigid_gym')}, numpy "
            f"{np.__version__}, gymnasium {gym.__version__}; mujoco {version('mujoco')}, "
            f"pybullet {version('pybullet')}, panda-gym {version('panda-gym')}")


# -- solver ----------------------------------------------------------------------------------

PYRAMID_AND_BALL = "55-box pyramid, a ball rolling"
"""The settled pyramid beside a ball rolling away from it at 1 m/s: one body awake among
resting ones, what an island that sleeps costs a step while another moves."""
FALLING = ", falling"
"""The name's ending of a scene timed from its start (settle = 0), reset before each timing."""


def solver_scenes(quick: bool) -> list[tuple[str, rg.Scene, int, int]]:
    """(name, scene, settle steps, timed steps per repeat) for each scene: settled ones after
    ``settle`` steps, falling ones (settle 0, the name ending in FALLING) over the first
    ``steps`` after the drop. The piles settle equally long, so their growth with N compares
    piles in the same state."""
    if quick:
        return [("10-cube stack", cube_stack(10), 240, 60), ("pile of 10", pile(10), 120, 60),
                ("pile of 100", pile(100), 120, 8), ("pile of 10" + FALLING, pile(10), 0, 60)]
    return [("10-cube stack", cube_stack(10), 240, 240), ("55-box pyramid", pyramid(10), 240, 120),
            (PYRAMID_AND_BALL, pyramid_and_ball(10, speed=-1.0), 240, 120),
            ("pile of 10", pile(10), 240, 240), ("pile of 100", pile(100), 240, 48),
            ("pile of 1000", pile(1000), 240, 4), ("pile of 10" + FALLING, pile(10), 0, 240),
            ("pile of 100" + FALLING, pile(100), 0, 240)]


def dynamic_bodies(scene: rg.Scene) -> int:
    return sum(body.motion == DYNAMIC for body in scene.bodies)


def build(engine: str, scene: rg.Scene, sleep_speed: float = SLEEP_SPEED):
    """A world of ``engine`` (one of ENGINES) for ``scene``, or why a peer has none (str);
    ours, sleeping, stops islands slower than ``sleep_speed`` (m/s, SolverConfig.sleep_speed)."""
    if engine not in PEERS:
        speed = sleep_speed if engine == OURS_SLEEPING else 0.0
        return rg.World(scene, dt=DT, config=rg.SolverConfig.for_scene(scene, sleep_speed=speed))
    module, world_class, _ = PEERS[engine]
    if not peers.available()[module]:
        return 'not installed (pip install -e ".[compare]")'
    try:
        return world_class(scene, DT)
    except Exception as exc:  # noqa: BLE001 - a peer raises its own kinds; its failure is a cell
        return f"cannot build: {exc}".replace("|", "/")


def moved_mm(world, body: int, seconds: float) -> float:
    """How far the centre of ``body`` moves while ``world`` runs ``seconds`` s, mm."""
    start = np.array(world.position[body])
    world.step(round(seconds / DT))
    return 1e3 * float(np.linalg.norm(world.position[body] - start))


def rate_text(rate: float) -> str:
    """Steps/s to the unit from 100 up, to 3 significant digits below."""
    return f"{rate:,.0f}" if rate >= 100 else f"{rate:.3g}"


WARM_SHARE = 24
"""A settled scene's timing of ``steps`` follows ``steps // WARM_SHARE`` (at least 1) untimed
ones: each engine's turn comes after the others' (MuJoCo's 1000-body pile fills the caches
with its own data), and a sleeping stack's step is so cheap that a cold start would weigh as
much as its timed steps."""


def stepping_rate(world, steps: int, from_start: bool = False) -> float:
    """Steps/s of one ``world.step(steps)`` after a few untimed ones (WARM_SHARE); from_start:
    of the first ``steps`` after a reset to the scene's start (the reset, not timed, instead)."""
    if from_start:
        world.reset()
    else:
        world.step(max(1, steps // WARM_SHARE))
    start = time.perf_counter()
    world.step(steps)
    return steps / (time.perf_counter() - start)


def timed_rates(scenes, repeats: int, sleep_speed: float) -> tuple[dict, dict]:
    """({(scene name, engine): [steps/s of each repeat], or why the engine has no world
    (str)}, {(stack scene name, engine): mm its top cube moved in STACK_SECONDS after the
    timings}). Every world is built and settled first; then each repeat times every world
    once in turn (rates_in_rounds), so repeat r of every scene and engine falls in the same
    stretch of the run. Ratios and growth exponents are taken repeat by repeat (a VM whose
    speed drifts while one engine's timings run would otherwise move the ratio). Ours with
    ``sleep_speed`` (``build``)."""
    worlds, runs = {}, {}
    for name, scene, settle, steps in scenes:
        for engine in ENGINES:
            world = worlds[name, engine] = build(engine, scene, sleep_speed)
            if not isinstance(world, str):
                world.step(settle)
                runs[name, engine] = functools.partial(stepping_rate, world, steps,
                                                       name.endswith(FALLING))
    rates = ENV_BENCHMARK.rates_in_rounds(runs, repeats)
    rates.update({key: world for key, world in worlds.items() if isinstance(world, str)})
    moved = {}
    for name, scene, _, _ in scenes:
        for engine in ENGINES:
            world = worlds[name, engine]
            if isinstance(world, str):
                continue
            if name.endswith("stack"):  # the top cube
                moved[name, engine] = moved_mm(world, len(scene.bodies) - 1, STACK_SECONDS)
            if engine in PEERS:
                world.close()
    return rates, moved


def rate_cells(ours: list, peer) -> str:
    """The peer's median steps/s and the median over repeats of ours / theirs, or why the peer
    has no rate."""
    if isinstance(peer, str):
        return f"{peer} | —"
    ratio = statistics.median(o / p for o, p in zip(ours, peer))
    return f"{rate_text(statistics.median(peer))} | {ratio:.2f}x"


def print_solver_table(rates: dict, scenes) -> None:
    print(f"| scene | bodies | {OURS} | {OURS_SLEEPING} | "
          + " | ".join(f"{p} | {ours}/{p}" for p, (_, _, ours) in PEERS.items()) + " |")
    print("|---|---|---|---|" + "---|---|" * len(PEERS))
    for name, scene, _, _ in scenes:
        print(f"| {name} | {dynamic_bodies(scene)} | "
              f"{rate_text(statistics.median(rates[name, OURS]))} | "
              f"{rate_text(statistics.median(rates[name, OURS_SLEEPING]))} | "
              + " | ".join(rate_cells(rates[name, ours], rates[name, p])
                           for p, (_, _, ours) in PEERS.items()) + " |")


def print_stack_health(rates: dict, moved: dict, name: str) -> None:
    print(f"\n{name}: top cube moved in {STACK_SECONDS:.0f} s from the settled state "
          f"(bar: < {STACK_BAR_MM:g} mm for ours)\n")
    print("| engine | moved (mm) |")
    print("|---|---|")
    for engine in ENGINES:
        cell = f"{moved[name, engine]:.3g}" if (name, engine) in moved else rates[name, engine]
        print(f"| {engine} | {cell} |")
    ours = moved[name, OURS]
    print(f"\nbar {'met' if ours < STACK_BAR_MM else 'NOT met'}: ours moved {ours:.3g} mm")


def growth_exponent(counts, microseconds) -> float:
    """k of cost ~ N^k between the last two (N, cost) points."""
    return float(np.log(microseconds[-1] / microseconds[-2]) / np.log(counts[-1] / counts[-2]))


def print_pile_growth(rates: dict, scenes) -> None:
    piles = [(name, dynamic_bodies(scene)) for name, scene, _, _ in scenes
             if name.startswith("pile") and not name.endswith(FALLING)]
    counts = np.array([n for _, n in piles], dtype=float)
    print(f"\nPiles: cost per step and per body-step (us, medians), and k of cost ~ N^k between "
          f"N = {counts[-2]:.0f} and {counts[-1]:.0f} (the median of each repeat's k)\n")
    print("| engine | " + " | ".join(f"us/step N={n:.0f}" for n in counts) + " | "
          + " | ".join(f"us/body-step N={n:.0f}" for n in counts) + " | k |")
    print("|---|" + "---|" * (2 * len(counts) + 1))
    for engine in ENGINES:
        runs = [rates[name, engine] for name, _ in piles]
        if any(isinstance(run, str) for run in runs):
            print(f"| {engine} | " + " | ".join(["—"] * (2 * len(counts))) + " | — |")
            continue
        per_repeat = 1e6 / np.array(runs)  # (piles, repeats) us per step
        per_step = np.median(per_repeat, axis=1)
        k = statistics.median(growth_exponent(counts, per_repeat[:, r])
                              for r in range(per_repeat.shape[1]))
        print(f"| {engine} | " + " | ".join(f"{t:,.1f}" for t in per_step) + " | "
              + " | ".join(f"{t:.2f}" for t in per_step / counts) + f" | {k:.2f} |")


def solver_section(quick: bool, repeats: int, sleep_speed: float = SLEEP_SPEED) -> None:
    scenes = solver_scenes(quick)
    print(f"\nSolver steps/s, dt = 1/240, one world (median of {repeats} timings after "
          "settling, every engine and scene timed in turn in each repeat; ratios are the "
          f"median over repeats of ours / theirs). {OURS}: exact sleeping only "
          f"(SolverConfig's default); {OURS_SLEEPING}: islands slower than {sleep_speed:g} m/s "
          "for 0.5 s stopped and asleep too (SolverConfig.sleep_speed), compared with MuJoCo "
          "with its sleep on\n")
    rates, moved = timed_rates(scenes, repeats, sleep_speed)
    print_solver_table(rates, scenes)
    print_stack_health(rates, moved, "10-cube stack")
    print_pile_growth(rates, scenes)


# -- envs ------------------------------------------------------------------------------------

def envs_section(quick: bool, repeats: int) -> None:
    ENV_BENCHMARK.print_speed_table(200 if quick else 1000, repeats)


# -- batched envs ----------------------------------------------------------------------------

def has_vector_env(env_id: str) -> bool:
    return getattr(gym.spec(env_id), "vector_entry_point", None) is not None


def batched_rate(env_id: str, batch: int, steps: int, repeats: int,
                 scripted: bool = False) -> float:
    """Median env steps/s (batch x vector steps per second) of ``gym.make_vec`` with ``batch``
    envs over ``repeats`` timings of at least ``steps`` env steps, each a whole number of
    episodes of vector steps: the copies start together and random actions never end an
    episode early, so every copy resets exactly once per episode length in every timing
    (timings of 10 vector steps let the median leave the resets out: at B = 1024 only one
    timing in five had them). ``scripted``: actions from the task's scripted policy, copy by
    copy, whose time is left out (only ``envs.step`` is timed); its episodes touch the cubes
    all the time, where random actions touch them rarely."""
    envs = gym.make_vec(env_id, num_envs=batch, vectorization_mode="vector_entry_point")
    space = envs.single_action_space
    rng = np.random.default_rng(0)
    observations, _ = envs.reset(seed=0)
    episode = envs.unwrapped.max_episode_steps
    if scripted:
        policy = scripted_policy(gym.make(env_id))

    def actions(observations):
        if not scripted:
            return rng.uniform(space.low, space.high, (batch, *space.shape)).astype(space.dtype)
        return np.array([policy({key: value[i] for key, value in observations.items()})
                         for i in range(batch)], dtype=space.dtype)

    def run(count) -> float:
        nonlocal observations
        seconds = 0.0
        for _ in range(count):
            chosen = actions(observations)
            start = time.perf_counter()
            observations = envs.step(chosen)[0]
            seconds += time.perf_counter() - start
        return seconds

    run(BATCH_WARMUP)
    vector_steps = episode * max(1, -(-steps // (batch * episode)))
    rates = [batch * vector_steps / run(vector_steps) for _ in range(repeats)]
    envs.close()
    return statistics.median(rates)


def batched_section(quick: bool, repeats: int) -> None:
    steps = 200 if quick else 1000
    sizes = QUICK_BATCH_SIZES if quick else BATCH_SIZES
    print(f"\nBatched env steps/s, gym.make_vec(vectorization_mode=\"vector_entry_point\"), "
          f"B x vector steps per second (median of {repeats} timings; random actions, and "
          "Push under its scripted policy, whose time is left out)\n")
    print("| env | " + " | ".join(f"B = {b}" for b in sizes) + " |")
    print("|---|" + "---|" * len(sizes))
    rows = [(env_id, False) for env_id in ENV_BENCHMARK.TASKS] + [(SCRIPTED_BATCHED, True)]
    for env_id, scripted in rows:
        label = f"{env_id}, scripted policy" if scripted else env_id
        if not has_vector_env(env_id):
            cells = ["not available (no vector_entry_point)"] * len(sizes)
        else:
            cells = [f"{batched_rate(env_id, b, steps, repeats, scripted):,.0f}" for b in sizes]
        print(f"| {label} | " + " | ".join(cells) + " |", flush=True)


# -- pixel observations ----------------------------------------------------------------------

def pixels_section(quick: bool, repeats: int) -> None:
    """benchmarks/pixels.py's tables: 84 x 84 pixel envs, single and batched, beside
    PandaPush-v3 rendering a frame per step, and the CPU time of a frame. Loaded here, not at
    import: pixels.py loads this module for its machine line."""
    spec = importlib.util.spec_from_file_location("benchmark_pixels",
                                                  Path(__file__).with_name("pixels.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    if quick:
        module.print_speed_tables(repeats, steps=100, env_steps=128, panda_steps=5)
    else:
        module.print_speed_tables(repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=["solver", "envs", "batched", "pixels"])
    parser.add_argument("--quick", action="store_true", help="small counts: a smoke run")
    parser.add_argument("--repeats", type=int, default=5, help="timings per median")
    parser.add_argument("--sleep-speed", type=float, default=SLEEP_SPEED,
                        help="ours, sleeping: SolverConfig.sleep_speed, m/s (default "
                             f"{SLEEP_SPEED:g})")
    parser.add_argument("--out", type=Path, default=None,
                        help="also write the tables to this markdown file (README quotes "
                             "docs/benchmarks.md, written by a whole run)")
    args = parser.parse_args()
    out = open(args.out, "w") if args.out else None  # noqa: SIM115  (closed below)
    if out is not None:
        command = " ".join(["python benchmarks/speed.py", *sys.argv[1:]])
        out.write(f"# Speed\n\nWritten by `{command}`; README quotes this run.\n\n")
        sys.stdout = Tee(sys.stdout, out)
    try:
        print(machine_line(), flush=True)
        sections = {"solver": functools.partial(solver_section, sleep_speed=args.sleep_speed),
                    "envs": envs_section, "batched": batched_section,
                    "pixels": pixels_section}
        for name, section in sections.items():
            if args.only in (None, name):
                section(args.quick, args.repeats)
    finally:
        if out is not None:
            sys.stdout = sys.__stdout__
            out.close()


class Tee:
    """A text stream that writes to several: the terminal and the markdown file."""

    def __init__(self, *streams):
        self.streams = streams

    def write(self, text: str) -> int:
        for stream in self.streams:
            stream.write(text)
        return len(text)

    def flush(self) -> None:
        for stream in self.streams:
            stream.flush()


if __name__ == "__main__":
    main()
