"""`rigopt calibrate --rigs DIR` finds a rig file in DIR or below it, the shallowest of equal names first, and
falls back to the library; a rig measured from its rear axle (an imported dataset rig) is moved to its
vehicle's centre, the frame the synthetic benchmark renders it in, with a note."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from console import run_console

from rigopt.rig.library import load_rig
from rigopt.rig.pccr_format import write_rig
from rigopt.vehicle.placement import benchmark_rig_lookup

REAL_RIGS = Path(__file__).resolve().parents[2] / "measurements" / "rigs"


def test_rigs_are_found_below_the_folder_shallowest_first(tmp_path):
    r5 = load_rig("R5")
    (tmp_path / "deep" / "deeper").mkdir(parents=True)
    write_rig(load_rig("R1-c6"), tmp_path / "deep" / "deeper" / "mine.json")
    write_rig(r5, tmp_path / "deep" / "mine.json")
    (tmp_path / "deep" / "notes.json").write_text(json.dumps({"not": "a rig"}))
    lookup = benchmark_rig_lookup(tmp_path)
    assert len(lookup("mine")) == len(r5)  # the shallower file (R5, 4 cameras) over the deeper one (6)
    assert lookup("R2").name == "R2" and len(lookup("R2")) == len(load_rig("R2"))  # not in the folder: the library


def test_a_rear_axle_rig_is_moved_to_the_vehicle_centre_once(tmp_path):
    notes = []
    lookup = benchmark_rig_lookup(REAL_RIGS, notes.append)
    axle = load_rig(REAL_RIGS / "real" / "nuscenes.json")
    centred = lookup("nuscenes")
    assert centred.origin.is_benchmark and not axle.origin.is_benchmark
    shift = np.array([c.position for c in centred.cameras]) - np.array([c.position for c in axle.cameras])
    np.testing.assert_allclose(shift[:, 1:], 0.0, atol=1e-12)  # moved along x only
    assert np.ptp(shift[:, 0]) < 1e-12 and shift[0, 0] < 0  # the axle lies behind the centre
    assert lookup("nuscenes") is centred and len(notes) == 1 and "rear axle" in notes[0]


@pytest.mark.slow
def test_calibrate_on_results_with_a_dataset_rig(tmp_path):
    """Synthetic results naming R1, its variants and nuScenes' rig: calibrate reads nuScenes' rig from --rigs,
    converts it with a note on stderr, and prints JSON only on stdout."""
    rigs = ["R1", "R1-r", "R1-t", "R1-f", "R1-c6", "R1-c10", "nuscenes"]
    rng = np.random.default_rng(0)
    (tmp_path / "lss").mkdir()
    for a in rigs:
        results = {b: {"metrics": {"mAP": 0.3 if a == b else float(0.3 * rng.uniform(0.2, 0.9))}} for b in rigs}
        (tmp_path / "lss" / f"trained_on_{a}.json").write_text(json.dumps({"model": "lss", "trained_on": a,
                                                                          "results": results}))
    done = run_console("calibrate", "--results", tmp_path, "--rigs", REAL_RIGS, "--bootstrap", "0", "--json")
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert list(report["models"]) == ["lss"] and report["joint"]
    assert "rigopt: note: nuscenes: positions converted from the rear axle" in done.stderr
