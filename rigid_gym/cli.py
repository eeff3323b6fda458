"""The ``rigid-gym`` command.

    rigid-gym demo [--steps N] [--dt S] [--order {1,2,3}]
    rigid-gym record ENV_ID [--policy random|scripted|MODEL.zip] [--algo NAME] [--episodes N]
                     [--seed S] [--out DIR] [--run NAME] [--contacts]
    rigid-gym replay FILE [FILE ...] [--web]
    rigid-gym train ENV_ID [--algo sac|tqc|ppo|bc_sac|RECIPE] [--learner auto|sbx|sb3|batch] [--steps N]
                    [--seed S] [--n-envs N] [--out DIR] [--eval-freq N] [--eval-episodes N]
                    [--final-episodes N] [--results DIR] [--checkpoint-freq N] [--resume]
                    [--demos N] [--demo-dataset ID] [--progress-bar]
    rigid-gym sweep ENV_ID [ENV_ID ...] --seeds S [S ...] [--param KEY=V1,V2 ...] [--steps N]
                    [--out DIR] [--name NAME] [--eval-freq N] [--eval-episodes N]
                    [--cpus-per-trial C] [--max-failures K]
    rigid-gym sweep --resume EXPERIMENT_DIR
    rigid-gym evaluate MODEL [--env ENV_ID] [--episodes N] [--record DIR]
    rigid-gym report [--out DIR] [--quick] [--no-compare]
    rigid-gym dataset ENV_ID --dataset-id ID [--policy random|scripted|MODEL.zip] [--episodes N]
                      [--noise SIGMA] [--seed S]
    rigid-gym dataset --verify ID
    rigid-gym dataset --recipes [--episodes N]

``demo`` runs a few scenes (tumbling bodies of every shape, a ten-cube tower, a bouncing ball,
a sliding box) and prints each result next to its closed form. ``record`` writes episodes of
an env to ``.rrd`` files (``rigid_gym.recording``) and ``replay`` opens them in the rerun
viewer installed with rerun-sdk. ``train`` and ``evaluate`` run the stable-baselines3
baselines (``rigid_gym.agents``): settings from ``agents/hyperparams.yml``, success rates over
seeded episodes; ``sweep`` runs many training runs as Ray Tune trials on the Ray cluster
that RAY_ADDRESS names (``rigid_gym.agents.sweep``). ``report`` regenerates the accuracy and
stability report (``rigid_gym.report``: OUT/report.md and OUT/images/report/*.png).
``dataset`` writes a Minari dataset of an env's episodes (under MINARI_DATASETS_PATH),
replays one bit for bit (``--verify``) or regenerates the shipped ones
(``rigid_gym.agents.datasets``).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import importlib.util
import os
import shutil
import subprocess
import sys
import sysconfig
import time
from pathlib import Path

import numpy as np

from rigid_gym.checks import BadFile, allowed


def timed_steps(world, steps: int) -> float:
    """Step ``world`` ``steps`` times; return steps/s, the first step (which sizes the pair
    buffers) left out of the timing."""
    world.step(1)
    start = time.perf_counter()
    world.step(steps - 1)
    return (steps - 1) / (time.perf_counter() - start)


def demo(steps: int, dt: float, order: int) -> int:
    """Run a few scenes and print each result next to its closed form."""
    import rigid_gym as rg
    from rigid_gym import analytic
    from rigid_gym.meshes import l_shape_mesh

    print(f"rigid_gym demo (dt = {dt:g} s)")
    # 1. free flight: every shape tumbling; L and energy are invariants, the centre falls exactly
    scene = rg.Scene(gravity=(0.0, 0.0, -9.81))
    shapes = [rg.Box((0.1, 0.2, 0.3)), rg.Sphere(0.1), rg.Capsule(0.05, 0.2), l_shape_mesh()]
    for k, shape in enumerate(shapes):
        scene.add_body(shape, density=500.0, position=(k, 0.0, 10.0), velocity=(0.0, 1.0, 5.0),
                       angular_velocity=(3.0, 0.1 * k, 5.0), name=type(shape).__name__.lower())
    world = rg.World(scene, dt=dt, config=rg.SolverConfig.for_scene(scene, rotation_order=order))

    def rotational_energy():
        return 0.5 * np.sum(world.body_angular_momentum * world.angular_velocity, axis=-1)

    momentum0, energy0 = world.body_angular_momentum.copy(), rotational_energy()
    rate = timed_steps(world, steps)
    x, _ = analytic.free_fall_discrete(scene.bodies[0].position, scene.bodies[0].velocity,
                                       scene.gravity, dt, steps)
    print(f"  free flight, 4 shapes tumbling for {steps * dt:g} s ({rate:,.0f} steps/s):")
    print(f"    box centre vs discrete free fall        {np.abs(world.position[0] - x).max():.1e} m")
    print(f"    angular momentum change                 "
          f"{np.abs(world.body_angular_momentum - momentum0).max():.1e} kg m^2/s")
    print(f"    rotational energy change (rotation order {order})  "
          f"{np.max(np.abs(rotational_energy() / energy0 - 1.0)):.1e}")
    # 2. a ten-cube tower standing on the ground
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    for k in range(10):
        scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0.0, 0.0, 0.05 + 0.1 * k))
    world = rg.World(scene, dt=dt)
    top = world.position[10].copy()
    rate = timed_steps(world, steps)
    print(f"  ten-cube tower, {steps * dt:g} s ({rate:,.0f} steps/s): top cube moved "
          f"{np.linalg.norm(world.position[10] - top):.1e} m, deepest overlap "
          f"{world.contacts().depth.max(initial=0.0):.1e} m")
    # 3. a ball bouncing with restitution 0.8, and a box sliding to a stop
    scene = rg.Scene()
    scene.add_ground(restitution=0.8, friction=0.4)
    scene.add_body(rg.Sphere(0.05), mass=1.0, position=(0.0, 0.0, 1.05), restitution=0.8)
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(1.0, 0.0, 0.05),
                   velocity=(2.0, 0.0, 0.0), friction=0.4)
    world = rg.World(scene, dt=dt)
    apex, rising = 0.0, False
    while not (rising and world.velocity[1, 2] <= 0.0) or apex == 0.0:
        rising = world.velocity[1, 2] > 0.0
        world.step()
        if rising and world.velocity[1, 2] <= 0.0:
            apex = world.position[1, 2] - 0.05
    world.step(max(0, int(2.0 / dt) - world.steps))
    slide = world.position[2, 0] - 1.0
    print(f"  ball dropped from 1 m, e = 0.8: first apex {apex:.4f} m (e^2 h0 = 0.6400 m)")
    print(f"  box sliding at 2 m/s, mu = 0.4: stops after {slide:.4f} m "
          f"(v0^2 / (2 mu g) = {2.0 ** 2 / (2 * 0.4 * 9.81):.4f} m)")
    return 0


def record(env_id: str, policy: str, algo: str | None, episodes: int, seed: int, out: str,
           run: str | None, contacts: bool, effector: str = "pad") -> int:
    """Record ``episodes`` episodes of ``env_id`` driven by ``policy`` through ``effector``
    (the pad, or the two-finger gripper); print each file."""
    import gymnasium as gym

    from rigid_gym.agents.policies import make_policy
    from rigid_gym.recording import RecordRerun

    kwargs: dict = {"effector": effector}
    if policy.endswith(".zip"):  # a pixel model's env shows it what it was trained on
        from rigid_gym.agents.evaluate import observation_kwargs, run_metadata

        kwargs |= observation_kwargs(run_metadata(policy))
    env = RecordRerun(gym.make(env_id, **kwargs), out, episode_trigger=lambda k: True,
                      run=run or f"{policy_name(policy)}-seed{seed}", contacts=contacts)
    act = make_policy(env, policy, algo, seed)
    print(f"recording {episodes} episode(s) of {env_id}, policy {policy}, seed {seed}")
    try:
        for episode in range(episodes):
            observation, _ = env.reset(seed=seed if episode == 0 else None)
            steps, total, done, info = 0, 0.0, False, {}
            while not done:
                observation, reward, terminated, truncated, info = env.step(act(observation))
                steps, total, done = steps + 1, total + float(reward), terminated or truncated
            env.sync()  # the file is written in the background: wait for it to print its size
            written = f"{env.paths[-1]} ({env.paths[-1].stat().st_size / 1024:.0f} KiB)" \
                if len(env.paths) > episode else "not written (RERUN=off)"
            print(f"  episode {episode}: {steps} steps, return {total:.2f}, success "
                  f"{bool(info.get('is_success'))}: {written}")
    finally:
        env.close()
    return 0


def policy_name(policy: str) -> str:
    """The run-name part of a --policy value: random, scripted or the model file's stem."""
    return Path(policy).stem if policy.endswith(".zip") else policy


