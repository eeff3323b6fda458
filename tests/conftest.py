"""Fixtures shared by the test modules."""

import pytest

from rigid_gym.cli import main


@pytest.fixture
def usage_error(capsys):
    """``usage_error(args)``: run ``rigid-gym args``, which must refuse them as argparse does
    (SystemExit, exit status 2), and return what it wrote on stderr."""

    def run(args: list[str]) -> str:
        with pytest.raises(SystemExit) as exit_info:
            main(args)
        assert exit_info.value.code == 2
        return capsys.readouterr().err

    return run
