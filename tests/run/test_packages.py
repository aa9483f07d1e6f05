"""The packages of pytest_emrd import each other one way: no upward import, no circle between
packages or between modules, and no module imports another package's private module (a
package's face exports what others use).

The graph is built from the source with :mod:`ast`, every import counted wherever it is
written (inside a function, under ``TYPE_CHECKING``): a lazy import is still a dependency.
"""

from __future__ import annotations

import ast
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

import pytest_emrd

PACKAGE = Path(pytest_emrd.__file__).parent

#: ``user -> used`` pairs that must not appear: the lower stage never imports the higher one.
FORBIDDEN = [
    ("cassette", "gate"),
    ("cassette", "run"),
    ("cassette", "plugin"),
    ("gate", "run"),
    ("gate", "cassette"),
    ("gate", "plugin"),
    ("run", "plugin"),
    ("run", "cli"),
    ("run", "report"),
    ("cassette", "episode"),
    ("progress", "cassette"),
    ("progress", "episode"),
    ("episode", "run"),
    ("metrics", "run"),
    ("metrics", "gate"),
    ("agent", "reference"),
    ("world", "reference"),
    ("trajectory", "reference"),
    ("metrics", "reference"),
    ("cassette", "reference"),
    ("gate", "reference"),
    ("reference", "episode"),
    ("reference", "run"),
    ("reference", "plugin"),
    ("reference", "cli"),
    ("reference", "preflight"),
    ("reference", "validate"),
]


UNITS = {p.name.removesuffix(".py") for p in PACKAGE.iterdir() if p.suffix == ".py" or p.is_dir()}


def _unit(path: Path) -> str:
    """The top-level package or module a source file belongs to (``gate``, ``episode``)."""
    return path.relative_to(PACKAGE).parts[0].removesuffix(".py")


def _imported(tree: ast.AST) -> set[str]:
    """The top-level units of pytest_emrd a module's source imports."""
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module]
            if node.module == "pytest_emrd":
                names = [f"pytest_emrd.{alias.name}" for alias in node.names]
        else:
            continue
        found.update(n.split(".")[1] for n in names if n.startswith("pytest_emrd."))
    return found & UNITS


def import_graph() -> dict[str, set[str]]:
    """``unit -> units it imports`` over every module of pytest_emrd (itself left out)."""
    graph: dict[str, set[str]] = {}
    for path in PACKAGE.rglob("*.py"):
        unit = _unit(path)
        used = _imported(ast.parse(path.read_text(encoding="utf-8"), filename=str(path)))
        graph.setdefault(unit, set()).update(used - {unit})
    return graph


def test_the_graph_sees_the_imports_it_checks() -> None:
    graph = import_graph()
    assert {"gate", "cassette"} <= graph["run"]
    assert "episode" in graph["plugin"]
    assert "run" in graph["plugin"]


def test_no_package_imports_a_higher_stage() -> None:
    graph = import_graph()
    upward = [(user, used) for user, used in FORBIDDEN if used in graph.get(user, set())]
    assert upward == []


def test_the_packages_import_each_other_without_a_circle() -> None:
    try:
        order = list(TopologicalSorter(import_graph()).static_order())
    except CycleError as exc:
        raise AssertionError(f"import circle between packages: {exc.args[1]}") from None
    assert order.index("run") > order.index("gate")
    assert order.index("plugin") > order.index("run") > order.index("cassette")
    assert order.index("episode") > order.index("reference") > order.index("agent")


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imported_modules(path: Path, modules: set[str]) -> set[str]:
    """The modules of pytest_emrd a source file imports (a name imported from a package that
    is itself a module, ``from pytest_emrd.world import _render``, counts as that module)."""
    found: set[str] = set()
    package = _module_name(path) if path.name == "__init__.py" else _module_name(path.parent)
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{anchor}.{base}" if base else anchor
            submodules = {f"{base}.{alias.name}" for alias in node.names} & modules
            found.update(submodules)
            if len(submodules) < len(node.names):  # a name defined in ``base`` itself
                found.add(base)
    return {name for name in found if name in modules}


def module_graph() -> dict[str, set[str]]:
    """``module -> modules of pytest_emrd it imports``, every import counted (see above)."""
    paths = {_module_name(path): path for path in PACKAGE.rglob("*.py")}
    return {name: _imported_modules(path, set(paths)) - {name} for name, path in paths.items()}


def _is_private(module: str) -> bool:
    return any(part.startswith("_") and part != "__init__" for part in module.split("."))


def _package_of(module: str) -> str:
    """The package whose own a private module is: ``pytest_emrd.gate`` for ``gate._table``,
    ``pytest_emrd`` (every module) for a ground-floor module such as ``pytest_emrd._files``."""
    parts = module.split(".")
    return ".".join(parts[:2]) if len(parts) > 2 else parts[0]


def test_no_module_reaches_itself_through_imports() -> None:
    try:
        list(TopologicalSorter(module_graph()).static_order())
    except CycleError as exc:
        raise AssertionError(f"import circle between modules: {exc.args[1]}") from None


def test_no_module_imports_another_package_s_private_module() -> None:
    graph = module_graph()
    reaching = sorted(
        (user, used)
        for user, modules in graph.items()
        for used in modules
        if _is_private(used) and not (user + ".").startswith(_package_of(used) + ".")
    )
    assert reaching == []
