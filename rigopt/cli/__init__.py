"""rigopt's command line: thin commands over the library. ``main`` is the console script."""

from __future__ import annotations

import sys

from rigopt.cli.app import app
from rigopt.cli import (  # noqa: F401  (importing registers the commands)
    baseline_commands, bench_commands, calibrate_command, coverage_command, design_command, metric_commands,
    rig_commands, vehicle_commands,
)
from rigopt.errors import RigoptError


def main() -> None:
    """Run the CLI; input errors print one line on stderr and exit with code 2."""
    try:
        app()
    except RigoptError as error:
        print(f"rigopt: error: {error}", file=sys.stderr)
        sys.exit(2)
