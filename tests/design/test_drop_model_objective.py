"""The designer under a drop model (``DesignSettings.drop_model``): its MILP minimises the model's score, the
continuous stage stays off, and ``rigopt design --objective`` takes a model file fitted from the reference only."""

from __future__ import annotations

import json

import numpy as np
import pytest

from box_car import BOX_ZONES, ROOF_ZONE, spec_text
from rigopt.design.designer import design_rig
from rigopt.design.problem import ReferenceRig
from rigopt.design.settings import DesignSettings
from rigopt.metrics import drop_model as dm
from rigopt.metrics.calibration import load_weights
from rigopt.rig.library import load_rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

#: Weights of the kind a fit on measured drops gives: depth prior, tilt and height dominate; no weight on the
#: uncovered share, so that the MILP's objective is the whole score over 1 + the count weight.
WEIGHTS = {"depth_prior": 0.7, "raise": 0.3, "lower": 0.3, "tilt_down": 4.0, "tilt_up": 4.0, "yaw": 0.05,
           "plan": 0.02, "zoom": 0.5, "count": 0.3}
SETTINGS = dict(lenses=(90.0, 120.0), yaw_step_deg=30.0, pitches_deg=(-10.0, 0.0), near_field=False, require="none")


def a_model() -> dm.DropModel:
    reference = load_rig("R1")
    weights = np.array([WEIGHTS.get(name, 0.0) for name in dm.FEATURES])
    n = len(dm.FEATURES)
    return dm.DropModel("test", "lss-R1", "R1", dm.camera_table(reference), weights, np.array([0.1, 0.1, 0.1]),
                        np.tile([0.0, 10.0], (n, 1)), False, "a test model")


def score(model: dm.DropModel, rig) -> float:
    """The model's score of ``rig`` from R1 under its own matching (what the MILP minimises, scaled)."""
    return float(model.terms(load_rig("R1"), [rig.perception()])[0] @ model.weights)


@pytest.fixture(scope="module")
def designs(tmp_path_factory):
    path = tmp_path_factory.mktemp("dropbox") / "vehicle.toml"
    path.write_text(spec_text("dropbox", zones=BOX_ZONES + ROOF_ZONE))
    vehicle = Vehicle.from_spec(read_spec(path))
    reference = ReferenceRig.on_own_vehicle(load_rig("R1"))
    model = a_model()
    return model, {name: design_rig(vehicle, reference, load_weights("joint"), DesignSettings(drop_model=m, **SETTINGS))
                   for name, m in (("model", model), ("rigcd", None))}


@pytest.mark.slow  # two whole designs
def test_the_milp_minimises_the_models_score(designs):
    model, results = designs
    mine, other = score(model, results["model"].design.rig), score(model, results["rigcd"].design.rig)
    assert mine <= other + 1e-9  # the RigCD design is a feasible point of the same problem
    count_weight = WEIGHTS["count"]
    assert results["model"].milp.selection.objective == pytest.approx(mine / (1 + count_weight), rel=1e-6, abs=1e-9)
    assert mine < other - 1e-3  # the objective changed the design


@pytest.mark.slow
def test_the_continuous_stage_is_off_under_a_model(designs):
    result = designs[1]["model"]
    assert result.refinement.status.startswith("off (the MILP minimised a drop model") and not result.refinement.accepted


def test_the_models_pair_costs_are_its_terms_under_its_weights():
    from rigopt.camera import CameraModel

    model, r1, r2 = a_model(), load_rig("R1"), load_rig("R2")
    costs = model.pair_costs(r2.positions, r2.rotations, CameraModel.of_cameras(r2.cameras), r1, chunk=2)
    pairs = dm.PairTerms.of(r1, r2).pairs  # (R, N, terms)
    assert costs == pytest.approx((pairs @ model.weights[:len(dm.PAIR_FEATURES)]).T, abs=1e-12)


def test_the_objective_option_refuses_a_model_of_another_reference(tmp_path):
    from console import run_console

    path = tmp_path / "model.json"
    path.write_text(json.dumps(a_model().to_dict()))
    result = run_console("design", "--vehicle", "tt", "--ref", "R2", "--objective", str(path), "--out",
                        str(tmp_path / "out"))
    assert result.returncode == 2 and result.stderr.count("rigopt: error:") == 1
    assert "fitted from R1" in result.stderr and "Traceback" not in result.stderr
    broken = tmp_path / "broken.json"
    broken.write_text(json.dumps({**a_model().to_dict(), "weights": [1.0, 2.0]}))
    result = run_console("design", "--vehicle", "tt", "--ref", "R1", "--objective", str(broken), "--out",
                        str(tmp_path / "out"))
    assert result.returncode == 2 and "not a drop model file" in result.stderr and not (tmp_path / "out").exists()
