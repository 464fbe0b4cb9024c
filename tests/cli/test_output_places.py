"""Places given to the commands (input files and folders, --out): a folder where a file is expected, or a file
where a folder is, is named as such ("X is a folder; give the ... file itself", "X is a file; give the folder
holding ..."), a missing one as missing; never "no such file" for something that exists, never a missing trained
model for a missing --data folder. One ``rigopt: error:`` line, exit 2, nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest

from in_process import run_rigopt

R1_FILE = next((Path(__file__).resolve().parents[2] / "vehicles").glob("*/rigs/R1.json"))


@pytest.fixture
def places(tmp_path):
    """{tmp}/d and {tmp}/d.json, .urdf, .yaml: folders; {tmp}/f.txt: a file."""
    for name in ("d", "d.json", "d.urdf", "d.yaml"):
        (tmp_path / name).mkdir()
    (tmp_path / "f.txt").write_text("a file\n")
    return tmp_path


FOLDER_FOR_FILE = [
    (["rigv", "{tmp}/d.json"], "{tmp}/d.json is a folder; give the rig file itself"),
    (["rigv", "{tmp}/d"], "{tmp}/d is a folder; give the rig file itself"),
    (["import", "urdf", "{tmp}/d", "--out", "{tmp}/r.json"], "{tmp}/d is a folder; give the URDF file itself"),
    (["import", "opencv", "{tmp}/d", "--out", "{tmp}/r.json"],
     "{tmp}/d is a folder; give the Kalibr camchain YAML file itself"),
    (["import", "carla", "{tmp}/d", "--out", "{tmp}/r.json"], "{tmp}/d is a folder; give the CARLA camera list file"),
    (["export", "R1", "--format", "urdf", "--out", "{tmp}/d.urdf"],
     "--out {tmp}/d.urdf is a folder; give the name of the file to write, e.g. {tmp}/d.urdf/NAME.urdf"),
    (["validate", "{tmp}/d", "--ref", "R1", "--model", "lss", "--data", "{tmp}/d"],
     "{tmp}/d is a folder; give the design file"),
    (["bench", "evaluate", "--data", "{tmp}/d", "--rig", "R1", "--model", "lss", "--checkpoint", "{tmp}/d"],
     "--checkpoint {tmp}/d is a folder; give the checkpoint file"),
]

FILE_FOR_FOLDER = [
    (["import", "nuscenes", "{tmp}/f.txt", "--out", "{tmp}/r.json"],
     "{tmp}/f.txt is a file; give the folder holding the nuScenes tables"),
    (["import", "argoverse2", "{tmp}/f.txt", "--out", "{tmp}/r.json"],
     "{tmp}/f.txt is a file; give the folder holding egovehicle_SE3_sensor.feather"),
    (["export", "R1", "--format", "nuscenes", "--out", "{tmp}/f.txt"],
     "--out {tmp}/f.txt is a file; give the name of a folder to write"),
    (["bench", "show", "{tmp}/f.txt", "--rig", "R1", "--out", "{tmp}/s.png"],
     "{tmp}/f.txt is a file; give the folder holding the benchmark's rig folders"),
    (["bench", "train", "--data", "{tmp}/f.txt", "--rig", "R1", "--model", "lss"],
     "--data {tmp}/f.txt is a file; give the folder holding the benchmark's rig folders"),
    (["calibrate", "--results", "{repo}/metrics/pccr_transfer.csv", "--rigs", "{tmp}/f.txt"],
     "--rigs {tmp}/f.txt is a file; give the folder holding the rig files"),
]

MISSING_DATA = [
    ["bench", "train", "--data", "{tmp}/none", "--rig", "R1", "--model", "lss"],
    ["bench", "evaluate", "--data", "{tmp}/none", "--rig", "R1", "--model", "lss"],
    ["bench", "matrix", "--data", "{tmp}/none", "--rigs", "R1", "--model", "lss", "--out", "{tmp}/m"],
    ["validate", str(R1_FILE), "--ref", "R1", "--model", "lss", "--data", "{tmp}/none"],
]


def run(args, tmp_path):
    repo = Path(__file__).resolve().parents[2]
    before = sorted(p.name for p in tmp_path.iterdir())
    result = run_rigopt(*(a.format(tmp=tmp_path, repo=repo) for a in args))
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and lines[0].startswith("rigopt: error: "), result.stderr
    assert result.stdout == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written
    return lines[0].replace(str(tmp_path), "{tmp}")


@pytest.mark.parametrize("args, message", FOLDER_FOR_FILE)
def test_a_folder_for_a_file_is_named_as_such(places, args, message):
    line = run(args, places)
    assert message in line and "no such" not in line


@pytest.mark.parametrize("args, message", FILE_FOR_FOLDER)
def test_a_file_for_a_folder_is_named_as_such(places, args, message):
    line = run(args, places)
    assert message in line and "no such" not in line


@pytest.mark.parametrize("args", MISSING_DATA)
def test_a_missing_data_folder_is_said_as_such(places, args):
    line = run(args, places)
    assert "--data {tmp}/none: no such folder; give the folder holding the benchmark's rig folders" in line
    assert "trained" not in line and "checkpoint" not in line
