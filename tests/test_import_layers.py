"""The import-layer contract: every part of rigopt imports only parts in lower layers, never upward.

Layers, lowest first; parts in one layer are independent of each other:

    errors  ->  resources, geometry, output, quiet, background, benchmark  ->  camera, raycast  ->  rig  ->  metrics | vehicle  ->  mounting
    ->  coverage  ->  design  ->  validation  ->  report  ->  cli

Every ``import rigopt...`` counts, including imports inside functions (lazy imports are still
dependencies), relative imports (``from ..cli import app``) and ``importlib.import_module("rigopt...")`` with a
literal name; imports under ``if TYPE_CHECKING:`` are annotations only and do not. The package's
``__init__`` (the public API, loaded lazily) and ``__main__`` may import any part.

Above the package, ``studies/`` and ``benchmarks/`` may import any part, but only modules that exist (a
restructuring that leaves a study importing a moved module fails here, not months later), and the package never
imports them or the tests. The torch-free core is checked in a real interpreter.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "rigopt"

LAYERS = (
    {"errors"},
    {"resources", "geometry", "output", "quiet", "background", "benchmark"},
    {"camera", "raycast"},
    {"rig"},
    {"metrics", "vehicle"},
    {"mounting"},
    {"coverage"},
    {"design"},
    {"validation"},
    {"report"},
    {"cli"},
)
TOP = {"__init__", "__main__", "_data"}
LEVEL = {part: level for level, parts in enumerate(LAYERS) for part in parts}


def part_of(module: str) -> str:
    """'rigopt.metrics.rigcd' -> 'metrics'; 'rigopt.camera' -> 'camera'."""
    return module.split(".")[1]


def runtime_imports(tree: ast.AST, package: tuple[str, ...] = ()) -> list[tuple[int, str]]:
    """(line, module) of every rigopt import in ``tree`` outside ``if TYPE_CHECKING:`` blocks; ``package`` the
    dotted parts of the tree's own package (e.g. ("rigopt", "metrics")), against which relative imports resolve."""
    found = []

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            found.extend((node.lineno, alias.name) for alias in node.names if alias.name.startswith("rigopt."))
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: up level - 1 packages from this one
                parent = package[:len(package) - node.level + 1] if node.level <= len(package) else ()
                base = ".".join((*parent, *([node.module] if node.module else [])))
            if base == "rigopt":
                found.extend((node.lineno, f"rigopt.{alias.name}") for alias in node.names)
            elif base.startswith("rigopt."):
                found.append((node.lineno, base))
        elif isinstance(node, ast.Call) and ast.unparse(node.func) in ("importlib.import_module", "import_module") \
                and node.args and isinstance(node.args[0], ast.Constant) and str(node.args[0].value).startswith("rigopt."):
            found.append((node.lineno, node.args[0].value))
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return found


def package_of(path: Path) -> tuple[str, ...]:
    """("rigopt", "metrics") for rigopt/metrics/rigcd.py: the package a module's relative imports start from."""
    return ("rigopt", *path.relative_to(PACKAGE).parts[:-1])


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


def test_the_checker_resolves_relative_and_dynamic_imports():
    tree = ast.parse("from ..cli import app\nfrom . import lifting\nfrom .rigcd import rigcd\nimport importlib\n"
                     "importlib.import_module('rigopt.validation.detectors.lss')\n")
    assert runtime_imports(tree, ("rigopt", "metrics")) == [
        (1, "rigopt.cli"), (2, "rigopt.metrics"), (3, "rigopt.metrics.rigcd"), (5, "rigopt.validation.detectors.lss")]


def test_an_injected_relative_upward_import_fails_the_contract(tmp_path):
    module = PACKAGE / "metrics" / "rigcd.py"
    tree = ast.parse(module.read_text() + "\n\ndef _injected():\n    from ..cli import app\n")
    assert upward_imports(module, tree) == [f"line {len(module.read_text().splitlines()) + 4}: rigopt.cli"]


def upward_imports(path: Path, tree: ast.AST | None = None) -> list[str]:
    """'line N: module' for each import of the module at ``path`` into its own layer's other parts or above."""
    own = path.relative_to(PACKAGE).with_suffix("").parts[0]
    tree = ast.parse(path.read_text()) if tree is None else tree
    return [f"line {line}: {module}" for line, module in runtime_imports(tree, package_of(path))
            if part_of(module) != own and LEVEL.get(part_of(module), -1) >= LEVEL[own]]


