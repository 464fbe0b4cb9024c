"""RigCD+ study: does a vehicle-aware rig distance predict transfer better than the published RigCD?

Implements the protocol of README.md (fixed before any held-out result). Steps, in this order:
  1. features:  every RigCD+ term of every rig pair (rig profiles computed once per rig) -> features.csv;
  2. cv:        leave-one-rig-out CV inside the calibration set, the choice of V* -> cv.md, cv.csv;
  3. heldout:   every variant refitted on all calibration pairs, held-out reliability, the paired bootstrap
                against V0 and the decision -> heldout.csv, paired.csv, fits.json, chosen.json, results.md;
  4. synthetic: the same on rigopt's synthetic transfer (studies/baselines/results/transfer) -> synthetic.md.
Usage: OMP_NUM_THREADS=1 python studies/rigcd_plus/run.py [--bootstrap 1000] [--seed 0]
The study's own modules sit beside this script (plus_terms.py: the candidate terms; plus_study.py: variants,
fits, cross-validation, bootstrap); Python finds them because it puts the script's folder on sys.path.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from plus_study import (BASELINE, REMATCH, VARIANTS, StudyPairs, beats_baseline, choose_variant,
                        cv_predictions, fit_full, groups_above, pair_index, paired_rho_difference, rematcher)
from plus_terms import TERMS, PlusSettings, rig_profile, term_matrices
from rigopt.metrics.calibration import AGREEMENT_BETA_ATOL, load_weights, pair_features
from rigopt.metrics.protocol import calibrate
from rigopt.metrics.reliability import reliability, spearman
from rigopt.metrics.transfer import read_transfer
from rigopt.report.tables import markdown, write_csv
from rigopt.resources import data_dir
from rigopt.rig.library import load_rig, rig_names

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
CONTROL = ("R1", "R1-r", "R1-t", "R1-f", "R1-c6", "R1-c10")
SYNTHETIC = HERE.parent / "baselines" / "results" / "transfer"
SYNTHETIC_FAMILIES = ("lss", "petr")
SYNTHETIC_RIGS = (*CONTROL, "R2", "R5", "R9")
PAIRED_HEADER = ["variant", "role", "n", "rho_variant", "rho_V0", "difference", "ci_lo", "ci_hi", "resamples_used",
                 "groups_above_V0", "groups"]
HELDOUT_HEADER = ["variant", "fit", "detector", "n", "rho", "p", "ci_lo", "ci_hi", "mae", "rmse"]
NOTES = "\n".join([
    "- Choice rule: only candidates whose joint CV rho is at least 0.01 above V0's are eligible; among them the "
    "highest, candidates within 0.01 of it going to fewer features, then to table order; a NaN score is never "
    "eligible.",
    "- V0 in every fit (CV folds included) is the published pipeline: L-BFGS-B from 0.5, predictions from the "
    "reported (K, alpha, lambdas). Candidates predict with the QP betas. Where a fold leaves a feature at 0 on "
    "every training pair (r without R1-r, f and focal without R1-f) the two optima differ only in that "
    "feature's beta (0.5 against 0), so V2, identical to V0 as a model on the control rigs, scores differently "
    "in CV. The solver-sensitivity table in cv.md shows the joint CV rho with one solver throughout.",
    "- V6: round 0 fits the unit-matching features; each round sets match_lambdas to the last fit's QP "
    "(beta_t, beta_r, beta_f), recomputes and refits; on convergence the lambdas that reproduced the training "
    "features are kept (the last fit's betas) and predict the other pairs; otherwise the round with the lowest "
    "training objective (its lambdas and fit).",
    "- Paired bootstrap: one generator (seed 0) draws, detector by detector in the order of the data, a "
    "(1000, n_detector) array of indices within that detector; both rhos are computed on the same resampled "
    "pairs; resamples with a constant side are skipped.",
    "- Synthetic: the joint fit stacks the pairs of every family run (synthetic.md names them), one beta for all.",
])
START = time.time()


def log(message: str) -> None:
    print(f"[{time.time() - START:7.1f} s] {message}", flush=True)


def nan_to_none(row: list) -> list:
    return [None if isinstance(v, float) and not np.isfinite(v) else v for v in row]


def build_pairs(drops, names, rigs, matrices, settings) -> StudyPairs:
    rows, cols = pair_index(names, drops.train, drops.test)
    return StudyPairs(drops.model, drops.train, drops.test, drops.delta,
                      {term: matrices[term][rows, cols] for term in TERMS},
                      pair_features(rigs, drops.train, drops.test),
                      rematcher(rigs, names, drops.train, drops.test, settings))


# --- Step 2: cross-validation ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class CrossValidation:
    """CV of every variant: ``table`` [header, *rows]; ``scores`` joint CV rho per variant; over all ``fits``
    fold fits, how many have QP and L-BFGS-B betas that differ (``beta_differ``) and, of those, how many also
    differ in objective (``objective_differ``; the rest are non-unique optima)."""

    table: list
    scores: dict
    fits: int
    beta_differ: int
    objective_differ: int


def cross_validate(pairs: StudyPairs, solver: str | None = None, verbose: bool = True) -> CrossValidation:
    """Leave-one-rig-out CV of every variant; ``solver`` as in ``fit_variant`` (None: the protocol)."""
    calibration, fits, rows, scores = pairs.both_in(CONTROL), [], [], {}
    in_group = [calibration & (pairs.model == g) for g in pairs.groups]
    for variant in VARIANTS:
        joint, own = cv_predictions(variant, pairs, CONTROL, solver, fits)
        scores[variant] = spearman(joint[calibration], pairs.delta[calibration])[0]
        rows.append([variant, " ".join(VARIANTS[variant]), len(VARIANTS[variant]), scores[variant],
                     *(spearman(own[m], pairs.delta[m])[0] for m in in_group),
                     *(spearman(joint[m], pairs.delta[m])[0] for m in in_group)])
        if verbose:
            log(f"cv {variant}: joint CV rho {scores[variant]:.4f}")
    header = ["variant", "features", "k", "joint CV rho", *(f"{g} own CV rho" for g in pairs.groups),
              *(f"{g} joint-fit CV rho" for g in pairs.groups)]
    return CrossValidation([header, *rows], scores, len(fits), sum(not f.agrees for f in fits),
                           sum(not f.objectives_agree for f in fits))


def choose(scores: dict) -> str:
    return choose_variant(scores, {v: len(f) for v, f in VARIANTS.items()})


def cv_report(pairs: StudyPairs, cv: CrossValidation) -> tuple[list[str], str]:
    """The CV section (table, solvers, the choice, the solver-sensitivity diagnostic) and V*."""
    chosen = choose(cv.scores)
    best = max((v for v in VARIANTS if v != BASELINE), key=lambda v: np.nan_to_num(cv.scores[v], nan=-2.0))
    diagnostic = {solver: cross_validate(pairs, solver, verbose=False).scores for solver in ("qp", "lbfgsb")}
    sensitivity = [["variant", "protocol", "all QP betas", "all L-BFGS-B betas"]]
    sensitivity += [[v, cv.scores[v], diagnostic["qp"][v], diagnostic["lbfgsb"][v]] for v in VARIANTS]
    sensitivity.append(["choice", chosen, choose(diagnostic["qp"]), choose(diagnostic["lbfgsb"])])
    text = [markdown([cv.table[0], *map(nan_to_none, cv.table[1:])]),
            f"QP and L-BFGS-B betas differ (by more than {AGREEMENT_BETA_ATOL}) in {cv.beta_differ} of {cv.fits} "
            f"fold fits; their objectives differ in {cv.objective_differ} of them, the others are non-unique optima. "
            "Candidates predict with the QP betas, V0 with the published pipeline (L-BFGS-B, reported weights).",
            f"**V\\* = {chosen}** (V0 joint CV rho {cv.scores[BASELINE]:.4f}; best candidate {best}, "
            f"{cv.scores[best]:.4f}; a candidate must exceed V0 by at least 0.01). Rule as implemented: only "
            "candidates at least 0.01 above V0 are eligible; among them the highest, candidates within 0.01 of it "
            "going to fewer features, then to table order.",
            "### Diagnostic: solver sensitivity of the joint CV rho (does not change V\\*)",
            "In a fold that leaves out R1-r (or R1-f) every training pair has r = 0 (or f = focal = 0), so that "
            "feature's beta is not identified: L-BFGS-B leaves it at its start 0.5, HiGHS returns 0, at the same "
            "objective. Below, every variant predicts with one solver's betas (V0 under \"all QP betas\": beta . x "
            "with its QP betas; under \"all L-BFGS-B betas\": the published pipeline).",
            markdown(sensitivity)]
    return text, chosen


# --- Step 3: held-out ----------------------------------------------------------------------------------------

def heldout_rows(pairs: StudyPairs, fits: dict, resamples: int, seed: int) -> list[list]:
    """Rows (variant, fit, group, n, rho, p, ci_lo, ci_hi, mae, rmse) on the held-out pairs."""
    held, rows = ~pairs.both_in(CONTROL), []
    for variant, full in fits.items():
        cells = [("joint", "pooled", full.joint_predicted, held)]
        for group in pairs.groups:
            mine = held & (pairs.model == group)
            cells += [("joint", group, full.joint_predicted, mine), ("own", group, full.own_predicted, mine)]
        for fit, group, predicted, mask in cells:
            r = reliability(predicted[mask], pairs.delta[mask], resamples, seed)
            rows.append([variant, fit, group, r.n, r.rho, r.p, *r.ci, r.mae, r.rmse])
    return rows


def heldout_tables(pairs: StudyPairs, rows) -> list[str]:
    def cell(variant, fit, group) -> str:
        row = next(r for r in rows if r[:3] == [variant, fit, group])
        return "undefined" if not np.isfinite(row[4]) else f"{row[4]:.3f} [{row[6]:.3f}, {row[7]:.3f}]"

    out = []
    for fit, groups in (("joint", ("pooled", *pairs.groups)), ("own", pairs.groups)):
        table = [["variant", *(f"{g} rho [95 % CI]" for g in groups)]]
        table += [[v, *(cell(v, fit, g) for g in groups)] for v in VARIANTS]
        out += [f"### Held-out rho, {'joint fit' if fit == 'joint' else 'each group under its own fit'}",
                markdown(table)]
    return out


def paired_rows(pairs: StudyPairs, fits: dict, chosen: str, resamples: int, seed: int) -> list[list]:
    """rho(V) - rho(V0) under the joint fit, pooled held-out pairs resampled within each group, and the
    number of groups where V is above V0; the chosen variant's row decides, the others are exploratory."""
    held, rows = ~pairs.both_in(CONTROL), []
    base, delta, model = fits[BASELINE].joint_predicted[held], pairs.delta[held], pairs.model[held]
    for variant in VARIANTS:
        if variant == BASELINE:
            continue
        mine = fits[variant].joint_predicted[held]
        d = paired_rho_difference(mine, base, delta, model, resamples, seed)
        rows.append([variant, "decision" if variant == chosen else "exploratory", d.n, d.rho_a, d.rho_b,
                     d.difference, *d.ci, d.used, groups_above(mine, base, delta, model), len(pairs.groups), d])
    return rows


