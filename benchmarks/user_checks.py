"""What a new user reaches for, checked as they would try it: every check runs the installed
package (commands through ``rigid-gym`` in subprocesses, as a shell would) and prints PASS or
FAIL with what it saw; the exit status is the number of failures.

- snapshots: ``save_state``/``restore_state``, ``copy.deepcopy`` and ``pickle`` of each task's
  env (and a vector env) go on bit for bit as the original with the same actions;
- ``render()`` at the env's ``width`` and ``height``;
- ``rigid-gym --version``;
- ``rigid-gym dataset`` errors (a dataset id without a version, a missing episode folder, a
  truncated .arrow file, a garbage metadata.json): non-zero exit, no traceback, the file
  named, nothing left behind;
- ``rigid-gym replay`` without a display: it says so and serves rerun's web viewer;
- Ctrl-C (SIGINT to the process group, as a terminal sends it) at five moments of a
  recording process while busy loops hold every core: each process exits within
  ``CTRL_C_LIMIT`` s, and every episode it finished is a whole rerun file once the writer
  process is done;
- the package metadata (importlib.metadata): author, classifiers, license, URLs.

    python benchmarks/user_checks.py            # about a minute on 2 cores
"""

import copy
import importlib.metadata
import json
import os
import pickle
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import rigid_gym  # noqa: F401  (registers the ids)
from rigid_gym.cli import find_rerun

CTRL_C_LIMIT = 10.0
"""s: the longest a recording process may take to exit after Ctrl-C."""
CTRL_C_DELAYS = (0.0, 0.05, 0.3, 1.0, 3.0)
"""s after the first recorded reset at which Ctrl-C is sent: while the writer process is
still importing, then while it writes."""
RIGID_GYM = [sys.executable, "-c",
             "import sys; from rigid_gym.cli import main; sys.exit(main())"]
"""``rigid-gym`` as this interpreter runs it (the console script of the same install)."""
failures = 0


def report(ok: bool, name: str, detail: str) -> None:
    global failures
    failures += not ok
    print(f"{'PASS' if ok else 'FAIL'} {name}: {detail}", flush=True)


def run(args: list[str], env: dict | None = None, timeout: float = 120):
    """``rigid-gym args``: (exit status, stdout, stderr)."""
    done = subprocess.run(RIGID_GYM + args, capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, **(env or {})}, check=False)
    return done.returncode, done.stdout, done.stderr


def trace(env, actions) -> bytes:
    """Every step's observation and reward, with a reset (no seed) half way."""
    out = []
    for k, action in enumerate(actions):
        obs, reward, *_ = env.step(action)
        if k == len(actions) // 2:
            obs, _ = env.reset()
        out += [np.ascontiguousarray(v).tobytes() for v in obs.values()]
        out.append(np.asarray(reward, dtype=np.float64).tobytes())
    return b"".join(out)


def check_snapshots() -> None:
    for env_id in ("rigid_gym/Push-v0", "rigid_gym/Stack-v0", "rigid_gym/Throw-v0"):
        env = gym.make(env_id, randomize=True).unwrapped
        env.reset(seed=7)
        rng = np.random.default_rng(7)
        trace(env, rng.uniform(-1, 1, (20, *env.action_space.shape)))
        state = env.save_state()
        copies = {"deepcopy": copy.deepcopy(env), "pickle": pickle.loads(pickle.dumps(env))}
        actions = rng.uniform(-1, 1, (120, *env.action_space.shape))
        first = trace(env, actions)
        env.restore_state(state)
        same = {"restore_state": trace(env, actions) == first}
        same |= {name: trace(other, actions) == first for name, other in copies.items()}
        report(all(same.values()), f"snapshot {env_id}",
               f"120 steps with a reset, bit for bit: {same}")
    envs = gym.make_vec("rigid_gym/Stack-v0", num_envs=4, max_episode_steps=30,
                        observation_noise=0.01)
    envs.reset(seed=3)
    actions = np.random.default_rng(3).uniform(-1, 1, (100, *envs.action_space.shape))
    state = envs.save_state()
    twin = pickle.loads(pickle.dumps(envs))
    first = trace(envs, actions)
    envs.restore_state(state)
    same = {"restore_state": trace(envs, actions) == first, "pickle": trace(twin, actions) == first}
    report(all(same.values()), "snapshot make_vec Stack x 4",
           f"100 steps, autoresets and noise, bit for bit: {same}")


def check_render() -> None:
    env = gym.make("rigid_gym/Push-v0", render_mode="rgb_array", width=128, height=96)
    env.reset(seed=0)
    shape = env.render().shape
    report(shape == (96, 128, 3), "render size", f"width=128, height=96 -> {shape}")


def check_version() -> None:
    code, out, _ = run(["--version"])
    expected = f"rigid-gym {importlib.metadata.version('rigid_gym')}"
    report(code == 0 and out.strip() == expected, "rigid-gym --version", repr(out.strip()))


