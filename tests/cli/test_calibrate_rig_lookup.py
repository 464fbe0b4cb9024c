"""`rigopt calibrate --rigs DIR` finds a rig file in DIR or below it, the shallowest of equal names first, and
falls back to the library."""

from __future__ import annotations

import json

from rigopt.cli.calibrate_command import _rig_lookup
from rigopt.rig.library import load_rig
from rigopt.rig.pccr_format import write_rig


def test_rigs_are_found_below_the_folder_shallowest_first(tmp_path):
    r5 = load_rig("R5")
    (tmp_path / "deep" / "deeper").mkdir(parents=True)
    write_rig(load_rig("R1-c6"), tmp_path / "deep" / "deeper" / "mine.json")
    write_rig(r5, tmp_path / "deep" / "mine.json")
    (tmp_path / "deep" / "notes.json").write_text(json.dumps({"not": "a rig"}))
    lookup = _rig_lookup(tmp_path)
    assert len(lookup("mine")) == len(r5)  # the shallower file (R5, 4 cameras) over the deeper one (6)
    assert lookup("R2").name == "R2" and len(lookup("R2")) == len(load_rig("R2"))  # not in the folder: the library
