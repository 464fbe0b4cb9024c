"""rigopt.metrics.pair_kernels: the compiled assignment answers as scipy's linear_sum_assignment does.

Small integer costs make most matchings tie, so a solver that breaks ties in any other order than scipy's
picks other pairs: of these 10,800 matrices, searching the remaining columns in the opposite order changes
6,597 pairings, and ignoring whether a tied column is free changes 6,405. Every shape from 1 x 1 to 6 x 6 is
checked, wide and tall.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from rigopt.errors import RigoptError
from rigopt.metrics.pair_kernels import assign_pairs

SHAPES = [(na, nb) for na in range(1, 7) for nb in range(1, 7)]


def _scipy_pairs(cost):
    """(G, M) rows and cols of scipy's assignment of each (Na, Nb) matrix of cost (G, Na, Nb)."""
    solved = [linear_sum_assignment(c) for c in cost]
    return np.array([rows for rows, _ in solved]), np.array([cols for _, cols in solved])


@pytest.mark.parametrize("shape", SHAPES, ids=[f"{na}x{nb}" for na, nb in SHAPES])
def test_pairing_is_scipys_on_tie_heavy_integer_costs(shape):
    rng = np.random.default_rng(sum(shape) * 7 + shape[0])
    t = rng.integers(0, 3, size=(300, *shape)).astype(float)
    zero = np.zeros_like(t)
    rows, cols = assign_pairs(t, zero, zero, (1.0, 1.0, 1.0))
    expected_rows, expected_cols = _scipy_pairs(t)
    np.testing.assert_array_equal(rows, expected_rows)
    np.testing.assert_array_equal(cols, expected_cols)


@pytest.mark.parametrize("shape", [(8, 9), (9, 8), (10, 6), (6, 10), (12, 12)])
def test_pairing_is_scipys_on_weighted_float_costs(shape):
    rng = np.random.default_rng(shape[0] * 100 + shape[1])
    t, r, f = rng.uniform(0, 5, size=(3, 200, *shape))
    lambdas = (0.3, 2.0, 0.05)
    rows, cols = assign_pairs(t, r, f, lambdas)
    expected_rows, expected_cols = _scipy_pairs((lambdas[0] * t + lambdas[1] * r) + lambdas[2] * f)
    np.testing.assert_array_equal(rows, expected_rows)
    np.testing.assert_array_equal(cols, expected_cols)


def test_a_matrix_with_no_finite_matching_is_an_error_naming_its_pair():
    t = np.ones((3, 2, 2))
    t[1, :, 0] = np.inf  # both rows need column 0 or 1; column 0 is closed, so one row has no finite column
    zero = np.zeros_like(t)
    with pytest.raises(RigoptError, match="pair 1 admit no finite matching"):
        assign_pairs(t, zero, zero, (1.0, 1.0, 1.0))
    with pytest.raises(ValueError):  # scipy agrees that it is infeasible
        linear_sum_assignment(t[1])


def test_a_folder_named_coverage_on_the_path_does_not_break_the_import(tmp_path):
    # numba takes any importable `coverage` for coverage.py; a plain folder of that name must not break rigopt.
    (tmp_path / "coverage").mkdir()
    script = ("import sys; sys.path.insert(0, '.'); import coverage; "
              "from rigopt.metrics.rigcd import rigcd; from rigopt.rig.library import library_rig; "
              "print(round(rigcd(library_rig('R1'), library_rig('R1')).rigcd, 6)); "
              "print(coverage.__spec__.origin)")  # the folder stays importable for everyone else
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["0.0", "None"]