@pytest.mark.parametrize("path", layered_modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_module_imports_upward_or_sideways(path):
    own = path.relative_to(PACKAGE).with_suffix("").parts[0]
    wrong = upward_imports(path)
    assert not wrong, f"{path.relative_to(PACKAGE)} ({own}, layer {LEVEL[own]}) imports upward or sideways: {wrong}"


#: The validation wing's own parts, lowest first: the synthetic benchmark (numpy), the detectors (torch), a
#: design's validation.
WING = ("synthetic", "detectors", "designs")


def wing_part(module: str) -> str | None:
    """'rigopt.validation.detectors.lss' -> 'detectors'; None outside the wing or for the wing's ``__init__``."""
    parts = module.split(".")
    return parts[2] if len(parts) > 2 and parts[:2] == ["rigopt", "validation"] else None


@pytest.mark.parametrize("path", sorted((PACKAGE / "validation").rglob("*.py")), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_the_validation_wing_imports_only_downward_inside(path):
    own = wing_part(".".join((*package_of(path), *([path.stem] if path.stem != "__init__" else []))))
    if own is None:
        return
    wrong = [f"line {line}: {module}" for line, module in runtime_imports(ast.parse(path.read_text()), package_of(path))
             if wing_part(module) is not None and WING.index(wing_part(module)) > WING.index(own)]
    assert not wrong, f"{path.relative_to(PACKAGE)} ({own}) imports a higher part of the validation wing: {wrong}"


def test_the_wing_check_sees_an_upward_import():
    tree = ast.parse("from rigopt.validation.detectors.lss import LSSDetector\n")
    found = runtime_imports(tree, ("rigopt", "validation", "synthetic"))
    assert [WING.index(wing_part(m)) > WING.index("synthetic") for _, m in found] == [True]


def test_the_package_never_imports_studies_benchmarks_or_tests():
    outside = ("studies", "benchmarks", "tests")
    wrong = []
    for path in modules():
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else []
            wrong += [f"{path.relative_to(PACKAGE)}: {n}" for n in names if n.split(".")[0] in outside]
    assert not wrong


def _exists(module: str) -> bool:
    parts = module.split(".")
    return (PACKAGE.parent.joinpath(*parts).with_suffix(".py").is_file()
            or (PACKAGE.parent.joinpath(*parts) / "__init__.py").is_file())


@pytest.mark.parametrize("folder", ["studies", "benchmarks"])
def test_studies_and_benchmarks_import_only_modules_that_exist(folder):
    missing = []
    for path in sorted((PACKAGE.parent / folder).rglob("*.py")):
        for line, module in runtime_imports(ast.parse(path.read_text())):
            # "from rigopt.x import name": module rigopt.x, or rigopt.x.name when name is a module
            if not _exists(module):
                missing.append(f"{path.relative_to(PACKAGE.parent)} line {line}: {module}")
    assert not missing, f"imports of rigopt modules that do not exist: {missing}"


def test_benchmarks_import_only_oracles_that_exist():
    """benchmarks/ reach the tests' oracles (tests/oracles/) by putting tests/ on sys.path."""
    oracles = PACKAGE.parent / "tests" / "oracles"
    used, missing = set(), []
    for path in sorted((PACKAGE.parent / "benchmarks").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("oracles."):
                used.add(node.module)
                if not (oracles / f"{node.module.split('.', 1)[1]}.py").is_file():
                    missing.append(f"{path.name} line {node.lineno}: {node.module}")
    assert used >= {"oracles.metrics", "oracles.raycast"} and not missing, missing


def test_the_core_imports_no_torch():
    code = ("import sys; import rigopt.design.designer, rigopt.coverage.regulations, rigopt.metrics.calibration, "
            "rigopt.cli; print('torch' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "False"


def test_the_synthetic_benchmark_and_the_detector_settings_import_no_torch():
    code = ("import sys; import rigopt.validation.synthetic.generate, rigopt.validation.synthetic.evaluation; "
            "from rigopt.validation.detectors.config import model_config; model_config('petr', 'tiny'); "
            "print('torch' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "False"
