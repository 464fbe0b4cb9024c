"""The designer under a lifting metric (``rigopt.metrics.lifting``): its MILP minimises the metric's pair costs,
the report predicts with the metric, and the continuous stage (RigCD's terms only) stays off."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from box_car import BOX_ZONES, ROOF_ZONE, spec_text
from rigopt.design.designer import design_rig, rig_costs
from rigopt.design.problem import ReferenceRig
from rigopt.design.settings import DesignSettings
from rigopt.metrics.calibration import lifting_calibration, load_weights
from rigopt.metrics.lifting import TERMS, lifting_terms
from rigopt.rig.library import load_rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

pytestmark = pytest.mark.slow  # two whole designs (about 20 s)

#: Weights of the kind the validation study fits: height, tilt and the depth prior dominate, yaw and plan are free.
WEIGHTS = {"f": 0.015, "count": 0.3, "t_vert": 0.1, "r_yaw": 0.08, "r_tilt": 6.0, "dpm": 0.7}
SETTINGS = DesignSettings(lenses=(90.0, 120.0), yaw_step_deg=30.0, pitches_deg=(-10.0, 0.0), near_field=False,
                          require="none")


@pytest.fixture(scope="module")
def designs(tmp_path_factory):
    path = tmp_path_factory.mktemp("liftbox") / "vehicle.toml"
    path.write_text(spec_text("liftbox", zones=BOX_ZONES + ROOF_ZONE))
    vehicle = Vehicle.from_spec(read_spec(path))
    reference = ReferenceRig.on_own_vehicle(load_rig("R1"))
    lifting = lifting_calibration("test", WEIGHTS, "test-lifting")
    return reference, lifting, {name: design_rig(vehicle, reference, calibration, SETTINGS)
                                for name, calibration in (("lifting", lifting), ("rigcd", load_weights("joint")))}


def _objective(rig, reference, calibration) -> float:
    """The metric's distance of ``rig`` under its cheapest matching: what the MILP minimises."""
    costs = rig_costs(rig, reference, calibration)
    rows, cols = linear_sum_assignment(costs)
    m = min(costs.shape)
    count = abs(len(rig) - len(reference)) / max(len(rig), len(reference))
    return calibration.alpha / m * costs[rows, cols].sum() + (1 - calibration.alpha) * count


def test_the_milp_minimises_the_lifting_distance(designs):
    reference, lifting, results = designs
    mine, other = (_objective(results[k].design.rig, reference.rig, lifting) for k in ("lifting", "rigcd"))
    assert mine <= other + 1e-9  # the RigCD design is a feasible point of the same problem
    assert results["lifting"].milp.selection.objective == pytest.approx(mine, rel=1e-6, abs=1e-9)


def test_the_report_predicts_with_the_metric_and_the_continuous_stage_is_off(designs):
    reference, lifting, results = designs
    result = results["lifting"]
    terms = lifting_terms([reference.rig], [result.design.rig.perception()])[0]
    expected = sum(w * terms[TERMS.index(name)] for name, w in WEIGHTS.items())
    prediction = result.design.predictions[0]
    assert prediction.linear_drop == pytest.approx(expected, rel=1e-9)
    assert prediction.predicted_drop == pytest.approx(np.clip(expected, 0, 1), rel=1e-9)
    assert result.refinement.status.startswith("off (test-lifting") and not result.refinement.accepted
