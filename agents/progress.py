"""What the long steps of training and evaluation show while they run: tqdm bars and notes on
standard error (tqdm comes with the ``train`` extra, as the rest of ``rigid_gym.agents``)."""

from __future__ import annotations

import sys

from tqdm import tqdm


def bar(total: int, description: str, shown: bool, unit: str = "episode") -> tqdm:
    """A progress bar of ``total`` ``unit``s: ``update(n)`` as they finish,
    ``set_postfix_str`` for a figure so far, ``close()`` at the end. Nothing is drawn
    unless ``shown`` and standard output is a terminal: a log written to a file gets no
    redraws (the notes, one line each, still go to it)."""
    return tqdm(total=total, desc=description, unit=unit, leave=False,
                disable=not (shown and sys.stdout.isatty()),
                file=sys.stderr, dynamic_ncols=True)


def note(text: str, shown: bool) -> None:
    """A line on standard error saying what starts now (if ``shown``), which does not break a
    bar being drawn."""
    if shown:
        tqdm.write(text, file=sys.stderr)
