"""The import-layer contract: every part of rigopt imports only parts in lower layers, never upward.

Layers, lowest first; parts in one layer are independent of each other:

    errors  ->  resources, geometry, output, quiet, background, benchmark  ->  camera, raycast  ->  rig  ->  metrics | vehicle  ->  mounting
    ->  coverage  ->  design  ->  validation  ->  report  ->  cli

Every ``import rigopt...`` counts, including imports inside functions (lazy imports are still
dependencies), relative imports (``from ..cli import app``), ``importlib.import_module("rigopt...")`` with a
literal name and imports under ``if TYPE_CHECKING:`` (annotations only, but a type a module names is one it
depends on). Within one part the modules' imports, type-only ones included, form no cycle: two modules that
name each other's types share a record that belongs in a module of its own (as ``rigopt/mounting/records.py``).
The package's ``__init__`` (the public API, loaded lazily) and ``__main__`` may import any part.

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


def import_statements(tree: ast.AST, package: tuple[str, ...] = ()) -> list[tuple[int, str, tuple[str, ...], bool]]:
    """(line, module, names, type_only) of every rigopt import in ``tree``: the module imported (relative imports
    resolved against ``package``, the dotted parts of the tree's own package, e.g. ("rigopt", "metrics")), the
    names a ``from`` import takes from it (empty for the others), and whether it is under ``if TYPE_CHECKING:``."""
    found = []

    def visit(node: ast.AST, type_only: bool) -> None:
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                visit(child, True)
            for child in node.orelse:
                visit(child, type_only)
            return
        if isinstance(node, ast.Import):
            found.extend((node.lineno, alias.name, (), type_only) for alias in node.names
                         if alias.name.startswith("rigopt."))
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: up level - 1 packages from this one
                parent = package[:len(package) - node.level + 1] if node.level <= len(package) else ()
                base = ".".join((*parent, *([node.module] if node.module else [])))
            if base == "rigopt" or base.startswith("rigopt."):
                found.append((node.lineno, base, tuple(alias.name for alias in node.names), type_only))
        elif isinstance(node, ast.Call) and ast.unparse(node.func) in ("importlib.import_module", "import_module") \
                and node.args and isinstance(node.args[0], ast.Constant) and str(node.args[0].value).startswith("rigopt."):
            found.append((node.lineno, node.args[0].value, (), type_only))
        for child in ast.iter_child_nodes(node):
            visit(child, type_only)

    visit(tree, False)
    return found


def _modules(statements) -> list[tuple[int, str]]:
    """(line, module) of each of ``statements`` (:func:`import_statements`); ``from rigopt import a, b`` imports
    rigopt.a and rigopt.b."""
    found = []
    for line, module, names, _ in statements:
        if module == "rigopt":
            found.extend((line, f"rigopt.{name}") for name in names)
        else:
            found.append((line, module))
    return found


def runtime_imports(tree: ast.AST, package: tuple[str, ...] = ()) -> list[tuple[int, str]]:
    """(line, module) of every rigopt import in ``tree`` outside ``if TYPE_CHECKING:`` blocks (``package``: see
    :func:`import_statements`)."""
    return _modules(s for s in import_statements(tree, package) if not s[3])


def type_only_imports(tree: ast.AST, package: tuple[str, ...] = ()) -> list[tuple[int, str]]:
    """(line, module) of every rigopt import in ``tree`` under ``if TYPE_CHECKING:``."""
    return _modules(s for s in import_statements(tree, package) if s[3])


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


def test_the_checker_sees_lazy_imports_and_tells_type_checking_ones_apart():
    tree = ast.parse("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from rigopt.rig.model import Rig\n"
                     "def f():\n    from rigopt.cli.app import app\n    from rigopt import raycast\n")
    assert runtime_imports(tree) == [(5, "rigopt.cli.app"), (6, "rigopt.raycast")]
    assert type_only_imports(tree) == [(3, "rigopt.rig.model")]


def test_the_checker_resolves_relative_and_dynamic_imports():
    tree = ast.parse("from ..cli import app\nfrom . import lifting\nfrom .rigcd import rigcd\nimport importlib\n"
                     "importlib.import_module('rigopt.validation.detectors.lss')\n")
    assert runtime_imports(tree, ("rigopt", "metrics")) == [
        (1, "rigopt.cli"), (2, "rigopt.metrics"), (3, "rigopt.metrics.rigcd"), (5, "rigopt.validation.detectors.lss")]


def test_an_injected_relative_upward_import_fails_the_contract(tmp_path):
    module = PACKAGE / "metrics" / "rigcd.py"
    tree = ast.parse(module.read_text() + "\n\ndef _injected():\n    from ..cli import app\n")
    assert upward_imports(module, tree) == [f"line {len(module.read_text().splitlines()) + 4}: rigopt.cli"]


def test_an_injected_type_only_upward_import_fails_the_contract():
    module = PACKAGE / "metrics" / "rigcd.py"
    tree = ast.parse(module.read_text() + "\n\nif TYPE_CHECKING:\n    from rigopt.design.result import DesignResult\n")
    line = len(module.read_text().splitlines()) + 4
    assert upward_imports(module, tree) == [f"line {line}: rigopt.design.result (type only)"]


def upward_imports(path: Path, tree: ast.AST | None = None) -> list[str]:
    """'line N: module' for each import of the module at ``path`` into its own layer's other parts or above;
    'line N: module (type only)' for one under ``if TYPE_CHECKING:``."""
    own = path.relative_to(PACKAGE).with_suffix("").parts[0]
    tree = ast.parse(path.read_text()) if tree is None else tree
    found = [(line, module, "") for line, module in runtime_imports(tree, package_of(path))]
    found += [(line, module, " (type only)") for line, module in type_only_imports(tree, package_of(path))]
    return [f"line {line}: {module}{kind}" for line, module, kind in found
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
    tree = ast.parse(path.read_text())
    found = runtime_imports(tree, package_of(path)) + type_only_imports(tree, package_of(path))
    wrong = [f"line {line}: {module}" for line, module in found
             if wing_part(module) is not None and WING.index(wing_part(module)) > WING.index(own)]
    assert not wrong, f"{path.relative_to(PACKAGE)} ({own}) imports a higher part of the validation wing: {wrong}"


def test_the_wing_check_sees_an_upward_import():
    tree = ast.parse("from rigopt.validation.detectors.lss import LSSDetector\n")
    found = runtime_imports(tree, ("rigopt", "validation", "synthetic"))
    assert [WING.index(wing_part(m)) > WING.index("synthetic") for _, m in found] == [True]


def dotted(path: str) -> tuple[str, ...]:
    """("rigopt", "mounting", "rules") for 'mounting/rules.py', a path in rigopt/; ("rigopt", "mounting") for
    'mounting/__init__.py'."""
    parts = ("rigopt", *Path(path).with_suffix("").parts)
    return parts[:-1] if parts[-1] == "__init__" else parts


def module_graph(sources: dict[str, str]) -> dict[str, set[str]]:
    """Each module of ``sources`` ({path in rigopt/: its source}) -> the modules of ``sources`` it imports, at
    run time (lazily too) or under TYPE_CHECKING. ``from p import n`` imports the module p.n where ``sources``
    holds one, else p."""
    names = {".".join(dotted(path)) for path in sources}
    graph = {}
    for path, source in sources.items():
        package = ("rigopt", *Path(path).parts[:-1])
        imported = set()
        for _, module, taken, _ in import_statements(ast.parse(source), package):
            submodules = {f"{module}.{name}" for name in taken} & names
            if not taken or len(submodules) < len(taken):  # the module itself, or names defined in it
                submodules |= {module} & names
            imported |= submodules
        graph[".".join(dotted(path))] = imported
    return graph


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The cycles of ``graph`` (module -> the modules it imports): each set of two or more modules that all reach
    each other (a strongly connected component), sorted."""
    reach = {}
    for start in graph:
        seen, todo = set(), list(graph[start])
        while todo:
            module = todo.pop()
            if module not in seen:
                seen.add(module)
                todo.extend(graph.get(module, ()))
        reach[start] = seen
    cycles = []
    for module in sorted(graph):
        together = sorted(other for other in graph if other in reach[module] and module in reach[other])
        if len(together) > 1 and together not in cycles:
            cycles.append(together)
    return cycles


def test_the_cycle_check_sees_a_cycle_through_a_type_only_import():
    sources = {"x/__init__.py": "",
               "x/a.py": "from typing import TYPE_CHECKING\nfrom rigopt.x.c import C\n"
                         "if TYPE_CHECKING:\n    from rigopt.x.b import B\n",
               "x/b.py": "from rigopt.x import a\n",
               "x/c.py": "def f():\n    from . import d, helper\n",
               "x/d.py": "import rigopt.x.c\n"}
    graph = module_graph(sources)
    assert graph == {"rigopt.x": set(), "rigopt.x.a": {"rigopt.x.b", "rigopt.x.c"}, "rigopt.x.b": {"rigopt.x.a"},
                     "rigopt.x.c": {"rigopt.x", "rigopt.x.d"}, "rigopt.x.d": {"rigopt.x.c"}}
    assert import_cycles(graph) == [["rigopt.x.a", "rigopt.x.b"], ["rigopt.x.c", "rigopt.x.d"]]
    sources["x/a.py"] = sources["x/a.py"].replace("rigopt.x.b import B", "rigopt.x.d import D")
    assert import_cycles(module_graph(sources)) == [["rigopt.x.c", "rigopt.x.d"]]


#: The parts of rigopt that are packages (the others are single modules).
PACKAGED_PARTS = sorted(part for part in LEVEL if (PACKAGE / part / "__init__.py").is_file())


@pytest.mark.parametrize("part", PACKAGED_PARTS)
def test_the_modules_of_a_part_form_no_import_cycle(part):
    sources = {path.relative_to(PACKAGE).as_posix(): path.read_text()
               for path in sorted((PACKAGE / part).rglob("*.py"))}
    cycles = import_cycles(module_graph(sources))
    assert not cycles, f"modules of {part} that import each other (at run time, lazily or for types): {cycles}"


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
