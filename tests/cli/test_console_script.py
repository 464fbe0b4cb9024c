"""The installed ``rigopt`` console script in real processes: every ``--json`` command's stdout parses as
JSON (a banner a C library prints, such as HiGHS's "Running HiGHS ...", fails this), and one process per
exit path of bad input (a library error, a usage error, an interrupt-free OS error) prints one line.

The commands start together (a module fixture) and run side by side; the design runs on the small tt with
few candidates. The commands that run a design or write a report folder run with ``-m slow``, and so does
Ctrl-C in the MILP (Ctrl-C while mount candidates are sampled is in the default run). ``bench evaluate --json`` and ``validate --json`` need a trained detector: they are checked
the same way in tests/validation/detectors/test_commands.py.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest
from console import console_script
from marks import cases

REPO = Path(__file__).resolve().parents[2]
SHIPPED_CSV = REPO / "metrics" / "pccr_transfer.csv"
SMALL_DESIGN = ["--vehicle", "tt", "--ref", "R1", "--fov", "120", "--pitch", "0", "--yaw-step", "30"]

#: name -> (arguments, exit codes that are fine); {tmp} is the run's folder.
JSON_COMMANDS = {
    "rigs": (["rigs", "--json"], {0}),
    "rigv": (["rigv", "R1", "R5", "--json"], {0}),
    "rigcd": (["rigcd", "R1", "R5", "--weights", "joint", "--json"], {0}),
    "rank": (["rank", "R5", "R6", "--ref", "R1", "--json"], {0}),
    "check": (["check", "R1", "--json"], {0, 1}),  # exit 1 is an invalid rig, still JSON
    "vehicles": (["vehicles", "--json"], {0}),
}

#: The commands that run a design or write a report folder (7-15 s each): run with -m slow.
WHOLE_COMMANDS = {
    "design": (["design", *SMALL_DESIGN, "--cameras", "6", "--json", "--out", "{tmp}/design"], {0}),
    "calibrate --out": (["calibrate", "--results", str(SHIPPED_CSV), "--bootstrap", "5", "--json", "--out",
                         "{tmp}/calibration"], {0}),
    "coverage --out": (["coverage", "R1", "--json", "--out", "{tmp}/coverage"], {0}),
    "design --pareto": (["design", *SMALL_DESIGN, "--cameras", "6-7", "--pareto", "--json", "--out",
                         "{tmp}/pareto"], {0}),
}


def start(args, tmp: Path) -> subprocess.Popen:
    env = {**os.environ, "RIGOPT_HOME": str(tmp / "home")}  # no user vehicles of the machine
    return subprocess.Popen([str(console_script()), *(a.format(tmp=tmp) for a in args)], cwd=tmp, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint)


def _default_sigint():
    """Ctrl-C's default disposition in the child: a suite started in the background (``pytest &``) passes on
    SIGINT ignored, and Python then installs no KeyboardInterrupt handler."""
    import signal

    signal.signal(signal.SIGINT, signal.default_int_handler)


def run_together(commands, tmp: Path) -> dict:
    """Every case of ``commands`` started together and run to its end: name -> (exit code, stdout, stderr)."""
    processes = {name: start(args, tmp) for name, (args, _) in commands.items()}
    results = {}
    try:
        for name, process in processes.items():
            stdout, stderr = process.communicate(timeout=600)
            results[name] = (process.returncode, stdout, stderr)
    finally:
        for process in processes.values():
            if process.poll() is None:
                process.kill()
                process.communicate()
    return results


@pytest.fixture(scope="module")
def json_runs(tmp_path_factory):
    return run_together(JSON_COMMANDS, tmp_path_factory.mktemp("console_script"))


@pytest.fixture(scope="module")
def whole_runs(tmp_path_factory):
    return run_together(WHOLE_COMMANDS, tmp_path_factory.mktemp("console_script_whole"))


def json_parses(runs, commands, name):
    code, stdout, stderr = runs[name]
    assert code in commands[name][1], stderr
    json.loads(stdout)  # fails on any banner or progress line before or after the JSON


@pytest.mark.parametrize("name", list(JSON_COMMANDS))
def test_json_stdout_parses(json_runs, name):
    json_parses(json_runs, JSON_COMMANDS, name)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(WHOLE_COMMANDS))
def test_json_stdout_of_whole_commands_parses(whole_runs, name):
    json_parses(whole_runs, WHOLE_COMMANDS, name)


@pytest.mark.slow
def test_no_solver_banner_on_either_stream(whole_runs):
    """The design runs HiGHS, which prints a licence banner at the C level on a process's first solver object:
    it reaches neither stream (rigopt.solvers.quiet_highs), and no library log line does either."""
    code, stdout, stderr = whole_runs["design"]
    assert code == 0, stderr
    assert "HiGHS" not in stdout and "HiGHS" not in stderr
    assert "samples!" not in stderr  # trimesh's "only got N/M samples!" log line


@pytest.mark.parametrize("args, fragment", [
    (["rigcd", "R1", "R99"], "R99"),                      # a RigoptError from the library
    (["design", "--vehicle", "tt", "--ref", "R1", "--yaw-step", "abc"], "--yaw-step"),  # a click usage error
    (["desgn"], "design"),                                # an unknown command, with a suggestion
    (["rigs", "--jsn"], "--json"),                        # an unknown option, with the one meant
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, fragment):
    process = start(args, tmp_path)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 2, stderr
    assert "Traceback" not in stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rigopt: error: "), stderr
    assert fragment in lines[0]
    assert stdout == ""


def test_help_goes_to_stdout(tmp_path):
    process = start(["--help"], tmp_path)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 0, stderr
    assert "design" in stdout and "calibrate" in stdout


@pytest.mark.parametrize("after_line", cases(["sampling mount candidates", "MILP:"], slow={"MILP:"}))
def test_ctrl_c_during_a_design_ends_cleanly(tmp_path, after_line):
    """Ctrl-C at two stages of a design (native ray casting; the MILP): exit 130, one 'interrupted' line, no
    traceback or interpreter abort, and no output folder or partial sibling left behind."""
    import signal

    process = start(["design", *SMALL_DESIGN, "--out", "{tmp}/design"], tmp_path)
    seen = []
    for line in process.stderr:  # the progress lines: interrupt once the stage has started
        seen.append(line)
        if after_line in line:
            process.send_signal(signal.SIGINT)
            break
    stdout, rest = process.communicate(timeout=120)
    stderr = "".join(seen) + rest
    assert process.returncode == 130, stderr
    assert "rigopt: interrupted" in stderr
    assert "Traceback" not in stderr and "Fatal Python error" not in stderr
    assert not (tmp_path / "design").exists()
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith(".design")]
