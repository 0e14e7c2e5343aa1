"""Every ```python block in README.md and docs/*.md runs (blocks of one file share a namespace)."""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

ROOT = Path(__file__).resolve().parents[1]
FILES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCK = re.compile(r"```python\n(.*?)```", re.S)


@pytest.mark.parametrize("path", [f for f in FILES if BLOCK.search(f.read_text())],
                         ids=lambda p: p.name)
def test_doc_examples_run(path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "docs" / "figures").mkdir(parents=True)
    ns: dict = {"__name__": "__doc_example__"}
    for k, code in enumerate(BLOCK.findall(path.read_text())):
        exec(compile(code, f"{path.name}[block {k}]", "exec"), ns)  # noqa: S102


def test_api_reference_is_current():
    import importlib.util

    spec = importlib.util.spec_from_file_location("gen_api", ROOT / "docs" / "gen_api.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    render = mod.render
    assert (ROOT / "docs" / "api.md").read_text() == render(), (
        "docs/api.md is stale: run `python docs/gen_api.py`")
