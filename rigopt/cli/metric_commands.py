"""``rigopt rigv``, ``rigopt rigcd`` and ``rigopt rank``: rig metrics and predicted transfer."""

from __future__ import annotations

from dataclasses import asdict, replace
from typing import List, Optional

import typer

from rigopt.cli.app import PLACE_HELP, app, note, note_fallback, note_vehicle, print_json, print_table
from rigopt.errors import RigoptError

WEIGHTS_HELP = "Calibrated weights: a shipped name (BEVDet, BEVFusion, Fast-BEV, PETR, joint) or a weights JSON file."
METRIC_HELP = ("Rig distance: rigcd (the published RigCD, default) or rigcd+ (RigCD+: matching under the calibrated "
               "weights; see docs/metrics.md for the evidence).")
JSON_HELP = "Print JSON instead of a table."
PREDICTOR_HELP = ("What predicts the drop: auto (default: the shipped model of the measured drop where the reference is "
                  "its detector's training rig and its study found it better than RigCD, else RigCD under --weights), "
                  "rigcd, or a drop model's name (lss-R1). See docs/metrics.md.")
#: The calibration predictions use when none is named.
DEFAULT_WEIGHTS = "joint"


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
    weights: Optional[str] = typer.Option(None, help=WEIGHTS_HELP + " Its lambdas weight rigcd and match; without "
                                                  "it they have unit weights and the predicted drop a -> b uses the "
                                                  "joint calibration."),
    metric: str = typer.Option("rigcd", "--metric", help=METRIC_HELP + " Needs --weights for rigcd+."),
    predictor: str = typer.Option("auto", "--predictor", help=PREDICTOR_HELP),
    vehicle: Optional[str] = typer.Option(None, "--vehicle", help=PLACE_HELP),
    as_json: bool = typer.Option(False, "--json", help=JSON_HELP),
):
    """Rig Contrastive Distance between two rigs, its components and the predicted drop, with its interval.

    Rigs measured from different origins (the benchmark's vehicle centre, a dataset's rear axle) are
    converted to their vehicles' centres first, and the conversion is reported."""
    from rigopt.metrics.calibration import check_metric, load_weights
    from rigopt.metrics.drop_model import choose_model
    from rigopt.metrics.ranking import predict_transfer
    from rigopt.metrics.view_overlap import view_overlap
    from rigopt.mounting.candidates import rig_body_share

    metric = check_metric(metric)
    if metric == "rigcd+" and not weights:
        raise RigoptError("--metric rigcd+ matches cameras under calibrated weights: add --weights (e.g. joint)")
    calibration = load_weights(weights or DEFAULT_WEIGHTS, metric)
    (rig_a, rig_b), changes, left_out = _comparable([a, b], vehicle)
    model = choose_model(predictor, rig_a, weights is not None or metric != "rigcd")
    p = predict_transfer(rig_a, [rig_b], calibration, model, rig_body_share)[0]
    if weights is None and calibration.lifting is None:  # RigCD's unit-weight distance, the default drop
        unit = predict_transfer(rig_a, [rig_b], None)[0]
        p = replace(p, rigcd=unit.rigcd, match=unit.match)
    overlap = view_overlap(rig_a, rig_b)
    _note_changes((rig_a, rig_b), changes)
    data = {"a": p.reference, "b": p.rig, **{k: v for k, v in p.to_dict().items() if k not in ("reference", "rig")},
            "weights": weights or f"{DEFAULT_WEIGHTS} (default)", "origin_changes": [c.as_dict() for c in changes],
            "near_field_left_out": left_out, **_overlap_fields(overlap)}
    if as_json:
        print_json(data)
        _warn_overlap([p], {p.rig: overlap})
        return
    distance = "unit weights" if weights is None and calibration.lifting is None else f"{calibration.name} weights"
    columns = [f"{metric} ({distance})", f"match ({distance})", "count", "t (m)", "r (rad)", "f (deg)",
               f"predicted drop ({p.predictor})", "interval", f"sees of {p.reference}"]
    drop = "-" if p.predicted_drop is None else p.predicted_drop
    print_table(f"{'RigCD' if calibration.lifting is None else metric} {p.reference} -> {p.rig}", columns,
                [[p.rigcd, p.match, p.count, p.t, p.r, p.f, drop, _interval(p), _overlap_cell(overlap)]])
    _warn_prediction([p], calibration, model)
    _warn_overlap([p], {p.rig: overlap})


