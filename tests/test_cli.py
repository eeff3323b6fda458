"""The rigid-gym command."""

import re
import sys

import pytest
from rigid_gym.agents.train import load_hyperparams

from rigid_gym.cli import main


def test_demo_prints_each_result_next_to_its_closed_form(capsys):
    """The demo's figures, read back from what it prints: the invariants of free flight to
    round-off, a tower that does not move, the first apex within 2% of e^2 h0 (its error is
    first order in dt: 1.2% at 1/240) and the slide within 1% of v0^2 / (2 mu g) (v0 dt / 2
    short, 0.8%)."""
    assert main(["demo", "--steps", "48"]) == 0
    out = capsys.readouterr().out

    def figure(label: str) -> float:
        match = re.search(re.escape(label) + r"[^0-9-]*(-?[0-9.]+(?:e[-+][0-9]+)?)", out)
        assert match, f"{label!r} not in the demo's output:\n{out}"
        return float(match.group(1))

    assert figure("box centre vs discrete free fall") < 1e-9
    assert figure("angular momentum change") < 1e-9
    assert figure("rotational energy change (rotation order 2)") < 1e-9
    assert figure("top cube moved") < 1e-12
    assert figure("deepest overlap") < 1e-9
    assert figure("first apex") == pytest.approx(0.8 ** 2, rel=0.02)
    assert figure("stops after") == pytest.approx(2.0 ** 2 / (2 * 0.4 * 9.81), rel=0.01)


@pytest.mark.parametrize("args, message", [
    (["demo", "--steps", "1"], "must be in [2, 10000000], got 1"),
    (["demo", "--dt", "-1"], "must be in [1e-06, 0.1], got -1"),
    (["demo", "--steps", "many"], "expected int, got 'many'"),
])
def test_bad_arguments_fail_with_the_allowed_range(args, message, usage_error):
    assert message in usage_error(args)


# -- record and replay ----------------------------------------------------------------------------

def test_record_writes_one_readable_file_per_episode(tmp_path, capsys):
    from rerun.chunk import RrdReader

    args = ["record", "rigid_gym/Throw-v0", "--policy", "random", "--episodes", "2",
            "--seed", "1", "--out", str(tmp_path)]
    assert main(args) == 0
    folder = tmp_path / "rigid_gym-Throw-v0"
    assert sorted(p.name for p in folder.iterdir()) == [
        "random-seed1-episode-0.rrd", "random-seed1-episode-1.rrd", "rigid_gym-Throw-v0.rbl"]
    for path in folder.glob("*.rrd"):
        (recording,) = RrdReader(path).recordings()
        assert recording.application_id == "rigid_gym-Throw-v0"
    out = capsys.readouterr().out
    assert "episode 0: 50 steps" in out and "episode 1: 50 steps" in out


def test_record_the_scripted_policy(tmp_path, capsys):
    assert main(["record", "rigid_gym/Throw-v0", "--out", str(tmp_path), "--run", "demo",
                 "--contacts"]) == 0
    path = tmp_path / "rigid_gym-Throw-v0" / "demo-episode-0.rrd"
    assert path.stat().st_size < 2 * 1024 ** 2
    assert "success True" in capsys.readouterr().out


def test_record_the_gripper(tmp_path, capsys):
    """--effector gripper records the two-finger gripper (its hand and fingers in the file)."""
    from rerun.chunk import RrdReader

    assert main(["record", "rigid_gym/PickAndPlace-v0", "--effector", "gripper", "--out",
                 str(tmp_path)]) == 0
    assert "success True" in capsys.readouterr().out
    path = tmp_path / "rigid_gym-PickAndPlace-v0" / "scripted-seed0-episode-0.rrd"
    entities = {chunk.entity_path for chunk in RrdReader(path).stream()}
    assert {"/world/bodies/hand", "/world/bodies/finger0", "/world/bodies/finger1"} <= entities