def train(args) -> int:
    """Train a baseline; print where the run went and its final evaluation."""
    from rigid_gym.agents.train import latest_checkpoint, load_hyperparams, run_directory
    from rigid_gym.agents.train import train as run_training

    resume = None
    if args.resume and args.obs_mode == "pixels":
        # the pixel recipe goes on from its run folder's checkpoints/latest.pt
        resume = run_directory(args.out, args.env_id, args.algo or "distill",
                               args.seed) / "checkpoints"
    elif args.resume:
        folder = run_directory(args.out, args.env_id,
                               args.algo or load_hyperparams(args.env_id)["algo"], args.seed)
        resume = latest_checkpoint(folder)
        if resume is None:
            raise ValueError(f"--resume: no checkpoint in {folder}/checkpoints (runs write "
                             "them with --checkpoint-freq)")
        print(f"resuming from {resume}")
    folder = run_training(args.env_id, algo=args.algo, timesteps=args.steps, seed=args.seed,
                          n_envs=args.n_envs, out=args.out, eval_freq=args.eval_freq,
                          eval_episodes=args.eval_episodes,
                          checkpoint_freq=args.checkpoint_freq,
                          progress_bar=args.progress_bar and sys.stdout.isatty(),
                          demonstrations=args.demos, demo_dataset=args.demo_dataset,
                          resume=resume, progress=True,
                          learner=None if args.learner == "auto" else args.learner,
                          final_episodes=args.final_episodes, results=args.results,
                          obs_mode=args.obs_mode, teacher=args.teacher)
    print(f"trained {args.env_id}: {folder / 'model.zip'}")
    if args.final_episodes:
        import json

        result = json.loads((folder / "result.json").read_text())
        print(f"final evaluation ({result['episodes']} episodes): success rate "
              f"{result['success']:.0%}; {result['env_steps']:,} env steps in "
              f"{result['wall_s']:.0f} s wall, {result['cpu_s']:.0f} s CPU ({result['learner']})")
    return 0


