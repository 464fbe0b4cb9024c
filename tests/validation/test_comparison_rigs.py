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