def sb3_model(algorithm: str):
    """An untrained model for Throw: PPO, or SAC with HER (whose loading needs the env)."""
    import gymnasium as gym
    from stable_baselines3 import PPO, SAC, HerReplayBuffer

    env = gym.make("rigid_gym/Throw-v0")
    if algorithm == "ppo":
        return PPO("MultiInputPolicy", env, n_steps=8, batch_size=8, device="cpu")
    return SAC("MultiInputPolicy", env, replay_buffer_class=HerReplayBuffer, buffer_size=1000,
               device="cpu")


@pytest.mark.parametrize("algorithm", ["ppo", "sac"])
def test_record_a_stable_baselines3_model_reads_its_algorithm_from_the_zip(algorithm, tmp_path,
                                                                           usage_error):
    model = tmp_path / f"{algorithm}_throw.zip"
    sb3_model(algorithm).save(model)
    assert main(["record", "rigid_gym/Throw-v0", "--policy", str(model), "--out",
                 str(tmp_path)]) == 0
    assert (tmp_path / "rigid_gym-Throw-v0" / f"{algorithm}_throw-seed0-episode-0.rrd").is_file()
    assert "does not fit rigid_gym/Push-v0" in usage_error(
        ["record", "rigid_gym/Push-v0", "--policy", str(model), "--out", str(tmp_path)])


@pytest.mark.parametrize("args, message", [
    (["record", "Nope-v0"], "unknown env id 'Nope-v0'; choose from rigid_gym/Push-v0"),
    (["record", "rigid_gym/Push-v0", "--policy", "greedy"],
     "expected random, scripted or a model .zip, got 'greedy'"),
    (["record", "rigid_gym/Push-v0", "--episodes", "0"], "must be in [1, 10000], got 0"),
    (["record", "rigid_gym/Push-v0", "--run", "a/b"], "RecordRerun.run: must be a non-empty"),
    (["record", "rigid_gym/Push-v0", "--effector", "gripper"],
     "PushEnv: effector='gripper' is for the tasks that pick objects up"),
    (["record", "rigid_gym/Stack-v0", "--effector", "suction"],
     "argument --effector: invalid choice: 'suction'"),
])
def test_bad_record_arguments_fail_clearly(args, message, usage_error):
    assert message in usage_error(args)


def test_replay_runs_the_viewer_installed_with_this_python(tmp_path, monkeypatch):
    import os
    import subprocess

    import rerun

    from rigid_gym import cli

    monkeypatch.setenv("PATH", str(tmp_path))  # nothing there: not found through PATH
    viewer = cli.find_rerun()
    assert viewer is not None and os.path.isfile(viewer)
    monkeypatch.undo()
    version = subprocess.run([viewer, "--version"], check=True, capture_output=True,
                             text=True).stdout
    assert f"rerun-cli {rerun.__version__}" in version
    # a stand-in viewer that writes down its arguments
    fake, log = tmp_path / "rerun", tmp_path / "args.txt"
    fake.write_text(f"#!/bin/sh\necho \"$@\" > {log}\n")
    fake.chmod(0o755)
    monkeypatch.setattr(cli, "find_rerun", lambda: str(fake))
    monkeypatch.setenv("DISPLAY", ":0")  # a window can open
    episode = tmp_path / "episode.rrd"
    episode.write_bytes(b"")  # not a rerun file: opened alone
    assert main(["replay", str(episode)]) == 0
    assert log.read_text().split() == [str(episode)]
    # recordings are opened with the layout beside them (once for several files)
    assert main(["record", "rigid_gym/Throw-v0", "--policy", "random", "--episodes", "2",
                 "--out", str(tmp_path), "--run", "r"]) == 0
    folder = tmp_path / "rigid_gym-Throw-v0"
    episodes = [str(folder / f"r-episode-{k}.rrd") for k in range(2)]
    assert main(["replay", *episodes]) == 0
    assert log.read_text().split() == [*episodes, str(folder / "rigid_gym-Throw-v0.rbl")]


