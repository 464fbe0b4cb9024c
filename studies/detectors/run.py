"""The cross-rig study of rigopt's torch baselines on its synthetic benchmark.

Steps (each resumable; rerun the script to continue):
  1. data:        render the train split (48 scenes) of the matrix rigs and the test split (16 scenes) of
                  those and of the validation rigs, 160 x 90, under --data;
  2. validation:  the R1 model of each family (seed 0 the matrix's, other seeds trained again) tested on
                  the firetruck and hgv designs from R1 and their comparison rigs (rigopt validate);
  3. matrix:      per family, train on every matrix rig and test on every one (rigopt bench matrix);
  4. calibration: RigCD calibrated on the measured synthetic transfer (rigopt calibrate), held-out rho;
  5. sim_to_real: the joint weights fitted on the synthetic transfer alone (its control pairs; every pair; the
                  pairs of the rigs outside the real held-out set), judged on the real benchmark's held-out
                  pairs beside 20 fits on random drops;
  6. ship:        the fit on the pairs of the rigs the real benchmark does not hold out, as the named
                  calibration sim-lss (metrics/weights*/), for rigcd and rigcd+, where it beats the benchmark's
                  joint calibration on the real held-out pairs of the family's counterparts (BEVDet, BEVFusion);
  7. agreement:   Spearman rho of synthetic against real relative drops on the same pairs;
  8. report:      results/results.md from all of the above.
Writes results/ (matrices, loss logs, calibration, figures, tables, results.md); checkpoints stay under
--data. Usage: python studies/detectors/run.py --data DIR [--families lss] [--epochs 4]
              [--steps data validation matrix calibration sim_to_real ship agreement report] [--device cpu]
              [--seeds 0 1 2] [--ray ADDRESS]
"""

from __future__ import annotations

import argparse
import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

from rigopt.output import write_text_atomic

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies/: the studies' shared code (studylib)
from studylib.tables import markdown, read_csv, write_csv  # noqa: E402

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"  # the readings: tables, calibration, logs
#: The committed measurements, as metrics/ holds the benchmark's: the cross-rig matrix in the benchmark's
#: results layout, the validation outputs, the validated design rigs.
MEASUREMENTS = HERE.parents[1] / "measurements"
TRANSFER, VALIDATION = MEASUREMENTS / "transfer", MEASUREMENTS / "validation"
RIGS = MEASUREMENTS / "rigs"
CONTROL = ["R1", "R1-r", "R1-t", "R1-f", "R1-c6", "R1-c10"]
DIVERSE = ["R2", "R3", "R4", "R5", "R6", "R7", "R8", "R9"]
#: The real datasets' rigs (measurements/rigs/real/README.md) and the designs validated below.
REAL = [RIGS / "real" / f"{name}.json" for name in ("nuscenes", "argoverse2", "waymo", "ddad")]
DESIGNS = [RIGS / "firetruck_from_R1.json", RIGS / "hgv_from_R1.json"]
#: The firetruck design without the regulation fields (rigopt design ... --require none): 8 cameras, as R1; the
#: hgv's default design has none already (no design sees them all), so it is that design.
VALIDATED = DESIGNS + [RIGS / "firetruck_from_R1_no_fields.json"]
#: The matrix's training (and test) rigs: counts 4 to 12, heights 0.5 to 3 m, FOVs 47 to 120 degrees, four
#: vehicles, the real datasets' rigs and two designs.
MATRIX = CONTROL + DIVERSE + REAL + DESIGNS
TRAIN_SCENES, TEST_SCENES = 48, 16
#: Epochs of the v2 recipe (recipe.py's s0): its validation outputs are measurements/validation/*.json; a longer
#: schedule's go to measurements/validation/epochs<E>/ and its runs to <data>/runs-epochs<E>[-seed<S>].
RECIPE_EPOCHS = 4
#: The real benchmark's measured transfer, beside the checkout.
REAL_RESULTS = HERE.parents[2] / "shared" / "pccr" / "results"
#: Each synthetic family against its real counterparts in the benchmark.
COUNTERPARTS = {"lss": ["BEVDet", "BEVFusion"], "petr": ["PETR"]}
STEPS = ("data", "validation", "matrix", "calibration", "sim_to_real", "ship", "agreement", "report")


