"""A study's progress log: each message printed and appended to the log file with the time, a rerun adding to it."""

from __future__ import annotations

import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))  # the studies' shared code
from studylib.logs import timestamped_log  # noqa: E402


def test_each_message_is_printed_and_appended_with_its_time(tmp_path, capsys):
    path = tmp_path / "study.log"
    for message in ("first run", "second run"):
        with timestamped_log(path) as progress:
            progress(message)
            assert path.read_text().endswith(f" {message}\n")  # flushed at once, before the block ends
    lines = path.read_text().splitlines()
    assert [line[9:] for line in lines] == ["first run", "second run"]
    assert all(re.fullmatch(r"\d\d:\d\d:\d\d", line[:8]) for line in lines)
    assert capsys.readouterr().out.splitlines() == lines


def test_a_log_in_a_folder_not_made_yet_makes_it(tmp_path, capsys):
    path = tmp_path / "results" / "new" / "study.log"
    with timestamped_log(path) as progress:
        progress("started")
    assert path.read_text().endswith(" started\n")
