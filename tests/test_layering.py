"""The import graph, read from the source with ``ast`` (imports at module level and inside functions alike):
no cycles between modules, packages layered ``ground <- curate <- synth, train, eval <- fuzzyfire``, and the ground floor
layered by concept (docs/architecture.md)."""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from pathlib import Path

import pytest
from conftest import REPO

PACKAGES = ("ground", "curate", "synth", "train", "eval", "fuzzyfire")

#: Which packages each package may import (itself included):
#: ``ground <- curate <- synth, train, eval <- fuzzyfire``.
ALLOWED: dict[str, frozenset[str]] = {
    "ground": frozenset({"ground"}),
    "curate": frozenset({"ground", "curate"}),
    "synth": frozenset({"ground", "curate", "synth"}),
    "train": frozenset({"ground", "curate", "train"}),
    "eval": frozenset({"ground", "curate", "eval"}),
    "fuzzyfire": frozenset(PACKAGES),
}

#: Inside the ground floor: which concepts each may import (itself included).
GROUND: dict[str, frozenset[str]] = {
    "run": frozenset({"run"}),
    "config": frozenset({"config"}),
    "image": frozenset({"image"}),
    "data": frozenset({"run", "image", "data"}),
    "detect": frozenset({"run", "image", "data", "detect"}),
    "cli": frozenset({"run", "config", "image", "data", "cli"}),
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for pkg in PACKAGES for p in sorted((REPO / pkg).rglob("*.py"))}


def _imports(name: str, path: Path, known: set[str]) -> Iterator[tuple[str, int]]:
    """(imported module of ours, line) for every import statement in ``path``, wherever it stands."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join([*anchor, *([base] if base else [])])
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        else:
            continue
        for target in targets:
            while target and target not in known:  # `import ground.data.formats.coco` -> that module
                target = target.rpartition(".")[0]
            if target:
                yield target, node.lineno


@pytest.fixture(scope="module")
def graph() -> dict[str, dict[str, int]]:
    """module -> {imported module: first line}; only the modules of PACKAGES."""
    modules = _modules()
    known = set(modules)
    out: dict[str, dict[str, int]] = {}
    for name, path in modules.items():
        edges = out.setdefault(name, {})
        for target, line in _imports(name, path, known):
            if target != name:
                edges.setdefault(target, line)
    return out


def _cycles(graph: dict[str, dict[str, int]]) -> list[frozenset[str]]:
    """The strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[frozenset[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(frozenset(component))
    return found


def test_the_graph_is_read(graph: dict[str, dict[str, int]]) -> None:
    assert "ground.data.boxes" in graph["ground.detect.nms"]  # module level
    assert "curate.effnet" in graph["curate.embed"]  # inside a function
    assert "curate.cli.dataset" in graph["curate.cli"]  # `from package import module`


def test_no_import_cycles(graph: dict[str, dict[str, int]]) -> None:
    assert [sorted(c) for c in _cycles(graph)] == []


def test_the_cycle_finder_finds_cycles() -> None:
    toy = {"a": {"b": 1}, "b": {"c": 1}, "c": {"a": 1}, "d": {"a": 1}, "e": {"f": 1}, "f": {"e": 1}}
    assert sorted(sorted(c) for c in _cycles(toy)) == [["a", "b", "c"], ["e", "f"]]


def test_packages_import_only_the_packages_below(graph: dict[str, dict[str, int]]) -> None:
    modules = _modules()
    wrong = [
        f"{modules[src].relative_to(REPO)}:{line}: {src} imports {dst}"
        for src, edges in graph.items()
        for dst, line in edges.items()
        if dst.split(".")[0] not in ALLOWED[src.split(".")[0]]
    ]
    assert wrong == []


def test_the_ground_floor_is_layered_by_concept(graph: dict[str, dict[str, int]]) -> None:
    """Inside the ground floor each concept imports only those below it: ``run, config, image <- data <- detect,
    cli`` (docs/architecture.md)."""
    modules = _modules()
    floor = [name for name in graph if name.startswith("ground.") and name.count(".") >= 1]
    assert len(floor) > 30
    wrong = [
        f"{modules[src].relative_to(REPO)}:{line}: {src} imports {dst}"
        for src in floor
        for dst, line in graph[src].items()
        if dst.startswith("ground.") and dst.split(".")[1] not in GROUND[src.split(".")[1]]
    ]
    assert wrong == []


def test_every_ground_floor_module_is_used_above_it(graph: dict[str, dict[str, int]]) -> None:
    """No module of the ground floor that no package imports (a drawer of leftovers)."""
    used = {dst for src, edges in graph.items() if not src.startswith("ground") for dst in edges}
    used |= {dst for src, edges in graph.items() for dst in edges if src.startswith("ground")}
    floor = [n for n in graph if n.startswith("ground.") and not _modules()[n].name == "__init__.py"]
    assert [n for n in floor if n not in used] == []


def _trees() -> Iterator[tuple[Path, ast.AST]]:
    for path in _modules().values():
        yield path, ast.parse(path.read_text(encoding="utf-8"), str(path))


def test_config_class_names_are_unique() -> None:
    """One name per settings concept: no two ``...Config`` classes share a name anywhere in the tree."""
    where: dict[str, list[str]] = {}
    for path, tree in _trees():
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef) and node.name.endswith("Config"):
                where.setdefault(node.name, []).append(f"{path.relative_to(REPO)}:{node.lineno}")
    assert len(where) > 30
    assert {name: places for name, places in where.items() if len(places) > 1} == {}


def test_no_config_key_is_read_with_a_default_of_its_own() -> None:
    """``getattr(cfg, "key", default)`` on a config would take the default silently for a typo or a renamed key:
    a key is read as an attribute of a typed config, so a wrong one fails at load or in the type check."""
    wrong = [
        f"{path.relative_to(REPO)}:{node.lineno}: {ast.unparse(node)}"
        for path, tree in _trees()
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id == "getattr"
        and len(node.args) == 3
        and re.search(r"cfg|config|settings", ast.unparse(node.args[0]))
    ]
    assert wrong == []


def test_each_ground_floor_package_names_its_concept() -> None:
    """Every package of the ground floor says in its docstring what it holds (docs/architecture.md has a line each)."""
    architecture = (REPO / "docs" / "architecture.md").read_text(encoding="utf-8")
    packages = sorted(p.parent for p in (REPO / "ground").glob("*/__init__.py"))
    assert len(packages) >= 6
    for package in packages:
        doc = ast.get_docstring(ast.parse((package / "__init__.py").read_text(encoding="utf-8")))
        assert doc and len(doc) > 40, package
        assert f"`ground.{package.name}`" in architecture, package
