"""``rigopt`` run in-process through the console script's own error handling (:func:`rigopt.cli.run`).

Exit code, stdout and stderr come out as a real process would show them, only without the start-up cost;
the one thing a real process adds, the diversion of C-level output from stdout, is checked in real
processes in tests/cli/test_console_script.py. Test modules import this file as ``in_process`` (the tests
folder is on sys.path through its conftest.py).
"""

from __future__ import annotations

import contextlib
import io
import os
from dataclasses import dataclass

from rigopt.cli import run


@dataclass(frozen=True)
class Outcome:
    """What the command left: ``returncode`` (0 fine, 2 bad input), ``stdout`` and ``stderr`` text."""

    returncode: int
    stdout: str
    stderr: str


def run_rigopt(*args, cwd=None, env: dict[str, str] | None = None) -> Outcome:
    """Run ``rigopt ARGS`` in ``cwd`` (default: here) with ``env`` added to the environment."""
    out, err = io.StringIO(), io.StringIO()
    previous_cwd, previous_env = os.getcwd(), {key: os.environ.get(key) for key in env or {}}
    try:
        os.environ.update(env or {})
        if cwd is not None:
            os.chdir(cwd)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = run([str(a) for a in args])
    finally:
        os.chdir(previous_cwd)
        for key, value in previous_env.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
    return Outcome(code, out.getvalue(), err.getvalue())


def refused(result: Outcome, fragment: str) -> str:
    """The one error line of a refused command: asserts exit 2, nothing on stdout, one ``rigopt: error:`` line on
    stderr holding ``fragment``, and returns that line."""
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and lines[0].startswith("rigopt: error: "), result.stderr
    assert fragment in lines[0], lines[0]
    assert result.stdout == ""
    return lines[0]
