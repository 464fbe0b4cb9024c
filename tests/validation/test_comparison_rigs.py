"""The yardsticks a measured rig is compared with (rigopt.validation.designs.comparison_rigs)."""

from __future__ import annotations

from rigopt.rig.library import load_rig
from rigopt.validation.designs import comparison_rigs


def test_a_rig_on_the_references_own_vehicle_is_not_compared_with_itself_nor_the_reference():
    """R2 sits on R1's vehicle: the hand-designed rigs of that vehicle are compared, but not R2 again nor R1, so the
    rigs to measure have distinct names (validate --data refused every such rig before)."""
    rigs = comparison_rigs(load_rig("R2"), load_rig("R1"))
    names = [rig.name for _, rig in rigs]
    assert len(set(names)) == len(names) and "R1" not in names and names.count("R2") == 1
    hand = {rig.name for role, rig in rigs if role == "hand-designed"}
    assert {"R3", "R7", "R1-f"} <= hand
    assert [role for role, _ in rigs][-2:] == ["naive transfer", "height-matched transfer"]


def test_a_reference_measured_from_its_rear_axle_is_compared_and_predicted_from_its_vehicles_centre():
    """nuScenes' rig as imported (origin: the rear axle) against a rig on its vehicle measured from the centre: the
    copies are made and the drops predicted (they failed on the mixed origins), and the prediction is the one from
    the reference moved to its vehicle's centre."""
    from pathlib import Path

    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.ranking import predict_transfer
    from rigopt.mounting.candidates import rig_body_share
    from rigopt.validation.designs import predicted_transfers
    from rigopt.vehicle.placement import in_vehicle_frame

    reference = load_rig(Path(__file__).resolve().parents[2] / "measurements" / "rigs" / "real" / "nuscenes.json")
    assert reference.origin.kind == "rear_axle"
    rigs = comparison_rigs(load_rig("R4"), reference)
    assert [role for role, _ in rigs][-2:] == ["naive transfer", "height-matched transfer"]
    assert all(rig.origin.is_benchmark for _, rig in rigs)
    calibration = load_weights("joint")
    predicted = predicted_transfers(reference, [rig for _, rig in rigs], calibration)
    moved = predict_transfer(in_vehicle_frame(reference)[0], [rig for _, rig in rigs], calibration, None, rig_body_share)
    assert [p.predicted_drop for p in predicted] == [p.predicted_drop for p in moved]
