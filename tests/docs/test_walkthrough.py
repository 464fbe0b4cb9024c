"""docs/your_rig_and_vehicle.md runs as written: every ``$ rigopt ...`` line of its console blocks, in order, from a
folder that holds the checkout's ``examples`` and ``measurements`` (the files the walk-through ships with), and
every output line the page shows is what the command printed (timings and the vehicles folder aside)."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from in_process import run_rigopt

REPO = Path(__file__).resolve().parents[2]
PAGE = REPO / "docs" / "your_rig_and_vehicle.md"


def console_steps(text: str) -> list[tuple[list[str], list[str]]]:
    """(command arguments after ``rigopt``, the output lines shown under it) for each ``$ rigopt`` line."""
    steps = []
    for block in re.findall(r"```console\n(.*?)```", text, flags=re.DOTALL):
        for line in block.splitlines():
            if line.startswith("$ "):
                words = shlex.split(line[2:])
                assert words[0] == "rigopt", line
                steps.append((words[1:], []))
            elif line.strip():
                steps[-1][1].append(line)
    return steps


def normalised(text: str, home: Path) -> str:
    """Timings as 'N s' and the vehicles folder as the page's ~/.rigopt."""
    return re.sub(r"\(\d+(\.\d+)? s\)", "(N s)", text.replace(str(home), "~/.rigopt"))


@pytest.mark.slow
def test_the_walkthrough_runs_as_written(tmp_path):
    steps = console_steps(PAGE.read_text())
    assert len(steps) >= 8
    for shipped in ("examples", "measurements"):
        (tmp_path / shipped).symlink_to(REPO / shipped)
    home = tmp_path / "home"
    for args, shown in steps:
        result = run_rigopt(*args, cwd=tmp_path, env={"RIGOPT_HOME": str(home)})
        said = normalised(result.stdout + result.stderr, home).splitlines()
        expected = 2 if any(s.startswith("rigopt: error:") for s in shown) else (0, 1) if args[0] == "check" else 0
        assert result.returncode in (expected if isinstance(expected, tuple) else (expected,)), (args, result.stderr)
        for line in shown:
            assert normalised(line, home) in said, (args, line, said)
