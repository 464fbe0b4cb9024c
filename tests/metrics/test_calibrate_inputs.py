"""`rigopt calibrate`'s places: --rigs must be folders (several may be given, the first holding a rig wins), a
rig the results name that rigopt does not know is said as such with --rigs as the fix, and --results / --test-on
must be a results folder or a CSV file. Every refusal comes before any work: nothing is written."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from in_process import refused, run_rigopt
from rigopt.errors import RigoptError, UnknownNameError
from rigopt.metrics.transfer import read_transfer
from rigopt.rig.library import load_rig
from rigopt.rig.pccr_format import write_rig
from rigopt.vehicle.placement import benchmark_rig_lookup

REPO = Path(__file__).resolve().parents[2]
BASELINE_RIGS = REPO / "measurements" / "rigs"
RIGS = ["R1", "R1-r", "R1-t", "R1-f", "R1-c6", "R1-c10", "nuscenes"]


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """A results folder (one detector) over R1, its variants and nuScenes' rig, which is no library rig."""
    root = tmp_path_factory.mktemp("results")
    rng = np.random.default_rng(0)
    (root / "lss").mkdir()
    for a in RIGS:
        maps = {b: {"metrics": {"mAP": 0.3 if a == b else float(0.3 * rng.uniform(0.2, 0.9))}} for b in RIGS}
        (root / "lss" / f"trained_on_{a}.json").write_text(json.dumps({"model": "lss", "trained_on": a,
                                                                        "results": maps}))
    return root


def test_a_rig_the_library_lacks_names_rigs_as_the_fix(results, tmp_path):
    line = refused(run_rigopt("calibrate", "--results", results, "--bootstrap", "0", "--out", tmp_path / "c"),
                   "the results name rig 'nuscenes', which rigopt does not know")
    assert "give --rigs FOLDER, the folder of the rig files the results were measured with (nuscenes.json" in line
    assert not (tmp_path / "c").exists()


def test_a_rig_missing_from_the_rigs_folders_names_them(results, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    line = refused(run_rigopt("calibrate", "--results", results, "--rigs", empty, "--bootstrap", "0"),
                   f"there is no nuscenes.json in or below --rigs {empty}")
    assert "add --rigs with the folder holding nuscenes.json" in line


@pytest.mark.parametrize("make, fragment", [
    (lambda tmp: tmp / "none", "no such folder; give the folder holding the rig files"),
    (lambda tmp: write_rig(load_rig("R5"), tmp / "nuscenes.json"), "is a file; give the folder holding the rig files"),
])
def test_rigs_must_be_an_existing_folder(results, tmp_path, make, fragment):
    place = make(tmp_path)
    line = refused(run_rigopt("calibrate", "--results", results, "--rigs", place, "--out", tmp_path / "c"), fragment)
    assert line.startswith(f"rigopt: error: --rigs {place}")
    assert not (tmp_path / "c").exists()


def test_the_real_rigs_are_found_below_baselines_rigs():
    """``--rigs measurements/rigs`` finds the real datasets' rigs in its real/ subfolder: every rig of the committed
    transfer matrix resolves."""
    table = read_transfer(REPO / "measurements" / "transfer")
    lookup = benchmark_rig_lookup(BASELINE_RIGS)
    names = set(table.train.tolist() + table.test.tolist())
    assert {"argoverse2", "nuscenes", "waymo", "ddad"} <= names
    assert all(len(lookup(name)) > 0 for name in names)
    with pytest.raises(UnknownNameError, match="argoverse2"):
        benchmark_rig_lookup()("argoverse2")


def test_several_rigs_folders_the_first_holding_a_rig_wins(tmp_path):
    first, second = tmp_path / "first", tmp_path / "second"
    write_rig(load_rig("R5"), first / "deep" / "mine.json")
    write_rig(load_rig("R1-c10"), second / "mine.json")  # shallower, but in the later folder
    write_rig(load_rig("R2"), second / "other.json")
    lookup = benchmark_rig_lookup([first, second])
    assert len(lookup("mine")) == len(load_rig("R5"))
    assert len(lookup("other")) == len(load_rig("R2"))


def test_calibrate_takes_several_rigs_folders(results, tmp_path):
    decoy = tmp_path / "decoy"
    decoy.mkdir()
    done = run_rigopt("calibrate", "--results", results, "--rigs", decoy, "--rigs", BASELINE_RIGS, "--bootstrap",
                      "0", "--json")
    assert done.returncode == 0, done.stderr
    assert list(json.loads(done.stdout)["models"]) == ["lss"]


@pytest.mark.parametrize("option", ["--results", "--test-on"])
def test_results_must_be_a_results_folder_or_a_csv(results, tmp_path, option):
    def calibrate(place):
        shipped = ["--results", REPO / "metrics" / "pccr_transfer.csv"] if option == "--test-on" else []
        return run_rigopt("calibrate", *shipped, option, place, "--out", tmp_path / "c")

    one_model = results / "lss" / "trained_on_R1.json"
    refused(calibrate(one_model), f"{option} {one_model} is a JSON file, one model's results; give the folder "
                                  "holding <model>/trained_on_<rig>.json")
    refused(calibrate(tmp_path / "none"), f"{option} {tmp_path / 'none'}: no such results folder or CSV file")
    assert not (tmp_path / "c").exists()


def test_the_lookup_refuses_a_missing_folder_itself(tmp_path):
    with pytest.raises(RigoptError, match="--rigs .*none: no such folder"):
        benchmark_rig_lookup(tmp_path / "none")