def rig_name(rig) -> str:
    return Path(rig).stem if str(rig).endswith(".json") else str(rig)


def rigopt(*args: str) -> None:
    command = ["rigopt", *map(str, args)]
    print("$", " ".join(command), flush=True)
    subprocess.run(command, check=True)


def data_step(data: Path, ray: str | None) -> None:
    cluster = ["--ray", ray] if ray else []
    rigopt("bench", "generate", "--rigs", *MATRIX, "--split", "train", "--scenes", TRAIN_SCENES, "--out", data,
           *cluster)
    rigopt("bench", "generate", "--rigs", *MATRIX, "--split", "test", "--scenes", TEST_SCENES, "--out", data, *cluster)


def matrix_step(data: Path, family: str, epochs: int, device: str, ray: str | None) -> None:
    rigopt("bench", "matrix", "--data", data, "--rigs", *map(rig_name, MATRIX), "--model", family, "--epochs", epochs,
           "--device", device, "--out", TRANSFER, *(["--ray", ray] if ray else []))
    logs = RESULTS / "logs" / family
    logs.mkdir(parents=True, exist_ok=True)
    for rig in map(rig_name, MATRIX):
        shutil.copy(data / "runs" / family / rig / "train_log.csv", logs / f"{rig}.csv")


def calibration_step() -> None:
    rigopt("calibrate", "--results", TRANSFER, "--rigs", RIGS, "--out", RESULTS / "calibration", "--force")


#: The fits judged on the real benchmark: on the synthetic control pairs (the benchmark's protocol); on every
#: synthetic pair (--control all: the matrix's 20 rigs, what it was rendered for); and on the pairs of the rigs
#: the real benchmark holds out none of (its held-out rigs R2-R9 left out of the fit: rigs it has never seen).
SIM_TO_REAL = {"sim_to_real.json": ("control pairs", lambda: []),
               "sim_to_real_all.json": ("every pair", lambda: ["--control", "all"]),
               "sim_to_real_unseen.json": ("pairs without the real held-out rigs",
                                           lambda: ["--control", ",".join(rigs_unseen_by_real_fit())])}
NULL_SEEDS = 20


def rigs_unseen_by_real_fit() -> list[str]:
    """The matrix's rigs that are not among the real benchmark's held-out rigs (its rigs outside its control
    rigs): a fit on their pairs has seen none of the rigs of the real held-out pairs."""
    from rigopt.metrics.protocol import CONTROL_RIGS
    from rigopt.metrics.transfer import read_transfer

    real = read_transfer(REAL_RESULTS)
    held_out = set(real.train.tolist() + real.test.tolist()) - set(CONTROL_RIGS)
    return [rig for rig in map(rig_name, MATRIX) if rig not in held_out]


def sim_to_real_step() -> None:
    """The joint weights fitted on the synthetic transfer alone, judged on the real benchmark's held-out pairs,
    beside NULL_SEEDS fits on random drops over the same pairs (the yardstick)."""
    running = {}
    for name, (_, control) in SIM_TO_REAL.items():  # side by side
        command = ["rigopt", "calibrate", "--results", str(TRANSFER), "--rigs", str(RIGS), *control(), "--test-on",
                   str(REAL_RESULTS), "--null", str(NULL_SEEDS), "--json"]
        print("$", " ".join(command), flush=True)
        running[name] = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    for name, process in running.items():
        output, errors = process.communicate()
        if process.returncode != 0:
            raise SystemExit(f"sim_to_real: {name}: rigopt calibrate failed:\n{errors}")
        write_text_atomic(RESULTS / "calibration" / name, output)


