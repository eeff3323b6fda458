"""No module reaches into another module's private names: what crosses a module is public.

Every module of rigid_gym, envs and agents is parsed with ``ast``; a use fails when it is

- ``from x import _y`` (a name, not a module: the package's private modules, such as the
  compiled ``rigid_gym._core``, are imported by the package's own modules);
- ``obj._y`` for an ``obj`` other than ``self``, ``cls`` or ``super()``, where ``_y`` is not
  defined in the module itself (defined: a def, class, assignment, argument or attribute set
  there): another module's private attribute (``gripper._grip``, ``task._add_markers``);
- ``self._y`` or ``cls._y`` where ``_y`` is defined in another of these modules and not in
  this one: a private hook one of our modules gives another. Protected members a
  third-party base class gives its subclasses (stable-baselines3's
  ``self._update_learning_rate``) are the base's subclass interface and pass.

Dunder names and namedtuple's ``_asdict``, ``_replace``, ``_fields``, ``_make`` are public.
"""

import ast
import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = {"rigid_gym": ROOT / "rigid_gym", "envs": ROOT / "envs", "agents": ROOT / "agents"}
PUBLIC = {"_asdict", "_replace", "_fields", "_make", "_field_defaults"}
SELF = ("self", "cls")


def private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__")) \
        and name not in PUBLIC


def modules() -> list[Path]:
    return sorted(path for folder in PACKAGES.values() for path in folder.rglob("*.py"))


def defined_names(tree: ast.AST) -> set[str]:
    """Every name a module defines or binds: defs, classes, assignments (attributes too),
    arguments and imports."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            names.add(node.attr)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.arg):
            names.add(node.arg)
        elif isinstance(node, ast.alias):
            names.add((node.asname or node.name).split(".")[0])
    return names


TREES = {path: ast.parse(path.read_text(), filename=str(path)) for path in modules()}
DEFINED = {path: defined_names(tree) for path, tree in TREES.items()}


def is_module(package: str, name: str) -> bool:
    """Whether ``package.name`` is a module (``rigid_gym._core``), not a name in one."""
    try:
        return importlib.util.find_spec(f"{package}.{name}") is not None
    except ModuleNotFoundError:
        return False


def owner(expression: ast.expr) -> str:
    """The text of an attribute's object: ``self``, ``super()``, ``gripper``, ..."""
    if isinstance(expression, ast.Call) and isinstance(expression.func, ast.Name) \
            and expression.func.id == "super":
        return "super()"
    return ast.unparse(expression)


def violations(path: Path) -> list[str]:
    tree, own = TREES[path], DEFINED[path]
    elsewhere = set().union(*(names for other, names in DEFINED.items() if other != path))
    found = []
    for node in ast.walk(tree):
        where = f"{path.relative_to(ROOT)}:{getattr(node, 'lineno', 0)}"
        if isinstance(node, ast.ImportFrom) and node.module:
            for alias in node.names:
                if private(alias.name) and not is_module(node.module, alias.name):
                    found.append(f"{where}: from {node.module} import {alias.name}")
        elif isinstance(node, ast.Attribute) and private(node.attr):
            obj = owner(node.value)
            if obj in SELF:
                if node.attr not in own and node.attr in elsewhere:
                    found.append(f"{where}: {obj}.{node.attr}, defined in another module")
            elif obj != "super()" and node.attr not in own:
                found.append(f"{where}: {ast.unparse(node)}, another module's private name")
    return found


def test_the_modules_are_found():
    names = {path.relative_to(ROOT).as_posix() for path in TREES}
    assert {"rigid_gym/recording.py", "envs/core.py", "agents/vec_env.py"} <= names


@pytest.mark.parametrize("path", modules(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_no_module_uses_another_modules_private_names(path):
    assert violations(path) == []


def test_the_check_finds_what_it_is_for():
    """A module that does each forbidden thing is caught, each use once."""
    source = ("from rigid_gym.render import _color\n"
              "from rigid_gym import _core\n"  # a private module: allowed
              "def f(gripper):\n"
              "    gripper._grip(1.0)\n"
              "    return _core.STATIC\n"
              "class A:\n"
              "    def g(self):\n"
              "        self._mine = 1\n"
              "        return self._mine, self._place_cubes_of_another_module\n")
    path = ROOT / "envs" / "probe_private.py"
    TREES[path] = ast.parse(source)
    DEFINED[path] = defined_names(TREES[path])
    DEFINED[ROOT / "envs" / "probe_other.py"] = {"_place_cubes_of_another_module"}
    try:
        found = violations(path)
    finally:
        for key in (path, ROOT / "envs" / "probe_other.py"):
            TREES.pop(key, None)
            DEFINED.pop(key, None)
    assert [line.split(": ", 1)[1] for line in found] == [
        "from rigid_gym.render import _color",
        "gripper._grip, another module's private name",
        "self._place_cubes_of_another_module, defined in another module",
    ]
