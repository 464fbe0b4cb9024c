"""RigCD+ study, protocol 2 (README.md beside this file, fixed before any protocol-2 held-out figure).

Steps, in this order:
  1. features:  every RigCD+ term of every rig pair, incl. the framed ones -> features.csv (rig profiles cached
                in .cache/, ignored by git);
  2. cv:        leave-one-control-rig-out CV, both solvers, the choice of V* (primary solver) -> cv.md, cv.csv;
  3. heldout:   every variant refitted on all calibration pairs, held-out S with the rig bootstrap and the
                jackknife, both solvers, the decision -> heldout.csv, paired.csv, fits.json;
  4. link:      linear vs bounded held-out MAE / RMSE -> link.csv;
  5. origin:    each vehicle's origin moved by +-1 m -> origin.csv;
  6. synthetic: the same on rigopt's synthetic transfer -> synthetic.md; then results.md.
Usage: OMP_NUM_THREADS=1 python studies/rigcd_plus/run.py [--bootstrap 1000] [--seed 0] [--reuse-features]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np
import plus_study as ps
from plus_study import BASELINE, PRIMARY_SOLVER, SOLVERS, VARIANTS
from plus_terms import TERMS, PlusSettings, RigProfile, rig_profile, term_matrices

from rigopt.metrics.prediction import choose_link
from rigopt.metrics.transfer import read_transfer
from rigopt.resources import data_dir
from rigopt.rig.library import load_rig, rig_names
from rigopt.vehicle.library import load_vehicle

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies/: the studies' shared code (studylib)
from studylib.tables import markdown, write_csv  # noqa: E402

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
CACHE = HERE / ".cache" / "profiles.npz"
CONTROL = ("R1", "R1-r", "R1-t", "R1-f", "R1-c6", "R1-c10")
SYNTHETIC = HERE.parents[1] / "measurements" / "transfer"
SYNTHETIC_FAMILIES = ("lss", "petr")
SYNTHETIC_RIGS = (*CONTROL, "R2", "R5", "R9")
START = time.time()


def log(message: str) -> None:
    print(f"[{time.time() - START:7.1f} s] {message}", flush=True)


def fmt(value, digits: int = 3) -> str:
    return "undefined" if value is None or not np.isfinite(value) else f"{value:.{digits}f}"


def interval(ci) -> str:
    return f"[{fmt(ci[0])}, {fmt(ci[1])}]"


# --- 1. features -------------------------------------------------------------------------------------------

def profiles_of(rigs, vehicles, settings: PlusSettings, reuse: bool) -> list[RigProfile]:
    """One profile per rig, from the cache when ``reuse`` and it holds every rig with these settings."""
    key = repr(asdict(settings.coverage))
    if reuse and CACHE.exists():
        data = np.load(CACHE, allow_pickle=False)
        if str(data["key"]) == key and all(f"sees_{r.name}" in data for r in rigs):
            log("profiles read from the cache")
            return [RigProfile(r, v.name, settings.coverage, data[f"sees_{r.name}"], data[f"ring_{r.name}"],
                               data[f"sector_{r.name}"], data[f"occ_{r.name}"]) for r, v in zip(rigs, vehicles)]
    profiles, arrays = [], {"key": np.array(key)}
    for rig, vehicle in zip(rigs, vehicles):
        p = rig_profile(rig, vehicle, settings)
        profiles.append(p)
        arrays.update({f"sees_{rig.name}": p.sees, f"ring_{rig.name}": p.ring, f"sector_{rig.name}": p.sector,
                       f"occ_{rig.name}": p.self_occlusion})
        log(f"profile {rig.name} ({len(rig.cameras)} cameras, vehicle {vehicle.name})")
    CACHE.parent.mkdir(exist_ok=True)
    np.savez_compressed(CACHE, **arrays)
    return profiles


def every_term(profiles, vehicles, settings, shifts=None) -> dict[str, np.ndarray]:
    """Every term (R, R) of the (possibly moved) profiles."""
    entries = profiles if shifts is None else [ps.moved(p, s) for p, s in zip(profiles, shifts)]
    terms = term_matrices(entries, entries, TERMS, settings)
    terms.update(ps.framed_terms(entries, vehicles, shifts))
    return terms


def features_step(settings: PlusSettings, reuse: bool):
    names = rig_names()
    rigs = [load_rig(n) for n in names]
    vehicles = [load_vehicle(r.vehicle) for r in rigs]
    profiles = profiles_of(rigs, vehicles, settings, reuse)
    terms = every_term(profiles, vehicles, settings)
    keys = list(terms)
    rows = [[a, b, "calibration" if a in CONTROL and b in CONTROL else "held-out",
             *(float(terms[t][i, j]) for t in keys)] for i, a in enumerate(names) for j, b in enumerate(names)]
    write_csv(RESULTS / "features.csv", ["train", "test", "set", *keys], rows)
    log(f"features of {len(rows)} rig pairs ({len(keys)} terms) -> features.csv")
    return names, rigs, vehicles, profiles, terms


def study_of(drops, names, groups, terms, rematch) -> ps.Study:
    delta = ps.delta_matrix(drops.model, drops.train, drops.test, drops.delta, names, groups)
    return ps.Study(tuple(names), tuple(groups), delta, terms, np.isin(names, CONTROL), rematch)


# --- 2. cross-validation -----------------------------------------------------------------------------------

def cross_validate(study: ps.Study) -> dict:
    """{solver: {variant: (CV score, (D,) per-group CV rho)}}."""
    out = {}
    for solver in SOLVERS:
        out[solver] = {}
        for variant in VARIANTS:
            pairs, predicted = ps.cv_predictions(variant, study, solver)
            rhos = ps.group_rhos(predicted, pairs, len(study.groups))
            out[solver][variant] = (float(np.mean(rhos)), rhos)
        log(f"cv ({solver}): " + ", ".join(f"{v} {fmt(s)}" for v, (s, _) in out[solver].items()))
    return out


def cv_section(study: ps.Study, cv: dict, csv: Path | None = None) -> tuple[list[str], str, dict]:
    chosen = {s: ps.choose({v: cv[s][v][0] for v in VARIANTS}) for s in SOLVERS}
    header = ["variant", "features", *(f"CV score ({s})" for s in SOLVERS),
              *(f"{g} CV rho ({PRIMARY_SOLVER})" for g in study.groups)]
    rows = [[v, " ".join(VARIANTS[v]) + (" (calibrated matching)" if v == ps.REMATCH else ""),
             *(cv[s][v][0] for s in SOLVERS), *cv[PRIMARY_SOLVER][v][1]] for v in VARIANTS]
    if csv is not None:
        write_csv(csv, header, rows)
    table = markdown([header, *[[r[0], r[1], *(fmt(x) for x in r[2:])] for r in rows]])
    v = chosen[PRIMARY_SOLVER]
    text = [table,
            f"CV score = mean over the {len(study.groups)} groups of Spearman rho of the out-of-fold joint-fit "
            f"predictions (leave one control rig out). Primary solver: {PRIMARY_SOLVER}.",
            f"**V\\* = {v}** (primary solver; V0 {fmt(cv[PRIMARY_SOLVER][BASELINE][0])}"
            + (f", {v} {fmt(cv[PRIMARY_SOLVER][v][0])})." if v != BASELINE else
               "; no candidate exceeds V0, so none is tested).")
            + f" The choice under L-BFGS-B (check only) would be {chosen['lbfgsb']}."]
    return text, v, chosen


# --- 3. held-out -------------------------------------------------------------------------------------------

def heldout_step(study: ps.Study, resamples: int, seed: int, label: str) -> dict:
    """{solver: {variant: {...}}}: full fit, held-out S, per-group rho, pooled rho, bootstrap rhos,
    jackknife replicates."""
    draws = ps.rig_draws(study, resamples, seed)
    out = {}
    for solver in SOLVERS:
        out[solver] = {}
        for variant in VARIANTS:
            model, pairs, predicted = ps.heldout(variant, study, solver)
            rhos = ps.group_rhos(predicted, pairs, len(study.groups))
            boot = ps.bootstrap_rhos(variant, study, solver, draws)
            jack = ps.jackknife_scores(variant, study, solver)
            s = float(np.mean(rhos))
            out[solver][variant] = dict(model=model, pairs=pairs, predicted=predicted, rhos=rhos, score=s,
                                        pooled=ps.rank_rho(predicted, pairs.delta), boot=boot,
                                        ci=ps.percentile_interval(ps.bootstrap_scores(boot)), jack=jack,
                                        jack_ci=ps.jackknife_interval(s, jack))
            log(f"{label} held-out ({solver}) {variant}: S {fmt(s)} {interval(out[solver][variant]['ci'])}")
        base = out[solver][BASELINE]
        for variant, r in out[solver].items():
            r["diff"] = r["score"] - base["score"]
            r["diff_ci"], r["diff_used"] = ps.paired_interval(r["boot"], base["boot"])
            r["diff_jack_ci"] = ps.jackknife_interval(r["diff"], r["jack"] - base["jack"])
    return out


def heldout_tables(study: ps.Study, held: dict, chosen: str) -> tuple[list[str], list[list], list[list]]:
    rows, paired, text = [], [], []
    for solver in SOLVERS:
        table = [["variant", "S held-out", "rig bootstrap 95 %", "jackknife 95 %", "pooled rho",
                  *study.groups, "S - S(V0)", "rig bootstrap 95 %", "jackknife 95 %", "role"]]
        for variant, r in held[solver].items():
            role = ("baseline" if variant == BASELINE else "decision" if variant == chosen and
                    solver == PRIMARY_SOLVER else "exploratory")
            rows.append([variant, solver, len(r["pairs"].delta), r["score"], *r["ci"], *r["jack_ci"], r["pooled"],
                         *r["rhos"]])
            if variant != BASELINE:
                paired.append([variant, solver, role, r["diff"], *r["diff_ci"], r["diff_used"], *r["diff_jack_ci"]])
            table.append([variant, fmt(r["score"]), interval(r["ci"]), interval(r["jack_ci"]), fmt(r["pooled"]),
                          *(fmt(x) for x in r["rhos"]),
                          "" if variant == BASELINE else f"{r['diff']:+.3f}",
                          "" if variant == BASELINE else interval(r["diff_ci"]),
                          "" if variant == BASELINE else interval(r["diff_jack_ci"]), role])
        text += [f"### Solver {solver}" + (" (primary, decides)" if solver == PRIMARY_SOLVER else " (check)"),
                 markdown(table)]
    return text, rows, paired


def decide(held: dict, chosen: str) -> tuple[bool, str]:
    if chosen == BASELINE:
        return False, "V* is V0: no candidate exceeded V0 in CV, none was tested; the published RigCD stays."
    r = held[PRIMARY_SOLVER][chosen]
    beats = bool(np.isfinite(r["diff_ci"][0]) and r["diff_ci"][0] > 0)
    verdict = ("beats the published RigCD (proposed as default; the lead decides)" if beats
               else "no improvement shown; the published RigCD stays")
    return beats, (f"{chosen}: S(V*) - S(V0) = {r['diff']:+.4f}, rig-bootstrap 95 % interval "
                   f"[{r['diff_ci'][0]:+.4f}, {r['diff_ci'][1]:+.4f}] over {r['diff_used']} resamples "
                   f"({'entirely above 0' if beats else 'not entirely above 0'}) -> {verdict}.")


# --- 4. link -----------------------------------------------------------------------------------------------

def link_step(study: ps.Study) -> list[list]:
    """Per variant (primary solver): chosen link, its LORO MAE, held-out MAE / RMSE linear and bounded."""
    rows_c, cols_c = ps.calibration_pairs(study)
    calibration = ps.expand(study, rows_c, cols_c)
    names = np.array(study.rigs)
    out = []
    for variant in VARIANTS:
        def refit(fit_mask, variant=variant):
            model = ps.fit(variant, study, ps._take(calibration, fit_mask), PRIMARY_SOLVER)
            return lambda mask: model.predict(study, ps._take(calibration, mask))

        choice = choose_link(names[calibration.row], names[calibration.col], calibration.delta, refit)
        model, pairs, linear = ps.heldout(variant, study, PRIMARY_SOLVER)
        bounded = choice.link(linear)
        errors = {k: p - pairs.delta for k, p in (("linear", linear), ("bounded", bounded))}
        out.append([variant, choice.link.kind, *choice.link.parameters, *([None] * (2 - len(choice.link.parameters))),
                    choice.loro_mae[choice.link.kind], choice.interval.halfwidth,
                    *(f(errors[k]) for k in ("linear", "bounded")
                      for f in (lambda e: float(np.mean(np.abs(e))), lambda e: float(np.sqrt(np.mean(e ** 2)))))])
    log("link done")
    return out


LINK_HEADER = ["variant", "link", "param_1", "param_2", "loro_mae", "interval_halfwidth", "heldout_mae_linear",
               "heldout_rmse_linear", "heldout_mae_bounded", "heldout_rmse_bounded"]


# --- 5. origin sensitivity ---------------------------------------------------------------------------------

def origin_step(study: ps.Study, names, rigs, vehicles, profiles, settings) -> list[list]:
    """Per variant: largest |change| of any pair's prediction over every vehicle x axis x sign move of 1 m,
    the range of held-out S over the moves, and R1 -> R9 with the hgv moved by -1 / +1 m along x."""
    base = {v: ps.heldout(v, study, PRIMARY_SOLVER) for v in VARIANTS}
    every = np.arange(len(names))
    full_rows, full_cols = ps.all_pairs(every)
    worst = {v: 0.0 for v in VARIANTS}
    scores = {v: [ps.score(base[v][2], base[v][1], len(study.groups))] for v in VARIANTS}
    r1, r9 = names.index("R1"), names.index("R9")
    example = {v: {} for v in VARIANTS}
    for vehicle in dict.fromkeys(r.vehicle for r in rigs):
        for axis in range(3):
            for sign in (-1.0, 1.0):
                shift = np.zeros(3)
                shift[axis] = sign
                shifts = np.array([shift if r.vehicle == vehicle else np.zeros(3) for r in rigs])
                terms = every_term(profiles, vehicles, settings, shifts)
                entries = [ps.moved(p, s) for p, s in zip(profiles, shifts)]
                moved = ps.Study(study.rigs, study.groups, study.delta, terms, study.control, ps.rematcher(entries))
                for v in VARIANTS:
                    model, pairs, predicted = ps.heldout(v, moved, PRIMARY_SOLVER)
                    every_pair = ps.Pairs(np.zeros(len(full_rows), int), full_rows, full_cols, np.zeros(len(full_rows)))
                    before = base[v][0].predict(study, every_pair)
                    after = model.predict(moved, every_pair)
                    worst[v] = max(worst[v], float(np.max(np.abs(after - before))))
                    scores[v].append(ps.score(predicted, pairs, len(study.groups)))
                    if vehicle.endswith("european_hgv") and axis == 0:
                        one = ps.Pairs(np.zeros(1, int), np.array([r1]), np.array([r9]), np.zeros(1))
                        example[v][sign] = float(model.predict(moved, one)[0])
        log(f"origin moves of {vehicle} done")
    out = []
    for v in VARIANTS:
        one = ps.Pairs(np.zeros(1, int), np.array([r1]), np.array([r9]), np.zeros(1))
        out.append([v, worst[v], min(scores[v]), max(scores[v]), example[v].get(-1.0),
                    float(base[v][0].predict(study, one)[0]), example[v].get(1.0)])
    return out


ORIGIN_HEADER = ["variant", "max_abs_prediction_change", "heldout_S_min", "heldout_S_max", "R1_R9_hgv_minus_1m",
                 "R1_R9", "R1_R9_hgv_plus_1m"]


# --- 6. synthetic ------------------------------------------------------------------------------------------

def synthetic_step(study: ps.Study, real_chosen: str, resamples: int, seed: int) -> str:
    parts = ["# RigCD+ protocol 2 on rigopt's synthetic transfer (generated by run.py)",
             f"Data: `measurements/transfer/`; rigs {', '.join(SYNTHETIC_RIGS)}; held-out = pairs with "
             "R2, R5 or R9; S = mean over the families; rig bootstrap: 6 control draws and 3 other draws."]
    drops = read_transfer(SYNTHETIC).drops()
    run = [f for f in SYNTHETIC_FAMILIES if set(CONTROL) <= set(drops.train[drops.model == f].tolist())]
    parts += [f"**{f}: not run** (a control training rig is missing)." for f in SYNTHETIC_FAMILIES if f not in run]
    if not run:
        return "\n\n".join(parts) + "\n"
    delta = ps.delta_matrix(drops.model, drops.train, drops.test, drops.delta, SYNTHETIC_RIGS, run)
    sub = study.subset(SYNTHETIC_RIGS, run, delta)
    cv = cross_validate(sub)
    cv_text, chosen, _ = cv_section(sub, cv)
    held = heldout_step(sub, resamples, seed, "synthetic")
    text, _, _ = heldout_tables(sub, held, chosen)
    _, own = decide(held, chosen)
    r = held[PRIMARY_SOLVER][real_chosen]
    if real_chosen == BASELINE:
        confirm = "nothing to confirm (the real-data V* is V0)."
    else:
        above = np.isfinite(r["diff_ci"][0]) and r["diff_ci"][0] > 0
        confirm = (f"real-data V* {real_chosen} here: S - S(V0) = {r['diff']:+.3f} {interval(r['diff_ci'])} -> "
                   + ("confirms" if above else "does not confirm") + ".")
    parts += [f"Families run: {', '.join(run)}.", "## Cross-validation", *cv_text,
              "## Held-out", *text, f"**Decision for the synthetic V\\***: {own}", f"Confirms: {confirm}"]
    return "\n\n".join(parts) + "\n"


# --- main ----------------------------------------------------------------------------------------------------

def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bootstrap", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--reuse-features", action="store_true", help="read the rig profiles from .cache/")
    parser.add_argument("--stop-after-cv", action="store_true")
    args = parser.parse_args()
    RESULTS.mkdir(exist_ok=True)
    settings = PlusSettings()

    names, rigs, vehicles, profiles, terms = features_step(settings, args.reuse_features)
    table = read_transfer(data_dir("metrics") / "pccr_transfer.csv")
    drops = table.drops()
    study = study_of(drops, names, tuple(dict.fromkeys(drops.model.tolist())), terms, ps.rematcher(profiles))
    log(f"real data: groups {', '.join(study.groups)}; {int(np.isfinite(study.delta).sum())} pairs")

    cv = cross_validate(study)
    cv_text, chosen, _ = cv_section(study, cv, RESULTS / "cv.csv")
    (RESULTS / "cv.md").write_text("\n\n".join([
        "# RigCD+ protocol 2: cross-validation inside the calibration set (generated by run.py, before the "
        "held-out step)", *cv_text]) + "\n")
    log(f"cv.md written; V* = {chosen}")
    if args.stop_after_cv:
        return

    held = heldout_step(study, args.bootstrap, args.seed, "real")
    held_text, held_rows, paired = heldout_tables(study, held, chosen)
    write_csv(RESULTS / "heldout.csv", ["variant", "solver", "n", "S", "boot_lo", "boot_hi", "jack_lo", "jack_hi",
                                        "pooled_rho", *(f"rho_{g}" for g in study.groups)], held_rows)
    write_csv(RESULTS / "paired.csv", ["variant", "solver", "role", "S_minus_S_V0", "boot_lo", "boot_hi",
                                       "resamples_used", "jack_lo", "jack_hi"], paired)
    beats, decision = decide(held, chosen)
    fits = {s: {v: {"features": list(VARIANTS[v]), "beta": [float(b) for b in r["model"].beta],
                    "match_lambdas": list(r["model"].lambdas)} for v, r in held[s].items()} for s in SOLVERS}
    (RESULTS / "fits.json").write_text(json.dumps(fits, indent=2) + "\n")
    log(f"held-out done; {decision}")

    links = link_step(study)
    write_csv(RESULTS / "link.csv", LINK_HEADER, links)
    origin = origin_step(study, names, rigs, vehicles, profiles, settings)
    write_csv(RESULTS / "origin.csv", ORIGIN_HEADER, origin)

    synthetic = synthetic_step(study, chosen, args.bootstrap, args.seed)
    (RESULTS / "synthetic.md").write_text(synthetic)
    confirm = next((line for line in synthetic.splitlines() if line.startswith("Confirms")), "not run")

    summary = [["variant", "CV score (qp)", "S held-out (qp) [rig bootstrap]", "S - S(V0) (qp) [rig bootstrap]",
                "CV score (lbfgsb)", "S held-out (lbfgsb)", "S - S(V0) (lbfgsb) [rig bootstrap]",
                "origin: max |change| of a prediction", "MAE linear / bounded (link)"]]
    for (v, r_q), r_l, o, l in zip(held["qp"].items(), held["lbfgsb"].values(), origin, links):
        summary.append([v, fmt(cv["qp"][v][0]), f"{fmt(r_q['score'])} {interval(r_q['ci'])}",
                        "" if v == BASELINE else f"{r_q['diff']:+.3f} {interval(r_q['diff_ci'])}",
                        fmt(cv["lbfgsb"][v][0]), fmt(r_l["score"]),
                        "" if v == BASELINE else f"{r_l['diff']:+.3f} {interval(r_l['diff_ci'])}",
                        fmt(o[1]), f"{fmt(l[6])} / {fmt(l[8])} ({l[1]})"])
    (RESULTS / "results.md").write_text("\n\n".join([
        "# RigCD+ protocol 2: results (generated by run.py)",
        f"Protocol: [README.md](../README.md) (protocol 2). Rig bootstrap {args.bootstrap} resamples, seed "
        f"{args.seed}; primary solver {PRIMARY_SOLVER}. S = mean over the four detectors of held-out Spearman rho "
        "under the joint fit.",
        "## Summary", markdown(summary),
        "## Choice (cross-validation, [cv.md](cv.md))", cv_text[2],
        f"## Decision\n\n**{decision}**",
        "## Held-out, every variant (only V* can decide; the rest is exploratory)", *held_text,
        "## Link (primary solver, joint fit): held-out MAE / RMSE, linear vs bounded",
        markdown([LINK_HEADER, *[[r[0], r[1], *(fmt(x, 4) for x in r[2:])] for r in links]]),
        "## Origin sensitivity (primary solver): each vehicle's origin moved by +-1 m along x, y, z",
        markdown([ORIGIN_HEADER, *[[r[0], *(fmt(x) for x in r[1:])] for r in origin]]),
        f"## Synthetic check ([synthetic.md](synthetic.md))\n\n{confirm}",
    ]) + "\n")
    log(f"done; V* {chosen} beats published: {beats}; total {time.time() - START:.1f} s")


if __name__ == "__main__":
    main()
