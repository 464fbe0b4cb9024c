"""The ``rigopt`` command-line application object and the output helpers its commands share."""

from __future__ import annotations

import json
import math

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
vehicle_app = typer.Typer(help="Vehicles: show, export and add your own.", no_args_is_help=True)
app.add_typer(vehicle_app, name="vehicle")

console = Console()
if not console.is_terminal:
    console.width = 160  # piped or captured output: wide enough for every table
#: Progress bars, spinners and warnings: stderr, so that stdout holds only results.
status_console = Console(stderr=True)


def print_json(data) -> None:
    """Print ``data`` as JSON on stdout; NaN and inf become null."""
    print(json.dumps(json_ready(data), indent=2))


#: How the running command resumes after an interrupt, said on the line that reports it (:func:`resumable`).
RESUME_HINTS: list[str] = []


def resumable(how: str) -> None:
    """Say, should the command be interrupted from here on, how to resume it (e.g. 'rerun the same command: ...')."""
    RESUME_HINTS.append(how)


def note(message: str) -> None:
    """One ``rigopt: note: ...`` line on stderr: something the command did that the user should know."""
    typer.echo(f"rigopt: note: {message}", err=True)


def print_next(*steps: str) -> None:
    """What to run or open next after a command wrote something: one ``next: ...`` line each on stdout (never
    with --json, whose stdout is JSON only)."""
    for step in steps:
        console.print(f"next: {step}", highlight=False, markup=False, soft_wrap=True)


def note_vehicle(rig, vehicle, change=None) -> None:
    """One note naming the vehicle a command put ``rig`` on and where its positions are measured from, e.g.
    'nuscenes: on renault_zoe (nuScenes' Renault Zoe), positions from the rear axle, converted to the vehicle
    centre (x -1.385 m)'. ``rig``: as loaded (its own origin); ``vehicle``: the rigopt Vehicle; ``change``: the
    OriginChange made, None when the positions were kept."""
    car = f"{vehicle.name} ({vehicle.spec.title})" if vehicle.spec.title else vehicle.name
    if change is None:
        note(f"{rig.name}: on {car}, positions from the {rig.origin.describe()}")
        return
    moved = ", ".join(f"{axis} {value:+.3f} m" for axis, value in zip("xyz", change.offset) if abs(value) > 5e-4)
    note(f"{rig.name}: on {car}, positions from the {change.source.describe()}, converted to the "
         f"{change.target.describe()} ({moved or 'no shift'})")


def note_fallback(calibration) -> None:
    """Say so when a calibration is a fallback (its fit kept no geometric term, e.g. Fast-BEV's)."""
    if calibration.fallback:
        note(f"the {calibration.name} calibration is a fallback (its fit kept no geometric term): its predictions "
             "do not weigh camera geometry as a fitted calibration would")


MIN_HEIGHT_HELP = ("Lowest lens height above the ground (m); default: the vehicle's min_lens_height, else 0.5 "
                   "(tyre spray, kerbs).")
NO_TRAILER_HELP = "Lift the vehicle's optional trailer keep-out (a tractor unit driven without its semi-trailer)."
#: The --field-pixels option's help (design and coverage).
FIELD_PIXELS_HELP = ("Pixels a field's test object must be tall in a camera's image for its point to count as seen "
                     "(default 25, KITTI's smallest evaluated box; 0: in view is enough, however small). The test "
                     "objects and their heights: docs/regulations.md.")


def mount_rules(min_height, no_trailer: bool):
    """The mount rules of the command line's --min-height and --no-trailer."""
    from rigopt.mounting.records import MountPractice, MountRules

    return MountRules(practice=MountPractice(min_height=min_height, lifted=("trailer",) if no_trailer else ()))


#: Help of the commands' ``--vehicle`` for rigs whose own vehicle rigopt does not know.
PLACE_HELP = ("Vehicle (name, alias or blueprint) to place rigs on whose own vehicle rigopt does not know "
              "(imported rigs): their positions are converted to its centre.")


def print_table(title: str, columns: list[str], rows: list[list]) -> None:
    """Print a rich table; numbers are right-aligned with 3 decimals, text left-aligned, None as '-'."""
    table = Table(title=title)
    first = rows[0] if rows else [None] * len(columns)
    for column, sample in zip(columns, first):
        table.add_column(column, justify="right" if isinstance(sample, (int, float)) else "left")
    for row in rows:
        table.add_row(*(f"{v:.3f}" if isinstance(v, float) else "-" if v is None else str(v) for v in row))
    console.print(table)


def more_than(low: float, unit: str = "", high: float = math.inf):
    """An option callback that refuses, at parse time, a number not in (low, high] (and NaN or inf)."""
    def check(value):
        if value is None:
            return value
        if not math.isfinite(value) or not low < value <= high:
            upper = f" and at most {high:g}{unit}" if math.isfinite(high) else ""
            raise typer.BadParameter(f"must be a number more than {low:g}{unit}{upper}, got {value:g}")
        return value
    return check


def between(low: float, high: float, unit: str = "", why: str = ""):
    """An option callback that refuses, at parse time, a number not in [low, high] (and NaN or inf), saying ``why``."""
    def check(value):
        if value is not None and not (math.isfinite(value) and low <= value <= high):
            raise typer.BadParameter(f"must be from {low:g}{unit} to {high:g}{unit}{why}, got {value:g}")
        return value
    return check


def finite():
    """An option callback that refuses NaN and inf at parse time (typer's min/max let them through)."""
    def check(value):
        if value is not None and not math.isfinite(value):
            raise typer.BadParameter(f"must be a finite number, got {value:g}")
        return value
    return check


#: Picture formats the figure writers (matplotlib) are offered for; the extension of --out picks one.
PICTURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")

FORCE_HELP = "Replace an existing output folder whole (without it, an existing non-empty folder is refused)."
