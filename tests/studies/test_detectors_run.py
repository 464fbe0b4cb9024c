"""studies/detectors/run.py's readings of the validation outputs: the recipe's validations and a longer
schedule's (measurements/validation/epochs<E>/) side by side, seed 0 only, with the ordering rho of each;
the own mAP per schedule and seed."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest
from scipy.stats import spearmanr

SCRIPT = Path(__file__).resolve().parents[2] / "studies" / "detectors" / "run.py"


@pytest.fixture()
def run(tmp_path, monkeypatch):
    spec = importlib.util.spec_from_file_location("baselines_run", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    monkeypatch.setattr(module, "VALIDATION", tmp_path / "validation")
    return module


def write_validation(path: Path, own: float, drops: dict[str, tuple[float, float]]) -> None:
    """A validation output with rigs {name: (predicted drop, measured drop)}; bootstrap draws shift the
    measured drops by a constant, so every draw keeps their order."""
    rigs = [{"role": "design" if i == 0 else "other", "rig": name, "predicted_drop": predicted,
             "measured_drop": measured, "measured_drop_ci": [measured - 0.05, measured + 0.05],
             "measured_drop_visible": measured - 0.01} for i, (name, (predicted, measured)) in enumerate(drops.items())]
    draws = {name: [measured + shift for shift in (-0.02, 0.0, 0.02)] for name, (_, measured) in drops.items()}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"reference_mAP": own, "rigs": rigs, "bootstrap": {"measured_drops": draws}}))


def test_validation_folder_keeps_the_recipe_at_the_top(run):
    assert run.validation_folder(run.RECIPE_EPOCHS) == run.VALIDATION
    assert run.validation_folder(16) == run.VALIDATION / "epochs16"


def test_schedule_rows_put_seed_zero_of_each_schedule_side_by_side(run):
    recipe = {"a": (0.2, 0.1), "b": (0.5, 0.4), "c": (0.9, 0.3)}
    longer = {"a": (0.2, 0.2), "b": (0.5, 0.5), "c": (0.9, 0.8)}
    write_validation(run.VALIDATION / "lss_design.json", 0.18, recipe)
    write_validation(run.VALIDATION / "lss_design_seed1.json", 0.17, {k: (p, m + 0.1) for k, (p, m) in recipe.items()})
    write_validation(run.VALIDATION / "epochs16" / "lss_design.json", 0.25, longer)

    header, *rows = run.schedule_rows("lss")
    assert header[:3] == ["rig", "predicted drop", "drop, 4 epochs"] and "drop, 16 epochs" in header
    by_rig = {row[0]: row for row in rows}
    assert [by_rig[rig][2] for rig in "abc"] == [0.1, 0.4, 0.3]  # seed 0's, not seed 1's
    assert [by_rig[rig][5] for rig in "abc"] == [0.2, 0.5, 0.8]
    assert by_rig["b"][3] == "[0.350, 0.450]" and by_rig["b"][4] == pytest.approx(0.39)
    own = by_rig["own mAP (fixed set)"]
    assert (own[2], own[5]) == (0.18, 0.25)
    rho = by_rig["Spearman rho, predicted vs measured"]
    assert rho[2] == pytest.approx(spearmanr([0.2, 0.5, 0.9], [0.1, 0.4, 0.3]).statistic)
    assert rho[5] == pytest.approx(1.0)


def test_schedule_rows_are_empty_without_a_longer_schedule(run):
    write_validation(run.VALIDATION / "lss_design.json", 0.18, {"a": (0.2, 0.1), "b": (0.5, 0.4)})
    assert run.schedule_rows("lss") == []


def test_own_map_rows_list_each_schedule_and_seed_once(run):
    drops = {"a": (0.2, 0.1), "b": (0.5, 0.4)}
    write_validation(run.VALIDATION / "lss_design.json", 0.18, drops)
    write_validation(run.VALIDATION / "lss_other.json", 0.18, drops)
    write_validation(run.VALIDATION / "lss_design_seed2.json", 0.17, drops)
    write_validation(run.VALIDATION / "epochs16" / "lss_design_seed1.json", 0.26, drops)

    header, *rows = run.own_map_rows("lss")
    assert header[:3] == ["epochs", "seed", "own mAP (fixed set)"]
    assert [row[:3] for row in rows] == [[run.RECIPE_EPOCHS, 0, 0.18], [run.RECIPE_EPOCHS, 2, 0.17], [16, 1, 0.26]]