def decide(rows, variant: str, needed: int) -> tuple[bool, str]:
    """Whether ``variant`` beats V0 under the decision rule, and why."""
    if variant == BASELINE:
        return False, "V* is V0: no candidate proceeded; the published RigCD stays."
    row = next(r for r in rows if r[0] == variant)
    d, above, groups = row[-1], row[9], row[10]
    beats, ci_ok = beats_baseline(d, above, needed), bool(d.ci[0] > 0)
    verdict = "beats the published RigCD" if beats else "no improvement shown; the published RigCD stays"
    return beats, (f"{variant}: paired difference {d.difference:.4f}, 95 % CI [{d.ci[0]:.4f}, {d.ci[1]:.4f}] "
                   f"({'entirely above 0' if ci_ok else 'not entirely above 0'}); rho above V0 for {above} of "
                   f"{groups} groups (needed {needed}) -> {verdict}.")


def v0_check(pairs: StudyPairs, fits: dict, table) -> str:
    """How V0 compares with the shipped weights and with rigopt.metrics.protocol.calibrate."""
    published, v0 = calibrate(table, resamples=0), fits[BASELINE]
    own_diff = max(np.max(np.abs(m.pairs.predicted - v0.own_predicted[pairs.model == m.model]))
                   for m in published.models)
    joint_diff = float(np.max(np.abs(published.joint.pairs.predicted - v0.joint_predicted)))
    weights = [(v0.joint.calibration, load_weights("joint"))]
    weights += [(v0.own[g].calibration, load_weights(g)) for g in pairs.groups]
    weight_diff = max(abs(getattr(a, k) - getattr(b, k)) for a, b in weights
                      for k in ("K", "alpha", "lambda_t", "lambda_r", "lambda_f"))
    return (f"V0 check: largest |difference| of V0's predictions from `protocol.calibrate`'s: {own_diff:.2e} "
            f"(own fits), {joint_diff:.2e} (joint fit); of its (K, alpha, lambdas) from the shipped "
            f"`metrics/weights/*.json`: {weight_diff:.2e}.")


