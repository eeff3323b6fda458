"""Fixtures shared by the test modules."""

import pytest

from rigid_gym import _core
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


@pytest.fixture
def two_threads():
    """The core's pool at two threads (the calling thread and one worker) whatever the
    machine has, so that a batch can be shared out; at its default size afterwards."""
    _core.set_num_threads(2)
    yield
    _core.set_num_threads(0)


@pytest.fixture
def step_both_ways(two_threads):
    """``step_both_ways(world, steps)``: ``world.step(1)`` ``steps`` (>= 2) times, with the
    pool at two threads. A batch's first call is shared out over the pool and its second runs
    on the calling thread (src/solver/sharing.h), so both ways step it: checked."""

    def run(world, steps: int) -> None:
        ways = set()
        for _ in range(steps):
            world.step(1)
            ways.add(world.core.shared)
        assert ways >= {False, True}

    return run
