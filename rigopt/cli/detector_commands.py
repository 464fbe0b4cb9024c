"""``rigopt bench train | evaluate | matrix`` and ``rigopt validate``: the torch detectors and the protocol.

torch is imported only inside these commands, so the rest of rigopt runs without it.
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import List, Optional

import typer

from rigopt.cli.app import (app, console, note, note_fallback, print_json, print_table, resumable,
                            status_console)
from rigopt.cli.bench_commands import bench_app
from rigopt.cli.metric_commands import METRIC_HELP, PREDICTOR_HELP
from rigopt.errors import RigoptError
from rigopt.validation.detectors.measuring import DEFAULT_PROTOCOL, protocol_named

MODEL_HELP = ("Detector family, a name in the registry (rigopt.validation.detectors.families): lss (lift-splat, BEVDet-like), "
              "petr (3D position embeddings, PETR-like), ...; an unknown name lists them.")
SIZE_HELP = "Model size preset: tiny (tests), small (CPU), base (GPU)."
DEVICE_HELP = "cpu, cuda or cuda:K."
RUNS_HELP = "Training runs folder (<runs>/<model>/<rig>/checkpoint.pt); default <data>/runs."


DATA_HOLDING = "the benchmark's rig folders (<data>/<rig>/<split>, made by rigopt bench generate --out)"
RUNS_HOLDING = "the training runs (<runs>/<model>/<rig>/checkpoint.pt, made by rigopt bench train)"


def check_data(data: Path) -> Path:
    """``--data`` must be an existing folder: a missing one is said as such, not as a missing trained model."""
    from rigopt.output import existing_folder

    return existing_folder(data, DATA_HOLDING, option="--data")


def check_runs(runs: Path | None, must_exist: bool) -> None:
    """``--runs``, when given, must be a folder: an existing one where runs are read (``must_exist``), else a folder
    or a place for one (training makes it)."""
    from rigopt.output import existing_folder

    if runs is not None and (must_exist or runs.exists()):
        existing_folder(runs, RUNS_HOLDING, option="--runs")


def require_torch() -> None:
    try:
        import torch  # noqa: F401
    except ImportError:
        raise RigoptError("the baselines need torch: pip install torch==2.13.0 (or pip install -e '.[bench]')") from None


@contextlib.contextmanager
def training_bar(label: str):
    """A progress bar; yields ``step(epoch, step, total_steps, loss)`` to advance it."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    columns = (TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total} steps"),
               TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(*columns, console=status_console, transient=True) as progress:
        task = progress.add_task(label, total=None)

        def step(epoch: int, done: int, total: int, loss: float) -> None:
            progress.update(task, completed=done, total=total,
                            description=f"{label} | epoch {epoch + 1} | loss {loss:.3f}")

        yield step


@bench_app.command("train")
def train_command(
    data: Path = typer.Option(..., "--data", help="Benchmark folder made by rigopt bench generate (<data>/<rig>/train)."),
    rig: str = typer.Option(..., "--rig", help="Rig to train on (a folder under --data)."),
    model: str = typer.Option(..., "--model", help=MODEL_HELP),
    size: str = typer.Option("small", "--size", help=SIZE_HELP),
    epochs: Optional[int] = typer.Option(None, "--epochs", help="Epochs in total (default: the size preset's)."),
    device: str = typer.Option("cpu", "--device", help=DEVICE_HELP),
    seed: int = typer.Option(0, "--seed", help="Seed of the weights and the sample order."),
    runs: Optional[Path] = typer.Option(None, "--runs", help=RUNS_HELP),
):
    """Train a detector on one rig's train split; rerun to resume from the last finished epoch."""
    require_torch()
    from rigopt.validation.detectors.config import model_config
    from rigopt.validation.detectors.models import resolve_device
    from rigopt.validation.detectors.protocol import configured, train_on

    check_data(data)
    check_runs(runs, must_exist=False)
    config = configured(model_config(model, size), epochs)
    resolve_device(device)
    runs = runs if runs is not None else data / "runs"
    resumable(f"rerun the same command: training goes on from the last finished epoch in {runs}")
    with training_bar(f"{config.family} on {rig}") as step:
        run = train_on(data, rig, config, runs, device, seed, step)
    if run.steps_now == 0:
        console.print(f"{config.family} on {rig}: already trained for {run.epochs} epochs; checkpoint {run.checkpoint} "
                      "(ask for more with --epochs)")
        return
    console.print(f"{config.family} on {rig}: {run.epochs}/{config.epochs} epochs, final epoch loss "
                  f"{run.final_loss:.4f}, {run.samples_per_second:.1f} samples/s; checkpoint {run.checkpoint}, "
                  f"log {run.folder / 'train_log.csv'}")


