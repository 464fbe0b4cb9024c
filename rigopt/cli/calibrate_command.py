"""``rigopt calibrate``: the benchmark's calibration protocol on measured cross-rig transfer."""

from __future__ import annotations

import json
from pathlib import Path
from typing import List, Optional

import typer

from rigopt.cli.app import FORCE_HELP, app, console, note, print_json, print_next, print_table
from rigopt.cli.metric_commands import METRIC_HELP
from rigopt.errors import RigoptError


@app.command("calibrate")
def calibrate_command(
    results: Path = typer.Option(..., help="Measured transfer: a benchmark results folder "
                                           "(<model>/trained_on_<rig>.json) or a CSV model,train_rig,test_rig,mAP."),
    control: Optional[str] = typer.Option(None, help="Comma-separated control rigs of --results (the calibration "
                                                     "set), or 'all' (every rig: fit on every pair, no held-out "
                                                     "pair); default: the benchmark's (R1 and its five variants)."),
    test_control: Optional[str] = typer.Option(None, "--test-control",
                                               help="With --test-on: its control rigs (the rest of its pairs are the "
                                                    "held-out pairs the fit is judged on); default: the "
                                                    "benchmark's."),
    bootstrap: Optional[int] = typer.Option(None, min=0, help="Bootstrap resamples for the 95 % interval of rho "
                                                               "(default: the benchmark protocol's 1000)."),
    seed: Optional[int] = typer.Option(None, min=0, help="Seed of the bootstrap (default 0)."),
    rigs: Optional[List[Path]] = typer.Option(None, "--rigs", help="Folder of the rig files (<rig>.json, in it or "
                                                                   "below it) the results were measured with, for "
                                                                   "rigs not in the library (e.g. measurements/rigs: "
                                                                   "its real/ holds the real datasets' rigs); may "
                                                                   "be given several times, the first holding a "
                                                                   "rig wins."),
    solver: str = typer.Option("lbfgsb", help="Whose beta is reported: lbfgsb (the benchmark's) or qp (the exact optimum, scipy's NNLS)."),
    metric: str = typer.Option("rigcd", "--metric", help=METRIC_HELP),
    test_on: Optional[Path] = typer.Option(None, "--test-on",
                                           help="Other measured transfer (e.g. the real benchmark's results) on "
                                                "which the joint calibration fitted on --results is judged, beside "
                                                "that data's own calibration: key 'test_on' of the JSON."),
    null: int = typer.Option(0, "--null", min=0, help="With --test-on: also fit this many joint calibrations on "
                                                       "--results' pairs with random drops and judge them the same "
                                                       "way, the bar a calibration must clear to have learned from "
                                                       "the measurements (key 'null' of 'test_on'; ~10 s each)."),
    out: Optional[Path] = typer.Option(None, help="Folder for the JSON, pairs CSV, weights and figures."),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print the JSON report instead of tables."),
):
    """Fit calibrated RigCD (or RigCD+) per detector and jointly; report reliability on control and held-out pairs."""
    from rigopt.metrics.protocol import calibrate, refuse_lifting
    from rigopt.metrics.reliability import DEFAULT_BOOTSTRAP, DEFAULT_SEED
    from rigopt.metrics.transfer import read_transfer
    from rigopt.output import atomic_folder, check_out_folder, published
    from rigopt.report.calibration_tables import study_dict, write_study_tables
    from rigopt.vehicle.placement import benchmark_rig_lookup

    refuse_lifting(metric)
    if null and test_on is None:
        raise RigoptError("--null judges chance calibrations on other measured transfer: give --test-on too "
                          "(e.g. --test-on ../shared/pccr/results)")
    if out is not None:
        check_out_folder(out, force=force)
    bootstrap = DEFAULT_BOOTSTRAP if bootstrap is None else bootstrap
    seed = DEFAULT_SEED if seed is None else seed
    if test_control is not None and test_on is None:
        raise RigoptError("--test-control names the control rigs of --test-on's data: give --test-on too "
                          "(e.g. --test-on ../shared/pccr/results)")
    # the results' rigs by name (--rigs first), as the benchmark measured them; one lookup, so each note once
    lookup = benchmark_rig_lookup(rigs, note)
    table = read_transfer(_results_place(results, "--results"))
    control_rigs = _control_rigs(control, table)
    _check_cross_rig_pairs(table, control_rigs, results)
    target = read_transfer(_results_place(test_on, "--test-on")) if test_on is not None else None
    if target is not None:
        target_control = _control_rigs(test_control, target)
        _check_cross_rig_pairs(target, target_control, test_on)
    for data in (table, target) if target is not None else (table,):  # every rig found before any work
        for name in dict.fromkeys(data.train.tolist() + data.test.tolist()):
            lookup(name)
    study = calibrate(table, control_rigs, lookup, bootstrap, seed, solver, metric)
    report = study_dict(study)
    if test_on is not None:
        from rigopt.metrics.protocol import calibration_on
        from rigopt.report.calibration_tables import transfer_dict

        transfer = calibration_on(study.joint.fit.calibration, target, target_control, lookup, bootstrap,
                                  seed, solver)
        report["test_on"] = {"results": str(test_on), "control_rigs": list(target_control),
                             **transfer_dict(transfer, study.joint.fit)}
        if null:
            from rigopt.metrics.protocol import null_yardstick

            yardstick = null_yardstick(table, target, null, control_rigs, lookup, solver, metric, target_control)
            figures = {m: e["heldout"]["rho"] for m, e in report["test_on"]["models"].items()}
            report["test_on"]["null"] = {"seeds": null, "models": yardstick.summary(figures)}
    if out is not None:
        from rigopt.report.calibration_figures import write_calibration_figures

        with atomic_folder(out, force=force) as work:
            (work / "calibration.json").write_text(json.dumps(report, indent=2) + "\n")
            written = published([work / "calibration.json", *write_study_tables(study, work),
                                 *write_calibration_figures(study, work)], work, out)
        if not as_json:
            console.print(f"wrote {len(written)} files to {out}")
            print_next(f"open {out} (calibration.json, the pairs table and the figures: heatmaps, scatter plots)")
    if as_json:
        print_json(report)
        return
    _print_tables(report)
    if test_on is not None:
        _print_transfer(report["test_on"])