def sim_to_real_rows() -> list[list]:
    """Per fit and real detector: held-out rho [CI], MAE (linear, bounded), the yardstick's median and 95th
    percentile, and the benchmark's own per-detector and joint held-out rho."""
    rows = []
    for name, (fit, _) in SIM_TO_REAL.items():
        path = RESULTS / "calibration" / name
        if not path.is_file():
            continue
        test = json.loads(path.read_text())["test_on"]
        for model, entry in test["models"].items():
            null = test.get("null", {}).get("models", {}).get(model, {})
            held = entry["heldout"]
            rows.append([fit, test["weights"]["n"], model, held["n"], held["rho"], *held["ci"], held["mae"],
                         entry["bounded"]["heldout"]["mae"], null.get("median"), null.get("p95"),
                         null.get("share_reaching"), entry["own_per_detector"]["heldout"]["rho"],
                         entry["own_joint"]["heldout"]["rho"], gain_text(entry["own_joint"]["rho_gain"])])
    return rows


#: The named calibration shipped from the synthetic transfer (in metrics/, per metric's WEIGHTS_FOLDERS).
SHIPPED_NAME = "sim-lss"


def ship_step() -> None:
    """Fit on the pairs of ``rigs_unseen_by_real_fit()`` (per metric) and ship it as ``SHIPPED_NAME`` where it
    beats the benchmark's joint calibration on the real held-out pairs of every counterpart of the lss family
    (``beats``); where it does not, say so and ship nothing."""
    import tempfile

    from rigopt.metrics.calibration import WEIGHTS_FOLDERS

    unseen = rigs_unseen_by_real_fit()
    for metric, folder in WEIGHTS_FOLDERS.items():
        with tempfile.TemporaryDirectory() as work:
            out = Path(work) / "calibration"
            command = ["rigopt", "calibrate", "--metric", metric, "--results", str(TRANSFER), "--rigs", str(RIGS),
                       "--control", ",".join(unseen), "--test-on", str(REAL_RESULTS),
                       "--out", str(out), "--json"]
            print("$", " ".join(command), flush=True)
            test = json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)["test_on"]
            weights = json.loads((out / "weights" / "joint.json").read_text())
        verdicts = {model: beats(test["models"][model]) for model in COUNTERPARTS["lss"]}
        for model, reasons in verdicts.items():
            verdict = "; ".join(reasons) or "beats the benchmark's joint calibration"
            print(f"{metric} {model}: {verdict}")
        if any(verdicts.values()):
            print(f"{metric}: {SHIPPED_NAME} not shipped")
            continue
        weights["name"] = SHIPPED_NAME
        weights["source"] = ("joint fit on the synthetic LSS-style transfer (measurements/transfer/lss) over the pairs of "
                             f"{', '.join(unseen)}; on the real benchmark's held-out pairs: " + "; ".join(
                                 f"{m} rho {test['models'][m]['heldout']['rho']:.3f} vs the benchmark's joint "
                                 f"{test['models'][m]['own_joint']['heldout']['rho']:.3f}" for m in test["models"]))
        path = HERE.parents[1] / "metrics" / folder / f"{SHIPPED_NAME}.json"
        write_text_atomic(path, json.dumps(weights, indent=2) + "\n")
        print("wrote", path)


def beats(entry: dict) -> list[str]:
    """Why a transferred calibration's entry (one real detector of calibrate --test-on's JSON) does not beat the
    benchmark's joint calibration on the held-out pairs; empty where it does: a rho gain whose paired interval
    lies above 0, and a lower MAE of the linear prediction and of the bounded drop."""
    own, gain = entry["own_joint"], entry["own_joint"]["rho_gain"]
    reasons = []
    if gain["ci"][0] is None or gain["ci"][0] <= 0:
        reasons.append(f"rho gain {gain['value']:+.3f}, interval {gain['ci']} not above 0")
    for name, mine, theirs in (("linear", entry["heldout"]["mae"], own["heldout"]["mae"]),
                               ("bounded", entry["bounded"]["heldout"]["mae"], own["bounded"]["heldout"]["mae"])):
        if mine >= theirs:
            reasons.append(f"{name} MAE {mine:.3f} not below {theirs:.3f}")
    return reasons


