"""The second predictor study's pre-registered statistics (``preregistration.md``): the first shipped drop model
(lss-R1), the second (lss-R1-v2, ``models/``) and RigCD on 54 rigs none of them was fitted on.

    python studies/predictor_v2/analysis.py

Reads ``results/measured.jsonl`` (``measure.py``); writes ``results/analysis.json`` (every figure and prediction)
and ``results/results.md``. The user vehicle ``van`` must be added (its body enters the second model).
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
PREDICTORS = ("lss-R1", "lss-R1-v2", "RigCD (joint)")
RESAMPLES, SEED = 2000, 0
#: The issue's acceptance on rigs never seen: MAE, pooled rho, and the design against the naive copy.
ACCEPTANCE = {"mae": 0.10, "pooled_rho": 0.8}


def rho(a, b) -> float:
    from rigopt.metrics.reliability import spearman

    return float(spearman(a, b)[0]) if len(set(np.round(b, 12))) > 1 else float("nan")


def interval(statistic, groups: np.ndarray) -> list[float]:
    """95 % percentile interval of ``statistic(rows)`` over RESAMPLES draws of the groups (rows of each group
    drawn whole; one group per row resamples rigs)."""
    names = np.unique(groups)
    members = {g: np.flatnonzero(groups == g) for g in names}
    rng = np.random.default_rng(SEED)
    values = [statistic(np.concatenate([members[g] for g in names[rng.integers(len(names), size=len(names))]]))
              for _ in range(RESAMPLES)]
    values = [v for v in values if np.isfinite(v)]
    return [float(np.percentile(values, 2.5)), float(np.percentile(values, 97.5))]


def statistics(predicted, measured, halfwidths, rows: dict) -> dict:
    """The pre-registered figures of one predictor."""
    from rigopt.metrics.drop_model import interval_bin

    error = np.abs(predicted - measured)
    every = np.arange(len(measured))
    van, designer = rows["van"], rows["van_designer"]
    out = {"pooled_rho": rho(predicted, measured),
           "pooled_rho_ci_rigs": interval(lambda k: rho(predicted[k], measured[k]), every),
           "pooled_rho_ci_sources": interval(lambda k: rho(predicted[k], measured[k]), rows["source"]),
           "mae": float(error.mean()),
           "mae_ci_rigs": interval(lambda k: float(error[k].mean()), every),
           "mae_ci_sources": interval(lambda k: float(error[k].mean()), rows["source"]),
           "van_rho": rho(predicted[van], measured[van]), "van_mae": float(error[van].mean()),
           "van_designer_rho": rho(predicted[designer], measured[designer]),
           "benchmark_rho": rho(predicted[~van], measured[~van]), "benchmark_mae": float(error[~van].mean())}
    design, naive = rows["design"], rows["naive"]
    out["design_vs_naive"] = bool(np.sign(predicted[design] - predicted[naive])
                                  == np.sign(measured[design] - measured[naive]))
    if halfwidths is not None:
        inside = error <= halfwidths
        bins = interval_bin(predicted)
        out["coverage"] = {str(b): [float(inside[bins == b].mean()), int((bins == b).sum())] for b in np.unique(bins)}
        out["coverage_all"] = float(inside.mean())
        out["mean_width"] = float(np.mean(2 * np.minimum(halfwidths, 1.0)))
    out["acceptance"] = {"mae": out["mae"] <= ACCEPTANCE["mae"], "pooled_rho": out["pooled_rho"] >= ACCEPTANCE["pooled_rho"],
                         "design_vs_naive": out["design_vs_naive"]}
    return out


def seed_agreement(entries: list[dict], keep: np.ndarray) -> float:
    """Mean over the three seeds of the Spearman rho between one seed's drops and the other two's mean, on the rigs
    ``keep``: how well the measurement orders those rigs against itself."""
    drops = np.array([[e["seeds"][s]["drop"] for s in sorted(e["seeds"])] for e in entries])[keep]
    seeds = drops.shape[1]
    return float(np.mean([rho(drops[:, [j for j in range(seeds) if j != k]].mean(axis=1), drops[:, k])
                          for k in range(seeds)]))


def main() -> int:
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.drop_model import load_drop_model
    from rigopt.metrics.ranking import predict_transfer
    from rigopt.mounting.candidates import rig_body_share
    from rigopt.output import write_text_atomic
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import in_vehicle_frame

    entries = [json.loads(line) for line in (RESULTS / "measured.jsonl").read_text().splitlines()]
    reference = in_vehicle_frame(load_rig("R1"))[0].perception()
    rigs = [in_vehicle_frame(load_rig(HERE / "rigs" / f"{e['rig']}.json"))[0].perception() for e in entries]
    measured = np.array([e["drop"] for e in entries])
    names = np.array([e["rig"] for e in entries])
    kinds = np.array([e["kind"] for e in entries])
    van = np.array([e["vehicle"] == "van" for e in entries])
    rows = {"van": van, "van_designer": van & np.isin(kinds, DESIGNER_KINDS),
            "source": np.array([e["source"] or "van" for e in entries]),
            "design": int(np.flatnonzero(names == "van_from_R1_default")[0]),
            "naive": int(np.flatnonzero(van & (kinds == "naive"))[0])}
    predictions = {}
    for name in PREDICTORS[:2]:
        model = load_drop_model(name if name == "lss-R1" else HERE / "models" / f"{name}.json")
        drops, halfwidths, _ = model.predict(reference, rigs, rig_body_share)
        predictions[name] = (drops, halfwidths)
    rigcd = predict_transfer(reference, rigs, load_weights("joint"))
    predictions[PREDICTORS[2]] = (np.array([p.predicted_drop for p in rigcd]), None)
    result = {"rigs": len(entries), "protocols": sorted({e["protocol"] for e in entries}),
              "statistics": {name: statistics(p, measured, w, rows) for name, (p, w) in predictions.items()},
              "seed_agreement": {"all": seed_agreement(entries, np.ones(len(entries), bool)),
                                 "van_designer": seed_agreement(entries, rows["van_designer"])},
              "per_rig": [{"rig": str(n), "kind": str(k), "source": str(s), "measured": float(m),
                           **{name: float(p[i]) for name, (p, _) in predictions.items()}}
                          for i, (n, k, s, m) in enumerate(zip(names, kinds, rows["source"], measured))]}
    v1, v2 = (result["statistics"][name] for name in PREDICTORS[:2])
    result["v2_replaces_v1"] = bool(v2["pooled_rho"] > v1["pooled_rho"] and v2["mae"] < v1["mae"])
    write_text_atomic(RESULTS / "analysis.json", json.dumps(result, indent=1) + "\n")
    write_text_atomic(RESULTS / "results.md", report(result))
    print(report(result))
    return 0


def report(result: dict) -> str:
    def ci(values):
        return f"[{values[0]:.3f}, {values[1]:.3f}]"

    stats = result["statistics"]
    table = [["statistic (54 rigs never fitted on)", *PREDICTORS]]
    for label, key in (("pooled rho", "pooled_rho"), ("MAE", "mae")):
        table.append([f"{label} (95 % over rigs)", *(f"{stats[p][key]:.3f} {ci(stats[p][key + '_ci_rigs'])}"
                                                      for p in PREDICTORS)])
        table.append([f"{label} (95 % over sources)", *(ci(stats[p][key + "_ci_sources"]) for p in PREDICTORS)])
    for label, key in (("van: rho", "van_rho"), ("van: MAE", "van_mae"), ("van: rho on the designer's rigs",
                                                                          "van_designer_rho"),
                       ("benchmark rigs' variations: rho", "benchmark_rho"),
                       ("benchmark rigs' variations: MAE", "benchmark_mae")):
        table.append([label, *(f"{stats[p][key]:.3f}" for p in PREDICTORS)])
    table.append(["van: design vs naive copy as measured", *(str(stats[p]["design_vs_naive"]) for p in PREDICTORS)])
    for p in PREDICTORS[:2]:
        stats[p]["coverage_text"] = (", ".join(f"bin {b}: {c:.2f} (n {n})" for b, (c, n) in stats[p]["coverage"].items())
                                     + f"; all {stats[p]['coverage_all']:.2f}; mean width {stats[p]['mean_width']:.3f}")
    per_rig = [["rig", "kind", "measured", *PREDICTORS]] + [
        [r["rig"], r["kind"], f"{r['measured']:.3f}", *(f"{r[p]:.3f}" for p in PREDICTORS)] for r in result["per_rig"]]
    decision = ("lss-R1-v2 replaces lss-R1 as the default predictor" if result["v2_replaces_v1"]
                else "lss-R1 stays the default predictor")
    accepted = ", ".join(f"{k} {'met' if v else 'not met'}" for k, v in stats["lss-R1-v2"]["acceptance"].items())
    return (f"# Second predictor study: results ({result['rigs']} rigs, protocol {', '.join(result['protocols'])})\n\n"
            f"{markdown(table)}\n\n90 % interval coverage: lss-R1 {stats['lss-R1']['coverage_text']}; lss-R1-v2 "
            f"{stats['lss-R1-v2']['coverage_text']}.\n\nSeed agreement (one seed's drops against the other two's, "
            f"mean rho): all rigs {result['seed_agreement']['all']:.3f}, the van's designer rigs "
            f"{result['seed_agreement']['van_designer']:.3f}.\n\n**Decision (pre-registered rule): {decision}.** "
            f"lss-R1-v2 against the issue's acceptance: {accepted}.\n\n## Every rig\n\n{markdown(per_rig)}\n")


if __name__ == "__main__":
    sys.exit(main())