def sweep(args) -> int:
    """Run (or resume) a sweep; print the results table; 1 if a trial failed."""
    from rigid_gym.agents.sweep import parse_param
    from rigid_gym.agents.sweep import sweep as run_sweep

    if args.resume is None and not (args.env_ids and args.seeds):
        raise ValueError("sweep: give ENV_ID... and --seeds, or --resume EXPERIMENT_DIR")
    params = dict(parse_param(text) for text in args.param)
    if importlib.util.find_spec("ray") is None:
        raise ValueError("sweep needs Ray: pip install 'rigid_gym[ray]'")
    folder, failed = run_sweep(args.env_ids, args.seeds, params, steps=args.steps, out=args.out,
                               name=args.name, eval_freq=args.eval_freq,
                               eval_episodes=args.eval_episodes,
                               cpus_per_trial=args.cpus_per_trial,
                               max_failures=args.max_failures, resume=args.resume)
    print((folder / "results.md").read_text(), end="")
    print(f"sweep: {folder} (results.md, curve_*.png, a folder per trial)")
    return 1 if failed else 0


def evaluate(args) -> int:
    """Evaluate a saved model; optionally record the episodes."""
    from rigid_gym.agents.evaluate import evaluate as run_evaluation

    result = run_evaluation(args.model, args.env, args.episodes, progress=True)
    print(f"{result['env_id']}: success rate {result['success_rate']:.0%} over "
          f"{result['episodes']} episodes, return {result['mean_return']:.1f} "
          f"+- {result['std_return']:.1f}")
    if args.record:
        return record(result["env_id"], args.model, None, min(args.episodes, 3), 0, args.record,
                      None, False)
    return 0


