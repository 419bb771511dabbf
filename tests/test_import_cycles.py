"""No import cycle in flic_cli, counting the imports inside functions too.

Every module of the package is parsed with :mod:`ast` (not imported); each ``import`` and
``from ... import`` statement anywhere in it -- at module level, inside functions, classes or
``try`` blocks -- is an edge, except those under ``if TYPE_CHECKING:`` (never executed). Importing
``a.b.c`` also runs the ``__init__`` of packages ``a.b`` and ``a``, so it is an edge to those too,
unless the importing module lies inside that package (whose ``__init__`` then runs already).
Loads by name through :mod:`importlib` (the registry's lazy load, ``flic_cli.io``'s lazy
re-exports) are no statements and are excepted.
"""

from __future__ import annotations

import ast
import graphlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "flic_cli"


def module_names(root: Path = ROOT) -> dict[str, Path]:
    """Dotted name -> file of every module of the package (packages by their ``__init__``)."""
    out = {}
    for path in sorted((root / PACKAGE).rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _type_checking_only(node: ast.AST) -> bool:
    test = node.test if isinstance(node, ast.If) else None
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement of a module, at any depth, but not under ``if TYPE_CHECKING:``."""
    found: list[ast.Import | ast.ImportFrom] = []
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and _type_checking_only(node):
            stack.extend(node.orelse)
            continue
        if isinstance(node, ast.Import | ast.ImportFrom):
            found.append(node)
        stack.extend(ast.iter_child_nodes(node))
    return found


def imported_modules(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The package's modules that module ``name`` imports (directly, and their packages)."""
    is_package = path.name == "__init__.py"
    targets: set[str] = set()
    for node in _imports(ast.parse(path.read_text("utf-8"), str(path))):
        if isinstance(node, ast.Import):
            targets.update(alias.name for alias in node.names)
            continue
        base = node.module or ""
        if node.level:  # relative: from the module's own package upwards
            here = name.split(".") if is_package else name.split(".")[:-1]
            anchor = here[: len(here) - (node.level - 1)]
            base = ".".join(anchor + ([base] if base else []))
        for alias in node.names:
            sub = f"{base}.{alias.name}"
            targets.add(sub if sub in modules else base)
    out = set()
    for target in targets:
        if target not in modules:
            continue
        parts = target.split(".")
        for k in range(1, len(parts) + 1):
            ancestor = ".".join(parts[:k])
            inside = name == ancestor or name.startswith(ancestor + ".")
            if ancestor in modules and ancestor != name and (ancestor == target or not inside):
                out.add(ancestor)
    return out


def import_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """Module -> the modules it imports, for every module of the package."""
    modules = module_names(root)
    return {name: imported_modules(name, path, modules) for name, path in modules.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle (``[a, b, ..., a]``), or None when there is none."""
    try:
        graphlib.TopologicalSorter(graph).prepare()
    except graphlib.CycleError as exc:
        return list(reversed(exc.args[1]))  # graphlib lists it against the import direction
    return None


def test_the_graph_sees_function_local_and_package_imports() -> None:
    graph = import_graph()
    assert len(graph) > 60
    # function-local: the segment run renders with flic_cli.plots, imported inside a function
    assert "flic_cli.plots" in graph["flic_cli.runs.segment"]
    # importing a submodule runs its package's __init__
    assert "flic_cli.io" in graph["flic_cli.runs.segment"]


def test_a_planted_cycle_is_found(tmp_path: Path) -> None:
    pkg = tmp_path / PACKAGE
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("from flic_cli.sub.a import x\n")
    (pkg / "sub" / "a.py").write_text("x = 1\n")
    (pkg / "b.py").write_text("def f():\n    from .sub import a\n")
    (pkg / "sub" / "c.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                                     "    import flic_cli.b\n")  # fmt: skip
    graph = import_graph(tmp_path)
    assert graph["flic_cli.b"] == {"flic_cli.sub", "flic_cli.sub.a"}
    assert graph["flic_cli.sub.c"] == set()  # TYPE_CHECKING only
    assert find_cycle(graph) is None
    (pkg / "sub" / "a.py").write_text("def g():\n    import flic_cli.b\n")
    cycle = find_cycle(import_graph(tmp_path))
    assert cycle is not None and cycle[0] == cycle[-1]
    assert sorted(cycle[:-1]) == ["flic_cli.b", "flic_cli.sub.a"]


def test_no_import_cycle() -> None:
    cycle = find_cycle(import_graph())
    if cycle is not None:
        pytest.fail("import cycle: " + " -> ".join(cycle))