def gain_text(gain: dict) -> str:
    """'+0.047 [0.003, 0.096]': a rho gain with its interval."""
    if gain["value"] is None:
        return "-"
    low, high = gain["ci"]
    return f"{gain['value']:+.3f}" + ("" if low is None else f" [{low:+.3f}, {high:+.3f}]")


def agreement_step() -> list[list]:
    """Spearman rho of every synthetic family against every real detector on the pairs both hold (the
    counterparts marked), and, as a yardstick, of the real detectors against one another on those rigs."""
    import numpy as np
    from studylib.agreement import drop_agreement

    from rigopt.metrics.transfer import read_transfer
    from rigopt.resources import data_dir

    synthetic = read_transfer(TRANSFER).drops()
    real = read_transfer(data_dir("metrics") / "pccr_transfer.csv").drops()
    rigs = list(map(rig_name, MATRIX))
    real = real.select(np.isin(real.train, rigs) & np.isin(real.test, rigs))
    detectors = list(dict.fromkeys(real.model))
    header = ["family", "real detector", "counterpart", "pairs", "rho", "ci_low", "ci_high", "p_value", "mae"]

    def measures(first, model_a, second, model_b) -> list:
        agreement = drop_agreement(first, model_a, second, model_b)
        return [agreement.n, agreement.rho, *agreement.ci, agreement.p, agreement.mae]

    rows = [[family, detector, "yes" if detector in COUNTERPARTS[family] else "no",
             *measures(synthetic, family, real, detector)]
            for family in COUNTERPARTS if family in set(synthetic.model) for detector in detectors]
    yardstick = [[a, b, *measures(real, a, real, b)] for i, a in enumerate(detectors) for b in detectors[i + 1:]]
    write_csv(RESULTS / "agreement_real.csv", ["real detector", "real detector", *header[3:]], yardstick)
    return write_csv(RESULTS / "agreement.csv", header, rows)


def validation_folder(epochs: int) -> Path:
    """Where the validation outputs of R1 models trained ``epochs`` epochs go (see RECIPE_EPOCHS)."""
    return VALIDATION if epochs == RECIPE_EPOCHS else VALIDATION / f"epochs{epochs}"


def validation_folders() -> dict[int, Path]:
    """{epochs: validation_folder(epochs)} of every schedule validated so far: the recipe's, then by epochs."""
    longer = {int(folder.name.removeprefix("epochs")): folder for folder in VALIDATION.glob("epochs*")}
    return {RECIPE_EPOCHS: VALIDATION, **dict(sorted(longer.items()))}


def validation_step(data: Path, family: str, device: str, epochs: int, seeds: list[int]) -> None:
    """rigopt validate of each design with the R1-trained model of ``family``; at the recipe's epochs seed 0 is
    the matrix's run (``<data>/runs``, trained here if the matrix has not run yet) and other seeds train R1
    again in ``<data>/runs-seed<S>``; a longer schedule trains in ``<data>/runs-epochs<E>[-seed<S>]``
    (resumable)."""
    folder = validation_folder(epochs)
    folder.mkdir(parents=True, exist_ok=True)
    name = "runs" if epochs == RECIPE_EPOCHS else f"runs-epochs{epochs}"
    for seed in seeds:
        runs = data / (name if seed == 0 else f"{name}-seed{seed}")
        rigopt("bench", "train", "--data", data, "--rig", "R1", "--model", family, "--epochs", epochs, "--seed",
               seed, "--device", device, "--runs", runs)
        for design in VALIDATED:
            suffix = "" if seed == 0 else f"_seed{seed}"
            out = folder / f"{family}_{design.stem}{suffix}.json"
            rigopt("validate", design, "--ref", "R1", "--model", family, "--data", data, "--device", device,
                   "--runs", runs, "--out", out)
            write_text_atomic(out, out.read_text().replace(f"{Path(data).resolve()}/", "<data>/"))  # no machine paths


