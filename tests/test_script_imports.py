"""Every script under benchmarks/ and studies/ still imports as it does when run: its imports (rigopt's API, the
oracles a benchmark borrows from tests/, a study's sibling modules) are executed, not only parsed, so a renamed
module or a moved helper fails here rather than when someone next measures. A script's work waits for
``if __name__ == "__main__"``; modules without one are a study's libraries."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SCRIPTS = sorted([*(REPO / "benchmarks").glob("*.py"), *(REPO / "studies").rglob("*.py")])


def test_there_are_benchmarks_and_studies():
    assert sum(p.parent.name == "benchmarks" for p in SCRIPTS) >= 5 and len(SCRIPTS) >= 20


@pytest.mark.parametrize("path", SCRIPTS, ids=[str(p.relative_to(REPO)) for p in SCRIPTS])
def test_a_script_imports_as_when_it_runs(path, monkeypatch):
    # As `python path` does: the script's folder first on the path; the module registered while it runs
    # (dataclasses look their module up). Both are undone after the test.
    monkeypatch.setattr(sys, "path", [str(path.parent), *sys.path])
    name = f"script_{path.parent.name}_{path.stem}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, name, module)
    spec.loader.exec_module(module)
    if hasattr(module, "main"):
        assert 'if __name__ == "__main__":' in path.read_text(), f"{path.name} runs main() on import"