@bench_app.command("evaluate")
def evaluate_command(
    data: Path = typer.Option(..., "--data", help="Benchmark folder (<data>/<rig>/<split>)."),
    rig: str = typer.Option(..., "--rig", help="Rig whose split to test on."),
    model: str = typer.Option(..., "--model", help=MODEL_HELP),
    trained_on: Optional[str] = typer.Option(None, "--trained-on", help="Rig the model was trained on (its run "
                                                                        "under --runs); default: --rig."),
    checkpoint: Optional[Path] = typer.Option(None, "--checkpoint", help="A checkpoint file instead of --trained-on."),
    split: str = typer.Option("test", "--split", help="Split to test on."),
    device: str = typer.Option("cpu", "--device", help=DEVICE_HELP),
    runs: Optional[Path] = typer.Option(None, "--runs", help=RUNS_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print the benchmark's metrics JSON."),
):
    """Evaluate a trained detector on any rig's split: centre-distance AP per class and mAP, against every
    annotated object (fixed set) and against the objects the rig sees (visible-only)."""
    require_torch()
    from rigopt.validation.detectors.config import model_config
    from rigopt.validation.synthetic.evaluation import DEFAULT_THRESHOLDS
    from rigopt.validation.detectors.protocol import evaluate_on, run_folder
    from rigopt.validation.synthetic.scene_model import CLASSES

    check_data(data)
    family = model_config(model).family
    if checkpoint is not None:
        from rigopt.output import existing_file

        existing_file(checkpoint, "checkpoint file (checkpoint.pt, written by rigopt bench train)",
                      option="--checkpoint")
    check_runs(runs, must_exist=checkpoint is None)
    if checkpoint is None:
        checkpoint = run_folder(runs if runs is not None else data / "runs", family, trained_on or rig) / "checkpoint.pt"
    with status_console.status(f"evaluating {checkpoint} on {rig}/{split}"):
        metrics = evaluate_on(checkpoint, data, rig, device, family, split)
    if as_json:
        print_json(metrics)
        return
    raw, raw_visible = metrics["raw"], metrics["raw_visible"]
    rows = [[name, *(_number(raw[f"{name}_AP_dist_{d}"]) for d in DEFAULT_THRESHOLDS),
             *(_number(raw_visible[f"{name}_AP_dist_{d}"]) for d in DEFAULT_THRESHOLDS)] for name in CLASSES]
    print_table(f"{family} ({checkpoint.parent.name}) on {rig}/{split}: mAP {_number(metrics['mAP'])} (every "
                f"annotated object), visible-only mAP {_number(metrics['mAP_visible'])} (the objects {rig} sees)",
                ["class", *(f"AP@{d:g} m" for d in DEFAULT_THRESHOLDS),
                 *(f"visible AP@{d:g} m" for d in DEFAULT_THRESHOLDS)], rows)


@bench_app.command("matrix")
def matrix_command(
    data: Path = typer.Option(..., "--data", help="Benchmark folder with train and test splits of every rig."),
    rigs: List[str] = typer.Option(..., "--rigs", help="Rigs: each is trained on and tested on; more may follow as "
                                                       "arguments (--rigs R1 R1-c6 R2) or commas."),
    more: List[str] = typer.Argument(None, hidden=True),
    model: str = typer.Option(..., "--model", help=MODEL_HELP),
    out: Path = typer.Option(..., "--out", help="Results folder: <out>/<model>/trained_on_<rig>.json."),
    size: str = typer.Option("small", "--size", help=SIZE_HELP),
    epochs: Optional[int] = typer.Option(None, "--epochs", help="Epochs per training run (default: the preset's)."),
    device: str = typer.Option("cpu", "--device", help=DEVICE_HELP),
    seed: int = typer.Option(0, "--seed", help="Seed of every training run."),
    runs: Optional[Path] = typer.Option(None, "--runs", help=RUNS_HELP),
    ray: Optional[str] = typer.Option(None, "--ray", help="Run each training as a task on the Ray cluster at this "
                                                          "address ('local' starts one here)."),
    workers: int = typer.Option(1, "--workers", min=1, help="Train (and test) this many rigs at once in processes "
                                                           "on this machine, sharing --device."),
):
    """Train on every rig, test on every rig, write the benchmark's results layout (resumable)."""
    require_torch()
    from rigopt.validation.detectors.config import model_config
    from rigopt.validation.detectors.models import resolve_device
    from rigopt.validation.detectors.protocol import configured, transfer_matrix
    from rigopt.metrics.transfer import read_transfer

    from rigopt.output import check_out_folder

    check_out_folder(out, resume=True)
    check_data(data)
    check_runs(runs, must_exist=False)
    config = configured(model_config(model, size), epochs)
    resolve_device(device)
    names = [n.strip() for text in [*rigs, *(more or [])] for n in text.split(",") if n.strip()]
    resumable(f"rerun the same command: finished results in {out} are kept, training goes on from the last "
              "finished epoch")
    with training_bar(f"{config.family} matrix") as step:
        transfer_matrix(data, names, config, out, runs, device, seed, ray,
                        lambda message: console.print(message), step, workers)
    table = read_transfer(out)
    value = {(m, a, b): v for m, a, b, v in zip(table.model, table.train, table.test, table.map)}
    rows = [[a, *(_number(value.get((config.family, a, b))) for b in names)] for a in names]
    print_table(f"{config.family}: mAP (every annotated object), trained on (rows) x tested on (columns); "
                f"results in {out}", ["trained on", *names], rows)
    visible = _visible_maps(out, config.family, names)
    rows = [[a, *(_number(visible.get((a, b))) for b in names)] for a in names]
    print_table(f"{config.family}: visible-only mAP (the objects the test rig sees)", ["trained on", *names], rows)


@app.command("validate")
def validate_command(
    designs: List[Path] = typer.Argument(..., metavar="RIG", help="The rigs: rig files, report.json files of "
                                         "rigopt design or library rigs (several share the loaded models; one with "
                                         "--data or --compare)."),
    ref: str = typer.Option(..., "--ref", help="Reference rig the detector was trained on."),
    model: Optional[str] = typer.Option(None, "--model", help=MODEL_HELP + " Default lss, unless --detector."),
    detector: Optional[str] = typer.Option(None, "--detector", help="Your own detector behind rigopt's detector "
                                           "contract (docs/detectors.md): a TorchScript file (rigopt detectors "
                                           "export makes one from a rigopt model) or package.module:factory. It is "
                                           "scored as the shipped models are, on the reference's test scenes "
                                           "rendered at its declared image size, the reference included."),
    detectors: Optional[Path] = typer.Option(None, "--detectors", help="Without --data: the folder of packed models "
                                             "to take --model's from (<dir>/<model>-<ref>/, made by rigopt detectors "
                                             "train); default $RIGOPT_DETECTORS, else the shipped ones."),
    data: Optional[Path] = typer.Option(None, "--data", help="Benchmark folder with the reference's test split and a "
                                        "trained run (rigopt bench generate, bench train). Without it, the models "
                                        "rigopt ships score the rig on the reference's test scenes, rendered into "
                                        "--cache."),
    weights: Optional[str] = typer.Option(None, "--weights", help="Calibrated RigCD weights for the predicted drops "
                                          "(default joint)."),
    metric: str = typer.Option("rigcd", "--metric", help=METRIC_HELP),
    predictor: str = typer.Option("auto", "--predictor", help=PREDICTOR_HELP),
    device: str = typer.Option("cpu", "--device", help=DEVICE_HELP),
    runs: Optional[Path] = typer.Option(None, "--runs", help=RUNS_HELP + " Needs --data."),
    cache: Optional[Path] = typer.Option(None, "--cache", help="Without --data: where the renderings are kept "
                                         "(default $RIGOPT_HOME/cache/validate, ~/.rigopt/cache/validate)."),
    workers: int = typer.Option(0, "--workers", min=0, help="Without --data: rendering processes (0: one per core)."),
    ray: Optional[str] = typer.Option(None, "--ray", help="Without --data: render each (rig, scene) pair and score "
                                      "each (rig, seed) as a task on the Ray cluster at this address ('local' "
                                      "starts one here); --cache must be on storage every node sees. The same "
                                      "figures as on one machine."),
    protocol: Optional[str] = typer.Option(None, "--protocol", help="Without --data: full (every frame of the "
                                           "reference's test scenes) or quick (every 4th frame, a quarter of the "
                                           "time; mean |quick - full| 0.005 on 63 rigs, "
                                           "studies/validation/protocol) or quick-s1 (quick's frames of 16 new "
                                           "scenes, to replicate a finding); "
                                           f"default {DEFAULT_PROTOCOL.name}."),
    compare: bool = typer.Option(False, "--compare", help="Without --data: also measure the hand-designed rigs of "
                                 "the rig's vehicle and the naive and height-matched transfers of the reference "
                                 "(as --data always does)."),
    out: Optional[Path] = typer.Option(None, "--out", help="Also write the result as JSON here."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
):
    """Measure rigs' transfer drops with a reference-trained detector, beside the predicted drops."""
    require_torch()
    import json

    from rigopt.validation.detectors.config import EXTERNAL_FAMILY, model_config
    from rigopt.validation.detectors.models import resolve_device
    from rigopt.validation.designs import contradictions, load_design, validate_design
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.drop_model import choose_model
    from rigopt.report.json_values import json_ready

    from rigopt.output import check_out_file, existing_file, write_text_atomic
    from rigopt.rig.library import rig_names
    from rigopt.validation.detectors.shipped import reference_rig

    if out is not None:
        check_out_file(out, suffixes=(".json",))
    for design in designs:
        if not (not design.exists() and str(design) in rig_names()):
            existing_file(design, "design file (a rig file, the report.json of rigopt design, or a library rig's name)")
    if len(designs) > 1 and (data is not None or compare):
        raise RigoptError(f"--{'data' if data is not None else 'compare'} validates one rig at a time; give one RIG "
                          f"(got {len(designs)})")
    if data is None and runs is not None:
        raise RigoptError("--runs names trained runs of a --data folder: add --data, or leave --runs out to use the "
                          "shipped models")
    if data is not None and (protocol is not None or ray is not None):
        option = "--protocol" if protocol is not None else "--ray"
        raise RigoptError(f"{option} is for the shipped models (no --data); with --data every test sample is scored "
                          "on this machine")
    if model is not None and detector is not None:
        raise RigoptError("give --model (rigopt's detectors, e.g. --model lss) or --detector (your own: a TorchScript "
                          "file or package.module:factory), not both")
    if detectors is not None:
        from rigopt.output import existing_folder

        existing_folder(detectors, "packed models (<dir>/<model>-<ref>/card.json, made by rigopt detectors train)",
                        option="--detectors")
    if data is not None and detector is not None:
        raise RigoptError("--detector is scored on the reference's test scenes rendered here (no --data); with --data "
                          "give --model and the folder's trained runs")
    if data is not None and detectors is not None:
        raise RigoptError("--detectors names packed models (no --data); with --data the folder's trained runs are "
                          "scored")
    chosen = protocol_named(protocol) if protocol is not None else DEFAULT_PROTOCOL
    if data is not None and (cache is not None or compare):
        raise RigoptError(f"--{'cache' if cache is not None else 'compare'} is for the shipped models (no --data); "
                          "with --data the renderings go into that folder and the comparison rigs are always measured")
    if data is not None:
        check_data(data)
    check_runs(runs, must_exist=True)
    family = EXTERNAL_FAMILY if detector is not None else model_config(model or "lss").family
    calibration = load_weights(weights or "joint", metric)
    drop_model = choose_model(predictor, reference_rig(ref, detectors).perception(),
                              weights is not None or metric != "rigcd")
    rigs = [load_design(design) for design in designs]
    if drop_model is None:
        note_fallback(calibration)
    resolve_device(device)
    if data is None:
        _validate_shipped(rigs, ref, family, calibration, drop_model, device, cache, workers, chosen, compare, out,
                          as_json, ray, detector, detectors)
        return
    rig = rigs[0]
    with status_console.status("validating") as status:
        result = validate_design(rig, ref, family, data, calibration, runs, device, status.update, drop_model=drop_model)
    result["contradictions"] = contradictions(result["rigs"], result["design_minus"], name=lambda row: row["rig"])
    if "near_field" in result:  # the note of the shipped path: what the detector was fed, what was kept
        note(result["near_field"]["note"])
    if out is not None:
        write_text_atomic(out, json.dumps(json_ready(result), indent=1) + "\n")
    if as_json:
        print_json(result)
        return
    rows = [[e["role"], e["rig"], e["n_cameras"], _number(e["mAP"]), _number(e["measured_drop"]),
             _interval(e["measured_drop_ci"]), _number(e["mAP_visible"]), _number(e["measured_drop_visible"]),
             _number(e["predicted_drop"]), _predicted_interval(e),
             "yes" if e["extrapolation"] else "-", e["rigcd"]] for e in result["rigs"]]
    print_table(f"{family} trained on {result['reference']} (own mAP {_number(result['reference_mAP'])}, "
                f"visible-only {_number(result['reference_mAP_visible'])}), {result['test_scenes']} test scenes; "
                f"predicted by {result['predicted_by']}",
                ["role", "rig", "cameras", "mAP", "measured drop", "95 % interval", "visible mAP", "visible drop",
                 "predicted drop", "90 % prediction interval", "extrapolates", "RigCD"], rows)
    _note_uninformative(result["rigs"], result["predicted_by"])
    _note_contradictions(result["contradictions"])
    rows = [[f"design - {e['rig']}", e["role"], _number(e["difference"]), _interval(e["ci"])]
            for e in result["design_minus"]]
    print_table(f"measured drop of the design minus the others (below 0: the design loses less); intervals from "
                f"{result['bootstrap']['resamples']} paired resamples of the {result['bootstrap']['blocks']} test "
                f"scenes", ["difference", "other rig's role", "value", "95 % interval"], rows)


def _validate_shipped(measured_rigs: list, ref: str, family: str, calibration, drop_model, device: str, cache,
                      workers: int, protocol, compare: bool, out, as_json: bool, ray: str | None = None,
                      yours: str | None = None, root: Path | None = None) -> None:
    """validate without --data: the packed models (in ``root``, default the shipped ones) or ``yours``, a detector
    behind the contract; the reference's test scenes rendered into the cache (as Ray tasks with ``ray``, a
    cluster's address or 'local')."""
    import json
    import os

    from rigopt.validation.detectors.shipped import (
        default_cache,
        measure,
        paired_differences,
        reference_rig,
        shipped_detector,
        user_detector,
        without_resamples,
    )
    from rigopt.validation.designs import WHOLE_ROLE, comparison_rigs, contradictions, fed_rigs, predicted_transfers
    from rigopt.output import existing_folder, write_text_atomic
    from rigopt.report.json_values import json_ready

    reference = reference_rig(ref, root)  # a library rig, a rig file (its name is its pack's) or a packed reference
    if yours is not None:
        from rigopt.validation.detectors.external import load_detector

        detector = user_detector(load_detector(yours), reference, root)
    else:
        detector = shipped_detector(family, reference.name, root)
    if cache is not None and cache.exists():
        existing_folder(cache, "renderings of the reference's test scenes (made by rigopt validate)", option="--cache")
    rigs, records = [], []
    for rig in measured_rigs:  # the perception cameras fed, the whole rig for the record
        rows, record = fed_rigs(rig, "rig", family)
        rigs += rows
        if record is not None:
            note(record["note"])
            records.append(record)
    if compare:
        rigs += comparison_rigs(measured_rigs[0], reference, calibration)[1:]
    names = [r.name for _, r in rigs]
    if len(set(names)) != len(names):
        raise RigoptError(f"rig names must differ from each other: {names}")
    workers = workers or os.cpu_count() or 1
    resumable(f"rerun the same command: the renderings finished so far are kept in {cache or default_cache()}")
    with status_console.status("validating") as status:
        measured = measure([r for _, r in rigs], detector, cache, device, workers, status.update, protocol, ray)
    predictions = predicted_transfers(reference, [r for _, r in rigs], calibration, drop_model)
    card = detector.card
    result = {"reference": reference.name, "model": family,
              "models": "yours" if yours else "shipped" if root is None else "packed",
              "detector": yours or detector.folder.name, "seeds": list(detector.seeds),
              "epochs": card["recipe"]["epochs"] if not yours else None,
              "protocol": {"name": protocol.name, "frame_stride": protocol.frame_stride,
                           "samples": protocol.samples(card["test_data"]), "description": protocol.describe(card["test_data"])},
              "reference_mAP": {s: measured[0]["seeds"][str(s)]["reference_mAP"] for s in detector.seeds},
              "reference_mAP_visible": {s: measured[0]["seeds"][str(s)]["reference_mAP_visible"]
                                        for s in detector.seeds},
              "test_scenes": card["test_data"]["scenes"], "image_size": card["test_data"]["image_size"],
              "cache": str(cache or default_cache()), "metric": calibration.metric, "weights": calibration.name,
              "predicted_by": predictions[0].predictor,
              "interval_note": "95 % intervals over resampled test scenes: the noise of the test, not uncertainty "
                               "over rigs or trainings",
              "rigs": [{"role": role, **without_resamples(entry), "predicted_drop": prediction.predicted_drop,
                        "predicted_interval": prediction.to_dict()["interval"],
                        "interval_informative": prediction.interval_informative,
                        "extrapolation": prediction.to_dict()["extrapolation"], "rigcd": prediction.rigcd}
                       for (role, _), entry, prediction in zip(rigs, measured, predictions)]}
    if records:  # one rig: its record; several: the records of those with near_field cameras
        result["near_field"] = records[0] if len(measured_rigs) == 1 else records
    if compare:  # the rig (its perception cameras) against each yardstick, on the same scene resamples
        result["paired"] = [{"role": role, **paired_differences(measured[0], entry)}
                            for (role, _), entry in zip(rigs[1:], measured[1:]) if role != WHOLE_ROLE]
    result["contradictions"] = contradictions([{**e, "measured_drop": e["drop"]} for e in result["rigs"]],
                                              result.get("paired", []), name=lambda row: row["rig"])
    if out is not None:
        write_text_atomic(out, json.dumps(json_ready(result), indent=1) + "\n")
    if as_json:
        print_json(result)
        return
    rows = [[e["role"], e["rig"], e["n_cameras"], " / ".join(_number(s["drop"]) for s in e["seeds"].values()),
             _number(e["drop"]), _interval(e["drop_ci"]), _number(e["drop_visible"]), _number(e["predicted_drop"]),
             _predicted_interval(e), "yes" if e["extrapolation"] else "-"] for e in result["rigs"]]
    own = " / ".join(_number(v) for v in result["reference_mAP"].values())
    which = (f"{detector.detector.name} ({yours}; own mAP {own})" if yours else f"{family} trained on "
             f"{reference.name}, {result['models']} ({len(detector.seeds)} seed(s), {result['epochs']} epochs; own "
             f"mAP {own})")
    print_table(f"{which}, {protocol.describe(card['test_data'])}; predicted by {result['predicted_by']}",
                ["role", "rig", "cameras", "drop per seed", "mean drop", "95 % interval (test scenes)",
                 "visible-only drop", "predicted drop", "90 % prediction interval", "extrapolates"], rows)
    _note_uninformative(result["rigs"], result["predicted_by"])
    _note_contradictions(result["contradictions"])
    if result.get("paired"):
        print_table(f"{rigs[0][1].name} minus each: below 0 it loses less (* the paired 95 % interval excludes 0)",
                    ["role", "rig", "difference per seed", "mean difference", "95 % interval (test scenes)"],
                    [[p["role"], p["rig"], " / ".join(f"{s['difference']:+.3f}{_excludes_zero(s['ci'])}"
                                                       for s in p["seeds"].values()),
                      f"{p['difference']:+.3f}", _interval(p["ci"])] for p in result["paired"]])
    console.print(f"drops are relative to the model's own fixed-set mAP on {reference.name}; intervals resample the "
                  f"{result['test_scenes']} test scenes (test noise only); renderings kept in {result['cache']}")


def _predicted_interval(entry: dict) -> str:
    """The prediction interval's cell: 'uninformative' where it spans the range a drop can take."""
    if entry.get("interval_informative") is False:
        return "uninformative"
    return _interval(entry["predicted_interval"])


def _note_uninformative(entries: list, predicted_by: str) -> None:
    from rigopt.metrics.prediction import UNINFORMATIVE_TEXT

    wide = [e for e in entries if e.get("interval_informative") is False]
    if wide:
        note(f"predicted drops of {', '.join(e['rig'] for e in wide)}: {UNINFORMATIVE_TEXT} with the 90 % interval "
             f"of {predicted_by}; --json keeps the numbers")


def _note_contradictions(lines: list) -> None:
    """Say where a predicted drop and the measured one beside it disagree (JSON ``contradictions``)."""
    for line in lines:
        note(f"prediction and measurement disagree: {line}")


def _visible_maps(out: Path, family: str, names: List[str]) -> dict:
    """{(trained on, tested on): visible-only mAP} from the results files under ``out`` (None where a file,
    made before the fixed set, has none)."""
    import json

    from rigopt.validation.detectors.protocol import results_path

    found = {}
    for trained in names:
        results = json.loads(results_path(out, family, trained).read_text()).get("results", {})
        for tested in names:
            found[(trained, tested)] = results.get(tested, {}).get("metrics", {}).get("mAP_visible")
    return found


def _excludes_zero(bounds) -> str:
    """'*' when the interval ``bounds`` lies wholly on one side of 0."""
    return "*" if None not in bounds and (bounds[0] > 0 or bounds[1] < 0) else ""


def _number(value) -> str:
    return "-" if value is None else f"{value:.3f}"


def _interval(bounds) -> str:
    return "-" if bounds is None or None in bounds else f"[{bounds[0]:.3f}, {bounds[1]:.3f}]"
