"""The package's structure as docs/structure.md draws it, read from the code itself: no
import circles, imports at module top, no reach into another package's private modules,
short functions, and the page naming every package, module and dependency as they are."""

from __future__ import annotations

import ast
import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "tactilevision"
DOC = ROOT / "docs" / "structure.md"

#: Imported where they are used, not at module top: the optional extras, and matplotlib
#: (pyplot picks a backend when imported: only when a figure is made, never on import).
LAZY = {"torch", "kornia", "onnx", "dask", "distributed", "zarr", "numcodecs", "pyarrow", "numba",
        "plotly", "threadpoolctl", "matplotlib"}
#: Longest function body allowed, lines of code (docstring, blanks and comments excluded).
MAX_LINES = 80


def _modules() -> dict[str, Path]:
    out = {}
    for p in PKG.rglob("*.py"):
        parts = p.relative_to(ROOT).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = p
    return out


MODULES = _modules()


def _target(mod: str, node: ast.ImportFrom) -> str:
    """The module a relative import names (the package for ``from .. import x``)."""
    base = mod.split(".")
    if not str(MODULES[mod]).endswith("__init__.py"):
        base = base[:-1]
    base = base[:len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _imports(mod: str, *, inner: bool | None = None):
    """(node, targets within the package, is_inside_a_function) of each import of `mod`."""
    tree = ast.parse(MODULES[mod].read_text())
    inside = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            inside.update(id(s) for s in ast.walk(node) if s is not node)
    for node in ast.walk(tree):
        if not isinstance(node, ast.Import | ast.ImportFrom):
            continue
        if isinstance(node, ast.ImportFrom) and node.level:
            tgt = _target(mod, node)
            targets = [f"{tgt}.{a.name}" if f"{tgt}.{a.name}" in MODULES else tgt
                       for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            targets = [node.module]
        else:
            targets = [a.name for a in node.names]
        yield node, targets, id(node) in inside


def _lazy_root_getattr(mod: str, node) -> bool:
    """The package root's ``__getattr__``: calibrate_session on first use."""
    return mod == "tactilevision" and isinstance(node, ast.ImportFrom)


def test_no_import_circles_between_files():
    graph = {m: set() for m in MODULES}
    for m in MODULES:
        for node, targets, inner in _imports(m):
            if inner and _lazy_root_getattr(m, node):
                continue
            graph[m].update(t for t in targets if t in MODULES and t != m)
    # Tarjan's strongly connected components
    index, low, stack, on, circles, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                circles.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    assert circles == []


def test_imports_at_module_top_but_the_lazy_extras():
    found = []
    for m in MODULES:
        for node, targets, inner in _imports(m):
            if inner and not _lazy_root_getattr(m, node):
                top = {t.split(".")[0] for t in targets}
                if not top <= LAZY:
                    found.append(f"{MODULES[m].relative_to(ROOT)}:{node.lineno} {targets}")
    assert found == []


def test_no_package_reaches_into_another_packages_private_modules():
    found = []
    for m in MODULES:
        here = m.split(".")[1] if m.count(".") else ""
        for _node, targets, _ in _imports(m):
            for t in targets:
                parts = t.split(".")
                if (t.startswith("tactilevision.") and len(parts) > 2 and parts[1] != here
                        and not parts[1].startswith("_")
                        and any(p.startswith("_") for p in parts[2:])):
                    found.append(f"{m} imports {t}")
    assert found == []


def _function_lengths():
    for path in MODULES.values():
        text = path.read_text().splitlines()
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            body = node.body
            first = body[0]
            doc = (isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
                   and isinstance(first.value.value, str))
            start = (body[1].lineno if len(body) > 1 else node.end_lineno + 1) if doc \
                else first.lineno
            code = [ln for ln in text[start - 1:node.end_lineno]
                    if ln.strip() and not ln.strip().startswith("#")]
            yield f"{path.relative_to(ROOT)}:{node.lineno} {node.name}", len(code)


def test_no_function_longer_than_80_lines_of_code():
    assert {k: n for k, n in _function_lengths() if n > MAX_LINES} == {}


def test_the_length_count_sees_a_long_function(tmp_path):
    """The count the test above relies on: a body of 81 statements is 81 lines."""
    src = 'def f():\n    """Doc."""\n' + "".join(f"    x{i} = {i}\n" for i in range(81))
    tree = ast.parse(src)
    fn = tree.body[0]
    code = [ln for ln in src.splitlines()[fn.body[1].lineno - 1:fn.end_lineno] if ln.strip()]
    assert len(code) == 81


def _package_edges() -> dict[str, set[str]]:
    """Which of our packages (and bottom modules) each package imports."""
    edges: dict[str, set[str]] = {}
    for m in MODULES:
        parts = m.split(".")
        if len(parts) == 1 or parts[1] == "__main__":
            continue
        src = parts[1]
        for _node, targets, _ in _imports(m):
            for t in targets:
                tp = t.split(".")
                if tp[0] != "tactilevision" or len(tp) == 1:
                    continue
                if tp[1] != src:
                    edges.setdefault(src, set()).add(tp[1])
    return edges


def _doc_table() -> dict[str, set[str]]:
    """The 'imports from' column of structure.md's layers table, by package."""
    rows = {}
    for line in DOC.read_text().splitlines():
        m = re.match(r"\| `tactilevision\.(\w+)` \| .* \| (.*) \|$", line)
        if m:
            deps = m.group(2)
            rows[m.group(1)] = (None if "every package" in deps
                                else set(re.findall(r"`(\w+)`", deps)))
    return rows


def test_structure_page_names_every_package_with_its_imports():
    packages = {p.name for p in PKG.iterdir() if (p / "__init__.py").is_file()}
    table = _doc_table()
    assert set(table) == packages, "structure.md's layers table names every subpackage"
    edges = _package_edges()
    for pkg, deps in table.items():
        if deps is not None:
            assert edges.get(pkg, set()) == deps, f"structure.md: what {pkg} imports"


def test_structure_page_names_only_what_exists():
    text = DOC.read_text()
    for path in set(re.findall(r"`(tactilevision/[\w/]+\.py)`", text)):
        assert (ROOT / path).is_file(), path
    for dotted in set(re.findall(r"`(?:tactilevision\.)?((?:io|fem|optics|contact|mechanics|"
                                 r"diagnosis|planning|viz|sim|pipeline|history|live|batch)"
                                 r"\.\w+(?:\.\w+)?)`",
                                 text)):
        pkg, *names = dotted.split(".")
        obj = importlib.import_module(f"tactilevision.{pkg}")
        for n in names:
            obj = getattr(obj, n)
        assert obj is not None


@pytest.mark.parametrize("line, deps", [
    ("| `tactilevision.io` | x | `_checks` |", {"_checks"}),
    ("| `tactilevision.cli` | x | every package above |", None)])
def test_the_table_reader(tmp_path, monkeypatch, line, deps):
    page = tmp_path / "s.md"
    page.write_text(line + "\n")
    monkeypatch.setattr(__import__(__name__), "DOC", page)
    assert list(_doc_table().values()) == [deps]
