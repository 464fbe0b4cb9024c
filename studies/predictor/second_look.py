"""Looks after the decision, not pre-registered: the predictor where nothing of it was fitted or chosen.

    python studies/predictor/second_look.py

1. The shipped model (fitted on this study's 329 rigs) on the validation study's 63 rigs (studies/validation/: R1
   variations, designs and copies on the fire truck, hgv and tt, measured under the full protocol on R1's 16 test
   scenes before this study; never used to fit the shipped model), beside RigCD; 95 % intervals resampling rigs
   (three vehicles are too few to resample).
2. New scenes and held-out vehicles: the drop-model designer study's measurements (studies/drop_model_designer/:
   five vehicles, 16 new scenes, quick-s1) predicted for each vehicle by the model fitted without it
   (``models/<V>.json``); the three yardsticks (today's design, the height-matched and the searched copy) apart
   from the two arms' designs, which minimised that very model; 95 % intervals resampling vehicles.

Writes ``results/second_look.md``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
VALIDATION = HERE.parent / "validation"
DESIGNER = HERE.parent / "drop_model_designer"
VEHICLES = ("tt", "renault_zoe", "ford_fusion_hybrid", "chrysler_pacifica_hybrid", "citybus")
ARMS = ("model", "model_free")
RESAMPLES, SEED = 2000, 0


def interval(statistic, units: int, draws_of) -> list[float]:
    """95 % percentile interval of ``statistic(index)`` over RESAMPLES draws of ``units`` units (``draws_of``
    turns drawn unit indices into a row index)."""
    rng = np.random.default_rng(SEED)
    values = [statistic(draws_of(rng.integers(units, size=units))) for _ in range(RESAMPLES)]
    values = [v for v in values if np.isfinite(v)]
    return [float(np.percentile(values, 2.5)), float(np.percentile(values, 97.5))]


def rho(a, b) -> float:
    from rigopt.metrics.reliability import spearman

    return float(spearman(a, b)[0]) if len(set(np.round(b, 12))) > 1 else float("nan")


def validation_rigs() -> str:
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.drop_model import load_drop_model
    from rigopt.metrics.ranking import predict_transfer
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.placement import in_vehicle_frame

    entries = [json.loads(line) for line in (VALIDATION / "results" / "measured.jsonl").read_text().splitlines()]
    rigs = []
    for entry in entries:
        path = VALIDATION / "rigs" / f"{entry['rig']}.json"
        rigs.append(in_vehicle_frame(load_rig(path if path.is_file() else entry["rig"]))[0].perception())
    reference, model = load_rig("R1"), load_drop_model("lss-R1")
    predicted, halfwidths, _ = model.predict(reference, rigs)
    rigcd = np.array([p.predicted_drop for p in predict_transfer(reference, rigs, load_weights("joint"))])
    measured = np.array([e["drop"] for e in entries])
    vehicles = np.array([e["vehicle"] for e in entries])
    rows = ["| vehicles | rigs | rho model | rho RigCD | MAE model | MAE RigCD |", "|---|---|---|---|---|---|"]
    for name, keep in [*((v, vehicles == v) for v in np.unique(vehicles)), ("all (pooled)", np.ones(len(entries), bool))]:
        index = np.flatnonzero(keep)
        cells = []
        for statistic in (lambda k, p: rho(p[k], measured[k]), lambda k, p: float(np.abs(p[k] - measured[k]).mean())):
            for prediction in (predicted, rigcd):
                low, high = interval(lambda k: statistic(k, prediction), len(index), lambda d: index[d])
                cells.append(f"{statistic(index, prediction):.3f} [{low:.3f}, {high:.3f}]")
        rows.append(f"| {name} | {keep.sum()} | {cells[0]} | {cells[1]} | {cells[2]} | {cells[3]} |")
    worst = np.argsort(-np.abs(predicted - measured))[:5]
    return ("## 1. The shipped model on the validation study's 63 rigs (full protocol, R1's test scenes; 95 % over "
            "resampled rigs)\n\n" + "\n".join(rows)
            + f"\n\n90 % interval coverage: {np.mean(np.abs(predicted - measured) <= halfwidths):.3f}.\n\n"
            "Largest errors:\n\n" + "\n".join(f"- {entries[k]['rig']}: measured {measured[k]:.3f}, predicted "
                                              f"{predicted[k]:.3f}" for k in worst) + "\n")


def new_scenes() -> str:
    from rigopt.metrics.drop_model import load_drop_model
    from rigopt.rig.library import load_rig

    reference = load_rig("R1")
    rows, measured, predicted, vehicle_of, is_arm = [], [], [], [], []
    for v, vehicle in enumerate(VEHICLES):
        cell = json.loads((DESIGNER / "results" / f"{vehicle}_quick-s1.json").read_text())
        model = load_drop_model(DESIGNER / "models" / f"{vehicle}.json")
        rigs = [load_rig(DESIGNER / "rigs" / f"{e['rig']}.json") if e["rig"].endswith(ARMS)
                else load_rig(HERE / "rigs" / f"{e['rig']}.json") for e in cell["rigs"]]
        predicted += model.predict(reference, rigs)[0].tolist()
        measured += [e["drop"] for e in cell["rigs"]]
        vehicle_of += [v] * len(rigs)
        is_arm += [e["rig"].endswith(ARMS) for e in cell["rigs"]]
    measured, predicted, vehicle_of, is_arm = map(np.array, (measured, predicted, vehicle_of, is_arm))
    for name, keep in (("yardsticks (today's design, height-matched and searched copy)", ~is_arm),
                       ("the arms' designs (made by minimising the same model)", is_arm),
                       ("all", np.ones(len(measured), bool))):
        rows_of = lambda drawn: np.concatenate([np.flatnonzero(keep & (vehicle_of == v)) for v in drawn])  # noqa: E731
        index = np.flatnonzero(keep)
        mae = float(np.abs(predicted[index] - measured[index]).mean())
        mae_ci = interval(lambda k: float(np.abs(predicted[k] - measured[k]).mean()), len(VEHICLES), rows_of)
        pooled = rho(predicted[index], measured[index])
        pooled_ci = interval(lambda k: rho(predicted[k], measured[k]), len(VEHICLES), rows_of)
        rows.append(f"| {name} | {len(index)} | {mae:.3f} [{mae_ci[0]:.3f}, {mae_ci[1]:.3f}] | "
                    f"{pooled:.3f} [{pooled_ci[0]:.3f}, {pooled_ci[1]:.3f}] |")
    return ("## 2. New scenes (quick-s1) on held-out vehicles, each predicted by the model fitted without it (95 % "
            "over resampled vehicles)\n\n| rigs | n | MAE | pooled rho |\n|---|---|---|---|\n" + "\n".join(rows) + "\n")


def main() -> int:
    from rigopt.output import write_text_atomic

    text = ("# The predictor where nothing of it was fitted or chosen (looks after the decision, not pre-registered)\n\n"
            + validation_rigs() + "\n" + new_scenes())
    write_text_atomic(HERE / "results" / "second_look.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
