"""Ray: the RLlib recipe (rigid_gym.agents.rllib) and sweeps of training runs as Tune trials
(rigid_gym.agents.sweep), each on a local Ray cluster of 2 CPUs. Skipped without Ray (the
``ray`` extra)."""

import json
import math
import os
import signal
import subprocess
import time

import pytest

pytest.importorskip("ray.tune")  # the tune extra too, which the sweeps use
import ray


def test_rllib_trains_ppo_on_a_task_by_its_id():
    import rigid_gym.agents.rllib  # noqa: F401  (registers the ids with RLlib)
    from ray.rllib.algorithms.ppo import PPOConfig

    ray.init(address="local", num_cpus=2, include_dashboard=False)  # not a `ray start` one
    try:
        config = (PPOConfig().environment("rigid_gym/PushDense-v0",
                                          env_config={"observation_noise": 0.01})
                  .env_runners(num_env_runners=1)  # a process that never imported rigid_gym
                  .training(train_batch_size_per_learner=200, minibatch_size=100, num_epochs=1))
        algo = config.build_algo()
        for iteration in (1, 2):
            result = algo.train()
            runners = result["env_runners"]
            assert runners["num_env_steps_sampled_lifetime"] == 200 * iteration
        assert math.isfinite(runners["episode_return_mean"])  # 50-step episodes finished
        assert runners["episode_len_mean"] == 50
        algo.stop()
    finally:
        ray.shutdown()


def sweep(*arguments, **popen) -> subprocess.Popen:
    """``rigid-gym sweep ARGUMENTS`` on a local cluster of its own (RAY_ADDRESS=local: not a
    cluster that ``ray start`` left running on this machine, which Ray would join)."""
    env = {**os.environ, "RAY_ADDRESS": "local"}
    return subprocess.Popen(["rigid-gym", "sweep", *arguments], env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, **popen)


def finish(process: subprocess.Popen) -> tuple[int, str]:
    output, _ = process.communicate(timeout=600)
    return process.returncode, output


def test_a_sweep_runs_every_seed_as_a_trial_and_writes_the_table(tmp_path):
    from rigid_gym.agents.evaluate import evaluate

    code, output = finish(sweep("rigid_gym/Push-v0", "--seeds", "0", "1", "--steps", "200",
                                "--eval-freq", "100", "--eval-episodes", "1",
                                "--out", str(tmp_path), "--name", "tiny"))
    assert code == 0, output[-4000:]
    folder = tmp_path / "tiny"
    table = (folder / "results.md").read_text()
    assert "| rigid_gym/Push-v0 | SAC + HER | 200 |" in table and "| 2 |" in table
    assert "Failed" not in table
    assert (folder / "curve_Push-v0.png").stat().st_size > 10_000
    trials = sorted(p for p in folder.iterdir() if p.is_dir())
    assert [t.name for t in trials] == ["Push-v0-seed0-00000", "Push-v0-seed1-00001"]
    for seed, trial in enumerate(trials):
        (checkpoint,) = trial.glob("checkpoint_*")  # Tune keeps the newest
        run = json.loads((checkpoint / "run.json").read_text())
        assert run["timesteps"] == 200 and run["seed"] == seed
        assert (checkpoint / "evaluations.csv").read_text().count("\n") == 3  # header, 100, 200
        assert evaluate(checkpoint / "model.zip", episodes=1)["episodes"] == 1


def test_a_killed_trial_is_reported_and_resumes_from_its_checkpoint(tmp_path):
    process = sweep("rigid_gym/Push-v0", "--seeds", "0", "--steps", "600", "--eval-freq", "50",
                    "--eval-episodes", "1", "--param", "learning_starts=100",
                    "--out", str(tmp_path), "--name", "killed")
    folder = tmp_path / "killed"
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and process.poll() is None:  # the first checkpoint
        reports = [line for path in folder.glob("*/result.json")
                   for line in path.read_text().splitlines()]
        if reports:
            os.kill(json.loads(reports[-1])["pid"], signal.SIGKILL)  # the trial's process
            break
        time.sleep(0.1)
    code, output = finish(process)
    assert code == 1, output[-4000:]
    table = (folder / "results.md").read_text()
    assert "Failed trials (1;" in table and "seed 0 learning_starts=100" in table
    assert f"rigid-gym sweep --resume {folder}" in table

    code, output = finish(sweep("--resume", str(folder)))
    assert code == 0, output[-4000:]
    table = (folder / "results.md").read_text()
    assert "| rigid_gym/Push-v0 (learning_starts=100) | SAC + HER | 600 |" in table
    assert "Failed" not in table
    (checkpoint,) = folder.glob("*/checkpoint_*")
    run = json.loads((checkpoint / "run.json").read_text())
    (resumed_at,) = run["resumed_at"]  # one resume, from a checkpoint before the end
    assert 50 <= resumed_at < 600 and resumed_at % 50 == 0
    steps = [int(line.split(",")[0])
             for line in (checkpoint / "evaluations.csv").read_text().splitlines()[1:]]
    assert steps == list(range(50, 601, 50))  # the curve goes on where the checkpoint was
