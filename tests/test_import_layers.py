"""The import-layer contract: every part of rigopt imports only parts in lower layers, never upward.

Layers, lowest first; parts in one layer are independent of each other:

    errors  ->  resources, geometry, output, quiet  ->  camera, raycast  ->  rig  ->  metrics | vehicle  ->  mounting
    ->  coverage  ->  design | bench  ->  baselines  ->  report  ->  cli

Every ``import rigopt...`` counts, including imports inside functions (lazy imports are still
dependencies); imports under ``if TYPE_CHECKING:`` are annotations only and do not. The package's
``__init__`` (the public API, loaded lazily) and ``__main__`` may import any part.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "rigopt"

LAYERS = (
    {"errors"},
    {"resources", "geometry", "output", "quiet"},
    {"camera", "raycast"},
    {"rig"},
    {"metrics", "vehicle"},
    {"mounting"},
    {"coverage"},
    {"design", "bench"},
    {"baselines"},
    {"report"},
    {"cli"},
)
TOP = {"__init__", "__main__", "_data"}
LEVEL = {part: level for level, parts in enumerate(LAYERS) for part in parts}


def part_of(module: str) -> str:
    """'rigopt.metrics.rigcd' -> 'metrics'; 'rigopt.camera' -> 'camera'."""
    return module.split(".")[1]


def runtime_imports(tree: ast.AST) -> list[tuple[int, str]]:
    """(line, module) of every rigopt import in ``tree`` outside ``if TYPE_CHECKING:`` blocks."""
    found = []

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            found.extend((node.lineno, alias.name) for alias in node.names if alias.name.startswith("rigopt."))
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module == "rigopt":
                found.extend((node.lineno, f"rigopt.{alias.name}") for alias in node.names)
            elif node.module.startswith("rigopt."):
                found.append((node.lineno, node.module))
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return found


def modules() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def layered_modules() -> list[Path]:
    """Every module of a layered part (not the package's own ``__init__``/``__main__``)."""
    return [path for path in modules() if path.relative_to(PACKAGE).with_suffix("").parts[0] not in TOP]


def test_every_part_has_a_layer():
    parts = {path.relative_to(PACKAGE).with_suffix("").parts[0] for path in modules()}
    assert parts - TOP <= set(LEVEL), f"parts without a layer: {sorted(parts - TOP - set(LEVEL))}"


def test_the_checker_sees_lazy_imports_and_skips_type_checking_ones():
    tree = ast.parse("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from rigopt.rig.model import Rig\n"
                     "def f():\n    from rigopt.cli.app import app\n    from rigopt import raycast\n")
    assert runtime_imports(tree) == [(5, "rigopt.cli.app"), (6, "rigopt.raycast")]


@pytest.mark.parametrize("path", layered_modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_module_imports_upward_or_sideways(path):
    own = path.relative_to(PACKAGE).with_suffix("").parts[0]
    wrong = [f"line {line}: {module}" for line, module in runtime_imports(ast.parse(path.read_text()))
             if part_of(module) != own and LEVEL.get(part_of(module), -1) >= LEVEL[own]]
    assert not wrong, f"{path.relative_to(PACKAGE)} ({own}, layer {LEVEL[own]}) imports upward or sideways: {wrong}"
