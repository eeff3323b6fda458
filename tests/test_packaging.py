"""How the package installs: the core's type stub, and what an install puts on sys.path."""

import ast
import inspect
from pathlib import Path

import rigid_gym
import rigid_gym._core as core


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