def test_replay_without_a_display_serves_the_web_viewer(tmp_path, monkeypatch, capsys):
    """Where no window can open (Linux without DISPLAY and WAYLAND_DISPLAY), replay serves
    the files with rerun's web viewer and says so; --web asks for it anywhere; a native
    viewer that fails points to it."""
    from rigid_gym import cli

    fake, log = tmp_path / "rerun", tmp_path / "args.txt"
    fake.write_text(f"#!/bin/sh\necho \"$@\" > {log}\n[ \"$1\" = --web-viewer ]\n")
    fake.chmod(0o755)
    monkeypatch.setattr(cli, "find_rerun", lambda: str(fake))
    monkeypatch.setattr(sys, "platform", "linux")
    episode = tmp_path / "episode.rrd"
    episode.write_bytes(b"")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["replay", str(episode)]) == 0
    assert log.read_text().split() == ["--web-viewer", str(episode)]
    assert "no display" in capsys.readouterr().err
    monkeypatch.setenv("DISPLAY", ":0")
    assert main(["replay", "--web", str(episode)]) == 0
    assert log.read_text().split() == ["--web-viewer", str(episode)]
    assert main(["replay", str(episode)]) == 1  # the stand-in fails without --web-viewer
    assert "rigid-gym replay --web FILE" in capsys.readouterr().err


def test_replay_explains_a_missing_file_or_viewer(tmp_path, monkeypatch, capsys):
    from rigid_gym import cli

    assert main(["replay", str(tmp_path / "nope.rrd")]) == 2
    assert "no such file" in capsys.readouterr().err
    monkeypatch.setattr(cli, "find_rerun", lambda: None)
    (tmp_path / "a.rrd").write_bytes(b"")
    assert main(["replay", str(tmp_path / "a.rrd")]) == 1
    assert "rerun viewer was not found" in capsys.readouterr().err


def test_train_then_evaluate(tmp_path, capsys):
    assert main(["train", "rigid_gym/PushDense-v0", "--steps", "64", "--n-envs", "2",
                 "--out", str(tmp_path), "--eval-freq", "64", "--eval-episodes", "1",
                 "--final-episodes", "2"]) == 0
    model = tmp_path / "PushDense-ppo-seed0" / "model.zip"
    assert f"trained rigid_gym/PushDense-v0: {model}" in capsys.readouterr().out
    assert main(["evaluate", str(model), "--episodes", "2"]) == 0
    assert "rigid_gym/PushDense-v0: success rate" in capsys.readouterr().out


def test_train_says_what_it_does_while_it_prepares_and_evaluates(tmp_path, capsys):
    assert main(["train", "rigid_gym/Stack-v0", "--steps", "120", "--demos", "1", "--out",
                 str(tmp_path), "--eval-freq", "120", "--eval-episodes", "1",
                 "--final-episodes", "2"]) == 0
    err = capsys.readouterr().err
    n_envs = load_hyperparams("rigid_gym/Stack-v0")["n_envs"]
    for stage in (f"making {n_envs} env(s) and the bc_sac model",
                  "training bc_sac for 120 env steps",
                  "final evaluation, 2 episodes"):
        assert stage in err
    assert "\r" not in err  # standard output is not a terminal: no bars redrawn in a log


@pytest.mark.parametrize("name, env_id", [("push_sac_seed0", "rigid_gym/Push-v0"),
                                          ("stack_bcsac_seed0", "rigid_gym/Stack-v0"),
                                          ("throw_sac_seed0", "rigid_gym/Throw-v0"),
                                          ("push_pixels_seed0", "rigid_gym/Push-v0")])
def test_every_committed_model_is_evaluated_with_the_settings_beside_it(name, env_id, capsys):
    """agents/models/NAME.zip is read with NAME.json (its env id and algorithm: bc_sac for
    Stack), as the README runs them. The committed models were trained with SBX, which the
    `fast` extra installs (without it, load_model says so: test_agents)."""
    from pathlib import Path

    pytest.importorskip("sbx", reason="the committed models need the fast extra (SBX, JAX)")
    model = Path(__file__).resolve().parent.parent / "agents" / "models" / f"{name}.zip"
    assert main(["evaluate", str(model), "--episodes", "1"]) == 0
    out, _err = capsys.readouterr()
    assert f"{env_id}: success rate" in out