def _print_transfer(test: dict) -> None:
    print_table(f"The joint calibration fitted on --results, judged on {test['results']} (held-out pairs)",
                ["model", "rho", "CI", "MAE (linear)", "MAE (bounded)", "own: rho per detector", "own: rho joint",
                 "gain over own joint (CI)"],
                [[m, e["heldout"]["rho"], _ci(e["heldout"]["ci"]), e["heldout"]["mae"], e["bounded"]["heldout"]["mae"],
                  e["own_per_detector"]["heldout"]["rho"], e["own_joint"]["heldout"]["rho"],
                  _gain(e["own_joint"]["rho_gain"])]
                 for m, e in test["models"].items()])
    if "null" in test:
        print_table(f"Yardstick: {test['null']['seeds']} joint calibrations fitted on random drops over the same "
                    "pairs, judged the same way (held-out rho)",
                    ["model", "median", "5th percentile", "95th percentile", "share reaching the fit's rho"],
                    [[m, e["median"], e["p5"], e["p95"], e["share_reaching"]] for m, e in test["null"]["models"].items()])


def _results_place(path: Path, option: str) -> Path:
    """``path`` when it can hold measured transfer: a results folder or a CSV file; a JSON file (one detector's
    results, trained_on_<rig>.json) or a missing path is refused, naming ``option``."""
    holding = "<model>/trained_on_<rig>.json (a results folder), or a CSV file model,train_rig,test_rig,mAP"
    if not path.exists():
        raise RigoptError(f"{option} {path}: no such results folder or CSV file; give the folder holding {holding}")
    if path.is_file() and path.suffix.lower() == ".json":
        raise RigoptError(f"{option} {path} is a JSON file, one model's results; give the folder holding {holding}")
    return path


def _control_rigs(names: str | None, table) -> tuple[str, ...]:
    """The control rigs named by a --control value: comma-separated names, 'all' (every rig of ``table``) or,
    without a value, the benchmark's."""
    from rigopt.metrics.protocol import CONTROL_RIGS

    if names is None:
        return CONTROL_RIGS
    if names.strip().lower() == "all":
        return tuple(dict.fromkeys(table.train.tolist() + table.test.tolist()))
    return tuple(r.strip() for r in names.split(",") if r.strip())


def _check_cross_rig_pairs(table, control_rigs: tuple[str, ...], source: Path) -> None:
    """Every detector needs cross-rig results (trained on one rig, tested on another) among the control rigs,
    or its fit has nothing to fit and would silently return default weights."""
    cross = table.train != table.test
    if not cross.any():
        raise RigoptError(f"--results {source}: only the diagonal (each rig tested on itself); calibration needs "
                          "cross-rig results: detectors trained on one rig and tested on others")
    control = set(control_rigs)
    for model in sorted(set(table.model.tolist())):
        mine = (table.model == model) & cross
        if not any(a in control and b in control for a, b in zip(table.train[mine], table.test[mine])):
            raise RigoptError(f"--results {source}: {model} has no cross-rig result among the control rigs "
                              f"({', '.join(control_rigs)}); add such results or name other rigs with --control")