def dataset(args) -> int:
    """Write a Minari dataset, verify one (1 if an episode does not replay bit for bit) or
    regenerate the shipped ones; print what was done."""
    if importlib.util.find_spec("minari") is None:
        raise ValueError("dataset needs Minari: pip install 'rigid_gym[datasets]'")
    from rigid_gym.agents import datasets

    if args.verify:
        def show(r):
            print(f"  episode {r.episode} (seed {r.seed}, {r.steps} steps): "
                  + ("pass" if r.ok else f"FAIL, {r.mismatch}"))

        data = datasets.load(args.verify)
        print(f"verifying {data.id}: {data.total_episodes} episodes replayed in "
              f"{data.env_spec.id}, reset with their seeds")
        results = datasets.verify(data, show)
        passed = sum(r.ok for r in results)
        print(f"{passed} of {len(results)} episodes replay bit for bit")
        return 0 if passed == len(results) else 1
    if args.recipes:
        written = datasets.write_recipes(args.episodes or datasets.RECIPE_EPISODES, progress=True)
    elif args.env_id is None or args.dataset_id is None:
        raise ValueError("dataset: give ENV_ID and --dataset-id, or --verify ID, or --recipes")
    else:
        written = [datasets.write_dataset(args.dataset_id, args.env_id, args.policy,
                                          args.episodes or 100, args.noise, args.seed,
                                          progress=True)]
    for data in written:
        meta = data.storage.metadata
        print(f"{data.id}: {data.total_episodes} episodes, {data.total_steps:,} steps of "
              f"{data.env_spec.id}, policy {meta['policy']}, noise {meta['action_noise']:g}, "
              f"success {meta['success_rate']:.0%}, {meta['dataset_size']:g} MB in "
              f"{datasets.datasets_root() / data.id}")
    return 0


def replay(files: list[str], web: bool = False) -> int:
    """Open ``files`` in the rerun viewer, with the layout (blueprint file) beside each;
    returns the viewer's exit status. ``web``, or no display (Linux without DISPLAY and
    WAYLAND_DISPLAY, where the native viewer cannot open a window): rerun's web viewer,
    served to a browser at the address it prints, until Ctrl-C."""
    missing = [f for f in files if not Path(f).is_file()]
    if missing:
        print(f"rigid-gym replay: no such file: {', '.join(missing)}", file=sys.stderr)
        return 2
    viewer = find_rerun()
    if viewer is None:
        print(f"rigid-gym replay: the rerun viewer was not found next to {sys.executable} or on "
              "PATH; it comes with pip install 'rerun-sdk==0.41.*'", file=sys.stderr)
        return 1
    from rigid_gym.envs.base import display_available
    from rigid_gym.recording import blueprint_of

    layouts = {str(b): None for b in map(blueprint_of, files) if b is not None}  # in order, once
    opened = [*files, *(b for b in layouts if b not in files)]
    if not web and not display_available():
        print("rigid-gym replay: no display (DISPLAY and WAYLAND_DISPLAY are unset), so no "
              "window can open: serving the recordings to a browser with rerun's web viewer "
              "instead (rerun --web-viewer). Open the address it prints below; from another "
              "machine, forward its two ports first (ssh -L 9090:localhost:9090 -L "
              "9876:localhost:9876 HOST). Ctrl-C stops it.", file=sys.stderr, flush=True)
        web = True
    if web:
        return subprocess.call([viewer, "--web-viewer", *opened])
    status = subprocess.call([viewer, *opened])
    if status != 0:
        print(f"rigid-gym replay: the rerun viewer exited with status {status}; where it "
              "could not open a window, rigid-gym replay --web FILE serves the recordings to "
              "a browser (rerun --web-viewer), and a recording can be read in Python "
              "(README, \"Reading a recording back\")", file=sys.stderr)
    return status


def find_rerun() -> str | None:
    """The ``rerun`` executable installed with this Python's rerun-sdk, else the first on
    PATH, else None. The SDK's install record names its script (in the scripts folder of the
    environment that holds the SDK: a venv's own, or its base's when the venv sees the base's
    packages); without a record, this interpreter's scripts folder and folder are tried."""
    name = "rerun.exe" if os.name == "nt" else "rerun"
    candidates = []
    try:
        sdk = importlib.metadata.distribution("rerun-sdk")
        candidates += [str(sdk.locate_file(f)) for f in sdk.files or ()
                       if f.name == name and f.parent.name in ("bin", "Scripts")]
    except importlib.metadata.PackageNotFoundError:
        pass
    candidates += [os.path.join(folder, name)
                   for folder in (sysconfig.get_path("scripts"), os.path.dirname(sys.executable))]
    for candidate in candidates:
        if os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            return os.path.normpath(candidate)
    return shutil.which("rerun")


