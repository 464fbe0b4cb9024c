"""Exploratory, not pre-registered: the factorial rigs' measured drops by factor level.

    python studies/validation/factors.py

The pre-registered analysis (``analysis.py``) asks which distance orders the test rigs; this asks what the
detector is sensitive to, read from the orthogonal array: for each factor (height offset, pitch, FOV, camera
count, plan offset) and level, the mean measured drop of the factorial rigs at that level, per vehicle and over
the three, and each factor's range of level means (its main effect; in an orthogonal array each level sees every
level of every other factor equally often, so the other factors average out, interactions aside). The
intervals resample the factorial rigs within each vehicle (2000 resamples, seed 0): one rig per level
combination, so they are wide. Prints a markdown table and writes ``results/factors.md``. It informs the
designer's defaults; it decides nothing about the distances.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
FACTORS = {"height_offset_m": "height offset (m)", "pitch_deg": "pitch (deg)", "fov_deg": "FOV (deg)",
           "cameras": "cameras", "plan_offset_m": "plan offset (m)"}
BOOTSTRAP = 2000
SEED = 0


def measured_drops() -> dict[str, float]:
    """{rig: mean measured drop over the seeds} of every measured rig."""
    seeds: dict[str, list[float]] = {}
    with open(RESULTS / "measured.csv", newline="") as handle:
        for row in csv.DictReader(handle):
            seeds.setdefault(row["rig"], []).append(float(row["drop"]))
    return {rig: float(np.mean(values)) for rig, values in seeds.items()}


def level_means(levels: np.ndarray, drops: np.ndarray) -> dict[float, float]:
    """{level: mean drop of the rigs at that level} of one factor; levels (n,), drops (n,)."""
    return {float(v): float(drops[levels == v].mean()) for v in np.unique(levels)}


def main() -> int:
    drops = measured_drops()
    with open(HERE / "rigs" / "index.csv", newline="") as handle:
        rows = [r for r in csv.DictReader(handle) if r["kind"] == "factorial" and r["rig"] in drops]
    vehicles = np.array([r["vehicle"] for r in rows])
    y = np.array([drops[r["rig"]] for r in rows])
    rng = np.random.default_rng(SEED)
    groups = {v: np.flatnonzero(vehicles == v) for v in dict.fromkeys(vehicles)}
    draws = [np.concatenate([rng.choice(index, len(index)) for index in groups.values()]) for _ in range(BOOTSTRAP)]
    lines = [f"# The factorial rigs by factor level (exploratory, not pre-registered; {len(rows)} rigs measured)", "",
             "Mean measured drop (3 seeds) at each level; 'effect' is the range of the level means over all vehicles, "
             "with its 95 % interval over rigs resampled within each vehicle.", ""]
    for key, label in FACTORS.items():
        x = np.array([float(r[key]) for r in rows])
        overall = level_means(x, y)
        effect = max(overall.values()) - min(overall.values())
        resampled = []
        for draw in draws:
            means = level_means(x[draw], y[draw])
            if len(means) == len(overall):
                resampled.append(max(means.values()) - min(means.values()))
        low, high = np.percentile(resampled, [2.5, 97.5])
        lines += [f"## {label}: effect {effect:.3f} [{low:.3f}, {high:.3f}]", "",
                  "| level | " + " | ".join(groups) + " | all |", "|---" * (len(groups) + 2) + "|"]
        for level in overall:
            per_vehicle = [level_means(x[index], y[index]).get(level) for index in groups.values()]
            cells = ["-" if m is None else f"{m:.3f}" for m in per_vehicle]
            lines.append(f"| {level:g} | " + " | ".join(cells) + f" | {overall[level]:.3f} |")
        lines.append("")
    text = "\n".join(lines)
    (RESULTS / "factors.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
