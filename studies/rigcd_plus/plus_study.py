"""The RigCD+ study's machinery: its variants and their fits (the non-negative fit and the V6 rematch loop
are the package's, ``rigopt.metrics.matched_fit``), leave-one-rig-out cross-validation over control rigs,
the choice rule and a paired bootstrap of a difference of Spearman rhos. Protocol: ``README.md`` beside
this file; imported by ``run.py`` from this folder (run it as ``python studies/rigcd_plus/run.py``).

Shapes: P pairs of one study (ordered (training rig, test rig) per detector), k features of a variant.
A variant's model is ``delta_hat = beta . x`` with ``beta >= 0``, except V0, which is the published pipeline
(:func:`rigopt.metrics.calibration.fit_calibration`: L-BFGS-B, predictions from the reported
(K, alpha, lambdas), fallback included).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Mapping, Sequence

import numpy as np
from scipy.stats import rankdata

from plus_terms import PlusSettings, term_matrices
from rigopt.errors import RigoptError
from rigopt.metrics.calibration import UNIT_LAMBDAS, Calibration, fit_calibration
from rigopt.metrics.matched_fit import SOLVERS, NonnegFit, RematchFit, fit_nonneg, fit_rematched
from rigopt.metrics.reliability import DEFAULT_BOOTSTRAP, DEFAULT_SEED, _pearson_rows, spearman

#: Every variant of the study and its features, in the order of the protocol's table.
VARIANTS: dict[str, tuple[str, ...]] = {
    "V0": ("t", "r", "f", "count"),
    "V1": ("dz", "dxy", "r", "f", "count"),
    "V2": ("t", "r", "focal", "count"),
    "V3": ("t", "r", "f", "count", "cover"),
    "V4": ("t", "r", "f", "count", "overlap"),
    "V5": ("t", "r", "f", "count", "selfocc"),
    "V6": ("t", "r", "f", "count"),  # under the calibrated matching
    "V7": ("cw_t", "cw_r", "cw_f", "count"),
    "C1": ("dz", "dxy", "r", "focal", "count"),
    "C2": ("t", "r", "f", "count", "cover", "overlap"),
    "C3": ("dz", "dxy", "r", "focal", "count", "cover", "overlap", "selfocc"),
}
BASELINE = "V0"
REMATCH = "V6"
CHOICE_MARGIN = 0.01


# --- Pairs of a study ---------------------------------------------------------------------------------------

@dataclass(frozen=True)
class StudyPairs:
    """Every pair of one study; arrays (P,) unless stated.

    ``model``, ``train``, ``test`` (str); ``delta`` (float) observed relative drop; ``terms``
    {term: (P,) float} under the unit-weight matching; ``published`` (P, 4) float: V0's features
    (t, r, f, count) as the published pipeline computes them; ``rematch``: match lambdas (3,) ->
    (P, 4) float (t, r, f, count) under that matching (V6).
    """

    model: np.ndarray
    train: np.ndarray
    test: np.ndarray
    delta: np.ndarray
    terms: Mapping[str, np.ndarray]
    published: np.ndarray
    rematch: Callable[[tuple[float, float, float]], np.ndarray]

    def features(self, names: Sequence[str]) -> np.ndarray:
        """(P, k) float: the unit-matching terms ``names`` as columns."""
        return np.stack([self.terms[name] for name in names], axis=1)

    @property
    def groups(self) -> tuple[str, ...]:
        """The detectors (or families) in order of first appearance."""
        return tuple(dict.fromkeys(self.model.tolist()))

    def both_in(self, rigs: Sequence[str]) -> np.ndarray:
        """(P,) bool: pairs whose training and test rigs are both among ``rigs`` (the calibration set)."""
        return np.isin(self.train, rigs) & np.isin(self.test, rigs)


def pair_index(names: Sequence[str], train, test) -> tuple[np.ndarray, np.ndarray]:
    """Row and column (P,) int of the pairs (train[p], test[p]) in matrices over the rigs ``names``."""
    index = {name: k for k, name in enumerate(names)}
    missing = sorted(set(train) - set(index) | set(test) - set(index))
    if missing:
        raise RigoptError(f"no rig for {', '.join(missing)} among {', '.join(names)}")
    return np.array([index[a] for a in train], dtype=int), np.array([index[b] for b in test], dtype=int)


def pair_terms_table(entries: Sequence, names: Sequence[str], train, test, terms: Sequence[str],
                     settings: PlusSettings | None = None) -> dict[str, np.ndarray]:
    """{term: (P,) float} of the pairs (train[p] -> test[p]); ``entries`` the rigs or RigProfiles named
    ``names`` (each computed once, all pairs in one :func:`term_matrices` call)."""
    rows, cols = pair_index(names, train, test)
    matrices = term_matrices(entries, entries, terms, settings)
    return {term: matrices[term][rows, cols] for term in terms}


def rematcher(rigs: Sequence, names: Sequence[str], train, test,
              settings: PlusSettings | None = None) -> Callable[[tuple[float, float, float]], np.ndarray]:
    """A cached function: match lambdas (3,) -> (P, 4) float (t, r, f, count) of the pairs
    (train[p] -> test[p]) under the matching with those lambdas (RigCD+ term 6)."""
    settings = PlusSettings() if settings is None else settings
    cache: dict[tuple[float, ...], np.ndarray] = {}

    def features(lambdas) -> np.ndarray:
        key = tuple(float(v) for v in lambdas)
        if key not in cache:
            table = pair_terms_table(rigs, names, train, test, ("t", "r", "f", "count"),
                                     replace(settings, match_lambdas=key))
            cache[key] = np.stack([table[t] for t in ("t", "r", "f", "count")], axis=1)
            cache[key].flags.writeable = False
        return cache[key]

    return features


# --- Fits ---------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class VariantFit:
    """A variant fitted on one training set.

    ``fit``: both solvers' betas (k,); ``solver``: whose betas predict ("qp", the protocol's for candidates);
    ``beta`` (k,) the weights predictions use; ``calibration``: V0's reported weights, which then predict
    (the published pipeline, L-BFGS-B; None otherwise); ``rematch``: V6's loop (None otherwise).
    """

    variant: str
    features: tuple[str, ...]
    fit: NonnegFit
    solver: str = "qp"
    calibration: Calibration | None = None
    rematch: RematchFit | None = None

    @property
    def beta(self) -> np.ndarray:
        return np.asarray(self.calibration.beta) if self.calibration is not None else self.fit.beta(self.solver)

    @property
    def match_lambdas(self) -> tuple[float, float, float]:
        return self.rematch.lambdas if self.rematch is not None else UNIT_LAMBDAS

    def to_dict(self) -> dict:
        """JSON-ready: features, betas by name, solvers' agreement, the matching's lambdas; V0's (K, alpha,
        lambdas); V6's loop."""
        named = lambda beta: {name: float(b) for name, b in zip(self.features, beta)}  # noqa: E731
        out = {"variant": self.variant, "features": list(self.features), "beta": named(self.beta),
               "solver": self.solver, "beta_qp": named(self.fit.beta_qp), "beta_lbfgsb": named(self.fit.beta_lbfgsb),
               "objective_qp": self.fit.objective_qp, "objective_lbfgsb": self.fit.objective_lbfgsb,
               "solvers_agree": self.fit.agrees, "n": self.fit.n, "match_lambdas": list(self.match_lambdas)}
        if self.calibration is not None:
            out["calibration"] = self.calibration.to_dict()
        if self.rematch is not None:
            out.update(rematch_rounds=self.rematch.rounds, rematch_converged=self.rematch.converged)
        return out