def test_train_resumes_from_the_newest_checkpoint(tmp_path, capsys):
    common = ["train", "rigid_gym/Push-v0", "--out", str(tmp_path), "--eval-freq", "0",
              "--checkpoint-freq", "48", "--final-episodes", "0"]
    assert main([*common, "--steps", "96"]) == 0
    assert main([*common, "--steps", "144", "--resume"]) == 0
    checkpoint = tmp_path / "Push-sac-seed0" / "checkpoints" / "step_96"
    assert f"resuming from {checkpoint}" in capsys.readouterr().out
    assert (checkpoint.parent / "step_144" / "replay_buffer.pkl").is_file()


def test_a_new_run_in_a_used_folder_chooses_only_among_its_own_checkpoints(tmp_path, capsys):
    """Training again into a run folder starts afresh: the earlier run's checkpoints (here of
    144 env steps, more than the new run's 96) are not candidates for its policy."""
    common = ["train", "rigid_gym/Push-v0", "--out", str(tmp_path), "--eval-freq", "0",
              "--final-episodes", "1"]
    assert main([*common, "--steps", "144", "--checkpoint-freq", "48"]) == 0
    assert main([*common, "--steps", "96"]) == 0
    assert "the policy of 96 env steps" in capsys.readouterr().err
    folder = tmp_path / "Push-sac-seed0"
    assert not (folder / "checkpoints").exists() and not (folder / "selected_model.zip").exists()


@pytest.mark.parametrize("args, message", [
    (["train", "rigid_gym/Push-v0", "--resume", "--out", "/nonexistent/runs"],
     "--resume: no checkpoint in /nonexistent/runs/Push-sac-seed0/checkpoints"),
    (["sweep", "rigid_gym/Push-v0"], "give ENV_ID... and --seeds, or --resume"),
    (["sweep", "rigid_gym/Push-v0", "--seeds", "0", "--param", "tau"], "--param must be KEY="),
    (["train", "rigid_gym/Push-v0", "--algo", "dqn"],
     ("'drq') or one of rigid_gym/Push-v0's recipes in hyperparams.yml ['distill', 'drq', "
      "'ppo'], got 'dqn'")),
    (["train", "rigid_gym/Push-v0", "--steps", "0"], "must be in [1, 1000000000], got 0"),
])
def test_bad_train_and_evaluate_arguments_fail_clearly(args, message, usage_error):
    assert message in usage_error(args)


def test_a_missing_or_corrupt_model_is_named_without_usage(tmp_path, capsys):
    """A file that is not there, or not a model zip: exit 1 with the file named, no usage
    banner (the arguments were fine) and no traceback."""
    corrupt = tmp_path / "corrupt.zip"
    corrupt.write_bytes(b"PK\x03\x04 not really a zip")
    (tmp_path / "corrupt.json").write_text('{"env_id": "rigid_gym/Push-v0"}')
    cases = [(["evaluate", "nope.zip"], "model file nope.zip not found"),
             (["evaluate", "nope.zip", "--env", "rigid_gym/Push-v0"],
              "model file nope.zip not found"),
             (["record", "rigid_gym/Push-v0", "--policy", "nope.zip", "--out", str(tmp_path)],
              "model file nope.zip not found"),
             (["evaluate", str(corrupt)], f"{corrupt} is not a stable-baselines3 model zip")]
    for args, message in cases:
        assert main(args) == 1
        err = capsys.readouterr().err
        assert message in err and "usage" not in err and "Traceback" not in err, err
        assert "pass the algorithm" not in err


def test_version_and_help_on_every_flag(capsys):
    """--version prints the package's version; every flag of every command has help; no
    help shows reStructuredText markup."""
    import argparse

    import rigid_gym
    from rigid_gym.cli import build_parser

    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0
    assert capsys.readouterr().out.strip() == f"rigid-gym {rigid_gym.__version__}"
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    texts = [parser.format_help()]
    for name, command in commands.choices.items():
        texts.append(command.format_help())
        for action in command._actions:
            assert action.help, f"rigid-gym {name} {action.option_strings or action.dest}"
    assert not any("``" in text for text in texts)