@app.command("rank")
def rank_command(
    candidates: List[str] = typer.Argument(..., help="Candidate rigs: library names or rig files."),
    ref: str = typer.Option(..., "--ref", help="Reference rig the detector was trained on."),
    weights: Optional[str] = typer.Option(None, help=WEIGHTS_HELP + f" Default: {DEFAULT_WEIGHTS}."),
    metric: str = typer.Option("rigcd", "--metric", help=METRIC_HELP),
    predictor: str = typer.Option("auto", "--predictor", help=PREDICTOR_HELP),
    vehicle: Optional[str] = typer.Option(None, "--vehicle", help=PLACE_HELP),
    as_json: bool = typer.Option(False, "--json", help=JSON_HELP),
):
    """Rank candidate rigs by the predicted relative mAP drop of a detector trained on the reference.

    Rigs measured from different origins are converted to their vehicles' centres first (reported)."""
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.drop_model import choose_model
    from rigopt.metrics.ranking import model_predictor, rank_candidates, rigcd_predictor
    from rigopt.metrics.view_overlap import view_overlaps
    from rigopt.mounting.candidates import rig_body_share

    calibration = load_weights(weights or DEFAULT_WEIGHTS, metric)
    (reference, *others), changes, left_out = _comparable([ref, *candidates], vehicle)
    model = choose_model(predictor, reference, weights is not None or metric != "rigcd")
    ranked = rank_candidates(reference, others, calibration, model, rig_body_share)
    overlaps = dict(zip((rig.name for rig in others), view_overlaps(reference, others).tolist()))
    _note_changes((reference, *others), changes)
    if as_json:
        print_json([{**p.to_dict(), "near_field_left_out": left_out.get(p.rig, 0), **_overlap_fields(overlaps[p.rig])}
                    for p in ranked])
        _warn_overlap(ranked, overlaps)
        return
    by = rigcd_predictor(calibration) if model is None else model_predictor(model)
    print_table(f"Candidates ranked by predicted drop from {ref} ({by})",
                ["rank", "rig", "predicted drop", "interval", f"sees of {reference.name}",
                 f"{calibration.metric} ({calibration.name} weights)", "t (m)", "r (rad)", "f (deg)", "count",
                 "extrapolates"],
                [[k + 1, p.rig, p.predicted_drop, _interval(p), _overlap_cell(overlaps[p.rig]), p.rigcd, p.t, p.r, p.f,
                  p.count, "yes" if p.extrapolation else "-"] for k, p in enumerate(ranked)])
    _warn_prediction(ranked, calibration, model)
    _warn_overlap(ranked, overlaps)


def _comparable(names: List[str], vehicle: Optional[str]):
    """The perception cameras of the rigs ``names`` in one frame (:func:`rigopt.vehicle.placement.comparable_rigs`),
    the origin changes made (:func:`_note_changes` says them once the command has succeeded) and {rig name: number
    of near_field cameras left out} of the rigs that have some. A name may be a packed reference (``nuscenes``)."""
    from rigopt.validation.detectors.shipped import reference_rig
    from rigopt.vehicle.library import load_vehicle
    from rigopt.vehicle.placement import comparable_rigs

    loaded = [reference_rig(name) for name in names]
    rigs, changes = comparable_rigs([_perception(rig) for rig in loaded],
                                    load_vehicle(vehicle) if vehicle is not None else None)
    return rigs, changes, {rig.name: rig.near_field_count for rig in loaded if rig.near_field_count}


def _perception(rig):
    """The rig's perception cameras, the ones a detector is fed and the rig distances compare; a note when
    near_field cameras are left out."""
    if rig.near_field_count:
        note(f"{rig.name}: its {rig.near_field_count} near_field camera(s) are not fed to the detector and are left "
             f"out; the distance compares its {len(rig) - rig.near_field_count} perception camera(s)")
    return rig.perception()


