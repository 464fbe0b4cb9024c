"""Calibration study as data: the JSON report, the pairs CSV and the weights files of every fit."""

from __future__ import annotations

import csv
from pathlib import Path

from rigopt.metrics.calibration import FEATURES, CalibrationFit, write_weights
from rigopt.metrics.prediction import LinkChoice
from rigopt.metrics.protocol import BoundedAccuracy, CalibrationStudy, PairPredictions
from rigopt.metrics.reliability import finite_or_none


def weights_dict(fit: CalibrationFit) -> dict:
    """Reported weights of one fit, with both solvers' beta and their agreement."""
    c = fit.calibration
    data = {"K": c.K, "alpha": c.alpha, "lambda_t": c.lambda_t, "lambda_r": c.lambda_r, "lambda_f": c.lambda_f}
    data.update({f"beta_{k}": v for k, v in zip(FEATURES, c.beta)})
    data.update({
        "fallback": c.fallback,
        "solver": fit.solver,
        "beta_lbfgsb": dict(zip(FEATURES, fit.beta_lbfgsb)),
        "beta_qp": dict(zip(FEATURES, fit.beta_qp)),
        "objective_lbfgsb": fit.objective_lbfgsb,
        "objective_qp": fit.objective_qp,
        "qp_agrees": fit.qp_agrees,
        "n": fit.n,
    })
    return data


def link_dict(fit: CalibrationFit, choice: LinkChoice) -> dict:
    """The bounded link of a fit: its kind and parameters, the leave-one-control-rig-out MAE of every
    candidate link (the smallest chosen), the prediction interval (with ``interval_informative``) and the
    folds' exact betas (``fold_betas``: left-out control rig -> {t, r, f, count})."""
    return {**choice.link.to_dict(), "loro_mae": choice.loro_mae,
            "interval": {**choice.interval.to_dict(), "interval_informative": choice.interval.informative},
            "fold_betas": {rig: dict(zip(FEATURES, map(float, beta))) for rig, beta in choice.fold_betas.items()}}


def intervals_dict(study: CalibrationStudy) -> dict:
    """The prediction intervals judged on the held-out pairs (``IntervalReport.to_dict``): ``models`` each
    detector's own fit, ``joint`` the joint fit on each detector's pairs."""
    def report(entry):
        return entry.interval_heldout.to_dict() if entry.interval_heldout is not None else None

    return {"models": {m.model: report(m) for m in study.models},
            "joint": {r.model: report(r) for r in study.joint.models}}


def bounded_dict(control: BoundedAccuracy, heldout: BoundedAccuracy) -> dict:
    """MAE, RMSE and interval coverage of the bounded drop on control and held-out pairs."""
    return {"control": control.to_dict(), "heldout": heldout.to_dict()}


def study_dict(study: CalibrationStudy) -> dict:
    """The JSON of ``rigopt calibrate``: ``{"metric", "models": {M: {"weights", "link", "control", "heldout",
    "bounded", "knockout"}}, "joint": {"weights", "link", "models": {M: {"control", "heldout", "bounded"}}}}``
    plus the control rigs and the skipped training rigs. ``control``/``heldout`` judge the linear prediction
    (the benchmark's figures: rho, CI, MAE, RMSE); ``bounded`` the predicted drop through the link (MAE, RMSE,
    and the fraction of pairs inside the prediction interval); ``intervals`` (:func:`intervals_dict`) the
    interval per predicted-drop bin on the held-out pairs, beside the best constant predictor."""
    models = {
        m.model: {
            "weights": weights_dict(m.fit),
            "link": link_dict(m.fit, m.link_choice),
            "control": m.control.to_dict(),
            "heldout": m.heldout.to_dict(),
            "bounded": bounded_dict(m.bounded_control, m.bounded_heldout),
            "knockout": {k: finite_or_none(getattr(m.knockout, k))
                         for k in ("full", "lambda_t", "lambda_r", "lambda_f", "count")},
        }
        for m in study.models
    }
    joint = {
        "weights": weights_dict(study.joint.fit),
        "link": link_dict(study.joint.fit, study.joint.link_choice),
        "models": {r.model: {"control": r.control.to_dict(), "heldout": r.heldout.to_dict(),
                             "bounded": bounded_dict(r.bounded_control, r.bounded_heldout)}
                   for r in study.joint.models},
    }
    return {"metric": study.metric, "control_rigs": list(study.control_rigs), "models": models, "joint": joint,
            "intervals": intervals_dict(study), "skipped": [list(s) for s in study.skipped]}


def transfer_dict(transfer, source_fit: CalibrationFit) -> dict:
    """A CalibrationTransfer as JSON: per target detector the transferred calibration's ``control`` and
    ``heldout`` agreement (linear prediction: rho, CI, MAE, RMSE) and ``bounded`` accuracy, beside the target's
    own per-detector and joint calibrations on the same pairs (``own_per_detector``, ``own_joint``), each with
    ``rho_gain``: the transferred calibration's held-out rho minus its own, ``{"value", "ci"}`` (paired
    bootstrap); ``weights``: those of ``source_fit``, the fit that was transferred."""
    own = {"own_per_detector": {m.model: m for m in transfer.own.models},
           "own_joint": {r.model: r for r in transfer.own.joint.models}}

    def own_entry(name: str, model: str) -> dict:
        fit, (gain, low, high) = own[name][model], transfer.gains[model][name]
        return {"heldout": fit.heldout.to_dict(), "bounded": bounded_dict(fit.bounded_control, fit.bounded_heldout),
                "rho_gain": {"value": finite_or_none(gain), "ci": [finite_or_none(low), finite_or_none(high)]}}

    return {
        "weights": weights_dict(source_fit),
        "models": {r.model: {
            "control": r.control.to_dict(), "heldout": r.heldout.to_dict(),
            "bounded": bounded_dict(r.bounded_control, r.bounded_heldout),
            **{name: own_entry(name, r.model) for name in own},
        } for r in transfer.models},
    }


PAIRS_HEADER = ["fit", "model", "train_rig", "test_rig", "split", *FEATURES, "delta", "predicted",
                "rank_observed", "rank_predicted", "rank_error", "drop", "low", "high"]


def pair_rows(pairs: PairPredictions, fit_name: str):
    """Rows of PAIRS_HEADER, one per pair: rigs, split, features, observed and linear predicted drop, ranks,
    and the bounded drop with its interval (low, high)."""
    for k in range(len(pairs.delta)):
        split = "control" if pairs.control[k] else "heldout"
        numbers = [*pairs.features[k], pairs.delta[k], pairs.predicted[k], pairs.rank_observed[k],
                   pairs.rank_predicted[k], pairs.rank_error[k], pairs.drop[k], pairs.low[k], pairs.high[k]]
        yield [fit_name, pairs.model[k], pairs.train[k], pairs.test[k], split, *(f"{float(v):.10g}" for v in numbers)]


def write_study_tables(study: CalibrationStudy, out_dir) -> list[Path]:
    """Write ``pairs.csv`` (every detector's own fit, then the joint fit) and ``weights/<fit>.json``."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    pairs_path = out_dir / "pairs.csv"
    with pairs_path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(PAIRS_HEADER)
        for m in study.models:
            writer.writerows(pair_rows(m.pairs, m.model))
        writer.writerows(pair_rows(study.joint.pairs, "joint"))
    weights = [write_weights(m.fit.calibration, out_dir / "weights" / f"{m.model}.json") for m in study.models]
    weights.append(write_weights(study.joint.fit.calibration, out_dir / "weights" / "joint.json"))
    return [pairs_path, *weights]
