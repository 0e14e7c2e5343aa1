"""The package layout: layers import only downwards, no private name crosses a package
boundary, and the old module paths still work (with a DeprecationWarning)."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[2] / "hammerbound"

# bottom to top; a module may import its own layer and the layers below it
LAYERS = [
    {"exceptions", "tolerances", "_compat", "data", "status", "terminal"},
    {"systems", "solvers", "tables", "plotting", "timeseries", "results"},
    {"relaxations"},
    {"modelset"},
    {"stage1", "stage2"},
    {"joint"},
    {"hammerstein", "model_selection"},
    {"discrepancy"},
    {"app", "__main__"},
]


# known exceptions, each with its reason (the lists must only shrink; both are empty)
ALLOWED_UPWARD: set = set()
ALLOWED_PRIVATE: set = set()


def _layer(top):
    for k, names in enumerate(LAYERS):
        if top in names:
            return k
    raise AssertionError(f"hammerbound.{top} is in no layer of tests/test_layout.py")


def _imports():
    """(importing module's top package, imported top package, imported names, file)."""
    for path in PKG.rglob("*.py"):
        rel = path.relative_to(PKG).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if not parts:
            continue
        pkg_parts = parts if path.name == "__init__.py" else parts[:-1]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level > 0:
                base = pkg_parts[: len(pkg_parts) - (node.level - 1)]
                target = base + (node.module.split(".") if node.module else [])
                if target:
                    yield parts[0], target, [a.name for a in node.names], path


def test_layers_import_only_downwards():
    bad = []
    for src, target, _, path in _imports():
        if src == "__init__" or target[0] == src:
            continue
        key = (str(path.relative_to(PKG)), ".".join(target))
        if _layer(target[0]) > _layer(src) and key not in ALLOWED_UPWARD:
            bad.append(f"{path.relative_to(PKG)} imports hammerbound.{'.'.join(target)}")
    assert not bad, "imports from a higher layer:\n" + "\n".join(bad)


def _package_graph() -> dict:
    """``{top package: {top packages it imports}}`` (relative imports, lazy ones included)."""
    graph: dict = {p.stem: set() for p in PKG.iterdir()
                   if p.stem != "__init__" and (p.suffix == ".py" or (p / "__init__.py").is_file())}
    for src, target, _, _ in _imports():
        if target[0] != src:
            graph[src].add(target[0])
    return graph


def _cycle(graph) -> list:
    """One import cycle ``[a, b, ..., a]`` of ``graph``, or ``[]`` (depth-first search)."""
    state: dict = {}  # 1: on the current path, 2: done
    path: list = []

    def visit(node):
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            if nxt not in state:
                found = visit(nxt)
                if found:
                    return found
        state[node] = 2
        path.pop()
        return []

    for node in sorted(graph):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return []


def test_cycle_finder_finds_cycles():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"a"}}) == ["a", "a"]
    assert _cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) == []


def test_no_import_cycle_between_packages():
    """No top-level package imports, directly or through others, one that imports it back
    (deprecated aliases included: lazy imports count)."""
    graph = _package_graph()
    assert {"app", "discrepancy", "tables", "results", "relaxations"} <= set(graph)
    cycle = _cycle(graph)
    assert not cycle, "import cycle between packages: " + " -> ".join(cycle)


def test_no_private_name_crosses_a_package():
    bad = []
    for src, target, names, path in _imports():
        if target[0] == src:
            continue
        private = [n for n in names if n.startswith("_")]
        private += [p for p in target[1:] if p.startswith("_")]
        if private and (str(path.relative_to(PKG)), ".".join(target)) not in ALLOWED_PRIVATE:
            bad.append(f"{path.relative_to(PKG)}: {'.'.join(target)} {private}")
    assert not bad, "private names across packages:\n" + "\n".join(bad)


@pytest.mark.parametrize("old, new", [("eiv", "stage2.estimator"), ("backlash", "stage1.estimator"),
                                      ("experiments", "systems.experiments"),
                                      ("iodata", "data.iodata")])
def test_old_module_paths_warn_and_work(old, new):
    code = (f"import warnings; warnings.simplefilter('error')\n"
            f"try:\n    import hammerbound.{old}\nexcept DeprecationWarning as e:\n"
            f"    print('warned', e)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "warned" in out.stdout and f"hammerbound.{new}" in out.stdout
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        assert importlib.import_module(f"hammerbound.{old}") is \
            importlib.import_module(f"hammerbound.{new}")


def test_importing_the_package_changes_no_sys_path():
    code = "import sys; before = list(sys.path); import hammerbound.app.cli; print(sys.path == before)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True"


def _top_imports(path: Path) -> set:
    """Top-level names of every absolute import in ``path``."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_tests_import_only_the_oracles_and_the_error_catalogue():
    """tests/oracles.py is independent of the package; test modules share code only through
    it and tests/error_cases.py (never through conftest.py or each other); file names are
    unique across the folders of tests/."""
    tests = PKG.parent / "tests"
    assert "hammerbound" not in _top_imports(tests / "oracles.py")
    files = sorted(tests.rglob("test_*.py"))
    assert len({f.name for f in files}) == len(files) > 50
    bad = [f"{f.relative_to(tests)} imports {name}" for f in files for name in _top_imports(f)
           if name == "conftest" or name.startswith("test_")]
    assert not bad, "\n".join(bad)


def test_architecture_import_graph_is_current():
    """docs/architecture.md lists the import graph as it is (python docs/gen_architecture.py)."""
    sys.path.insert(0, str(PKG.parent / "docs"))
    try:
        import gen_architecture
    finally:
        sys.path.pop(0)
    text = gen_architecture.DOC.read_text()
    assert gen_architecture.render(text) == text, (
        "docs/architecture.md is stale: run `python docs/gen_architecture.py`")
