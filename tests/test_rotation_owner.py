"""Rotation maths lives in rigopt/geometry.py alone (issue 32): a scan of the code for rotation maths written
anywhere else.

What counts as rotation maths (each rule an AST pattern, so comments and strings never trip it):
- ``library``: an import of ``scipy.spatial.transform`` or a use of trimesh's rotation builders
  (``transformations.rotation_matrix``, ``euler_matrix``, ``quaternion_matrix`` and their inverses): SO(3) goes
  through the owner, whose conventions (sequence letters, quaternion order) are stated once;
- ``matrix_angle``: an ``arctan2`` / ``atan2`` / ``arcsin`` / ``asin`` / ``arccos`` / ``acos`` of a matrix entry
  (``r[1, 0]``, ``r[..., 2, 1]``, a name ``r00`` .. ``r22``) or of a ``trace`` (a call, or a name ``trace``): an
  Euler decomposition or an angle read off a rotation matrix;
- ``builder``: a 3 x 3 array written out (nested lists or tuples, or array-making calls, ``ARRAY_CALLS``:
  ``np.stack``, ``np.array``, ``ca.vertcat`` / ``ca.horzcat``, ... of three rows of three) holding a ``cos`` or
  ``sin``, directly or through a name assigned from one in the same function: an elementary rotation built by hand;
- ``quaternion``: a quaternion-to-matrix term ``2 * (a * b +- c * d)`` over the names w, x, y, z (qw, ...), one of
  them the scalar w;
- ``frame``: a signed permutation matrix other than the identity written as a 3 x 3 literal, or a matrix product
  with the owner's ``R_CAM_OPTICAL`` / ``S_CARLA_ISO``: a frame convention (the optical frame, CARLA's reflection)
  restated outside the owner instead of its conversions (``body_from_optical``, ``carla_to_iso``, ...).

Not rotation maths: the heading of a direction vector (``arctan2(d[1], d[0])``), angles between rays, planar
(2D) heading rotations of the benchmark's ground boxes, matrix products with the owner's results.

Scanned: every .py file of rigopt/, benchmarks/ and studies/ except the owner (the tests' oracles, tests/oracles,
are definitions-as-code kept by hand on purpose and are not scanned). ``ORACLES`` are the definitions-as-code
kept by hand among the scanned files (the speed benchmark's naive loop must not share code with what it times);
each must still hold what it is excused for.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
OWNER = "rigopt/geometry.py"
SCANNED = ("rigopt", "benchmarks", "studies")
#: (file, function) -> the rule it is excused from.
ORACLES = {("benchmarks/rigcd_speed.py", "naive_numpy"): "matrix_angle"}

#: The owner's frame constants: a product with one is a frame conversion (body_from_optical, ...).
FRAME_CONSTANTS = {"R_CAM_OPTICAL", "S_CARLA_ISO"}
ANGLE_FUNCTIONS = {"arctan2", "atan2", "arcsin", "asin", "arccos", "acos"}
TRIG = {"cos", "sin"}
TRIMESH_ROTATIONS = {"rotation_matrix", "euler_matrix", "quaternion_matrix", "euler_from_matrix",
                     "quaternion_from_matrix", "euler_from_quaternion", "quaternion_from_euler"}
QUATERNION_NAMES = {"w", "x", "y", "z", "qw", "qx", "qy", "qz"}
ENTRY_NAME = re.compile(r"^r[0-2][0-2]$")


def _name(node) -> str | None:
    """The called or named identifier: ``np.arctan2`` -> "arctan2", ``cos`` -> "cos"."""
    if isinstance(node, ast.Attribute):
        return node.attr
    if isinstance(node, ast.Name):
        return node.id
    return None


def _is_entry(node) -> bool:
    """A matrix entry: a subscript whose index ends in two integer constants, or a name r00 .. r22."""
    if isinstance(node, ast.Name):
        return bool(ENTRY_NAME.match(node.id))
    if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Tuple) and len(node.slice.elts) >= 2:
        return all(isinstance(e, ast.Constant) and isinstance(e.value, int) for e in node.slice.elts[-2:])
    return False


#: Calls that make an array of their rows.
ARRAY_CALLS = {"array", "asarray", "stack", "vstack", "hstack", "column_stack", "row_stack", "concatenate", "tensor",
               "vertcat", "horzcat", "blockcat", "DM"}


def _rows(node) -> list | None:
    """The elements of a list/tuple literal, or of an array-making call's list argument or positional arguments."""
    if isinstance(node, (ast.List, ast.Tuple)):
        return node.elts
    if isinstance(node, ast.Call) and _name(node.func) in ARRAY_CALLS:
        if node.args and isinstance(node.args[0], (ast.List, ast.Tuple)):
            return node.args[0].elts
        return node.args
    return None


