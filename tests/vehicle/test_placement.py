"""Reference points: converting rig origins with a vehicle's axles, comparing rigs in one frame, placing
rigs on vehicles (cameras inside the body refused)."""

import json
from dataclasses import replace

import numpy as np
import pytest

from rigopt.errors import RigoptError
from rigopt.metrics.rigcd import rigcd, rigcd_matrix
from rigopt.rig.library import load_rig
from rigopt.rig.model import Rig, RigOrigin
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.placement import common_frame, comparable_rigs, place_rig, to_vehicle_centre
from tests.in_process import run_rigopt


def shifted(rig: Rig, offset, origin: RigOrigin, vehicle: str | None = None, name: str | None = None) -> Rig:
    """``rig`` with every position minus ``offset``: the same cameras measured from a point at ``offset``."""
    cameras = tuple(replace(c, position=c.position - np.asarray(offset, dtype=float)) for c in rig.cameras)
    return Rig(name or rig.name, vehicle or rig.vehicle, cameras, origin)


@pytest.fixture(scope="module")
def etron():
    return load_vehicle("etron")


def test_rear_axle_is_on_the_ground_below_the_rear_axle_or_the_middle_of_a_tandem():
    assert load_vehicle("etron").rear_axle.tolist() == [-1.43, 0.0, 0.0]
    hgv = load_vehicle("hgv")
    assert hgv.axles == (2.5, -1.85, -3.2)
    assert hgv.rear_axle == pytest.approx([(-1.85 - 3.2) / 2, 0.0, 0.0])


def test_a_rear_axle_rig_converted_to_the_vehicle_centre_is_the_original_rig(etron):
    r1 = load_rig("R1")
    axle = shifted(r1, etron.rear_axle, RigOrigin("rear_axle"))
    back, change = to_vehicle_centre(axle, etron)
    assert back.origin.is_benchmark and np.allclose(back.positions, r1.positions, atol=1e-12)
    assert change.offset.tolist() == etron.rear_axle.tolist()
    assert "rear axle" in change.describe() and "etron" in change.describe()
    assert to_vehicle_centre(r1, etron) == (r1, None)


def test_a_custom_origin_is_a_point_in_the_vehicle_centre_frame(etron):
    r1 = load_rig("R1")
    point = (0.4, -0.1, 1.2)
    custom = shifted(r1, point, RigOrigin("custom", point))
    back, change = to_vehicle_centre(custom, etron)
    assert np.allclose(back.positions, r1.positions, atol=1e-12)
    assert change.as_dict()["offset_m"] == pytest.approx(list(point))


def test_rigcd_refuses_rigs_measured_from_different_origins(etron):
    r1 = load_rig("R1")
    axle = shifted(r1, etron.rear_axle, RigOrigin("rear_axle"))
    with pytest.raises(RigoptError, match="different origins"):
        rigcd(r1, axle)
    with pytest.raises(RigoptError, match="different origins"):
        rigcd_matrix([r1], [r1, axle])
    # the same rig in one frame is at distance 0 whichever frame it is
    assert rigcd(axle, axle).rigcd == pytest.approx(0.0, abs=1e-12)


def test_common_frame_keeps_rigs_that_share_an_origin_and_converts_mixed_ones(etron):
    r1, r5 = load_rig("R1"), load_rig("R5")
    a = shifted(r1, etron.rear_axle, RigOrigin("rear_axle"), name="a")
    b = shifted(r5, etron.rear_axle, RigOrigin("rear_axle"), name="b")
    same, changes = common_frame([a, b])
    assert same == [a, b] and changes == []
    mixed, changes = common_frame([r1, a])
    assert [c.rig for c in changes] == ["a"]
    assert rigcd(*mixed).rigcd == pytest.approx(0.0, abs=1e-12)


def test_a_rig_on_an_unknown_vehicle_needs_a_vehicle_before_mixing_origins(etron):
    r1 = load_rig("R1")
    imported = shifted(r1, etron.rear_axle, RigOrigin("rear_axle"), vehicle="lab_car", name="nusc")
    with pytest.raises(RigoptError, match="--vehicle"):
        common_frame([r1, imported])
    rigs, changes = comparable_rigs([r1, imported], etron)
    assert rigs[1].vehicle == etron.blueprint and len(changes) == 1
    assert rigcd(*rigs).rigcd == pytest.approx(0.0, abs=1e-12)


