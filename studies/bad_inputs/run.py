"""Run every bad input of cases.py through the installed ``rigopt`` console script and write docs/errors.md.

Each error case must exit 2 with exactly one ``rigopt: error: ...`` line on stderr, no traceback and nothing on
stdout; each warning case (cases.WARNINGS) must exit 0 with exactly one ``rigopt: warning: ...`` line on stderr
and no traceback. The script stops with a list of the cases that do not. Usage: ``python
studies/bad_inputs/run.py``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))

from cases import CASES, WARNINGS, make_fixtures, one_error_line  # noqa: E402

DOC = REPO / "docs" / "errors.md"
INTRO = """# Errors: every bad input, its message

Every input rigopt cannot use ends in one line on stderr, `rigopt: error: ...`, and exit code 2: it names
the file or option and says how to fix it. Never a traceback. An error found after some work (a design with no
feasible point) follows the command's indented progress lines; the table shows the error line. Usage errors (unknown commands or options, values
of the wrong type or out of range) are found while the command line is parsed, and `--out` before any work.

Outputs are written whole or not at all (`rigopt/output.py`): a folder is built in a hidden temporary sibling
and renamed into place when complete; a file is written beside its target and renamed over it. A failure or
Ctrl-C (exit 130, `rigopt: interrupted`) or SIGTERM (exit 143, `rigopt: terminated`) leaves nothing, or the
previous complete output, and ends the command's worker processes at once (a worker whose command is killed
ends too). Where the command can resume, the line says how (`rigopt: interrupted; to resume, rerun the same
command: the renderings finished so far are kept in CACHE` for `validate`; `bench generate`, `bench train` and
`bench matrix` likewise), and the rerun says what it kept. An existing non-empty
output folder is refused unless `--force`, which replaces it whole. `bench generate` and `bench matrix` are
resumable instead: their `--out` may exist and is added to; each image is written whole, a scene counts once its
part file exists, and the split's tables are replaced whole, so they only ever describe complete scenes.

A full disk (ENOSPC) while writing gives `rigopt: error: --out OUT: cannot write the output (no space left on
the device; free some space or write elsewhere); nothing was changed there` (tested by injecting the error into
the writers: tests/test_output.py, tests/cli/test_atomic_outputs.py).

## Places: files, folders, partial outputs

