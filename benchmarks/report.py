"""Regenerate the accuracy and stability report (docs/report.md and docs/images/report/).

    python benchmarks/report.py            # the full report (under 15 minutes on 2 cores)
    python benchmarks/report.py --quick    # a tiny sweep, to check the pipeline

The same as ``rigid-gym report``; the code is ``rigid_gym.report``.
"""

import sys

from rigid_gym.cli import main

if __name__ == "__main__":
    sys.exit(main(["report", *sys.argv[1:]]))