def _note_changes(rigs, changes) -> None:
    """A note per converted rig naming the vehicle and the origins used (``rigs`` as :func:`_comparable` gave
    them, in one frame; the names are the rigs' own)."""
    from rigopt.vehicle.library import load_vehicle

    by_name = {rig.name: rig for rig in rigs}
    for change in changes:
        note_vehicle(by_name[change.rig], load_vehicle(change.vehicle), change)


def _interval(p) -> str:
    """The interval's cell: '[low, high]', '-' without one, 'uninformative' where it spans the range a drop can
    take (:func:`_warn_prediction` says so in full)."""
    if p.interval is None:
        return "-"
    return "uninformative" if not p.interval_informative else f"[{p.interval[0]:.2f}, {p.interval[1]:.2f}]"


def _overlap_fields(overlap: float) -> dict:
    """The JSON fields of a candidate's view overlap with the reference (:mod:`rigopt.metrics.view_overlap`):
    ``view_overlap`` (null where the reference sees no direction of the grid) and ``low_view_overlap``."""
    from rigopt.metrics.view_overlap import low_view_overlap

    return {"view_overlap": overlap, "low_view_overlap": low_view_overlap(overlap)}


def _overlap_cell(overlap: float) -> str:
    """The view overlap's cell: '97 %', or '0 % LOW' below the threshold (:func:`_warn_overlap` says why)."""
    from rigopt.metrics.view_overlap import low_view_overlap, percent

    return f"{percent(overlap)} LOW" if low_view_overlap(overlap) else percent(overlap)


def _warn_overlap(predictions, overlaps: dict) -> None:
    """One warning line per prediction whose candidate sees less of the reference's view than
    LOW_VIEW_OVERLAP (``overlaps``: {candidate name: view overlap}): its predicted drop, and so its rank, is not
    to be read as good."""
    from rigopt.metrics.view_overlap import LOW_VIEW_OVERLAP, low_overlap_text, low_view_overlap, percent

    for p in predictions:
        if low_view_overlap(overlaps[p.rig]):
            typer.echo(f"rigopt: warning: {p.reference} -> {p.rig}: {low_overlap_text(p.reference, overlaps[p.rig])} "
                       f"(view overlap below {percent(LOW_VIEW_OVERLAP)}, docs/metrics.md); do not read its rank or "
                       "drop as good", err=True)


def _warn_prediction(predictions, calibration, model=None) -> None:
    """Notes under a table: uninformative intervals, pairs outside the calibration data (or a drop ``model``'s
    fitting rigs), a fallback calibration."""
    from rigopt.metrics.prediction import UNINFORMATIVE_TEXT

    if model is not None:
        note(f"predicted by the {model.name} drop model, a model of the measured drop of {model.detector} "
             f"({model.study}); RigCD under --weights is in its columns and with --predictor rigcd")
        for p in predictions:
            if p.extrapolation is not None:
                note(f"{p.reference} -> {p.rig} lies beyond the model's fitting rigs: {p.extrapolation.describe()}; "
                     "its predicted drop is less certain than the interval says")
        return
    wide = [p for p in predictions if p.interval is not None and not p.interval_informative]
    if wide:
        pairs = "every pair" if len(wide) == len(predictions) > 1 else ", ".join(f"{p.reference} -> {p.rig}"
                                                                               for p in wide)
        note(f"{pairs}: {UNINFORMATIVE_TEXT}: the {calibration.name} calibration's "
             f"{calibration.interval.level:.0%} interval is +-{calibration.interval.halfwidth:.2f}; the predicted "
             "drop is a point estimate only (--json keeps the numbers)")
    for p in predictions:
        if p.extrapolation is not None:
            note(f"{p.reference} -> {p.rig} extrapolates beyond the calibration pairs: {p.extrapolation.describe()}; "
                 "its predicted drop is less certain than the interval says")
    note_fallback(calibration)
