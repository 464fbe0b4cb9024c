"""Worker processes end with the command that started them: Ctrl-C and SIGTERM end a pool at once (no wait for a
running job), a worker whose parent is killed ends too, and the console script says how it was stopped."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest


#: A main process that runs two 120 s jobs in a pool (each leaves a file when it starts), then waits.
SLEEPERS = """
import sys, time
from pathlib import Path
from rigopt.validation.synthetic.cluster import process_tasks
def nap(marker):
    Path(marker).touch()
    time.sleep(120)
if __name__ == "__main__":
    folder = sys.argv[1]
    try:
        for _ in process_tasks(2, nap, {k: (f"{folder}/job{k}",) for k in range(2)}):
            pass
    except KeyboardInterrupt:
        print("main: interrupted", file=sys.stderr, flush=True)
        sys.exit(130)
"""


def pool_workers(pid: int) -> list[int]:
    """The pool's worker processes of ``pid`` (its spawned children, not multiprocessing's resource tracker)."""
    found = subprocess.run(["ps", "-ww", "-o", "pid=,args=", "--ppid", str(pid)], capture_output=True, text=True).stdout
    return [int(line.split()[0]) for line in found.splitlines() if "--multiprocessing-fork" in line]


def alive(pid: int) -> bool:
    """Running (a zombie waiting to be reaped does not count)."""
    state = subprocess.run(["ps", "-o", "stat=", "-p", str(pid)], capture_output=True, text=True).stdout.strip()
    return bool(state) and not state.startswith("Z")


def gone(pids: list[int], within: float = 30.0) -> bool:
    deadline = time.monotonic() + within
    while any(map(alive, pids)) and time.monotonic() < deadline:
        time.sleep(0.2)
    return not any(map(alive, pids))


def start_sleepers(tmp_path: Path) -> tuple[subprocess.Popen, list[int]]:
    script = tmp_path / "sleepers.py"
    script.write_text(SLEEPERS)
    process = subprocess.Popen([sys.executable, str(script), str(tmp_path)], stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not all((tmp_path / f"job{k}").exists() for k in range(2)) and time.monotonic() < deadline:
        time.sleep(0.2)
    workers = pool_workers(process.pid)
    assert len(workers) == 2 and all(map(alive, workers))
    return process, workers


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ps --ppid and prctl are Linux's")
def test_an_interrupt_ends_the_pool_without_waiting_for_its_jobs(tmp_path):
    process, workers = start_sleepers(tmp_path)
    process.send_signal(signal.SIGINT)  # the console script turns SIGTERM into this interrupt too
    process.wait(timeout=60)  # the jobs sleep 120 s: a pool that waited for them would time out here
    assert process.returncode == 130 and "main: interrupted" in process.stderr.read()
    assert gone(workers)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="prctl's parent-death signal is Linux's")
def test_workers_end_when_their_parent_is_killed(tmp_path):
    process, workers = start_sleepers(tmp_path)
    process.kill()
    process.wait(timeout=30)
    assert gone(workers)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="signals as on Linux")
def test_sigterm_stops_a_design_with_one_line_and_no_output(tmp_path):
    from console import console_script

    out = tmp_path / "design"
    process = subprocess.Popen([str(console_script()), "design", "--vehicle", "tt", "--ref", "R1", "--out", str(out)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(4)
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 143
    assert stderr.strip().splitlines()[-1] == "rigopt: terminated" and "Traceback" not in stderr
    assert not out.exists()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="signals as on Linux")
def test_an_interrupted_render_says_how_to_resume_and_the_rerun_skips_what_was_finished(tmp_path):
    """SIGTERM once the first of 12 scenes is finished: the stop line says to rerun the same command, and the rerun
    keeps the finished scenes untouched (and says so) and renders the rest."""
    from console import console_script

    out = tmp_path / "bench"
    parts = out / "R1" / "mini" / ".parts"
    command = [str(console_script()), "bench", "generate", "--rigs", "R1", "--split", "mini", "--scenes", "12",
               "--frames", "2", "--size", "64x36", "--out", str(out)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not list(parts.glob("*.json")) and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.05)
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 143, stderr
    last = stderr.strip().splitlines()[-1]
    assert last.startswith("rigopt: terminated; to resume, rerun the same command") and str(out) in last
    finished = {p.name: p.stat().st_mtime_ns for p in parts.glob("*.json")}
    assert 1 <= len(finished) < 12
    rerun = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    assert f"resumed: {len(finished)} of the 12 (rig, scene) pairs were rendered before and kept" in rerun.stderr
    assert len(list(parts.glob("*.json"))) == 12
    assert all((parts / name).stat().st_mtime_ns == mtime for name, mtime in finished.items())
