"""Measured cross-rig transfer: mAP of detectors trained on one rig and tested on another.

Two layouts are read: the benchmark's results folder (``<model>/trained_on_<rig>.json`` whose
``results[<test rig>]["metrics"]["mAP"]`` is the mAP) and a long CSV with the header
``model,train_rig,test_rig,mAP``. The relative drop of a pair is

    delta(A -> B) = (mAP(A -> A) - mAP(A -> B)) / mAP(A -> A)

defined for every pair whose training rig has a positive own mAP (the diagonal gives 0).
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rigopt.errors import DataError, json_loads, not_utf8

CSV_HEADER = ("model", "train_rig", "test_rig", "mAP")


@dataclass(frozen=True)
class TransferTable:
    """Measured transfer in long form; every array is (P,).

    Attributes: ``model``, ``train``, ``test`` (str arrays) and ``map`` (float, mAP in [0, 1]).
    One row per (model, train rig, test rig); the diagonal (train == test) is each rig's own mAP.
    """

    model: np.ndarray
    train: np.ndarray
    test: np.ndarray
    map: np.ndarray

    def models(self) -> list[str]:
        """Model names in order of first appearance."""
        return list(dict.fromkeys(self.model.tolist()))

    def rigs(self) -> list[str]:
        """Every rig named as a training or test rig, in order of first appearance."""
        return list(dict.fromkeys(self.train.tolist() + self.test.tolist()))

    def own_map(self) -> dict[tuple[str, str], float]:
        """mAP(A -> A) keyed by (model, A)."""
        diagonal = self.train == self.test
        return {(m, a): float(v) for m, a, v in zip(self.model[diagonal], self.train[diagonal], self.map[diagonal])}

    def drops(self) -> "TransferDrops":
        """The relative drops of every pair whose training rig has a positive own mAP."""
        own = self.own_map()
        base = np.array([own.get((m, a), np.nan) for m, a in zip(self.model, self.train)])
        keep = base > 0
        skipped = sorted({(m, a) for m, a, b in zip(self.model, self.train, base) if not b > 0})
        delta = (base[keep] - self.map[keep]) / base[keep]
        return TransferDrops(self.model[keep], self.train[keep], self.test[keep], delta, tuple(skipped))

    def write_csv(self, path) -> Path:
        """Write the long CSV layout; returns the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(CSV_HEADER)
            for row in zip(self.model, self.train, self.test, self.map):
                writer.writerow([row[0], row[1], row[2], repr(float(row[3]))])
        return path


@dataclass(frozen=True)
class TransferDrops:
    """Relative mAP drops; arrays (P,). ``skipped`` lists (model, train rig) with no positive own mAP."""

    model: np.ndarray
    train: np.ndarray
    test: np.ndarray
    delta: np.ndarray
    skipped: tuple[tuple[str, str], ...]

    def select(self, mask) -> "TransferDrops":
        """The rows where ``mask`` (P,) bool is true."""
        return TransferDrops(self.model[mask], self.train[mask], self.test[mask], self.delta[mask], self.skipped)


def read_transfer(path) -> TransferTable:
    """Read measured transfer from a benchmark results folder or a long CSV file."""
    path = Path(path)
    if path.is_dir():
        table = _read_results_folder(path)
    elif path.is_file():
        table = _read_csv(path)
    else:
        raise DataError(f"{path}: no such results folder or CSV file")
    _check_diagonals(table, path)
    return table


def _table(rows: list[tuple[str, str, str, float]], source: Path) -> TransferTable:
    if not rows:
        raise DataError(f"{source}: no transfer results found (expected <model>/trained_on_<rig>.json or a CSV "
                        f"with header {','.join(CSV_HEADER)})")
    seen = set()
    for m, a, b, _ in rows:
        if (m, a, b) in seen:
            raise DataError(f"{source}: the pair {m} {a} -> {b} appears twice")
        seen.add((m, a, b))
    model, train, test, value = zip(*rows)
    return TransferTable(np.array(model), np.array(train), np.array(test), np.array(value, dtype=float))


def _check_map(value, where: str, text: bool = False) -> float | None:
    """A finite mAP in [0, 1], or None for a missing value (null / empty CSV field).

    ``text``: the value comes from a CSV field (a string); JSON values must be numbers or null.
    """
    if value is None or (text and value == ""):
        return None
    if not text and not isinstance(value, (int, float)):
        raise DataError(f"{where}: mAP must be a number or null, got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise DataError(f"{where}: mAP must be a number, got {value!r}") from None
    if isinstance(value, bool) or not math.isfinite(number) or not 0.0 <= number <= 1.0:
        raise DataError(f"{where}: mAP must be a finite number in [0, 1], got {value!r}")
    return number


def _read_results_folder(root: Path) -> TransferTable:
    rows = []
    for file in sorted(root.glob("*/trained_on_*.json")):
        model, train = file.parent.name, file.stem.removeprefix("trained_on_")
        try:
            data = json_loads(file.read_text())
        except json.JSONDecodeError as error:
            raise DataError(f"{file}: not valid JSON (line {error.lineno}: {error.msg})") from None
        except UnicodeDecodeError as error:
            raise not_utf8(file, "results file", error) from None
        results = data.get("results") if isinstance(data, dict) else None
        if not isinstance(results, dict):
            raise DataError(f"{file}: missing the 'results' object of test rigs")
        for test, entry in results.items():
            metrics = entry.get("metrics") if isinstance(entry, dict) else None
            if not isinstance(metrics, dict) or "mAP" not in metrics:
                raise DataError(f"{file}: test rig {test!r} has no metrics.mAP")
            value = _check_map(metrics["mAP"], f"{file}: test rig {test!r}")
            if value is not None:
                rows.append((model, train, test, value))
    return _table(rows, root)


def _read_csv(path: Path) -> TransferTable:
    try:
        return _read_csv_rows(path)
    except UnicodeDecodeError as error:
        raise not_utf8(path, "transfer CSV", error) from None


def _read_csv_rows(path: Path) -> TransferTable:
    with path.open(newline="", encoding="utf-8") as handle:
        reader = csv.reader(handle)
        header = next(reader, None)
        if header is None or tuple(h.strip() for h in header) != CSV_HEADER:
            raise DataError(f"{path}: the first line must be the header {','.join(CSV_HEADER)}, got {header}")
        rows = []
        for line, record in enumerate(reader, start=2):
            if not record:
                continue
            if len(record) != 4:
                raise DataError(f"{path}: line {line} has {len(record)} fields, expected 4 ({','.join(CSV_HEADER)})")
            model, train, test = (v.strip() for v in record[:3])
            value = _check_map(record[3].strip(), f"{path}: line {line}", text=True)
            if value is not None:
                rows.append((model, train, test, value))
    return _table(rows, path)


def _check_diagonals(table: TransferTable, source: Path) -> None:
    """Every training rig must report its own mAP (the diagonal), or its drops are undefined."""
    own = table.own_map()
    for model, train in dict.fromkeys(zip(table.model.tolist(), table.train.tolist())):
        if (model, train) not in own:
            where = source / model / f"trained_on_{train}.json" if source.is_dir() else source
            raise DataError(f"{where}: no result of {model} trained on {train} tested on {train} itself "
                            "(the diagonal), so its relative drops cannot be computed")