def fit_variant(variant: str, pairs: StudyPairs, mask, name: str = "fit", solver: str | None = None) -> VariantFit:
    """Fit ``variant`` on the pairs where ``mask`` (P,) bool is true.

    ``solver`` None: the protocol (V0 the published pipeline, candidates the QP betas); "qp" or "lbfgsb":
    every variant, V0 included, predicts with that solver's betas (a diagnostic; V0 under "lbfgsb" stays
    the published pipeline, whose reported weights equal its L-BFGS-B betas but for the fallback).
    """
    if variant not in VARIANTS:
        raise RigoptError(f"unknown variant {variant!r}; use one of {', '.join(VARIANTS)}")
    if solver is not None and solver not in SOLVERS:
        raise RigoptError(f"unknown solver {solver!r}; use one of {', '.join(SOLVERS)}")
    mask = np.asarray(mask, dtype=bool)
    delta, features = pairs.delta[mask], VARIANTS[variant]
    if variant == BASELINE:
        published = fit_calibration(pairs.published[mask], delta, name)
        fit = NonnegFit(np.array(published.beta_qp), np.array(published.beta_lbfgsb), published.objective_qp,
                        published.objective_lbfgsb, published.qp_agrees, published.n)
        if solver == "qp":
            return VariantFit(variant, features, fit, "qp")
        return VariantFit(variant, features, fit, "lbfgsb", calibration=published.calibration)
    solver = solver or "qp"
    if variant == REMATCH:
        loop = fit_rematched(lambda lambdas: pairs.rematch(lambdas)[mask], delta, solver=solver)
        return VariantFit(variant, features, loop.fit, solver, rematch=loop)
    return VariantFit(variant, features, fit_nonneg(pairs.features(features)[mask], delta), solver)


