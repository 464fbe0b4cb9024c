"""Agreement of two transfer tables: shared off-diagonal pairs and Spearman rho on hand-made tables."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from rigopt.errors import DataError

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))  # the studies' shared code
from studylib.agreement import drop_agreement, shared_drops  # noqa: E402

from rigopt.metrics.transfer import TransferTable


def table(model: str, maps: dict[tuple[str, str], float]) -> TransferTable:
    pairs = list(maps)
    return TransferTable(np.array([model] * len(pairs)), np.array([a for a, _ in pairs]),
                         np.array([b for _, b in pairs]), np.array([maps[p] for p in pairs], dtype=float))


def square(model: str, rigs: list[str], own: float, drops: dict[tuple[str, str], float]) -> TransferTable:
    maps = {(a, b): own * (1 - drops.get((a, b), 0.0)) for a in rigs for b in rigs}
    return table(model, maps)


RIGS = ["A", "B", "C"]
DROPS = {("A", "B"): 0.1, ("A", "C"): 0.5, ("B", "A"): 0.2, ("B", "C"): 0.4, ("C", "A"): 0.3, ("C", "B"): 0.6}


def test_same_order_gives_rho_one_and_the_shared_pairs():
    synthetic = square("lss", RIGS, 0.4, DROPS).drops()
    real = square("BEVDet", RIGS, 0.2, {k: v / 2 for k, v in DROPS.items()}).drops()  # same order, other scale
    pairs, a, b = shared_drops(synthetic, "lss", real, "BEVDet")
    assert pairs == sorted(DROPS)  # off-diagonal only
    np.testing.assert_allclose(a, [DROPS[p] for p in pairs])
    np.testing.assert_allclose(b, [DROPS[p] / 2 for p in pairs])
    agreement = drop_agreement(synthetic, "lss", real, "BEVDet", resamples=200)
    assert agreement.rho == pytest.approx(1.0)
    assert agreement.n == 6
    assert agreement.mae == pytest.approx(np.mean([v / 2 for v in DROPS.values()]))


def test_reversed_order_gives_rho_minus_one_on_pairs_both_hold():
    reversed_drops = {k: 1.0 - v for k, v in DROPS.items()}
    synthetic = square("petr", RIGS, 0.3, DROPS).drops()
    real = square("PETR", RIGS + ["D"], 0.3, reversed_drops).drops()  # D only in the real table
    pairs, _, _ = shared_drops(synthetic, "petr", real, "PETR")
    assert all("D" not in pair for pair in pairs) and len(pairs) == 6
    assert drop_agreement(synthetic, "petr", real, "PETR", resamples=0).rho == pytest.approx(-1.0)


def test_unknown_model_names_the_models_there():
    drops = square("lss", RIGS, 0.4, DROPS).drops()
    with pytest.raises(DataError, match="'petr'.*lss"):
        shared_drops(drops, "petr", drops, "lss")