def env_id(text: str) -> str:
    """An argparse type: a registered rigid_gym env id."""
    import rigid_gym

    if text not in rigid_gym.ENV_IDS:
        raise argparse.ArgumentTypeError(f"unknown env id {text!r}; choose from "
                                         f"{', '.join(rigid_gym.ENV_IDS)}")
    return text


def policy_spec(text: str) -> str:
    """An argparse type: random, scripted or a path ending in .zip."""
    if text in ("random", "scripted") or text.endswith(".zip"):
        return text
    raise argparse.ArgumentTypeError(f"expected random, scripted or a model .zip, got {text!r}")


def bounded(kind, low, high):
    """An argparse type: ``kind`` (int or float) within [low, high], else a clear error."""

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {kind.__name__}, got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be {allowed(low, high)}, got {text}")
        return value

    return parse


def build_parser() -> argparse.ArgumentParser:
    """The ``rigid-gym`` command line: a subcommand per job, help on every flag."""
    import rigid_gym

    parser = argparse.ArgumentParser(
        prog="rigid-gym", description="Robot-manipulation RL tasks (Gymnasium) on an "
        "impulse-based rigid-body solver: run the solver's demo, record and replay episodes, "
        "train and evaluate baselines, write offline datasets, regenerate the report. "
        "`rigid-gym COMMAND --help` tells more.")
    parser.add_argument("--version", action="version",
                        version=f"rigid-gym {rigid_gym.__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    p = commands.add_parser("demo", help="run a few scenes and compare them with closed forms")
    p.add_argument("--steps", type=bounded(int, 2, 10**7), default=2400,
                   help="number of steps, 2 to 1e7 (default 2400)")
    p.add_argument("--dt", type=bounded(float, 1e-6, 0.1), default=1 / 240,
                   help="time step, s, 1e-6 to 0.1 (default 1/240)")
    p.add_argument("--order", type=int, default=2, choices=(1, 2, 3),
                   help="order of the rotation update, 1 to 3 (default 2)")
    p = commands.add_parser("record", help="record episodes of an env to .rrd files")
    p.add_argument("env_id", type=env_id, help="e.g. rigid_gym/Push-v0")
    p.add_argument("--policy", type=policy_spec, default="scripted",
                   help="random, scripted (default) or a stable-baselines3 model .zip")
    p.add_argument("--algo", default=None,
                   help="the model's algorithm class (SAC, TQC, PPO, ...); default: read "
                        "from the zip")
    p.add_argument("--episodes", type=bounded(int, 1, 10**4), default=1,
                   help="number of episodes, 1 to 1e4 (default 1)")
    p.add_argument("--seed", type=bounded(int, 0, 2**32 - 1), default=0,
                   help="seed of the first reset (and of random actions), 0 to 2^32-1")
    p.add_argument("--out", default="recordings",
                   help="output folder (default recordings); files go to "
                        "OUT/<env id>/<run>-episode-<k>.rrd")
    p.add_argument("--run", default=None,
                   help="run name in the file names (default <policy>-seed<seed>)")
    p.add_argument("--contacts", action="store_true",
                   help="also record contact points and force arrows")
    p.add_argument("--effector", choices=("pad", "gripper"), default="pad",
                   help="pad (default) or gripper: the two-finger gripper, on the tasks that "
                        "pick objects up")
    p = commands.add_parser("replay", help="open .rrd recordings in the rerun viewer")
    p.add_argument("files", nargs="+", metavar="FILE", help=".rrd file(s)")
    p.add_argument("--web", action="store_true",
                   help="serve them to a browser with rerun's web viewer (the default where "
                        "no display is found) instead of opening a window")
    p = commands.add_parser("train", help="train a stable-baselines3 baseline on an env")
    p.add_argument("env_id", type=env_id, help="e.g. rigid_gym/Push-v0")
    p.add_argument("--obs-mode", choices=("state", "pixels"), default="state",
                   help="pixels: a pixel recipe, on the frame, goal and pad state (algo "
                   "distill, the default: a student taught on its own states by a state "
                   "policy; drq: SAC + HER with random shifts, no privileged state)")
    p.add_argument("--teacher", metavar="MODEL", default=None,
                   help="with --obs-mode pixels: the state policy that labels the student's "
                   "states (default hyperparams.yml's)")
    p.add_argument("--algo", default=None,
                   help="sac, tqc, ppo, bc_sac, distill, drq, or a recipe of the env's entry "
                        "in agents/hyperparams.yml (its `algos`: e.g. sac_gripper); default: "
                        "the entry's own")
    p.add_argument("--learner", choices=("auto", "sbx", "sb3", "batch"), default="auto",
                   help="sbx (JAX, the `fast` extra), sb3 (PyTorch) or batch (ppo only: JAX "
                        "over the batched env); auto: hyperparams.yml's, else sbx where "
                        "installed, ppo on batch")
    p.add_argument("--steps", type=bounded(int, 1, 10**9), default=None,
                   help="env steps, 1 to 1e9 (default: hyperparams.yml)")
    p.add_argument("--seed", type=bounded(int, 0, 2**32 - 1), default=0,
                   help="training seed, 0 to 2^32-1 (default 0): the run's folder and every "
                        "generator derive from it")
    p.add_argument("--n-envs", type=bounded(int, 1, 1024), default=None,
                   help="envs stepped together, 1 to 1024 (default: hyperparams.yml)")
    p.add_argument("--out", default="runs", help="runs folder (default runs)")
    p.add_argument("--eval-freq", type=bounded(int, 0, 10**9), default=None,
                   help="env steps between evaluations (0: none; default: 20 over the run)")
    p.add_argument("--eval-episodes", type=bounded(int, 1, 10**4), default=20,
                   help="episodes of each evaluation during training, 1 to 1e4 (default 20)")
    p.add_argument("--final-episodes", type=bounded(int, 0, 10**5), default=100,
                   help="episodes of the final evaluation, written to the run's result.json "
                        "(0: none; default 100)")
    p.add_argument("--results", default=None, metavar="DIR",
                   help="also copy the result to DIR/<name>-<algo>-seed<k>.json (the results "
                        "table reads agents/results)")
    p.add_argument("--checkpoint-freq", type=bounded(int, 0, 10**9), default=0,
                   help="env steps between checkpoints (0: none)")
    p.add_argument("--demos", type=bounded(int, 0, 10**6), default=None,
                   help="demonstration episodes put in the replay buffer first (off-policy only; "
                        "default: hyperparams.yml, else 0)")
    p.add_argument("--demo-dataset", metavar="ID", default=None,
                   help="the Minari dataset the --demos episodes come from (default: the "
                        "scripted policy's, written for the run to a temporary folder)")
    p.add_argument("--resume", action="store_true",
                   help="go on from the run's newest checkpoint (see --checkpoint-freq)")
    p.add_argument("--progress-bar", action="store_true",
                   help="also a bar of the training steps (stable-baselines3's)")
    p = commands.add_parser("sweep", help="training runs as Ray Tune trials on a Ray cluster "
                                          "(RAY_ADDRESS; a local one when unset)")
    p.add_argument("env_ids", nargs="*", type=env_id, metavar="ENV_ID",
                   help="e.g. rigid_gym/Push-v0 rigid_gym/Throw-v0")
    p.add_argument("--seeds", nargs="+", type=bounded(int, 0, 2**32 - 1), default=[],
                   help="training seeds, 0 to 2^32-1; every env id runs each")
    p.add_argument("--param", action="append", default=[], metavar="KEY=V1,V2",
                   help="an algorithm argument and the values to try (YAML; repeat for a grid)")
    p.add_argument("--steps", type=bounded(int, 1, 10**9), default=None,
                   help="env steps per run, 1 to 1e9 (default: hyperparams.yml)")
    p.add_argument("--out", default="runs/sweeps",
                   help="folder of experiment folders (default runs/sweeps; on a cluster, one "
                        "that every machine sees)")
    p.add_argument("--name", default=None, help="experiment name (default sweep-<date-time>)")
    p.add_argument("--eval-freq", type=bounded(int, 1, 10**9), default=10_000,
                   help="env steps between evaluations and checkpoints (default 10000)")
    p.add_argument("--eval-episodes", type=bounded(int, 1, 10**4), default=20,
                   help="episodes of each evaluation, 1 to 1e4 (default 20)")
    p.add_argument("--cpus-per-trial", type=bounded(float, 0.01, 1024), default=1.0,
                   help="CPUs Ray reserves per trial (default 1)")
    p.add_argument("--max-failures", type=bounded(int, 0, 100), default=0,
                   help="retries of a failed trial from its newest checkpoint (default 0)")
    p.add_argument("--resume", metavar="EXPERIMENT_DIR", default=None,
                   help="go on with a stopped sweep: failed and unfinished trials resume from "
                        "their newest checkpoints")
    p = commands.add_parser("evaluate", help="success rate of a trained model")
    p.add_argument("model", help="a model .zip: a run's model.zip (rigid-gym train), or one "
                                 "of agents/models/")
    p.add_argument("--env", type=env_id, default=None,
                   help="env id (default: from the model's settings: run.json in its folder, "
                        "or NAME.json beside NAME.zip)")
    p.add_argument("--episodes", type=bounded(int, 1, 10**5), default=100,
                   help="seeded evaluation episodes, 1 to 1e5 (default 100)")
    p.add_argument("--record", metavar="DIR", default=None,
                   help="also record up to 3 episodes to DIR")
    p = commands.add_parser("report", help="regenerate the accuracy and stability report")
    p.add_argument("--out", default="docs",
                   help="folder for report.md and images/report/ (default docs)")
    p.add_argument("--quick", action="store_true",
                   help="a tiny sweep and short stiff runs (seconds), to check the pipeline")
    p.add_argument("--no-compare", action="store_true",
                   help="skip the peer engines (PyBullet) even when installed")
    p = commands.add_parser("dataset", help="write, verify or regenerate Minari datasets "
                                            "(MINARI_DATASETS_PATH)")
    p.add_argument("env_id", nargs="?", type=env_id, default=None, help="e.g. rigid_gym/Push-v0")
    p.add_argument("--dataset-id", default=None,
                   help="the dataset's id, e.g. rigid_gym/push/expert-v0")
    p.add_argument("--policy", type=policy_spec, default="scripted",
                   help="random, scripted (default) or a stable-baselines3 model .zip")
    p.add_argument("--episodes", type=bounded(int, 1, 10**6), default=None,
                   help="episodes, 1 to 1e6 (default 100; with --recipes 200 per dataset)")
    p.add_argument("--noise", type=bounded(float, 0.0, 10.0), default=0.0,
                   help="standard deviation of Gaussian noise added to each action, 0 to 10 "
                        "(the actions then clipped to [-1, 1]; default 0)")
    p.add_argument("--seed", type=bounded(int, 0, 2**32 - 1), default=0,
                   help="episode k is reset with seed S + k (default 0)")
    p.add_argument("--verify", metavar="ID", default=None,
                   help="replay every episode of dataset ID and compare it bit for bit")
    p.add_argument("--recipes", action="store_true",
                   help="regenerate the shipped datasets rigid_gym/{push,stack,throw}/"
                        "{expert,noisy,random}-v0, replacing them")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command == "demo":
        return demo(args.steps, args.dt, args.order)
    if args.command == "replay":
        return replay(args.files, args.web)
    if args.command == "report":
        missing = [m for m in ("matplotlib", "scipy") if importlib.util.find_spec(m) is None]
        if missing:
            parser.error(f"report needs {' and '.join(missing)}: pip install 'rigid_gym[report]'")
        from rigid_gym.report import generate

        generate(args.out, quick=args.quick, compare=not args.no_compare)
        return 0
    try:
        if args.command == "train":
            return train(args)
        if args.command == "sweep":
            return sweep(args)
        if args.command == "evaluate":
            return evaluate(args)
        if args.command == "dataset":
            return dataset(args)
        return record(args.env_id, args.policy, args.algo, args.episodes, args.seed, args.out,
                      args.run, args.contacts, args.effector)
    except ValueError as exc:  # an argument: the usage says what is allowed
        parser.error(str(exc))
    except BadFile as exc:  # the arguments were fine, a file is not: no usage
        print(f"rigid-gym: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
