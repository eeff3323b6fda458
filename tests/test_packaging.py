"""How the package installs: the core's type stub, and what an install puts on sys.path."""

import ast
import inspect
import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import rigid_gym._core as core

import rigid_gym


def _stub_names(stub: Path) -> set[str]:
    names = set()
    for node in ast.parse(stub.read_text()).body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
    return names


def test_the_core_has_a_stub_beside_it_naming_every_public_name():
    """nanobind's stubgen writes _core.pyi at build time (CMakeLists.txt); it is installed beside
    the extension, parses as Python, and declares each public function, class and constant of the
    module as built, with the methods of each class."""
    stub = Path(core.__file__).with_name("_core.pyi")
    assert stub.is_file(), f"no stub beside {core.__file__}"
    public = {name for name in dir(core) if not name.startswith("_")}
    assert public <= _stub_names(stub)
    classes = {n.name: n for n in ast.parse(stub.read_text()).body if isinstance(n, ast.ClassDef)}
    for name, cls in inspect.getmembers(core, inspect.isclass):
        methods = {m for m, _ in inspect.getmembers(cls) if not m.startswith("_")}
        declared = {n.name for n in classes[name].body if isinstance(n, ast.FunctionDef)}
        assert methods <= declared, f"{name}: {sorted(methods - declared)} missing from the stub"


def test_the_package_is_marked_typed():
    """PEP 561: type checkers read a package's own annotations only when py.typed is beside
    its __init__.py."""
    assert (Path(rigid_gym.__file__).parent / "py.typed").is_file()


ROOT = Path(__file__).resolve().parents[1]


def test_an_install_puts_neither_the_checkout_nor_its_parent_on_sys_path(tmp_path):
    """Importing rigid_gym (an editable install included) adds no folder of the checkout, nor
    the folder holding it, to sys.path: otherwise every folder beside the checkout, and the
    checkout's own envs/, agents/, tests/ and benchmarks/, import by their bare names. Run in a
    fresh interpreter from an empty folder, without PYTHONPATH."""
    probe = ("import importlib.util, json, sys; import rigid_gym; "
             "print(json.dumps([sys.path, [n for n in ('envs', 'agents', 'tests', 'benchmarks') "
             "if importlib.util.find_spec(n) is not None]]))")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    out = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, env=env, check=True,
                         capture_output=True, text=True).stdout
    path, importable = json.loads(out)
    entries = {Path(p or tmp_path).resolve() for p in path}
    assert ROOT not in entries and ROOT.parent not in entries, path
    assert importable == []


def test_one_version_in_pyproject_the_changelog_and_the_package():
    """pyproject.toml holds the version; the changelog's newest entry and
    rigid_gym.__version__ (the installed metadata) name the same one."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert "version" not in project.get("dynamic", [])
    headings = [line for line in (ROOT / "CHANGELOG.md").read_text().splitlines()
                if line.startswith("## ")]
    assert headings[0].split()[1] == project["version"], headings[0]
    assert rigid_gym.__version__ == project["version"], "reinstall: pip install -e ."


def test_layout_agents_import_no_cli_and_the_library_no_ray():
    """The CLI imports agents/ (policies, datasets), so no module of agents/ imports the CLI
    (an import circle); Ray code lives in agents/ (sweep, rllib), none in rigid_gym/."""
    root = Path(__file__).resolve().parents[1]
    for path in (root / "agents").glob("*.py"):
        imported = _imports(path)
        assert not any(m.startswith("rigid_gym.cli") for m in imported), path
    for path in (root / "rigid_gym").rglob("*.py"):
        imported = _imports(path)
        assert not any(m == "ray" or m.startswith("ray.") for m in imported), path


def _imports(path: Path) -> set[str]:
    """The modules ``path`` imports (absolute names; relative ones as written)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names