def _is_three_by_three(node) -> bool:
    rows = _rows(node)
    return rows is not None and len(rows) == 3 and all((_rows(r) is not None and len(_rows(r)) == 3) for r in rows)


def _constant(node) -> float | None:
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        return float(node.value)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        value = _constant(node.operand)
        return None if value is None else -value
    return None


def _is_frame_literal(node) -> bool:
    """A 3 x 3 literal of constants that is a signed permutation other than the identity."""
    if not isinstance(node, (ast.List, ast.Tuple)) or not _is_three_by_three(node):
        return False
    values = [[_constant(v) for v in _rows(row)] for row in node.elts]
    if any(v is None for row in values for v in row):
        return False
    permutation = all(sorted(abs(v) for v in row) == [0.0, 0.0, 1.0] for row in values) and all(
        sorted(abs(values[i][j]) for i in range(3)) == [0.0, 0.0, 1.0] for j in range(3))
    return permutation and values != [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def _is_quaternion_term(node) -> bool:
    """``2 * (a * b +- c * d)`` with a, b, c, d among the quaternion names, one of them w (or qw)."""
    if not (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult)):
        return False
    for two, inner in ((node.left, node.right), (node.right, node.left)):
        if _constant(two) == 2.0 and isinstance(inner, ast.BinOp) and isinstance(inner.op, (ast.Add, ast.Sub)):
            products = (inner.left, inner.right)
            if all(isinstance(p, ast.BinOp) and isinstance(p.op, ast.Mult)
                   and all(isinstance(f, ast.Name) and f.id in QUATERNION_NAMES for f in (p.left, p.right))
                   for p in products) and any(n.id in ("w", "qw") for n in ast.walk(inner) if isinstance(n, ast.Name)):
                return True
    return False


def _scopes(tree):
    """The module and every function: (name, node); names assigned from cos/sin are tracked per scope."""
    yield "<module>", tree
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            yield getattr(node, "name", "<lambda>"), node


def _own_nodes(scope):
    """The nodes of ``scope`` that are not inside a nested function (those are scopes of their own)."""
    stack = list(ast.iter_child_nodes(scope))
    while stack:
        node = stack.pop()
        yield node
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            stack.extend(ast.iter_child_nodes(node))


def _holds_trig(node, trig_names: set[str]) -> bool:
    return any((isinstance(n, ast.Call) and _name(n.func) in TRIG) or (isinstance(n, ast.Name) and n.id in trig_names)
               for n in ast.walk(node))


def findings(source: str) -> list[tuple[int, str, str]]:
    """(line, rule, enclosing function) of every piece of rotation maths in ``source``."""
    tree = ast.parse(source)
    found = set()
    for scope_name, scope in _scopes(tree):
        nodes = list(_own_nodes(scope))
        trig_names = {t.id for n in nodes if isinstance(n, ast.Assign) and _holds_trig(n.value, set())
                      for target in n.targets for t in ast.walk(target) if isinstance(t, ast.Name)}
        for node in nodes:
            rule = None
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("scipy.spatial.transform"):
                rule = "library"
            elif isinstance(node, ast.Import) and any(a.name.startswith("scipy.spatial.transform") for a in node.names):
                rule = "library"
            elif (isinstance(node, ast.ImportFrom) and (node.module or "").startswith("scipy.spatial")
                  and any(a.name == "transform" for a in node.names)):
                rule = "library"
            elif (isinstance(node, ast.Attribute) and node.attr in TRIMESH_ROTATIONS
                  and _name(node.value) == "transformations"):
                rule = "library"
            elif isinstance(node, ast.Call) and _name(node.func) in ANGLE_FUNCTIONS and any(
                    _is_entry(n) or (isinstance(n, ast.Call) and _name(n.func) == "trace")
                    or (isinstance(n, ast.Name) and n.id == "trace")
                    for arg in node.args for n in ast.walk(arg)):
                rule = "matrix_angle"
            elif _is_three_by_three(node):
                if _holds_trig(node, trig_names):
                    rule = "builder"
                elif _is_frame_literal(node):
                    rule = "frame"
            elif _is_quaternion_term(node):
                rule = "quaternion"
            elif isinstance(node, ast.BinOp) and isinstance(node.op, ast.MatMult) and any(
                    _name(n) in FRAME_CONSTANTS for n in ast.walk(node)):
                rule = "frame"
            if rule:
                found.add((node.lineno, rule, scope_name))
    return sorted(found)


