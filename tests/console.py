"""The installed ``rigopt`` console script run in a real process, as a user's shell runs it.

The script is the one installed beside the Python running the tests (a virtual environment's ``bin/``), never
whatever ``rigopt`` comes first on PATH: that could be another installation's. Test modules import this file as
``console`` (the tests folder is on sys.path through its conftest.py).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest


def console_script() -> Path:
    """The ``rigopt`` script beside the running interpreter; the test fails when it is not installed."""
    script = Path(sys.executable).parent / ("rigopt.exe" if os.name == "nt" else "rigopt")
    if not script.is_file():
        pytest.fail(f"the rigopt console script is not installed beside {sys.executable}; pip install -e . first")
    return script


def run_console(*args, timeout: float = 300, **options) -> subprocess.CompletedProcess:
    """``rigopt ARGS`` in a real process: its exit code, stdout and stderr as text (``options`` go to
    subprocess.run, e.g. ``env`` or ``cwd``)."""
    return subprocess.run([str(console_script()), *map(str, args)], capture_output=True, text=True, timeout=timeout,
                          **options)