def matrix_tables(family: str) -> tuple[list[list], list[list]]:
    """[header, *rows] of the mAP matrix and of the relative drops (trained on rows, tested on columns)."""
    rigs = list(map(rig_name, MATRIX))
    rows_map, rows_drop = [], []
    for train in rigs:
        path = TRANSFER / family / f"trained_on_{train}.json"
        if not path.is_file():
            continue
        results = json.loads(path.read_text())["results"]
        maps = [results.get(test, {}).get("metrics", {}).get("mAP") for test in rigs]
        own = results[train]["metrics"]["mAP"]
        rows_map.append([train, *maps])
        rows_drop.append([train, *((own - m) / own if own and m is not None else None for m in maps)])
    header = ["trained on", *rigs]
    return [header, *rows_map], [header, *rows_drop]


def training_table(family: str) -> list[list]:
    rows = []
    for rig in map(rig_name, MATRIX):
        log = RESULTS / "logs" / family / f"{rig}.csv"
        if not log.is_file():
            continue
        steps = list(csv.DictReader(log.open()))
        last = [float(r["loss"]) for r in steps if r["epoch"] == steps[-1]["epoch"]]
        first = [float(r["loss"]) for r in steps if r["epoch"] == "0"]
        rows.append([rig, int(steps[-1]["epoch"]) + 1, len(steps), sum(first) / len(first), sum(last) / len(last),
                     float(steps[-1]["seconds"]) / 60])
    return [["rig", "epochs", "steps", "loss epoch 1", "loss last epoch", "minutes"], *rows]


def validation_seed(path: Path) -> int:
    """The training seed of a validation output, from its name (``<family>_<design>[_seed<S>].json``)."""
    return int(path.stem.partition("_seed")[2] or 0)


def seed_row(path: Path) -> list:
    """One validation file as [family, design, seed, own mAP, design drop, then the differences to the naive
    transfer, the height-matched transfer and the hand-designed rig with their intervals]."""
    result = json.loads(path.read_text())
    design = next(e for e in result["rigs"] if e["role"] == "design")
    against = {e["role"]: [e["difference"], *e["ci"]] for e in result["design_minus"]}
    return [result["model"], design["rig"], validation_seed(path), result["reference_mAP"], design["measured_drop"],
            *against.get("naive transfer", [None] * 3), *against.get("height-matched transfer", [None] * 3),
            *against.get("hand-designed", [None] * 3)]


def ordering_rows(family: str, folder: Path = VALIDATION) -> list[list]:
    """Does a lower predicted drop order the measured drops? Per training seed, Spearman rho between the
    predicted and the measured drops over every validated rig of both vehicles (the validations in ``folder``),
    with a 95 % interval over the resampled test scenes (the same scene draws for every rig) and the share of
    draws with rho > 0; then the same for the measured drops averaged over the seeds."""
    import numpy as np
    from scipy.stats import spearmanr

    by_seed: dict[int, list[dict]] = {}
    for path in sorted(folder.glob(f"{family}_*.json")):
        by_seed.setdefault(validation_seed(path), []).append(json.loads(path.read_text()))
    rows, means = [], {}
    for seed, results in sorted(by_seed.items()):
        predicted, measured, draws, seen = [], [], [], set()
        for result in results:
            for entry in result["rigs"]:
                if entry["rig"] in seen:  # a comparison rig of two designs of one vehicle counts once
                    continue
                seen.add(entry["rig"])
                predicted.append(entry["predicted_drop"])
                measured.append(entry["measured_drop"])
                draws.append(result["bootstrap"]["measured_drops"][entry["rig"]])
                means.setdefault(entry["rig"], [entry["predicted_drop"], []])[1].append(entry["measured_drop"])
        draws = np.array(draws, dtype=float).T  # (resamples, rigs)
        rhos = np.array([spearmanr(predicted, d).statistic for d in draws if np.isfinite(d).all()])
        rows.append([family, seed, len(predicted), spearmanr(predicted, measured).statistic,
                     *np.percentile(rhos, [2.5, 97.5]), float((rhos > 0).mean())])
    if len(by_seed) > 1:
        pairs = [(p, float(np.mean(m))) for p, m in means.values() if len(m) == len(by_seed)]
        rows.append([family, "mean of seeds", len(pairs), spearmanr(*zip(*pairs)).statistic, None, None, None])
    return rows