def v6_summary(fits: dict) -> str:
    full = fits[REMATCH]
    loops = [("joint", full.joint.rematch)] + [(g, f.rematch) for g, f in full.own.items()]
    return "; ".join(f"{name}: {'converged after' if loop.converged else 'not converged in'} {loop.rounds} "
                     f"refits, match lambdas ({', '.join(f'{v:.4g}' for v in loop.lambdas)})"
                     for name, loop in loops) + "."


def fits_dict(full, variant: str, settings: PlusSettings) -> dict:
    return {"variant": variant, "features": list(VARIANTS[variant]), "control_rigs": list(CONTROL),
            "settings": asdict(settings), "joint": full.joint.to_dict(),
            "detectors": {g: f.to_dict() for g, f in full.own.items()}}


def heldout_step(pairs: StudyPairs, chosen: str, needed: int, resamples: int, seed: int):
    """Every variant's full fits, the held-out rows, the paired rows and the decision for ``chosen``."""
    fits = {v: fit_full(v, pairs, pairs.both_in(CONTROL)) for v in VARIANTS}
    rows = heldout_rows(pairs, fits, resamples, seed)
    paired = paired_rows(pairs, fits, chosen, resamples, seed)
    return fits, rows, paired, decide(paired, chosen, needed)


# --- Steps 1 and 4 -------------------------------------------------------------------------------------------