def _scanned_files():
    for folder in SCANNED:
        for path in sorted((ROOT / folder).rglob("*.py")):
            relative = path.relative_to(ROOT).as_posix()
            if relative != OWNER:
                yield relative, path


def test_no_rotation_maths_outside_the_owner():
    outside, excused = [], set()
    for relative, path in _scanned_files():
        for line, rule, function in findings(path.read_text()):
            if ORACLES.get((relative, function)) == rule:
                excused.add((relative, function))
            else:
                outside.append(f"{relative}:{line} {rule} in {function}")
    assert outside == [], "rotation maths outside rigopt/geometry.py (use its functions):\n" + "\n".join(outside)
    assert excused == set(ORACLES), f"an excused oracle no longer holds rotation maths: {set(ORACLES) - excused}"


def test_the_scan_sees_the_owner_s_own_rotation_maths():
    rules = {rule for _, rule, _ in findings((ROOT / OWNER).read_text())}
    assert {"library", "matrix_angle", "builder", "quaternion", "frame"} <= rules


def test_the_scan_covers_the_three_folders():
    files = [relative for relative, _ in _scanned_files()]
    for folder in SCANNED:
        assert any(f.startswith(folder + "/") for f in files), folder
    assert OWNER not in files


CAUGHT = {
    "library": ["from scipy.spatial.transform import Rotation",
                "import scipy.spatial.transform",
                "from scipy.spatial import transform",
                "m = trimesh.transformations.rotation_matrix(0.5, [0, 0, 1])"],
    "matrix_angle": ["yaw = np.arctan2(r[..., 1, 0], r[..., 0, 0])",
                     "pitch = math.asin(rotation[2, 0])",
                     "a = np.arccos((np.trace(m) - 1) / 2)",
                     "a = ca.atan2(s, (ca.trace(m) - 1) / 2)",
                     "trace = sum(a[k][i] * b[k][i] for i in range(3) for k in range(3))\n"
                     "a = math.acos(trace / 2 - 0.5)",
                     "w = np.sqrt(1 + r00 + r11 + r22) / 2; x = np.arctan2(r21, r00)"],
    "builder": ["def f(a):\n    c, s = np.cos(a), np.sin(a)\n"
                "    return np.array([[c, -s, 0.0], [s, c, 0.0], [0, 0, 1]])",
                "t = np.stack([np.stack([np.cos(a), -np.sin(a), z], -1), np.stack([z, o, z], -1), "
                "np.stack([z, z, o], -1)], -2)",
                "m = ca.vertcat(ca.horzcat(cy, -sy, 0), ca.horzcat(sy, cy, 0), ca.horzcat(0, 0, ca.cos(p)))"],
    "quaternion": ["m01 = 2 * (x * y - z * w)", "m12 = 2.0 * (qy * qz + qx * qw)"],
    "frame": ["R = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])",
              "S = [[1, 0, 0], [0, -1, 0], [0, 0, 1]]",
              "r = pose[:3, :3] @ R_CAM_OPTICAL.T",
              "r = geometry.S_CARLA_ISO @ m @ geometry.S_CARLA_ISO"],
}

PASSED = [
    "x, y, z = (np.where(f, a, x), np.where(f, b, y), np.where(f, np.cos(t), z))",  # three arrays, not a matrix
    "angle = np.arctan2(np.hypot(rays[:, 0], rays[:, 1]), rays[:, 2])",  # a ray's angle off the axis
    "yaw = np.arctan2(forward[1], forward[0])",  # heading of a direction
    "d = np.array([np.cos(a), np.sin(a), 0.0])",  # a direction, not a matrix
    "c, s = np.cos(yaws), np.sin(yaws)\nxy = np.stack([c * x - s * y, s * x + c * y], axis=1)",  # planar box yaw
    "eye = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])",
    "k = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])",  # an intrinsic matrix
    "# np.arctan2(r[1, 0], r[0, 0]) in a comment\ntext = 'np.arctan2(r[1, 0], r[0, 0])'",
    "area = 2 * (x * y + y * z)",  # not a quaternion: y * z
]


@pytest.mark.parametrize("rule, source", [(rule, source) for rule, sources in CAUGHT.items() for source in sources])
def test_the_scan_catches(rule, source):
    assert rule in {r for _, r, _ in findings(source)}, source


@pytest.mark.parametrize("source", PASSED)
def test_the_scan_passes(source):
    assert findings(source) == [], source


def test_a_rotation_written_inside_a_function_is_reported_there():
    source = "def turn(a):\n    c, s = np.cos(a), np.sin(a)\n    return [[c, -s, 0], [s, c, 0], [0, 0, 1]]\n"
    assert findings(source) == [(3, "builder", "turn")]