def term_rows(family: str) -> list[list]:
    """Which of RigCD's terms orders the measured drops of the validated rigs? For every rig of the seed-0
    validations (the comparison rigs rebuilt as ``rigopt validate`` builds them): its calibration features
    against R1 (t m, r rad, f deg, count), the offset of its mean camera height from R1's (m), the measured
    drop averaged over the seeds; then Spearman rho of each against that drop. Cached in
    results/validation_terms.csv (delete it to recompute)."""
    import numpy as np
    from scipy.stats import spearmanr

    from rigopt.validation.designs import comparison_rigs, load_design
    from rigopt.metrics.calibration import load_weights
    from rigopt.metrics.ranking import predict_transfer
    from rigopt.rig.library import load_rig

    cache = RESULTS / "validation_terms.csv"
    header = ["rig", "t", "r", "f", "count", "height offset", "predicted drop", "measured drop (mean of seeds)"]
    if not cache.is_file():
        reference, calibration = load_rig("R1"), load_weights("joint", "rigcd")
        drops: dict[str, list[float]] = {}
        for path in VALIDATION.glob(f"{family}_*.json"):
            for entry in json.loads(path.read_text())["rigs"]:
                drops.setdefault(entry["rig"], []).append(entry["measured_drop"])
        rows, done = [], set()
        for design in VALIDATED:
            for _, rig in comparison_rigs(load_design(design), reference, calibration):
                if rig.name in done or rig.name not in drops:
                    continue
                done.add(rig.name)
                p = predict_transfer(reference, [rig], calibration)[0]
                height = abs(np.mean([c.position[2] for c in rig.cameras])
                             - np.mean([c.position[2] for c in reference.cameras]))
                rows.append([rig.name, p.t, p.r, p.f, p.count, float(height), p.predicted_drop,
                             float(np.mean(drops[rig.name]))])
        write_csv(cache, header, rows)
    rows = read_csv(cache)[1:]
    measured = [row[-1] for row in rows]
    rhos = ["Spearman rho with the measured drop",
            *(spearmanr([row[k] for row in rows], measured).statistic for k in range(1, len(header) - 1)), 1.0]
    return [header, *rows, rhos]


def own_map_rows(family: str) -> list[list]:
    """[header, *rows]: the R1 model's own mAP (fixed set, visible only) per schedule and training seed, read
    from each seed's first validation output (every design's output of one model holds the same figures)."""
    rows = {}
    for epochs, folder in validation_folders().items():
        for path in sorted(folder.glob(f"{family}_*.json")):
            seed = validation_seed(path)
            if (epochs, seed) not in rows:
                result = json.loads(path.read_text())
                rows[epochs, seed] = [epochs, seed, result["reference_mAP"], result.get("reference_mAP_visible")]
    return [["epochs", "seed", "own mAP (fixed set)", "own mAP (visible only)"], *(rows[k] for k in sorted(rows))]


def schedule_rows(family: str) -> list[list]:
    """[header, *rows]: the seed-0 validation at the recipe's epochs beside longer schedules
    (measurements/validation/epochs<E>/): per rig its predicted drop and the measured fixed-set drop [95 %
    interval] and visible-only drop of each schedule; then the own mAP (fixed set) and the ordering rho."""
    folders = validation_folders()
    entries: dict[int, dict[str, dict]] = {}
    own: dict[int, float] = {}
    for epochs, folder in folders.items():
        for path in sorted(folder.glob(f"{family}_*.json")):
            if validation_seed(path):
                continue
            result = json.loads(path.read_text())
            own[epochs] = result["reference_mAP"]
            for entry in result["rigs"]:
                entries.setdefault(epochs, {}).setdefault(entry["rig"], entry)
    if len(entries) < 2:
        return []
    rigs = [rig for rig in entries[RECIPE_EPOCHS] if all(rig in e for e in entries.values())]
    header = ["rig", "predicted drop", *(f"{what}, {e} epochs" for e in entries for what in ("drop", "ci", "visible"))]
    rows = []
    for rig in rigs:
        row = [rig, entries[RECIPE_EPOCHS][rig]["predicted_drop"]]
        for by_rig in entries.values():
            e = by_rig[rig]
            low, high = e["measured_drop_ci"]
            row += [e["measured_drop"], f"[{low:.3f}, {high:.3f}]", e.get("measured_drop_visible")]
        rows.append(row)
    rows.append(["own mAP (fixed set)", None, *(v for e in entries for v in (own[e], None, None))])
    orderings = {e: ordering_rows(family, folders[e]) for e in entries}
    rows.append(["Spearman rho, predicted vs measured", None,
                 *(v for e in entries for v in (orderings[e][0][3], f"[{orderings[e][0][4]:.3f}, "
                                                                   f"{orderings[e][0][5]:.3f}]", None))])
    return [header, *rows]


