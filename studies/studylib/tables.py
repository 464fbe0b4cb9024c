"""Small tables for studies: a CSV file and a markdown table from the same rows."""

from __future__ import annotations

import csv
from pathlib import Path


def write_csv(path: Path, header: list[str], rows: list[list]) -> list[list]:
    """Write ``rows`` under ``header`` (floats with 6 significant digits); returns [header, *rows]."""
    with Path(path).open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows([[f"{v:.6g}" if isinstance(v, float) else v for v in row] for row in rows])
    return [header, *rows]


def read_csv(path: Path) -> list[list]:
    """[header, *rows] of a CSV written by ``write_csv``, numbers back as int or float."""
    def value(text: str):
        for kind in (int, float):
            try:
                return kind(text)
            except ValueError:
                pass
        return text

    with Path(path).open(newline="") as handle:
        header, *rows = csv.reader(handle)
    return [header, *([value(v) for v in row] for row in rows)]


def markdown(table: list[list]) -> str:
    """A markdown table of [header, *rows]; numbers with 3 decimals, columns named p_* in scientific
    notation, None as '-'."""
    def cell(column: str, value) -> str:
        if value is None:
            return "-"
        if isinstance(value, float):
            return f"{value:.2e}" if column.startswith("p_") else f"{value:.3f}"
        return str(value)

    header = table[0]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(cell(c, v) for c, v in zip(header, row)) + " |" for row in table[1:]])


def write_rig_index(path: Path, columns: list[str], rows: list[dict]) -> None:
    """Write a rig set's index: one row per rig (a dict with at least ``rig``) under ``columns``; a repeated rig
    name is an error (SystemExit naming them), as two rigs would share one file."""
    names = [row["rig"] for row in rows]
    if len(set(names)) != len(names):
        raise SystemExit(f"rig names repeat: {sorted({n for n in names if names.count(n) > 1})}")
    with Path(path).open("w", newline="") as handle:
        writer = csv.DictWriter(handle, columns)
        writer.writeheader()
        writer.writerows(rows)