def predict_variant(fitted: VariantFit, pairs: StudyPairs, mask) -> np.ndarray:
    """(m,) float predicted drops of the pairs where ``mask`` (P,) bool is true (m of them)."""
    mask = np.asarray(mask, dtype=bool)
    if fitted.calibration is not None:
        return fitted.calibration.predict(*pairs.published[mask].T)
    if fitted.rematch is not None:
        return pairs.rematch(fitted.rematch.lambdas)[mask] @ fitted.beta
    x = pairs.published if fitted.variant == BASELINE else pairs.features(fitted.features)
    return x[mask] @ fitted.beta


# --- Leave-one-rig-out cross-validation over the control rigs ----------------------------------------------

@dataclass(frozen=True)
class Fold:
    """One fold: ``left_out`` control rig; ``fit`` (P,) bool: calibration pairs with neither rig left out;
    ``predict`` (P,) bool: calibration pairs trained on the left-out rig."""

    left_out: str
    fit: np.ndarray
    predict: np.ndarray


def loro_folds(train, test, control_rigs: Sequence[str], within=None) -> list[Fold]:
    """One fold per control rig over the calibration pairs (both rigs control) of train, test (P,) str,
    restricted to ``within`` (P,) bool (default all pairs). Every calibration pair is predicted by exactly
    one fold, whose fit never sees its training rig."""
    train, test = np.asarray(train), np.asarray(test)
    within = np.ones(len(train), dtype=bool) if within is None else np.asarray(within, dtype=bool)
    calibration = within & np.isin(train, control_rigs) & np.isin(test, control_rigs)
    return [Fold(rig, calibration & (train != rig) & (test != rig), calibration & (train == rig))
            for rig in control_rigs]


def out_of_fold(folds: Sequence[Fold], fit_predict: Callable[[np.ndarray, np.ndarray], np.ndarray],
                n: int) -> np.ndarray:
    """(n,) float out-of-fold predictions, NaN for pairs no fold predicts.

    ``fit_predict(fit_mask, predict_mask)`` fits on the first (n,) bool mask and returns the predictions
    (m,) of the second's m pairs. Raises RigoptError when a pair is predicted twice."""
    predicted = np.full(n, np.nan)
    for fold in folds:
        if np.any(~np.isnan(predicted[fold.predict])):
            raise RigoptError(f"fold {fold.left_out!r} predicts a pair another fold predicts")
        predicted[fold.predict] = fit_predict(fold.fit, fold.predict)
    return predicted