def listing(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def check_datasets() -> None:
    with tempfile.TemporaryDirectory() as root:
        env = {"MINARI_DATASETS_PATH": root}
        code, _, err = run(["dataset", "rigid_gym/Push-v0", "--dataset-id", "push",
                            "--episodes", "2"], env)
        left = listing(Path(root))
        report(code != 0 and "Traceback" not in err and "'push' is not a dataset id" in err
               and not left, "dataset --dataset-id push",
               f"exit {code}, leftovers {left}, says: {err.strip().splitlines()[-1]!r}")
        code, *_ = run(["dataset", "rigid_gym/Push-v0", "--dataset-id", "uc/good-v0",
                        "--episodes", "2"], env)
        data = Path(root) / "uc"
        damages = {
            "missing episode folder": ("b", lambda d: shutil.rmtree(d / "1"), "data/1"),
            "truncated .arrow": ("c", lambda d: (d / "1" / "part-0.arrow").write_bytes(
                (d / "1" / "part-0.arrow").read_bytes()[:-64]), "data/1/part-0.arrow"),
            "garbage metadata.json": ("d", lambda d: (d / "metadata.json").write_text(
                "garbage{"), "data/metadata.json"),
        }
        for what, (name, damage, file) in damages.items():
            shutil.copytree(data / "good-v0", data / f"{name}-v0")
            meta = data / f"{name}-v0" / "data" / "metadata.json"
            meta.write_text(meta.read_text().replace("uc/good-v0", f"uc/{name}-v0"))
            damage(data / f"{name}-v0" / "data")
            before = listing(Path(root))
            code, _, err = run(["dataset", "--verify", f"uc/{name}-v0"], env)
            named = str(data / f"{name}-v0" / file)
            report(code != 0 and "Traceback" not in err and "usage" not in err and named in err
                   and listing(Path(root)) == before, f"dataset --verify, {what}",
                   f"exit {code}: {err.strip()!r}")


def check_replay() -> None:
    with tempfile.TemporaryDirectory() as out:
        run(["record", "rigid_gym/Push-v0", "--out", out, "--run", "r"])
        episode = Path(out) / "rigid_gym-Push-v0" / "r-episode-0.rrd"
        env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
        process = subprocess.Popen(RIGID_GYM + ["replay", str(episode)], env=env, text=True,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                   start_new_session=True)  # Ctrl-C below reaches the viewer
        seen = ""
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and "Hosting a web-viewer" not in seen:
            line = process.stdout.readline()
            if not line:
                break
            seen += line
        os.killpg(process.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the viewer too
        try:
            process.wait(10)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
        address = re.search(r"connect at (\S+)", seen)
        report("no display" in seen and address is not None, "replay without a display",
               f"serves the web viewer at {address.group(1) if address else None}")


RECORDING = """
import signal
signal.signal(signal.SIGINT, signal.default_int_handler)  # as a terminal's foreground job
import gymnasium as gym
import rigid_gym
from rigid_gym.recording import RecordRerun
env = RecordRerun(gym.make("rigid_gym/Throw-v0", max_episode_steps=3), {folder!r},
                  episode_trigger=lambda k: True, run="interrupted")
env.reset(seed=0)
print("reset", flush=True)
while True:
    for _ in range(3):
        env.step(env.action_space.sample())
    print(env.paths[-1], flush=True)  # finished
    env.reset()
"""


def check_ctrl_c() -> None:
    cores = os.cpu_count() or 2
    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(cores)]
    try:
        for delay in CTRL_C_DELAYS:
            with tempfile.TemporaryDirectory() as folder:
                # output to files: the writer process inherits standard error, so a pipe
                # would stay open until the writer, not the process, has exited
                out, err = Path(folder) / "stdout", Path(folder) / "stderr"
                with out.open("w") as stdout, err.open("w") as stderr:
                    process = subprocess.Popen(
                        [sys.executable, "-c", textwrap.dedent(RECORDING.format(folder=folder))],
                        stdout=stdout, stderr=stderr, start_new_session=True)
                deadline = time.monotonic() + 60
                while "reset" not in out.read_text() and time.monotonic() < deadline:
                    time.sleep(0.01)
                time.sleep(delay)
                os.killpg(process.pid, signal.SIGINT)
                sent = time.monotonic()
                try:
                    process.wait(60)
                except subprocess.TimeoutExpired:
                    os.killpg(process.pid, signal.SIGKILL)
                    process.wait()
                took = time.monotonic() - sent
                finished = out.read_text().replace("reset", "", 1)
                errors = err.read_text()
                writer = re.search(r"writer process \(pid (\d+)\)", errors)
                while writer and Path(f"/proc/{writer.group(1)}").exists() and "zombie" \
                        not in Path(f"/proc/{writer.group(1)}/status").read_text(errors="replace"):
                    time.sleep(0.05)
                files = finished.split()
                whole = subprocess.run([find_rerun(), "rrd", "verify", *files], check=False,
                                       capture_output=True).returncode == 0 if files else True
                report(took <= CTRL_C_LIMIT and whole and process.returncode == -signal.SIGINT,
                       f"Ctrl-C {delay:g} s after the first recorded reset, {cores} busy loops",
                       f"exited in {took:.1f} s (code {process.returncode}); {len(files)} "
                       f"finished episodes, all whole: {whole}")
    finally:
        for p in busy:
            p.kill()
            p.wait()


def check_metadata() -> None:
    meta = importlib.metadata.metadata("rigid_gym")
    urls = meta.get_all("Project-URL") or []
    classifiers = meta.get_all("Classifier") or []
    author = meta.get("Author") or meta.get("Author-email")
    report(bool(author) and len(classifiers) >= 5 and bool(meta.get("License")),
           "package metadata", f"author {author!r}, license {meta.get('License')!r}, "
           f"{len(classifiers)} classifiers")
    report(bool(urls), "package URLs", f"{urls or 'none: the project has no public address '}"
           f"{'' if urls else 'yet; pyproject.toml gets [project.urls] when it is published'}")


if __name__ == "__main__":
    for check in (check_snapshots, check_render, check_version, check_datasets, check_replay,
                  check_ctrl_c, check_metadata):
        try:
            check()
        except Exception as error:  # noqa: BLE001 - a check that crashes is a failure, go on
            report(False, check.__name__, f"{type(error).__name__}: {error}")
    print(json.dumps({"failures": failures}))
    sys.exit(failures)
