"""rigopt.rig.library: the 14 benchmark rigs by name (case-insensitive) and rigs by path."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from rigopt.errors import RigFileError, RigoptError, UnknownNameError
from rigopt.rig.library import library_rig, load_rig, rig_names
from rigopt.rig.pccr_format import read_rig, write_rig

BENCHMARK_RIGS = Path(os.environ.get("RIGOPT_PCCR_RIGS", Path(__file__).resolve().parents[3] / "shared" / "pccr" / "rigs"))

#: Cameras per rig in the PCCR benchmark's rig files.
BENCHMARK_CAMERA_COUNTS = {
    "R1": 8, "R1-c10": 10, "R1-c6": 6, "R1-f": 8, "R1-r": 8, "R1-t": 8,
    "R2": 6, "R3": 10, "R4": 8, "R5": 4, "R6": 9, "R7": 7, "R8": 6, "R9": 7,
}


@pytest.fixture(autouse=True)
def _empty_working_directory(tmp_path, monkeypatch):
    """Run each test where no file can shadow a library name."""
    monkeypatch.chdir(tmp_path)


def test_library_has_exactly_the_14_benchmark_rigs():
    names = rig_names()
    assert len(names) == 14
    assert set(names) == {"R1", "R1-c10", "R1-c6", "R1-f", "R1-r", "R1-t",
                          "R2", "R3", "R4", "R5", "R6", "R7", "R8", "R9"}


def test_rig_names_put_the_r1_family_first_then_r2_to_r9():
    names = rig_names()
    assert names[0] == "R1"
    assert all(n.startswith("R1-") for n in names[1:6])
    assert names[6:] == [f"R{k}" for k in range(2, 10)]


@pytest.mark.parametrize("name", sorted(BENCHMARK_CAMERA_COUNTS))
def test_library_rig_has_the_benchmark_camera_count(name):
    rig = library_rig(name)
    assert rig.name == name
    assert len(rig) == BENCHMARK_CAMERA_COUNTS[name]


@pytest.mark.skipif(not BENCHMARK_RIGS.is_dir(), reason=f"benchmark rig files not found at {BENCHMARK_RIGS}")
@pytest.mark.parametrize("name", sorted(BENCHMARK_CAMERA_COUNTS))
def test_library_rig_camera_count_and_vehicle_match_the_benchmark_file(name):
    data = json.loads((BENCHMARK_RIGS / f"{name}.json").read_text())
    rig = library_rig(name)
    assert len(rig) == len(data["cameras"])
    assert rig.vehicle == data["vehicle_type"]


@pytest.mark.parametrize("spelling, canonical", [("r1-C10", "R1-c10"), ("r1", "R1"), ("R1-F", "R1-f"),
                                                 ("r9", "R9"), ("R1-c6", "R1-c6")])
def test_lookup_is_case_insensitive(spelling, canonical):
    rig = load_rig(spelling)
    assert rig.name == canonical
    assert rig.same_as(library_rig(canonical))
    assert library_rig(spelling).same_as(rig)


@pytest.mark.parametrize("name", ["R10", "R1-x", "etron", "R 1", ""])
def test_unknown_name_raises_and_lists_the_valid_names(name):
    with pytest.raises(UnknownNameError) as caught:
        load_rig(name) if name else library_rig(name)
    message = str(caught.value)
    assert all(valid in message for valid in rig_names())
    assert isinstance(caught.value, RigoptError) and isinstance(caught.value, LookupError)


def test_load_rig_reads_a_path(tmp_path):
    rig = library_rig("R5")
    path = write_rig(rig, tmp_path / "custom.json")
    for given in (path, str(path)):
        loaded = load_rig(given)
        assert loaded.name == "custom"
        assert loaded.vehicle == rig.vehicle and len(loaded) == len(rig)
        assert all(a.same_as(b, atol=1e-12) for a, b in zip(loaded.cameras, rig.cameras))


def test_load_rig_reads_a_relative_path_without_json_suffix(tmp_path):
    (tmp_path / "myrig").write_text(json.dumps({"vehicle_type": "v", "cameras": [
        {"id": "C", "location": [0, 0, 1], "rotation": [0, 0, 0], "fov": 60}]}))
    assert load_rig("myrig").same_as(read_rig(tmp_path / "myrig"))


def test_load_rig_returns_a_rig_unchanged():
    rig = library_rig("R2")
    assert load_rig(rig) is rig


@pytest.mark.parametrize("path", ["absent.json", "R1.json", "nowhere/else/rig.JSON"])
def test_missing_json_path_raises_rig_file_error(path):
    with pytest.raises(RigFileError) as caught:
        load_rig(path)
    assert Path(path).name in str(caught.value)


def test_a_folder_is_not_a_rig_file(tmp_path):
    (tmp_path / "folder").mkdir()
    with pytest.raises(RigFileError):
        load_rig("folder")


def test_a_folder_named_like_a_library_rig_leaves_the_name_to_the_library(tmp_path):
    # rigopt bench generate --out . makes a folder per rig; the next command naming R1 must still get R1.
    (tmp_path / "R1").mkdir()
    assert Path("R1").is_dir()  # the working directory is tmp_path
    assert load_rig("R1").same_as(library_rig("R1"))
    assert load_rig("r1").same_as(library_rig("R1"))
