"""Type-check the rigid_gym package as it installs, with mypy (settings: pyproject.toml).

The package's sources live in three folders of the checkout: rigid_gym/, envs/ (installed as
rigid_gym.envs) and agents/ (rigid_gym.agents). An install joins them with an import hook, which
a type checker does not run, so this script lays the package out as a wheel does, in
build/typecheck/rigid_gym/, from symbolic links to the sources, with the installed core's stub
_core.pyi beside them, and checks it there. Errors name files by their place in the package:
rigid_gym/envs/core.py is envs/core.py, rigid_gym/agents/train.py is agents/train.py.

Usage: python .ci/typecheck.py [mypy options]   (the core must be installed: pip install -e .)
"""

import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def lay_out(view: Path) -> None:
    """The package tree of a wheel under ``view``, linked to the checkout's sources."""
    if view.exists():
        shutil.rmtree(view)
    package = view / "rigid_gym"
    package.mkdir(parents=True)
    for entry in (ROOT / "rigid_gym").iterdir():
        if entry.name != "__pycache__" and not entry.name.startswith("_core"):
            (package / entry.name).symlink_to(entry)
    for folder in ("envs", "agents"):
        (package / folder).symlink_to(ROOT / folder)
    spec = importlib.util.find_spec("rigid_gym._core")
    if spec is None or spec.origin is None:
        sys.exit("rigid_gym._core is not installed: pip install -e . first")
    stub = Path(spec.origin).with_name("_core.pyi")
    if not stub.is_file():
        sys.exit(f"no type stub beside {spec.origin}: rebuild with pip install -e .")
    (package / "_core.pyi").symlink_to(stub)


def main() -> int:
    view = ROOT / "build" / "typecheck"
    lay_out(view)
    command = [sys.executable, "-m", "mypy", "--config-file", str(ROOT / "pyproject.toml"),
               "--cache-dir", str(ROOT / "build" / "mypy_cache"), "-p", "rigid_gym",
               *sys.argv[1:]]
    return subprocess.call(command, cwd=view)


if __name__ == "__main__":
    sys.exit(main())
