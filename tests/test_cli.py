"""The rigid-gym command."""

import pytest

from rigid_gym.cli import main


def test_demo_prints_each_result_next_to_its_closed_form(capsys):
    assert main(["demo", "--steps", "48"]) == 0
    out = capsys.readouterr().out
    for expected in ("discrete free fall", "ten-cube tower", "e^2 h0 = 0.6400 m", "v0^2 / (2 mu g)"):
        assert expected in out


@pytest.mark.parametrize("args, message", [
    (["demo", "--steps", "1"], "must be in [2, 10000000], got 1"),
    (["demo", "--dt", "-1"], "must be in [1e-06, 0.1], got -1"),
    (["demo", "--steps", "many"], "expected int, got 'many'"),
])
def test_bad_arguments_fail_with_the_allowed_range(args, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(args)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err
