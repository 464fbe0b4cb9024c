"""The predictor study's pre-registered statistics (``preregistration.md``): leave one vehicle out, the predictor
against the published RigCD on the same held-out rigs.

    python studies/predictor/analysis.py

Reads ``results/measured.jsonl`` (``measure.py``) and the rig files; writes ``results/analysis.json`` (every
figure, every held-out prediction) and ``results/results.md`` (the tables and the decision).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
sys.path.insert(0, str(HERE.parent))  # studies/: the studies' shared code (studylib)
from studylib.tables import markdown  # noqa: E402

DESIGNER_KINDS = ("design", "naive", "height_matched", "searched_copy", "swap")
RESAMPLES, SEED = 2000, 0
TARGETS = {"rho": 0.9, "mae": 0.08, "designer_rho": 0.8, "coverage": 0.85, "width": 0.35}
#: The pre-registered terms: every term of rigopt.metrics.drop_model but the later ``body`` (studies/predictor_v2).
TERMS = ("depth_prior", "raise", "lower", "tilt_down", "tilt_up", "roll", "yaw", "plan", "zoom", "centre", "count",
         "uncovered")


def load_measured() -> list[dict]:
    return [json.loads(line) for line in (RESULTS / "measured.jsonl").read_text().splitlines()]


def held_out(terms: list, drops: np.ndarray, vehicles: np.ndarray, fit, predict) -> np.ndarray:
    """(P,) predictions of each rig by a fit on the other vehicles' rigs."""
    out = np.empty(len(drops))
    for vehicle in np.unique(vehicles):
        test = vehicles == vehicle
        weights = fit([t for t, keep in zip(terms, ~test) if keep], drops[~test])
        out[test] = predict(weights, [t for t, keep in zip(terms, test) if keep])
    return out


def held_out_intervals(terms, drops, vehicles, fit, predict, predicted) -> np.ndarray:
    """(P,) interval half-widths: for each outer held-out vehicle, per-bin conformal widths from an inner
    leave-one-vehicle-out over the other vehicles."""
    from rigopt.metrics.drop_model import interval_bin, interval_halfwidths

    widths = np.empty(len(drops))
    for vehicle in np.unique(vehicles):
        test, rest = vehicles == vehicle, vehicles != vehicle
        inner = held_out([t for t, keep in zip(terms, rest) if keep], drops[rest], vehicles[rest], fit, predict)
        widths[test] = interval_halfwidths(inner, drops[rest])[interval_bin(predicted[test])]
    return widths


def within_rho(predicted, measured, vehicles, mask=None) -> dict[str, float]:
    from rigopt.metrics.reliability import spearman

    mask = np.ones(len(measured), bool) if mask is None else mask
    out = {}
    for vehicle in np.unique(vehicles):
        keep = (vehicles == vehicle) & mask
        if keep.sum() >= 3:
            out[str(vehicle)] = float(spearman(predicted[keep], measured[keep])[0])
    return out


def vehicle_interval(values_of, vehicles) -> list[float]:
    """95 % interval of a statistic over vehicle resamples: ``values_of(list of vehicles)``."""
    names = np.unique(vehicles)
    rng = np.random.default_rng(SEED)
    draws = [values_of(names[rng.integers(len(names), size=len(names))]) for _ in range(RESAMPLES)]
    draws = [d for d in draws if np.isfinite(d)]
    return [float(np.percentile(draws, 2.5)), float(np.percentile(draws, 97.5))]


def statistics(predicted, measured, vehicles, kinds, names, widths=None) -> dict:
    from rigopt.metrics.drop_model import interval_bin
    from rigopt.metrics.reliability import spearman

    rho = within_rho(predicted, measured, vehicles)
    designer = within_rho(predicted, measured, vehicles, np.isin(kinds, DESIGNER_KINDS))
    error = np.abs(predicted - measured)
    out = {"mean_within_rho": float(np.mean(list(rho.values()))),
           "mean_within_rho_ci": vehicle_interval(lambda vs: np.mean([rho[v] for v in vs if v in rho]), vehicles),
           "within_rho": rho, "mae": float(error.mean()),
           "mae_ci": vehicle_interval(lambda vs: np.mean(np.concatenate([error[vehicles == v] for v in vs])), vehicles),
           "designer_rho": float(np.mean(list(designer.values()))), "designer_within_rho": designer,
           "pooled_rho": float(spearman(predicted, measured)[0]), "design_vs_naive": {}}
    for vehicle in np.unique(vehicles):
        design = (vehicles == vehicle) & (names == f"{vehicle}_from_R1_default")
        naive = (vehicles == vehicle) & (kinds == "naive")
        if design.any() and naive.any():
            out["design_vs_naive"][str(vehicle)] = bool(
                np.sign(predicted[design][0] - predicted[naive][0]) == np.sign(measured[design][0] - measured[naive][0]))
    if widths is not None:
        inside = np.abs(measured - predicted) <= widths
        bins = interval_bin(predicted)
        out["coverage"] = {str(b): float(inside[bins == b].mean()) for b in np.unique(bins)}
        out["mean_width"] = float(np.mean(2 * np.minimum(widths, 1.0)))
    return out