Every path a command reads is checked for what it must be (`rigopt.output.existing_file` / `existing_folder`,
used by the rig file and format readers, `calibrate --results/--test-on/--rigs`, `--data`, `--runs`,
`--checkpoint`, `validate`'s design, `bench show`): a folder given for a file says `X is a folder; give the ...
file itself`, a file given for a folder `X is a file; give the folder holding ...`, and only a missing place
says `no such ...`. A missing `--data` folder is said as such, not as a missing trained model. `calibrate
--rigs` takes several folders (the first holding `<rig>.json`, in it or below it, wins); a rig the results name
that is in none of them nor in the library is refused before any work, naming `--rigs` as the fix (`--rigs
measurements/rigs` finds the real datasets' rigs in `measurements/rigs/real/`). Image sizes (`--image-size`,
`bench generate --size`) are whole pixels, 16 to 20000 a side (a rendering size for tests from 1), through one parser (`rigopt/cli/parsing.py`).

A run killed outright (SIGKILL, power loss) cannot remove its temporary sibling `.NAME.partial-PID`: the next
atomic write of the same target removes every such sibling whose process id no longer runs (`os.kill(pid, 0)`
finds no process), and puts back a previous output that was set aside (`.NAME.partial-PID.old`) when the
target itself is missing. A partial of a running process is left alone.

## Answered in the output, not by an error

Some inputs are right but were easy to misread; the command now says what they mean where it answers:

- A design's camera names say where a camera is mounted and where it looks (`CAM_FENDER_FRONT_LEFT_TO_BACK_LEFT`),
  not which reference camera it replaces: `rigopt design` prints each perception camera beside the reference
  camera it was designed for, with its height, pitch, yaw and FOV against that camera's and how far apart the
  lenses are (report.json `stands_in_for`), and notes where RigCD's own matching of the final rig pairs a camera
  otherwise (the fire truck from R1: two cameras, `CAM_FENDER_FRONT_LEFT_TO_BACK_LEFT` designed for
  `CAM_FENDER_BACK_LEFT`, matched by RigCD to `CAM_SIDE_LEFT`); the pose kept near the reference is height, pitch,
  yaw and lens, not place (README).
- A mesh's unit: `vehicle add` hints a scale with the length it gives (`which looks like centimetres (4.18 m
  long): add --scale 0.01`) and, where another unit is plausible too, that one with its length, so a hint can be
  checked against the real vehicle before it is taken.
- `validate --data` of a rig on the reference's own vehicle is measured (it was refused as "rig names must
  differ"): the measured rig and the reference are not compared again as hand-designed rigs.
- A rig exported to nuScenes is written from the rear axle, as nuScenes' readers assume; rigopt's nuScenes reader
  takes the rear axle as the file's origin itself (docs/formats.md, "Origins on export"), so reading it back needs
  no `--origin`.
- `rank` and `rigcd` flag a candidate that sees little of what the reference sees (the second table below).

## The catalogue

The table is written by `studies/bad_inputs/run.py`, which runs each case through the installed console script
(`{tmp}` is a scratch folder with the files named, `{repo}` the checkout); tests/cli/test_bad_inputs.py runs
each in-process and checks that the message here is the one rigopt prints.

| class | command | message |
|---|---|---|
"""


WARNINGS_INTRO = """
## Warnings: inputs rigopt takes but flags

Some inputs are valid yet make a number unreliable: the command does its work and exits 0, and says so in one
`rigopt: warning: ...` line on stderr per input (with `--json`, stdout stays JSON and carries the same fact). A
candidate rig whose cameras see less than a quarter of what the reference's see (`rank`, `rigcd`: the view
overlap, docs/metrics.md) is marked `LOW` in the table, and its predicted drop is not to be read as good.
`studies/bad_inputs/run.py` runs these through the installed console script too; tests/cli/test_bad_inputs.py
checks that the line here is the one rigopt prints.

| class | command | warning |
|---|---|---|
"""


def run_case(args: list[str], tmp: Path, env: dict[str, str]) -> subprocess.CompletedProcess:
    script = Path(sys.executable).parent / "rigopt"
    command = [str(script if script.is_file() else shutil.which("rigopt"))]
    filled = [a.format(tmp=tmp, repo=REPO) for a in args]
    return subprocess.run(command + filled, capture_output=True, text=True, cwd=tmp, env={**os.environ, **env},
                          timeout=300)


def normalised(text: str, tmp: Path) -> str:
    return text.replace(str(tmp), "{tmp}").replace(str(REPO), "{repo}")


def main() -> None:
    tmp = Path(tempfile.mkdtemp(prefix="rigopt-bad-inputs-")).resolve()
    try:
        env = make_fixtures(tmp)
        with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
            results = list(pool.map(lambda case: run_case(case[1], tmp, env), CASES + WARNINGS))
        rows, warning_rows, failures = [], [], []
        for k, ((name, args, fragment), result) in enumerate(zip(CASES + WARNINGS, results)):
            lines = [line for line in result.stderr.splitlines() if line.strip()]
            if k < len(CASES):
                line = normalised(lines[-1] if lines else "", tmp)
                ok = (result.returncode == 2 and one_error_line(lines) and line.startswith("rigopt: error: ")
                      and fragment in line and not result.stdout)
            else:
                warned = [normalised(w, tmp) for w in lines if w.startswith("rigopt: warning: ")]
                line = warned[0] if warned else ""
                ok = result.returncode == 0 and len(warned) == 1 and fragment in line
            if not ok or "Traceback" in result.stderr:
                failures.append(f"{name}: exit {result.returncode}, stdout {result.stdout[:80]!r}, stderr "
                                f"{normalised(result.stderr, tmp)[-400:]!r}")
            shown = " ".join(a if a and a.isprintable() and " " not in a else repr(a) for a in args)
            row = f"| {name} | `rigopt {shown}` | `{line.replace('|', '/')}` |"
            (rows if k < len(CASES) else warning_rows).append(row)
        DOC.write_text(INTRO + "\n".join(rows) + "\n" + WARNINGS_INTRO + "\n".join(warning_rows) + "\n")
        total = len(CASES) + len(WARNINGS)
        print(f"{total} cases, {total - len(failures)} as they should be; wrote {DOC}")
        if failures:
            print("\n".join(failures))
            sys.exit(1)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