def _print_tables(report: dict) -> None:
    models = report["models"]
    print_table(f"Per-detector weights ({report['metric']})", ["model", "K", "alpha", "l_t", "l_r", "l_f", "fallback", "QP agrees"],
                [[m, e["weights"]["K"], e["weights"]["alpha"], e["weights"]["lambda_t"], e["weights"]["lambda_r"],
                  e["weights"]["lambda_f"], "yes" if e["weights"]["fallback"] else "no",
                  "yes" if e["weights"]["qp_agrees"] else "NO"] for m, e in models.items()])
    joint = report["joint"]
    rows = [[label, e["control"]["rho"], e["heldout"]["rho"], _ci(e["heldout"]["ci"]),
             _ci(e["heldout"].get("rig_ci", [None, None])), e["heldout"]["mae"]]
            for label, e in [*models.items(), *((f"{m} (joint)", e) for m, e in joint["models"].items())]]
    print_table("Reliability (Spearman rho; 95 % intervals resampling the pairs, the benchmark's, and the rigs)",
                ["model", "rho ctrl", "rho held", "CI held (pairs)", "CI held (rigs)", "MAE held"], rows)
    w = joint["weights"]
    console.print(f"joint weights: K {w['K']:.3f}  alpha {w['alpha']:.3f}  lambdas {w['lambda_t']:.3f} "
                  f"{w['lambda_r']:.3f} {w['lambda_f']:.3f}  QP agrees: {'yes' if w['qp_agrees'] else 'NO'}")
    print_table("Knockout: held-out rho without one component", ["model", "full", "no t", "no r", "no f", "no count"],
                [[m, *(e["knockout"][k] for k in ("full", "lambda_t", "lambda_r", "lambda_f", "count"))]
                 for m, e in models.items()])
    _print_intervals(report["intervals"])


def _print_intervals(intervals: dict) -> None:
    """The prediction intervals on the held-out pairs per predicted-drop bin (coverage and pairs), overall
    width in [0, 1] and clipped share, the bounded MAE beside the constant predictors'; a note naming the fits
    whose intervals are uninformative."""
    named = [(m, e) for m, e in intervals["models"].items() if e is not None]
    named += [(f"{m} (joint)", e) for m, e in intervals["joint"].items() if e is not None]
    if not named:
        return
    bins = [f"[{b['bin'][0]:g}, {b['bin'][1]:g}{']' if k == len(named[0][1]['bins']) - 1 else ')'}"
            for k, b in enumerate(named[0][1]["bins"])]
    print_table("Prediction intervals on held-out pairs: half-width; informs: not spanning the range a drop can "
                "take; coverage (pairs) per predicted-drop bin; width: mean length within [0, 1]; clipped: share "
                "reaching past 0 or 1; MAE of the predicted drop, of the median of the calibration drops (const) and "
                "of the held-out drops' own median (const*, hindsight)",
                ["fit", "half", "informs", *bins, "all", "width", "clipped", "MAE", "MAE const",
                 "MAE const*"],
                [[name, e["halfwidth"], "yes" if e["interval_informative"] else "NO",
                  *(_coverage(b) for b in e["bins"]), _coverage(e["overall"]), e["overall"]["mean_width"],
                  e["overall"]["clipped"], e["bounded_mae"], e["constant_mae"], e["oracle_constant_mae"]]
                 for name, e in named])
    wide = [name for name, e in named if not e["interval_informative"]]
    if wide:
        from rigopt.metrics.prediction import UNINFORMATIVE_TEXT

        note(f"{', '.join(wide)}: {UNINFORMATIVE_TEXT}: the coverage above is that of intervals spanning "
             "(nearly) every possible drop, no finding")


def _coverage(entry: dict) -> str:
    return "-" if entry["n"] == 0 else f"{entry['coverage']:.2f} ({entry['n']})"


def _ci(ci) -> str:
    return "-" if None in ci else f"[{ci[0]:.3f}, {ci[1]:.3f}]"


def _gain(gain: dict) -> str:
    return "-" if gain["value"] is None else f"{gain['value']:+.3f} {_ci(gain['ci'])}"
