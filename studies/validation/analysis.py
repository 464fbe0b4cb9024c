"""The validation study's analysis, as pre-registered (``preregistration.md``): does a candidate distance order
the measured drops of the test rigs within each vehicle better than the published RigCD?

Run ``python studies/validation/analysis.py`` after ``measure.py``: reads ``results/measured.csv`` (one row per
test rig and seed) and ``candidates.json``, writes ``results/results.md``, ``results/analysis.json`` and one
predicted-vs-measured figure per candidate (``results/<candidate>.png``, a panel per vehicle).

Statistics (all functions below take plain arrays and are tested in ``tests/studies/test_validation_analysis.py``):

- the measured drop of a rig is the mean over the seeds of its relative fixed-set mAP drop;
- per vehicle, Spearman rho of a candidate's linear prediction against the measured drops (a monotone link would
  not change it); the primary statistic is their mean over the vehicles, the pooled rho over every rig secondary;
- rig bootstrap: rigs resampled with replacement within each vehicle (BOOTSTRAP resamples, seed SEED), the same
  draws for every candidate, so differences are paired; percentile intervals;
- permutation p (one-sided, rho > 0): the measured drops permuted within each vehicle (PERMUTATIONS random
  permutations, seed SEED; exact enumeration of 16+ rigs' orderings is out of reach), p = (1 + hits) / (1 + n);
- the decision rule of the pre-registration: :func:`decide`.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np
from scipy.stats import rankdata

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
RESULTS = HERE / "results"

BOOTSTRAP = 2000
PERMUTATIONS = 100_000
SEED = 0
LEVEL = 0.95
#: The candidates the rule may ship, compared with BASELINE at a Bonferroni-corrected level.
NEW = ("split", "depth_prior", "rigcd_depth", "split_depth")
BASELINE = "rigcd_joint"
TARGET_RHO = 0.8


def spearman(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Spearman rho along the last axis of x, y (..., n) (average ranks for ties); NaN where a side is constant."""
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    rx, ry = (rankdata(v, axis=-1) for v in (x, y))
    rx, ry = rx - rx.mean(-1, keepdims=True), ry - ry.mean(-1, keepdims=True)
    denominator = np.sqrt((rx ** 2).sum(-1) * (ry ** 2).sum(-1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(denominator > 0, (rx * ry).sum(-1) / denominator, np.nan)


def within_vehicle_rho(predicted: np.ndarray, measured: np.ndarray, groups: np.ndarray) -> dict[str, float]:
    """{vehicle: rho} over the rigs of each group; predicted, measured, groups (n,)."""
    return {str(g): float(spearman(predicted[groups == g], measured[groups == g])) for g in dict.fromkeys(groups)}


def bootstrap_draws(groups: np.ndarray, resamples: int = BOOTSTRAP, seed: int = SEED) -> np.ndarray:
    """(resamples, n) int: rig indices drawn with replacement within each group, group by group in order."""
    rng = np.random.default_rng(seed)
    parts = []
    for g in dict.fromkeys(groups):
        members = np.flatnonzero(groups == g)
        parts.append(members[rng.integers(0, len(members), size=(resamples, len(members)))])
    return np.concatenate(parts, axis=1)


def resampled_rhos(predicted, measured, groups, draws) -> dict[str, np.ndarray]:
    """{vehicle: (B,) rho, "mean": (B,) mean over vehicles, "pooled": (B,) rho over all drawn rigs}."""
    predicted, measured = np.asarray(predicted, float)[draws], np.asarray(measured, float)[draws]
    drawn_groups = np.asarray(groups)[draws[0]]
    out = {str(g): spearman(predicted[:, drawn_groups == g], measured[:, drawn_groups == g])
           for g in dict.fromkeys(drawn_groups)}
    out["mean"] = np.nanmean(np.stack(list(out.values())), axis=0)
    out["pooled"] = spearman(predicted, measured)
    return out


def interval(values: np.ndarray, level: float = LEVEL) -> list[float]:
    """Two-sided percentile interval of the finite values."""
    finite = values[np.isfinite(values)]
    tail = 100 * (1 - level) / 2
    return [float(v) for v in np.percentile(finite, [tail, 100 - tail])]


def lower_bound(values: np.ndarray, level: float) -> float:
    """One-sided lower percentile bound at ``level`` of the finite values."""
    finite = values[np.isfinite(values)]
    return float(np.percentile(finite, 100 * (1 - level)))


def permutation_p(predicted, measured, groups, permutations: int = PERMUTATIONS, seed: int = SEED) -> dict[str, float]:
    """One-sided permutation p of rho > 0 per vehicle and of the mean over vehicles (measured drops permuted
    within each vehicle): (1 + permuted statistics >= observed) / (1 + permutations)."""
    rng = np.random.default_rng(seed)
    predicted, measured, groups = np.asarray(predicted, float), np.asarray(measured, float), np.asarray(groups)
    observed = within_vehicle_rho(predicted, measured, groups)
    permuted = {}
    for g in observed:
        m = measured[groups == g]
        shuffled = m[np.argsort(rng.random((permutations, len(m))), axis=1)]
        permuted[g] = spearman(np.broadcast_to(predicted[groups == g], shuffled.shape), shuffled)
    out = {g: float((1 + np.sum(permuted[g] >= observed[g] - 1e-12)) / (1 + permutations)) for g in observed}
    mean_observed = np.mean(list(observed.values()))
    mean_permuted = np.mean(np.stack(list(permuted.values())), axis=0)
    out["mean"] = float((1 + np.sum(mean_permuted >= mean_observed - 1e-12)) / (1 + permutations))
    return out


def decide(resampled: dict[str, dict[str, np.ndarray]], observed: dict[str, dict[str, float]],
           vehicles, new=NEW, baseline: str = BASELINE) -> dict:
    """The pre-registered rule. ``resampled[c]`` as :func:`resampled_rhos` (the same draws for every c);
    ``observed[c]`` {vehicle: rho, "mean": rho}.

    1. A new candidate beats the baseline when the one-sided lower bound at 1 - 0.05 / len(new) (Bonferroni) of
       its paired rig-bootstrap difference in mean within-vehicle rho is above 0.
    2. Of those, the one with the highest observed mean within-vehicle rho ships as a named metric.
    3. It becomes the designer's default objective for lifting detectors when also its mean rho is at least
       TARGET_RHO and its per-vehicle differences' lower bounds (same level) are above 0 on every vehicle.
    """
    level = 1 - 0.05 / len(new)
    rows = {}
    for c in new:
        difference = resampled[c]["mean"] - resampled[baseline]["mean"]
        per_vehicle = {v: lower_bound(resampled[c][v] - resampled[baseline][v], level) for v in vehicles}
        rows[c] = {"mean_rho": observed[c]["mean"], "difference_lower_bound": lower_bound(difference, level),
                   "per_vehicle_lower_bounds": per_vehicle,
                   "beats_baseline": lower_bound(difference, level) > 0}
    winners = [c for c in new if rows[c]["beats_baseline"]]
    ships = max(winners, key=lambda c: rows[c]["mean_rho"]) if winners else None
    default = bool(ships and rows[ships]["mean_rho"] >= TARGET_RHO
                   and all(b > 0 for b in rows[ships]["per_vehicle_lower_bounds"].values()))
    return {"level": level, "candidates": rows, "ships": ships, "designer_default": default}


def read_measured(path: Path) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray, dict]:
    """(rigs, vehicles (n,), measured drop (n,) mean over seeds, visible-only drop (n,), per-seed drops)."""
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    rigs = list(dict.fromkeys(row["rig"] for row in rows))
    vehicle = {row["rig"]: row["vehicle"] for row in rows}
    seeds: dict[str, dict[int, float]] = {rig: {} for rig in rigs}
    visible: dict[str, list[float]] = {rig: [] for rig in rigs}
    for row in rows:
        seeds[row["rig"]][int(row["seed"])] = float(row["drop"])
        visible[row["rig"]].append(float(row["drop_visible"]))
    drop = np.array([np.mean(list(seeds[rig].values())) for rig in rigs])
    return rigs, np.array([vehicle[r] for r in rigs]), drop, np.array([np.mean(visible[r]) for r in rigs]), seeds


def predictions(rigs: list[str], candidates: dict) -> dict[str, np.ndarray]:
    """{candidate: (n,) linear prediction} of the test rigs against R1 from the frozen weights."""
    from rigopt.metrics.lifting import TERMS, lifting_terms
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import in_vehicle_frame

    reference = load_rig("R1")
    test = [in_vehicle_frame(load_rig(HERE / "rigs" / f"{rig}.json"))[0] for rig in rigs]
    terms = lifting_terms([reference] * len(test), test)
    return {name: sum(w * terms[:, TERMS.index(term)] for term, w in entry["weights"].items())
            for name, entry in candidates.items()}


def plot(name: str, predicted, measured, vehicles, rigs, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = list(dict.fromkeys(vehicles))
    figure, axes = plt.subplots(1, len(groups), figsize=(5 * len(groups), 4.2), squeeze=False)
    for axis, g in zip(axes[0], groups):
        mask = vehicles == g
        axis.scatter(predicted[mask], measured[mask], s=18)
        for x, y, rig in zip(predicted[mask], measured[mask], np.array(rigs)[mask]):
            if not rig.startswith(g + "_h"):
                axis.annotate(rig.replace(f"_{g}_from_R1", "").replace(f"{g}_from_R1", "design"), (x, y), fontsize=7)
        axis.set_title(f"{g}: rho {spearman(predicted[mask], measured[mask]):.2f}")
        axis.set_xlabel(f"{name} (linear prediction)")
        axis.set_ylabel("measured drop (mean of seeds)")
        axis.grid(alpha=0.3)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def markdown(report: dict, groups: list[str]) -> str:
    """results.md: the pre-registered figures of every candidate and the decision, from ``report``."""
    def cell(value, ci=None):
        return f"{value:.3f}" + (f" [{ci[0]:.3f}, {ci[1]:.3f}]" if ci is not None else "")

    lines = [f"# Validation study: results ({report['rigs']} test rigs: "
             + ", ".join(f"{g} {n}" for g, n in report["per_vehicle"].items()) + ")", "",
             "Spearman rho of each candidate's prediction against the measured drops (mean of 3 seeds), within each "
             "vehicle and their mean (the primary statistic), with 95 % intervals over rigs resampled within each "
             f"vehicle ({BOOTSTRAP} resamples); one-sided permutation p of the mean ({PERMUTATIONS} permutations "
             "within vehicles); the paired difference to rigcd_joint on the same resamples.", "",
             "| candidate | mean within-vehicle rho | " + " | ".join(groups) + " | pooled | p (mean) | "
             "difference to rigcd_joint (mean) |", "|---" * (len(groups) + 5) + "|"]
    for name, entry in report["candidates"].items():
        rho, ci, diff = entry["rho"], entry["rho_ci"], entry["difference_to_rigcd"]["mean"]
        lines.append(f"| {name} | {cell(rho['mean'], ci['mean'])} | "
                     + " | ".join(cell(rho[g], ci[g]) for g in groups)
                     + f" | {cell(rho['pooled'], ci['pooled'])} | {entry['permutation_p']['mean']:.5f} | "
                     + ("-" if name == BASELINE else cell(diff["value"], diff["ci"])) + " |")
    decision = report["decision"]
    lines += ["", f"## Decision (pre-registered rule; one-sided bounds at {decision['level']:.4f})", "",
              "| candidate | mean rho | lower bound of the difference to rigcd_joint | per vehicle | beats RigCD |",
              "|---|---|---|---|---|"]
    for name, row in decision["candidates"].items():
        per_vehicle = ", ".join(f"{g} {b:+.3f}" for g, b in row["per_vehicle_lower_bounds"].items())
        lines.append(f"| {name} | {row['mean_rho']:.3f} | {row['difference_lower_bound']:+.3f} | {per_vehicle} | "
                     f"{'yes' if row['beats_baseline'] else 'no'} |")
    ships = decision["ships"]
    lines += ["", f"Ships: {ships or 'none'}; the designer's default objective for lifting detectors: "
              f"{'yes' if decision['designer_default'] else 'no'}.", "",
              "Visible-only drops (secondary), mean within-vehicle rho: "
              + ", ".join(f"{n} {e['rho_visible_only']['mean']:.3f}" for n, e in report["candidates"].items()) + ".",
              ""]
    return "\n".join(lines)


def main() -> int:
    rigs, vehicles, measured, measured_visible, _ = read_measured(RESULTS / "measured.csv")
    candidates = json.loads((HERE / "candidates.json").read_text())["candidates"]
    predicted = predictions(rigs, candidates)
    groups = list(dict.fromkeys(vehicles))
    draws = bootstrap_draws(vehicles)
    resampled = {c: resampled_rhos(p, measured, vehicles, draws) for c, p in predicted.items()}
    observed = {}
    for c, p in predicted.items():
        rho = within_vehicle_rho(p, measured, vehicles)
        observed[c] = {**rho, "mean": float(np.mean(list(rho.values()))), "pooled": float(spearman(p, measured))}
    report = {"rigs": len(rigs), "per_vehicle": {g: int(np.sum(vehicles == g)) for g in groups}, "candidates": {}}
    for c in predicted:
        p = permutation_p(predicted[c], measured, vehicles)
        visible = within_vehicle_rho(predicted[c], measured_visible, vehicles)
        report["candidates"][c] = {
            "rho": observed[c], "rho_ci": {k: interval(v) for k, v in resampled[c].items()},
            "rho_visible_only": {**visible, "mean": float(np.mean(list(visible.values()))),
                                 "pooled": float(spearman(predicted[c], measured_visible))},
            "permutation_p": p,
            "difference_to_rigcd": {k: {"value": observed[c][k] - observed[BASELINE][k],
                                        "ci": interval(resampled[c][k] - resampled[BASELINE][k])}
                                    for k in [*groups, "mean", "pooled"]}}
        plot(c, predicted[c], measured, vehicles, rigs, RESULTS / f"{c}.png")
    report["decision"] = decide(resampled, observed, groups)
    (RESULTS / "analysis.json").write_text(json.dumps(report, indent=2) + "\n")
    (RESULTS / "results.md").write_text(markdown(report, groups))
    print(json.dumps(report["decision"], indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
