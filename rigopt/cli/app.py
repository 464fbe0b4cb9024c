"""The ``rigopt`` command-line application object and the output helpers its commands share."""

from __future__ import annotations

import json

import typer
from rich.console import Console
from rich.table import Table

from rigopt.report.json_values import json_ready

app = typer.Typer(
    name="rigopt",
    help="Design automotive camera rigs that transfer: rig metrics, calibration, ranking.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
import_app = typer.Typer(help="Convert rigs from other formats into rigopt's (the benchmark's) JSON.", no_args_is_help=True)
app.add_typer(import_app, name="import")
vehicle_app = typer.Typer(help="Vehicles: show, export and add your own.", no_args_is_help=True)
app.add_typer(vehicle_app, name="vehicle")

console = Console()
if not console.is_terminal:
    console.width = 160  # piped or captured output: wide enough for every table


def print_json(data) -> None:
    """Print ``data`` as JSON on stdout; NaN and inf become null."""
    print(json.dumps(json_ready(data), indent=2))


def print_table(title: str, columns: list[str], rows: list[list]) -> None:
    """Print a rich table; numbers are right-aligned with 3 decimals, text left-aligned."""
    table = Table(title=title)
    first = rows[0] if rows else [None] * len(columns)
    for column, sample in zip(columns, first):
        table.add_column(column, justify="right" if isinstance(sample, (int, float)) else "left")
    for row in rows:
        table.add_row(*(f"{v:.3f}" if isinstance(v, float) else str(v) for v in row))
    console.print(table)
