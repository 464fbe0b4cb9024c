"""Calibration figures: every PNG is written and named, heatmap matrices put pairs in the right cells."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.metrics.protocol import PairPredictions, calibrate
from rigopt.metrics.transfer import TransferTable
from rigopt.report.calibration_figures import _file_stem, _pair_matrix, _rig_order, write_calibration_figures

RIGS = ["R2", "R1", "R1-f", "R1-c6"]  # deliberately not in benchmark order
CONTROL = ("R1", "R1-c6", "R1-f")
MODELS = ["DetA", "Det B/2"]


@pytest.fixture(scope="module")
def study():
    rng = np.random.default_rng(3)
    rows = []
    for m, model in enumerate(MODELS):
        for train in RIGS:
            own = 0.4 + 0.05 * m
            for test in RIGS:
                value = own if train == test else own * rng.uniform(0.3, 0.95)
                rows.append((model, train, test, value))
    model, train, test, mAP = (np.array(column) for column in zip(*rows))
    table = TransferTable(model, train, test, mAP.astype(float))
    return calibrate(table, control_rigs=CONTROL, resamples=20)


@pytest.mark.slow
def test_writes_every_figure_as_png(study, tmp_path):
    out = tmp_path / "figs"
    written = write_calibration_figures(study, out)
    expected = {"scatter.png", "joint_scatter.png"}
    for stem in ("DetA", "Det_B_2"):
        expected |= {f"drop_heatmaps_{stem}.png", f"rank_error_{stem}.png"}
    assert {p.name for p in written} == expected
    assert len(written) == len(expected)
    assert sorted(written) == sorted(out.iterdir())
    for path in written:
        data = path.read_bytes()
        assert data.startswith(b"\x89PNG\r\n\x1a\n"), path.name
        assert len(data) > 10_000, path.name


def test_rig_order_follows_library_then_others():
    assert _rig_order(RIGS + ["custom", "R1"]) == ["R1", "R1-c6", "R1-f", "R2", "custom"]
    assert _rig_order(["r9", "R1-T", "R1"]) == ["R1", "R1-T", "r9"]


def test_file_stem_replaces_unsafe_characters():
    assert _file_stem("Fast-BEV") == "Fast-BEV"
    assert _file_stem("Det B/2") == "Det_B_2"


def test_pair_matrix_places_values_and_leaves_missing_nan(study):
    pairs = study.models[0].pairs
    rigs = _rig_order(RIGS)
    matrix = _pair_matrix(pairs, pairs.delta, rigs)
    k = int(np.flatnonzero((pairs.train == "R2") & (pairs.test == "R1-f"))[0])
    assert matrix[rigs.index("R2"), rigs.index("R1-f")] == pairs.delta[k]
    assert np.isfinite(matrix).all()

    keep = ~((pairs.train == "R2") & (pairs.test == "R1"))
    partial = PairPredictions(*(getattr(pairs, f)[keep] for f in PairPredictions.__dataclass_fields__))
    holed = _pair_matrix(partial, partial.predicted, rigs)
    assert np.isnan(holed[rigs.index("R2"), rigs.index("R1")])
    assert np.isfinite(holed[rigs.index("R1"), rigs.index("R2")])
    assert np.isnan(holed).sum() == 1