def main() -> int:
    from rigopt.metrics import drop_model
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.ranking import predict_transfer
    from rigopt.output import write_text_atomic
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import in_vehicle_frame

    entries = load_measured()
    reference = in_vehicle_frame(load_rig("R1"))[0]
    rigs = [in_vehicle_frame(load_rig(HERE / "rigs" / f"{e['rig']}.json"))[0] for e in entries]
    measured = np.array([e["drop"] for e in entries])
    vehicles = np.array([e["vehicle"] for e in entries])
    kinds = np.array([e["kind"] for e in entries])
    names = np.array([e["rig"] for e in entries])
    terms = [drop_model.PairTerms.of(reference, rig) for rig in rigs]
    fit = lambda t, d: drop_model.fit_weights(t, d, TERMS)  # noqa: E731
    predict = lambda w, t: drop_model.predict(w, t, TERMS)  # noqa: E731
    predicted = held_out(terms, measured, vehicles, fit, predict)
    widths = held_out_intervals(terms, measured, vehicles, fit, predict, predicted)
    rigcd = np.array([p.predicted_drop for p in predict_transfer(reference, rigs, load_weights("joint"))])
    result = {"rigs": len(entries), "vehicles": sorted(set(vehicles.tolist())),
              "protocols": sorted({e["protocol"] for e in entries}),
              "predictor": statistics(predicted, measured, vehicles, kinds, names, widths),
              "rigcd": statistics(rigcd, measured, vehicles, kinds, names),
              "weights_all": {name: float(w) for name, w in zip(drop_model.FEATURES, fit(terms, measured))
                              if name in TERMS},
              "per_rig": [{"rig": n, "vehicle": v, "kind": k, "measured": float(m), "predicted": float(p),
                           "halfwidth": float(w), "rigcd": float(r)}
                          for n, v, k, m, p, w, r in zip(names, vehicles, kinds, measured, predicted, widths, rigcd)]}
    p, r = result["predictor"], result["rigcd"]
    result["replaces_rigcd"] = bool(p["mean_within_rho"] > r["mean_within_rho"] and p["mae"] < r["mae"])
    result["targets"] = {"rho": p["mean_within_rho"] >= TARGETS["rho"], "mae": p["mae"] <= TARGETS["mae"],
                         "designer_rho": p["designer_rho"] >= TARGETS["designer_rho"],
                         "coverage": all(v >= TARGETS["coverage"] for v in p["coverage"].values()),
                         "width": p["mean_width"] <= TARGETS["width"]}
    write_text_atomic(RESULTS / "analysis.json", json.dumps(result, indent=1) + "\n")
    write_text_atomic(RESULTS / "results.md", report(result))
    print(report(result))
    return 0


def report(result: dict) -> str:
    p, r = result["predictor"], result["rigcd"]

    def ci(values):
        return f"[{values[0]:.3f}, {values[1]:.3f}]"

    rows = [["statistic (held-out vehicles)", "predictor", "RigCD (joint)", "target"],
            ["mean within-vehicle rho (95 % over vehicles)", f"{p['mean_within_rho']:.3f} {ci(p['mean_within_rho_ci'])}",
             f"{r['mean_within_rho']:.3f} {ci(r['mean_within_rho_ci'])}", ">= 0.9"],
            ["MAE", f"{p['mae']:.3f} {ci(p['mae_ci'])}", f"{r['mae']:.3f} {ci(r['mae_ci'])}", "<= 0.08"],
            ["rho on the designer's own rigs", f"{p['designer_rho']:.3f}", f"{r['designer_rho']:.3f}", ">= 0.8"],
            ["pooled rho", f"{p['pooled_rho']:.3f}", f"{r['pooled_rho']:.3f}", "-"],
            ["design vs naive copy ordered as measured", f"{sum(p['design_vs_naive'].values())} of "
             f"{len(p['design_vs_naive'])}", f"{sum(r['design_vs_naive'].values())} of {len(r['design_vs_naive'])}", "all"],
            ["90 % interval coverage per bin", ", ".join(f"{k}: {v:.2f}" for k, v in p["coverage"].items()), "-",
             ">= 0.85 each"],
            ["mean interval width", f"{p['mean_width']:.3f}", "-", "<= 0.35"]]
    per_vehicle = [["vehicle", "rigs", "rho predictor", "rho RigCD", "designer rho predictor", "designer rho RigCD"]]
    for vehicle in result["vehicles"]:
        n = sum(e["vehicle"] == vehicle for e in result["per_rig"])
        per_vehicle.append([vehicle, n, f"{p['within_rho'].get(vehicle, float('nan')):.3f}",
                            f"{r['within_rho'].get(vehicle, float('nan')):.3f}",
                            f"{p['designer_within_rho'].get(vehicle, float('nan')):.3f}",
                            f"{r['designer_within_rho'].get(vehicle, float('nan')):.3f}"])
    decision = ("the predictor replaces RigCD as the printed prediction" if result["replaces_rigcd"]
                else "RigCD stays the printed prediction")
    met = ", ".join(f"{k} {'met' if v else 'not met'}" for k, v in result["targets"].items())
    return (f"# Predictor study: results ({result['rigs']} rigs, {len(result['vehicles'])} vehicles, protocol "
            f"{', '.join(result['protocols'])})\n\n{markdown(rows)}\n\n{markdown(per_vehicle)}\n\n"
            f"**Decision (pre-registered rule): {decision}.** Targets: {met}.\n")


if __name__ == "__main__":
    sys.exit(main())
