"""Study tables: a CSV written by write_csv reads back with its numbers as numbers."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))  # the studies' shared code
from studylib.tables import markdown, read_csv, write_csv, write_rig_index  # noqa: E402


def test_csv_round_trip_keeps_text_and_numbers_to_six_significant_digits(tmp_path):
    path = tmp_path / "table.csv"
    written = write_csv(path, ["family", "pairs", "rho"], [["lss", 72, 0.8662954321], ["petr", 72, -0.5]])
    assert read_csv(path) == [["family", "pairs", "rho"], ["lss", 72, 0.866295], ["petr", 72, -0.5]]
    assert markdown(read_csv(path)) == markdown(written)


def test_a_rig_index_is_written_with_its_columns_and_a_repeated_name_refused(tmp_path):
    import csv

    import pytest

    rows = [{"rig": "a", "vehicle": "tt"}, {"rig": "b", "vehicle": "hgv"}]
    write_rig_index(tmp_path / "index.csv", ["rig", "vehicle", "kind"], rows)
    with open(tmp_path / "index.csv", newline="") as handle:
        assert list(csv.DictReader(handle)) == [{"rig": "a", "vehicle": "tt", "kind": ""},
                                                {"rig": "b", "vehicle": "hgv", "kind": ""}]
    with pytest.raises(SystemExit, match="repeat: \\['a'\\]"):
        write_rig_index(tmp_path / "again.csv", ["rig"], [{"rig": "a"}, {"rig": "a"}])
