"""``rigopt rigv``, ``rigopt rigcd`` and ``rigopt rank``: rig metrics and predicted transfer."""

from __future__ import annotations

from dataclasses import asdict
from typing import List, Optional

import typer

from rigopt.cli.app import PLACE_HELP, app, note, print_json, print_table
from rigopt.errors import RigoptError

WEIGHTS_HELP = "Calibrated weights: a shipped name (BEVDet, BEVFusion, Fast-BEV, PETR, joint) or a weights JSON file."
METRIC_HELP = ("Rig distance: rigcd (the published RigCD, default) or rigcd+ (RigCD+: matching under the calibrated "
               "weights; see docs/metrics.md for the evidence).")
JSON_HELP = "Print JSON instead of a table."


@app.command("rigv")
def rigv_command(
    rigs: List[str] = typer.Argument(..., help="Library rig names or rig files."),
    weights: Optional[str] = typer.Option(None, help=WEIGHTS_HELP + " Its lambdas weight the three terms."),
    as_json: bool = typer.Option(False, "--json", help=JSON_HELP),
):
    """Rig Variance of each rig: how diverse its cameras are (positions, orientations, FOVs)."""
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.rigcd import DEFAULT_LAMBDAS
    from rigopt.metrics.rigv import rigv
    from rigopt.rig.library import load_rig

    lambdas = load_weights(weights).lambdas if weights else DEFAULT_LAMBDAS
    results = [rigv(load_rig(name), lambdas) for name in rigs]
    if as_json:
        print_json([{k: v for k, v in asdict(r).items() if k != "lambdas"} for r in results])
        return
    print_table("Rig Variance", ["rig", "rigv", "tv (m)", "rv (rad)", "fv (deg)", "dmax (m)"],
                [[r.rig, r.rigv, r.tv, r.rv, r.fv, r.dmax] for r in results])


@app.command("rigcd")
def rigcd_command(
    a: str = typer.Argument(..., help="First rig: library name or rig file."),
    b: str = typer.Argument(..., help="Second rig: library name or rig file."),
    weights: Optional[str] = typer.Option(None, help=WEIGHTS_HELP + " Adds the predicted drop a -> b."),
    metric: str = typer.Option("rigcd", "--metric", help=METRIC_HELP + " Needs --weights for rigcd+."),
    vehicle: Optional[str] = typer.Option(None, "--vehicle", help=PLACE_HELP),
    as_json: bool = typer.Option(False, "--json", help=JSON_HELP),
):
    """Rig Contrastive Distance between two rigs, its components and (with --weights) the predicted drop.

    Rigs measured from different origins (the benchmark's vehicle centre, a dataset's rear axle) are
    converted to their vehicles' centres first, and the conversion is reported."""
    from rigopt.metrics.calibration import check_metric, load_weights
    from rigopt.metrics.ranking import predict_transfer

    metric = check_metric(metric)
    if metric == "rigcd+" and not weights:
        raise RigoptError("--metric rigcd+ matches cameras under calibrated weights: add --weights (e.g. joint)")
    calibration = load_weights(weights, metric) if weights else None
    (rig_a, rig_b), changes = _comparable([a, b], vehicle)
    p = predict_transfer(rig_a, [rig_b], calibration)[0]
    data = {"a": p.reference, "b": p.rig, "rigcd": p.rigcd, "match": p.match, "count": p.count,
            "t": p.t, "r": p.r, "f": p.f, "predicted_drop": p.predicted_drop,
            "origin_changes": [c.as_dict() for c in changes]}
    if as_json:
        print_json(data)
        return
    columns = ["rigcd", "match", "count", "t (m)", "r (rad)", "f (deg)", "predicted drop"]
    drop = "-" if p.predicted_drop is None else p.predicted_drop
    print_table(f"RigCD {p.reference} -> {p.rig}", columns, [[p.rigcd, p.match, p.count, p.t, p.r, p.f, drop]])


@app.command("rank")
def rank_command(
    candidates: List[str] = typer.Argument(..., help="Candidate rigs: library names or rig files."),
    ref: str = typer.Option(..., "--ref", help="Reference rig the detector was trained on."),
    weights: str = typer.Option("joint", help=WEIGHTS_HELP),
    metric: str = typer.Option("rigcd", "--metric", help=METRIC_HELP),
    vehicle: Optional[str] = typer.Option(None, "--vehicle", help=PLACE_HELP),
    as_json: bool = typer.Option(False, "--json", help=JSON_HELP),
):
    """Rank candidate rigs by the predicted relative mAP drop of a detector trained on the reference.

    Rigs measured from different origins are converted to their vehicles' centres first (reported)."""
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.ranking import rank_candidates

    calibration = load_weights(weights, metric)
    (reference, *others), _ = _comparable([ref, *candidates], vehicle)
    ranked = rank_candidates(reference, others, calibration)
    if as_json:
        print_json([{"rig": p.rig, "predicted_drop": p.predicted_drop, "rigcd": p.rigcd, "t": p.t, "r": p.r,
                     "f": p.f, "count": p.count} for p in ranked])
        return
    print_table(f"Candidates ranked by predicted drop from {ref} ({calibration.metric}, {weights} weights)",
                ["rank", "rig", "predicted drop", "rigcd", "t (m)", "r (rad)", "f (deg)", "count"],
                [[k + 1, p.rig, p.predicted_drop, p.rigcd, p.t, p.r, p.f, p.count] for k, p in enumerate(ranked)])


def _comparable(names: List[str], vehicle: Optional[str]):
    """The rigs ``names`` in one frame (:func:`rigopt.vehicle.placement.comparable_rigs`), each origin change
    reported as a note; returns (rigs, changes)."""
    from rigopt.rig.library import load_rig
    from rigopt.vehicle.library import load_vehicle
    from rigopt.vehicle.placement import comparable_rigs

    rigs, changes = comparable_rigs([load_rig(name) for name in names],
                                    load_vehicle(vehicle) if vehicle is not None else None)
    for change in changes:
        note(change.describe())
    return rigs, changes