def features_step(settings: PlusSettings):
    names = rig_names()
    rigs = [load_rig(name) for name in names]
    profiles = []
    for rig in rigs:
        profiles.append(rig_profile(rig, settings=settings))
        log(f"profile {rig.name} ({len(rig.cameras)} cameras, vehicle {profiles[-1].vehicle})")
    matrices = term_matrices(profiles, profiles, TERMS, settings)
    rows = [[a, b, "calibration" if a in CONTROL and b in CONTROL else "held-out",
             *(float(matrices[t][i, j]) for t in TERMS)] for i, a in enumerate(names) for j, b in enumerate(names)]
    write_csv(RESULTS / "features.csv", ["train", "test", "set", *TERMS], rows)
    log(f"features of {len(rows)} rig pairs -> features.csv")
    return names, rigs, matrices


def synthetic_step(names, rigs, matrices, settings, real_chosen: str, resamples: int, seed: int) -> str:
    parts = ["# RigCD+ on rigopt's synthetic transfer (generated by run.py)",
             f"Data: `studies/baselines/results/transfer/`; rigs {', '.join(SYNTHETIC_RIGS)}; held-out = pairs "
             "with R2, R5 or R9. Decision rule with \"all families\" in place of \"3 of 4 detectors\"."]
    drops = read_transfer(SYNTHETIC).drops()
    run = []
    for family in SYNTHETIC_FAMILIES:
        trained = set(drops.train[drops.model == family].tolist())
        if set(CONTROL) <= trained:
            run.append(family)
        else:
            parts.append(f"**{family}: not run** (control training rigs present: "
                         f"{', '.join(r for r in CONTROL if r in trained) or 'none'}).")
    if not run:
        return "\n\n".join(parts) + "\n"
    keep = np.isin(drops.model, run) & np.isin(drops.train, SYNTHETIC_RIGS) & np.isin(drops.test, SYNTHETIC_RIGS)
    pairs = build_pairs(drops.select(keep), names, rigs, matrices, settings)
    calibration = pairs.both_in(CONTROL)
    log(f"synthetic: families {', '.join(run)}, {len(pairs.delta)} pairs ({int(calibration.sum())} calibration)")
    cv_text, chosen = cv_report(pairs, cross_validate(pairs))
    _, rows, paired, (_, own_decision) = heldout_step(pairs, chosen, len(run), resamples, seed)
    real_beats, real_decision = decide(paired, real_chosen, len(run))
    confirm = ("nothing to confirm (real-data V* is V0)" if real_chosen == BASELINE
               else "yes" if real_beats else "no (it does not beat V0 here)")
    parts += [f"Families run: {', '.join(run)}; {len(pairs.delta)} pairs, {int(calibration.sum())} calibration, "
              f"{int((~calibration).sum())} held-out.",
              "## Cross-validation (leave one control rig out)", *cv_text,
              "## Held-out", *heldout_tables(pairs, rows),
              "## Paired bootstrap, joint fit, pooled held-out pairs (rho(V) - rho(V0))",
              markdown([PAIRED_HEADER, *(nan_to_none(r[:-1]) for r in paired)]),
              f"**Decision for the synthetic V\\***: {own_decision}",
              f"**Real-data V\\* ({real_chosen}) on the synthetic transfer**: {real_decision}",
              f"Confirms the real-data result: {confirm}."]
    return "\n\n".join(parts) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bootstrap", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    RESULTS.mkdir(exist_ok=True)
    settings = PlusSettings()

    # 1. features
    names, rigs, matrices = features_step(settings)
    table = read_transfer(data_dir("metrics") / "pccr_transfer.csv")
    pairs = build_pairs(table.drops(), names, rigs, matrices, settings)
    calibration = pairs.both_in(CONTROL)
    same = all(np.array_equal(pairs.published[:, k], pairs.terms[t]) for k, t in enumerate(VARIANTS[BASELINE]))
    log(f"real data: {len(pairs.delta)} pairs, {int(calibration.sum())} calibration; V0 features equal the "
        f"unit-matching terms: {same}")

    # 2. cross-validation, written before anything held-out is computed
    cv = cross_validate(pairs)
    write_csv(RESULTS / "cv.csv", cv.table[0], cv.table[1:])
    cv_text, chosen = cv_report(pairs, cv)
    (RESULTS / "cv.md").write_text("\n\n".join([
        "# RigCD+: cross-validation inside the calibration set (generated by run.py, before the held-out step)",
        "Leave one control rig out (6 folds); Spearman rho of out-of-fold predictions over the 36 pairs of each "
        "detector (own fits) and over the 144 pairs of the joint fits (joint CV rho, the choice).",
        *cv_text]) + "\n")
    log(f"cv.md, cv.csv written; V* = {chosen}")

    # 3. held-out
    fits, rows, paired, (beats, decision) = heldout_step(pairs, chosen, 3, args.bootstrap, args.seed)
    write_csv(RESULTS / "heldout.csv", HELDOUT_HEADER, rows)
    write_csv(RESULTS / "paired.csv", PAIRED_HEADER, [r[:-1] for r in paired])
    every = {v: fits_dict(full, v, settings) for v, full in fits.items()}
    (RESULTS / "fits.json").write_text(json.dumps(every, indent=2) + "\n")
    (RESULTS / "chosen.json").write_text(json.dumps(every[chosen], indent=2) + "\n")
    log(f"held-out done; {decision}")

    # 4. synthetic
    synthetic = synthetic_step(names, rigs, matrices, settings, chosen, args.bootstrap, args.seed)
    (RESULTS / "synthetic.md").write_text(synthetic)
    confirm = next((line for line in synthetic.splitlines() if line.startswith("Confirms")), "synthetic: not run")

    betas = [[v, ", ".join(f"{n} {b:.4g}" for n, b in zip(VARIANTS[v], full.joint.beta))] for v, full in fits.items()]
    agree = [[v, full.joint.fit.agrees, *(full.own[g].fit.agrees for g in pairs.groups)] for v, full in fits.items()]
    (RESULTS / "results.md").write_text("\n\n".join([
        "# RigCD+: results (generated by run.py)",
        f"Protocol: [README.md](../README.md). Bootstrap {args.bootstrap} resamples, seed {args.seed}. "
        f"Pairs: {int(calibration.sum())} calibration, {int((~calibration).sum())} held-out.",
        "## Choice (cross-validation, [cv.md](cv.md))", cv_text[2],
        "## Held-out reliability (every variant; only V* can decide, the rest is exploratory)",
        *heldout_tables(pairs, rows),
        "## Paired bootstrap, joint fit, 640 held-out pairs resampled within each detector (rho(V) - rho(V0))",
        markdown([PAIRED_HEADER, *(nan_to_none(r[:-1]) for r in paired)]),
        f"## Decision\n\n**{decision}**",
        f"## Synthetic check ([synthetic.md](synthetic.md))\n\n{confirm}",
        "## Joint-fit betas (predictions use these)", markdown([["variant", "beta"], *betas]),
        "## V6 loop (full-calibration fits)", v6_summary(fits),
        "## Solvers agree (QP vs L-BFGS-B, full-calibration fits)",
        markdown([["variant", "joint", *pairs.groups], *agree]), v0_check(pairs, fits, table),
        "## Notes on the protocol as run", NOTES, "## Deviations", "None.",
    ]) + "\n")
    log(f"done; beats published: {beats}; total {time.time() - START:.1f} s")


if __name__ == "__main__":
    main()