def null_summary() -> list[list]:
    """[header, *rows] of ``null_calibration.py``'s yardstick: per rig set and real detector, the median and the
    5th and 95th percentiles over seeds of the held-out rho of joint weights fitted on random drops."""
    import numpy as np

    rows = read_csv(RESULTS / "null_calibration.csv")[1:]
    table = [["rig set", "real detector", "rho median", "rho 5 %", "rho 95 %", "seeds"]]
    for rig_set in dict.fromkeys(r[0] for r in rows):
        for detector in dict.fromkeys(r[2] for r in rows):
            rho = np.array([float(r[3]) for r in rows if r[0] == rig_set and r[2] == detector])
            table.append([rig_set, detector, *np.percentile(rho, [50, 5, 95]).tolist(), len(rho)])
    return table


def report_step(families) -> None:
    parts = ["# Synthetic cross-rig study: results", "",
             "Produced by `python studies/detectors/run.py`; read [the README](../README.md) for the protocol "
             "and the reading of these numbers.", ""]
    for family in families:
        maps, drops = matrix_tables(family)
        if len(maps) == 1:
            continue
        parts += [f"## {family}: mAP (trained on rows, tested on columns)", "", markdown(maps), "",
                  f"## {family}: relative drop", "", markdown(drops), "",
                  f"## {family}: training", "", markdown(training_table(family)), ""]
    calibration = RESULTS / "calibration" / "calibration.json"
    if calibration.is_file():
        report = json.loads(calibration.read_text())
        rows = [[model, entry["control"]["rho"], entry["heldout"]["rho"], *entry["heldout"]["ci"], entry["heldout"]["n"],
                 entry["weights"]["K"], entry["weights"]["alpha"], entry["weights"]["fallback"]]
                for model, entry in report["models"].items()]
        parts += ["## RigCD calibrated on the synthetic transfer", "",
                  markdown([["family", "rho control", "rho held-out", "ci_low", "ci_high", "held-out pairs", "K",
                             "alpha", "fallback"], *rows]), ""]
    transferred = sim_to_real_rows()
    if transferred:
        parts += ["## Calibrated in simulation, judged on the real benchmark's held-out pairs", "",
                  "Joint weights fitted on the synthetic transfer alone (on its control pairs, on every pair, or on "
                  "the pairs of the rigs outside the real held-out set); "
                  f"null: {NULL_SEEDS} fits on random drops over the same pairs; own: the benchmark's calibrations; "
                  "gain: rho minus the own joint's on the same pairs, paired-bootstrap 95 % interval.",
                  "", markdown([["fit on", "fit pairs", "real detector", "held-out pairs", "rho", "ci_low", "ci_high",
                                 "MAE linear", "MAE bounded", "null median", "null p95", "null share reaching",
                                 "own per detector", "own joint", "gain over own joint"], *transferred]), ""]
    if (RESULTS / "agreement.csv").is_file():
        table = read_csv(RESULTS / "agreement.csv")
        parts += ["## Agreement with the benchmark's real transfer (Spearman rho of relative drops)", "",
                  markdown(table), ""]
    if (RESULTS / "agreement_real.csv").is_file():
        table = read_csv(RESULTS / "agreement_real.csv")
        parts += ["## Yardstick: the real detectors against one another on the same pairs", "", markdown(table), ""]
    if (RESULTS / "null_calibration.csv").is_file():
        parts += ["## Yardstick for sim-to-real: joint weights fitted on random drops, judged on the real held-out "
                  "pairs (null_calibration.py)", "", markdown(null_summary()), ""]
    validations = sorted((VALIDATION).glob("*.json"))
    ordering = [[family if folder == VALIDATION else f"{family}, {folder.name}", *row[1:]] for family in families
                for folder in validation_folders().values() for row in ordering_rows(family, folder)]
    if ordering:
        parts += ["## Does a lower predicted drop order the measured drops? (all validated rigs, both vehicles)", "",
                  markdown([["model", "seed", "rigs", "Spearman rho", "ci_low", "ci_high", "share of draws rho > 0"],
                            *ordering]), ""]
    own_maps = own_map_rows("lss") if "lss" in families else []
    if len(own_maps) > 1:
        parts += ["## Own mAP of the validated R1 models (lss, tested on R1's 16 test scenes)", "",
                  markdown(own_maps), ""]
    schedules = schedule_rows("lss") if "lss" in families else []
    if schedules:
        parts += ["## Validation with longer training (seed 0): measured drops as the detector gets stronger", "",
                  markdown(schedules), ""]
    if validations and "lss" in families:
        parts += ["## RigCD's terms against the measured drops (validated rigs, LSS, drops averaged over seeds)", "",
                  markdown(term_rows("lss")), ""]
    if validations:
        parts += ["## Validation across training seeds (design's drop minus the other rig's)", "",
                  markdown([["model", "design", "seed", "own mAP", "design drop", "- naive", "ci_low", "ci_high",
                             "- height-matched", "ci_low", "ci_high", "- hand-designed", "ci_low", "ci_high"],
                            *(seed_row(path) for path in validations)]), ""]
    for path in validations:
        result = json.loads(path.read_text())
        rows = [[e["role"], e["rig"], e["n_cameras"], e["mAP"], e["measured_drop"], *e["measured_drop_ci"],
                 e.get("measured_drop_visible"), e["predicted_drop"], e["rigcd"]] for e in result["rigs"]]
        differences = [[f"design - {e['rig']}", e["role"], e["difference"], *e["ci"]] for e in result["design_minus"]]
        parts += [f"## Validation: {path.stem} ({result['model']} trained on {result['reference']}, own mAP "
                  f"{result['reference_mAP']:.3f})", "",
                  markdown([["role", "rig", "cameras", "mAP", "measured drop", "ci_low", "ci_high",
                             "visible-only drop", "predicted drop", "RigCD"], *rows]), "",
                  markdown([["difference", "other rig's role", "measured", "ci_low", "ci_high"], *differences]), ""]
    (RESULTS / "results.md").write_text("\n".join(parts))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--families", nargs="+", default=["lss"])
    parser.add_argument("--epochs", type=int, default=RECIPE_EPOCHS)
    parser.add_argument("--ray", help="Ray cluster address for rendering and the matrix's training ('local': here)")
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2], help="training seeds of the validation step")
    parser.add_argument("--steps", nargs="+", default=list(STEPS), choices=STEPS)
    args = parser.parse_args()
    RESULTS.mkdir(parents=True, exist_ok=True)
    if "data" in args.steps:
        data_step(args.data, args.ray)
    for family in args.families:
        if "validation" in args.steps:
            validation_step(args.data, family, args.device, args.epochs, args.seeds)
        if "matrix" in args.steps:
            matrix_step(args.data, family, args.epochs, args.device, args.ray)
    if "calibration" in args.steps:
        calibration_step()
    if "sim_to_real" in args.steps:
        sim_to_real_step()
    if "ship" in args.steps:
        ship_step()
    if "agreement" in args.steps:
        print(markdown(agreement_step()))
    if "report" in args.steps:
        report_step(args.families)


if __name__ == "__main__":
    main()