def test_placing_a_rig_whose_cameras_land_inside_the_body_names_them_and_their_depth(etron):
    r1 = load_rig("R1")
    sunk = Rig("sunk", r1.vehicle, (replace(r1.cameras[0], position=np.array([0.0, 0.0, 0.8])), *r1.cameras[1:]))
    with pytest.raises(RigoptError, match=rf"{r1.cameras[0].id} \(0\.\d\d m deep\)"):
        place_rig(sunk, etron)
    placed, change = place_rig(r1, etron)
    assert change is None and placed.same_as(r1)


@pytest.fixture(scope="module")
def imported_rig(tmp_path_factory):
    """R1 measured from the etron's rear axle, on a vehicle rigopt does not know (as an import gives it)."""
    from rigopt.rig.pccr_format import write_rig

    etron = load_vehicle("etron")
    path = tmp_path_factory.mktemp("rigs") / "nusc.json"
    write_rig(shifted(load_rig("R1"), etron.rear_axle, RigOrigin("rear_axle"), vehicle="lab_car", name="nusc"), path)
    return path


def test_rigcd_command_reports_the_origin_conversion_it_applied(imported_rig):
    refused = run_rigopt("rigcd", "R1", str(imported_rig))
    assert refused.returncode == 2 and "--vehicle" in refused.stderr and "rear axle" in refused.stderr
    outcome = run_rigopt("rigcd", "R1", str(imported_rig), "--vehicle", "etron", "--json")
    assert outcome.returncode == 0, outcome.stderr
    assert ("rigopt: note: nusc: on etron, positions from the rear axle, converted to the vehicle centre (x -1.430 m)"
            in outcome.stderr)
    data = json.loads(outcome.stdout)
    assert data["rigcd"] == pytest.approx(0.0, abs=1e-12)
    assert data["origin_changes"] == [{"rig": "nusc", "vehicle": "etron", "from": "rear_axle", "to": "vehicle_centre",
                                       "offset_m": [-1.43, 0.0, 0.0]}]


def test_coverage_and_design_refuse_a_rig_on_an_unknown_vehicle_before_any_work(imported_rig, tmp_path):
    for args in (("coverage", str(imported_rig)),
                 ("design", "--vehicle", "tt", "--ref", str(imported_rig), "--out", str(tmp_path / "d"))):
        outcome = run_rigopt(*args)
        assert outcome.returncode == 2 and "not a rigopt vehicle" in outcome.stderr
        assert not (tmp_path / "d").exists()


@pytest.mark.slow
def test_vehicle_show_draws_a_rear_axle_rig_where_its_centre_form_is(etron, tmp_path):
    """One placement everywhere: ``vehicle show --rig`` of R1 measured from the rear axle draws the same picture as
    R1 itself (the rear-axle form used to be drawn 1.43 m forward on the etron)."""
    from matplotlib.image import imread

    from rigopt.rig.pccr_format import write_rig

    rear = write_rig(shifted(load_rig("R1"), etron.rear_axle, RigOrigin("rear_axle")), tmp_path / "R1.json")
    pictures = {}
    for label, rig in (("centre", "R1"), ("rear", rear)):
        pictures[label] = tmp_path / f"{label}.png"
        result = run_rigopt("vehicle", "show", "etron", "--rig", rig, "--out", pictures[label])
        assert result.returncode == 0, result.stderr
    assert "rear axle" in result.stderr  # the conversion is said
    np.testing.assert_array_equal(imread(pictures["centre"]), imread(pictures["rear"]))
    far = write_rig(shifted(load_rig("R1"), [1.0, 0.0, 0.0], RigOrigin("vehicle_centre")), tmp_path / "far.json")
    assert run_rigopt("vehicle", "show", "etron", "--rig", far, "--out", tmp_path / "far.png").returncode == 0
    assert not np.array_equal(imread(pictures["centre"]), imread(tmp_path / "far.png"))  # the test can fail