def cv_predictions(variant: str, pairs: StudyPairs, control_rigs: Sequence[str], solver: str | None = None,
                   fits: list | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Out-of-fold predictions (P,) of ``variant`` over the calibration pairs (NaN elsewhere): (joint, own).

    joint: each fold fitted on every group's training pairs stacked; own: each group fitted on its own.
    ``solver`` as in :func:`fit_variant`; every fold's :class:`NonnegFit` is appended to ``fits`` if given.
    """
    def fit_predict(fit_mask, predict_mask):
        fitted = fit_variant(variant, pairs, fit_mask, solver=solver)
        if fits is not None:
            fits.append(fitted.fit)
        return predict_variant(fitted, pairs, predict_mask)

    n = len(pairs.delta)
    joint = out_of_fold(loro_folds(pairs.train, pairs.test, control_rigs), fit_predict, n)
    own = np.full(n, np.nan)
    for group in pairs.groups:
        mine = pairs.model == group
        own[mine] = out_of_fold(loro_folds(pairs.train, pairs.test, control_rigs, mine), fit_predict, n)[mine]
    calibration = pairs.both_in(control_rigs)
    if np.any(np.isnan(joint[calibration])) or np.any(np.isnan(own[calibration])):
        raise RigoptError(f"{variant}: a calibration pair was not predicted out of fold")
    return joint, own


@dataclass(frozen=True)
class FullFits:
    """A variant fitted on all calibration pairs: ``joint`` (every group stacked) and ``own`` {group: fit};
    ``joint_predicted`` and ``own_predicted`` (P,) float: every pair under them."""

    joint: VariantFit
    own: dict[str, VariantFit]
    joint_predicted: np.ndarray
    own_predicted: np.ndarray


def fit_full(variant: str, pairs: StudyPairs, calibration) -> FullFits:
    """Fit ``variant`` on the pairs where ``calibration`` (P,) bool is true, jointly and per group."""
    calibration = np.asarray(calibration, dtype=bool)
    every = np.ones(len(pairs.delta), dtype=bool)
    joint = fit_variant(variant, pairs, calibration, "joint")
    own, own_predicted = {}, np.full(len(pairs.delta), np.nan)
    for group in pairs.groups:
        mine = pairs.model == group
        own[group] = fit_variant(variant, pairs, calibration & mine, group)
        own_predicted[mine] = predict_variant(own[group], pairs, mine)
    return FullFits(joint, own, predict_variant(joint, pairs, every), own_predicted)


def choose_variant(scores: Mapping[str, float], n_features: Mapping[str, int], baseline: str = BASELINE,
                   margin: float = CHOICE_MARGIN) -> str:
    """The protocol's choice: the candidate (every key of ``scores`` but ``baseline``, in table order) with
    the highest score, provided it exceeds the baseline's score by at least ``margin``; candidates within
    ``margin`` of that best go to fewer features, then to table order. Only candidates that themselves
    clear the baseline by ``margin`` can be chosen; NaN scores never are. Returns ``baseline`` otherwise."""
    base = scores[baseline]
    eligible = [v for v in scores if v != baseline and np.isfinite(scores[v])
                and (not np.isfinite(base) or scores[v] - base >= margin)]
    if not eligible:
        return baseline
    best = max(scores[v] for v in eligible)
    tied = [v for v in eligible if best - scores[v] <= margin]
    order = list(scores)
    return min(tied, key=lambda v: (n_features[v], order.index(v)))


# --- Paired bootstrap of a rho difference -------------------------------------------------------------------

@dataclass(frozen=True)
class PairedDifference:
    """``rho(a) - rho(b)`` on the n pairs (NaN when either is undefined) and its 95 % bootstrap ``ci``
    (2.5, 97.5 percentiles) over ``used`` of the resamples (those with no constant side)."""

    rho_a: float
    rho_b: float
    difference: float
    ci: tuple[float, float]
    used: int
    n: int


def stratified_resamples(strata, resamples: int, seed: int) -> np.ndarray:
    """(resamples, n) int indices into n pairs, drawn with replacement within each stratum of ``strata``
    (n,) (strata in order of first appearance, each as one (resamples, n_s) draw of one generator)."""
    strata = np.asarray(strata)
    rng = np.random.default_rng(seed)
    columns = []
    for stratum in dict.fromkeys(strata.tolist()):
        members = np.flatnonzero(strata == stratum)
        columns.append(members[rng.integers(0, len(members), (resamples, len(members)))])
    return np.concatenate(columns, axis=1)


def paired_rho_difference(predicted_a, predicted_b, observed, strata=None, resamples: int = DEFAULT_BOOTSTRAP,
                          seed: int = DEFAULT_SEED) -> PairedDifference:
    """Spearman rho of predictions a (n,) minus that of b (n,) against observed (n,), with a paired
    bootstrap: both rhos on the same resampled pairs, resampled within ``strata`` (n,) (default one)."""
    a, b, o = (np.asarray(v, dtype=float) for v in (predicted_a, predicted_b, observed))
    if not (len(a) == len(b) == len(o)):
        raise RigoptError(f"predictions and observations differ in length: {len(a)}, {len(b)}, {len(o)}")
    rho_a, rho_b = spearman(a, o)[0], spearman(b, o)[0]
    nan = float("nan")
    if not (np.isfinite(rho_a) and np.isfinite(rho_b)) or resamples <= 0:
        return PairedDifference(rho_a, rho_b, rho_a - rho_b, (nan, nan), 0, len(o))
    index = stratified_resamples(np.zeros(len(o)) if strata is None else strata, resamples, seed)
    ra, rb, ro = a[index], b[index], o[index]
    usable = (np.ptp(ra, axis=1) > 0) & (np.ptp(rb, axis=1) > 0) & (np.ptp(ro, axis=1) > 0)
    if not usable.any():
        return PairedDifference(rho_a, rho_b, rho_a - rho_b, (nan, nan), 0, len(o))
    ranks_o = rankdata(ro[usable], axis=1)
    differences = (_pearson_rows(rankdata(ra[usable], axis=1), ranks_o)
                   - _pearson_rows(rankdata(rb[usable], axis=1), ranks_o))
    low, high = np.percentile(differences, [2.5, 97.5])
    return PairedDifference(rho_a, rho_b, rho_a - rho_b, (float(low), float(high)), int(usable.sum()), len(o))


def groups_above(predicted_a, predicted_b, observed, groups) -> int:
    """How many groups (distinct values of ``groups`` (n,)) have rho(a) > rho(b) against ``observed`` (n,);
    an undefined rho of a is never above, an undefined rho of b is below any defined one."""
    a, b, o, groups = (np.asarray(v) for v in (predicted_a, predicted_b, observed, groups))
    count = 0
    for group in dict.fromkeys(groups.tolist()):
        mine = groups == group
        rho_a, rho_b = spearman(a[mine], o[mine])[0], spearman(b[mine], o[mine])[0]
        count += bool(np.isfinite(rho_a) and (not np.isfinite(rho_b) or rho_a > rho_b))
    return count


def beats_baseline(difference: PairedDifference, above: int, needed: int) -> bool:
    """The decision rule: the paired 95 % interval lies entirely above 0 and the variant's rho is above the
    baseline's in at least ``needed`` groups (``above`` of them are)."""
    return bool(np.isfinite(difference.ci[0]) and difference.ci[0] > 0 and above >= needed)
