"""The RigCD+ study's machinery (protocol 2 of ``README.md`` beside this file): variants, origin frames, one
solver for every fit, leave-one-control-rig-out cross-validation, the score over detectors, the rig bootstrap
and jackknife, and origin moves. Imported by ``run.py`` (run it as ``python studies/rigcd_plus/run.py``).

Shapes: R rigs of a study, D groups (detectors or families); a study's drops are (D, R, R) (training rig,
test rig), NaN where a pair is missing; every term is an (R, R) matrix. A set of pairs is given by rig
indices ``rows``, ``cols`` (n,) (a rig may appear several times: the bootstrap draws with replacement) and is
expanded over the groups, missing pairs dropped. A variant's model is ``delta_hat = beta . x``, ``beta >= 0``,
fitted jointly (every group's pairs stacked, one beta) by one solver ("qp" or "lbfgsb").
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Mapping, Sequence

import numpy as np
from scipy.stats import rankdata

from plus_terms import RigProfile, term_matrices
from rigopt.errors import RigoptError
from rigopt.metrics.calibration import UNIT_LAMBDAS, fit_lbfgsb, fit_nnls
from rigopt.metrics.matched_fit import fit_rematched
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle

#: Frames of the origin-invariant variants (README, protocol 2).
FRAMES = ("box", "extent", "axle")
#: Terms recomputed in every frame (a framed term is named "term@frame").
FRAMED_TERMS = ("t", "r", "f", "count", "dz", "dxy")

#: Every variant and its features, in the order of the protocol's tables.
VARIANTS: dict[str, tuple[str, ...]] = {
    "V0": ("t", "r", "f", "count"),
    "V1": ("dz", "dxy", "r", "f", "count"),
    "V2": ("t", "r", "focal", "count"),
    "V3": ("t", "r", "f", "count", "cover"),
    "V4": ("t", "r", "f", "count", "overlap"),
    "V5": ("t", "r", "f", "count", "selfocc"),
    "V6": ("t", "r", "f", "count"),  # under the calibrated matching
    "V7": ("cw_t", "cw_r", "cw_f", "count"),
    "V8": ("r@box", "f@box", "count@box"),
    "V9": ("t@box", "r@box", "f@box", "count@box"),
    "V10": ("t@extent", "r@extent", "f@extent", "count@extent"),
    "V11": ("t@axle", "r@axle", "f@axle", "count@axle"),
    "V12": ("dz@box", "dxy@box", "r@box", "f@box", "count@box"),
    "C1": ("dz", "dxy", "r", "focal", "count"),
    "C2": ("t", "r", "f", "count", "cover", "overlap"),
    "C3": ("dz", "dxy", "r", "focal", "count", "cover", "overlap", "selfocc"),
}
BASELINE = "V0"
REMATCH = "V6"
PRIMARY_SOLVER = "qp"
#: Both solvers, the primary first (the order of the tables' columns).
SOLVERS = ("qp", "lbfgsb")


# --- Frames and origin moves ---------------------------------------------------------------------------------

def frame_of(vehicle: Vehicle, frame: str, origin_shift=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """(reference (3,) m, scale (3,)) of ``frame`` on ``vehicle``: framed positions = (p - reference) / scale.

    box: the footprint centre on the ground (bounding-box x, y centre, bounding-box bottom z), scale 1;
    extent: the same reference, scale = the vehicle's (length, width, height) m; axle: ``vehicle.rear_axle``,
    scale 1. ``origin_shift`` (3,) m: the vehicle's origin moved by this (its points' coordinates all
    decrease by it), so framed positions do not change."""
    low, high = np.asarray(vehicle.mesh.bounds, dtype=float)
    shift = np.asarray(origin_shift, dtype=float)
    if frame in ("box", "extent"):
        reference = np.array([(low[0] + high[0]) / 2, (low[1] + high[1]) / 2, low[2]])
        scale = np.asarray(vehicle.size, dtype=float) if frame == "extent" else np.ones(3)
    elif frame == "axle":
        if vehicle.rear_axle is None:
            raise RigoptError(f"vehicle {vehicle.name!r} has no rear axle for the axle frame")
        reference, scale = np.asarray(vehicle.rear_axle, dtype=float), np.ones(3)
    else:
        raise RigoptError(f"unknown frame {frame!r}; use one of {', '.join(FRAMES)}")
    return reference - shift, scale


def repositioned(rig: Rig, reference, scale=(1.0, 1.0, 1.0)) -> Rig:
    """``rig`` with every camera position p replaced by (p - reference) / scale (rotations, FOVs kept)."""
    reference, scale = np.asarray(reference, dtype=float), np.asarray(scale, dtype=float)
    cameras = [replace(c, position=(np.asarray(c.position, dtype=float) - reference) / scale) for c in rig.cameras]
    return replace(rig, cameras=cameras)


def moved(entry, shift) -> Rig | RigProfile:
    """A rig (or profile) whose vehicle origin moved by ``shift`` (3,) m: positions p -> p - shift. A profile
    keeps its coverage and self-occlusion (the body moves with the cameras)."""
    if isinstance(entry, RigProfile):
        return replace(entry, rig=repositioned(entry.rig, shift))
    return repositioned(entry, shift)


def framed_terms(entries: Sequence, vehicles: Sequence[Vehicle], shifts=None) -> dict[str, np.ndarray]:
    """{"term@frame": (R, R)} for every FRAMES x FRAMED_TERMS; ``entries`` (R,) rigs or profiles, ``vehicles``
    (R,) each one's vehicle, ``shifts`` (R, 3) m the origin moves already applied to the entries (default 0)."""
    shifts = np.zeros((len(entries), 3)) if shifts is None else np.asarray(shifts, dtype=float)
    rigs = [e.rig if isinstance(e, RigProfile) else e for e in entries]
    out = {}
    for frame in FRAMES:
        framed = [repositioned(rig, *frame_of(vehicle, frame, shift))
                  for rig, vehicle, shift in zip(rigs, vehicles, shifts)]
        for term, matrix in term_matrices(framed, framed, FRAMED_TERMS).items():
            out[f"{term}@{frame}"] = matrix
    return out


def rematcher(entries: Sequence) -> Callable[[tuple[float, float, float]], np.ndarray]:
    """Cached: match lambdas (3,) -> (R, R, 4) float (t, r, f, count) under the matching with those lambdas."""
    from plus_terms import PlusSettings

    rigs = [e.rig if isinstance(e, RigProfile) else e for e in entries]
    cache: dict[tuple[float, ...], np.ndarray] = {}

    def features(lambdas) -> np.ndarray:
        key = tuple(float(v) for v in lambdas)
        if key not in cache:
            m = term_matrices(rigs, rigs, ("t", "r", "f", "count"), PlusSettings(match_lambdas=key))
            cache[key] = np.stack([m[t] for t in ("t", "r", "f", "count")], axis=-1)
        return cache[key]

    return features


# --- A study -------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Study:
    """``rigs`` (R,) names; ``groups`` (D,) detectors or families; ``delta`` (D, R, R) float, NaN missing;
    ``terms`` {name: (R, R) float}; ``control`` (R,) bool; ``rematch`` lambdas -> (R, R, 4) (V6)."""

    rigs: tuple[str, ...]
    groups: tuple[str, ...]
    delta: np.ndarray
    terms: Mapping[str, np.ndarray]
    control: np.ndarray
    rematch: Callable[[tuple[float, float, float]], np.ndarray]

    @property
    def control_index(self) -> np.ndarray:
        return np.flatnonzero(self.control)

    @property
    def other_index(self) -> np.ndarray:
        return np.flatnonzero(~self.control)

    def subset(self, names: Sequence[str], groups: Sequence[str] | None = None, delta=None) -> "Study":
        """The study restricted to the rigs ``names`` (and, with ``delta`` (D', R', R'), other groups)."""
        index = np.array([self.rigs.index(n) for n in names])
        grid = np.ix_(index, index)
        full = self.rematch
        return Study(tuple(names), tuple(groups or self.groups),
                     self.delta[:, index][:, :, index] if delta is None else np.asarray(delta, dtype=float),
                     {k: v[grid] for k, v in self.terms.items()}, self.control[index],
                     lambda lambdas: full(lambdas)[grid])


def delta_matrix(model, train, test, delta, rigs: Sequence[str], groups: Sequence[str]) -> np.ndarray:
    """(D, R, R) float from long-form drops (P,) each; NaN where a pair is absent."""
    out = np.full((len(groups), len(rigs), len(rigs)), np.nan)
    g, r = {x: k for k, x in enumerate(groups)}, {x: k for k, x in enumerate(rigs)}
    for m, a, b, d in zip(model, train, test, delta):
        if m in g and a in r and b in r:
            out[g[m], r[a], r[b]] = d
    return out


@dataclass(frozen=True)
class Pairs:
    """Pairs expanded over the groups, missing dropped; (m,) each: ``group``, ``row``, ``col`` indices and
    ``delta``."""

    group: np.ndarray
    row: np.ndarray
    col: np.ndarray
    delta: np.ndarray


def expand(study: Study, rows, cols) -> Pairs:
    """The pairs (rows[p], cols[p]) (n,) of every group, missing ones dropped."""
    rows, cols = np.asarray(rows, dtype=int), np.asarray(cols, dtype=int)
    groups = np.repeat(np.arange(len(study.groups)), len(rows))
    r, c = np.tile(rows, len(study.groups)), np.tile(cols, len(study.groups))
    delta = study.delta[groups, r, c]
    keep = ~np.isnan(delta)
    return Pairs(groups[keep], r[keep], c[keep], delta[keep])


def all_pairs(draws, draws_b=None) -> tuple[np.ndarray, np.ndarray]:
    """Every ordered pair (i, j) of the draws (n,) (and ``draws_b``): rows, cols (n * n_b,) rig indices."""
    a = np.asarray(draws, dtype=int)
    b = a if draws_b is None else np.asarray(draws_b, dtype=int)
    return np.repeat(a, len(b)), np.tile(b, len(a))


def calibration_pairs(study: Study, draws=None) -> tuple[np.ndarray, np.ndarray]:
    """Pairs among the control rigs (default: each once; ``draws`` a multiset of control rig indices)."""
    return all_pairs(study.control_index if draws is None else draws)


def heldout_pairs(study: Study, draws=None) -> tuple[np.ndarray, np.ndarray]:
    """Every ordered pair of ``draws`` (default: each rig once) with at least one non-control rig."""
    rows, cols = all_pairs(np.arange(len(study.rigs)) if draws is None else draws)
    keep = ~(study.control[rows] & study.control[cols])
    return rows[keep], cols[keep]


# --- One solver ------------------------------------------------------------------------------------------

def solve(x, delta, solver: str) -> np.ndarray:
    """(k,) beta >= 0 of least squares of delta (n,) on x (n, k), by ``solver`` alone."""
    if solver == "qp":
        return fit_nnls(x, delta)
    if solver == "lbfgsb":
        return np.asarray(fit_lbfgsb(x, delta), dtype=float)
    raise RigoptError(f"unknown solver {solver!r}; use one of {', '.join(SOLVERS)}")


@dataclass(frozen=True)
class Model:
    """A fitted variant: ``beta`` (k,), ``lambdas`` the matching (V6's calibrated one, else unit)."""

    variant: str
    beta: np.ndarray
    lambdas: tuple[float, float, float] = UNIT_LAMBDAS

    def features(self, study: Study, pairs: Pairs) -> np.ndarray:
        """(m, k) features of ``pairs``."""
        if self.variant == REMATCH:
            return study.rematch(self.lambdas)[pairs.row, pairs.col]
        return np.stack([study.terms[name][pairs.row, pairs.col] for name in VARIANTS[self.variant]], axis=1)

    def predict(self, study: Study, pairs: Pairs) -> np.ndarray:
        """(m,) linear predicted drops of ``pairs``."""
        return self.features(study, pairs) @ self.beta


def fit(variant: str, study: Study, pairs: Pairs, solver: str) -> Model:
    """``variant`` fitted jointly on ``pairs`` by ``solver`` (V6: the fit -> rematch loop with it)."""
    if variant not in VARIANTS:
        raise RigoptError(f"unknown variant {variant!r}; use one of {', '.join(VARIANTS)}")
    if variant == REMATCH:
        loop = fit_rematched(lambda lambdas: study.rematch(lambdas)[pairs.row, pairs.col], pairs.delta,
                             solver=solver)
        return Model(variant, loop.fit.beta(solver), loop.lambdas)
    x = Model(variant, np.zeros(len(VARIANTS[variant]))).features(study, pairs)
    return Model(variant, solve(x, pairs.delta, solver))


# --- The score -------------------------------------------------------------------------------------------

def rank_rho(a, b) -> float:
    """Spearman rho of a, b (n,) (average ranks for ties); NaN when a side is constant or n < 3."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if len(a) < 3 or np.ptp(a) == 0 or np.ptp(b) == 0:
        return float("nan")
    ra, rb = rankdata(a) - (len(a) + 1) / 2, rankdata(b) - (len(b) + 1) / 2
    return float(ra @ rb / np.sqrt((ra @ ra) * (rb @ rb)))


def group_rhos(predicted, pairs: Pairs, groups: int) -> np.ndarray:
    """(D,) Spearman rho of ``predicted`` (m,) against ``pairs.delta`` within each group (NaN if undefined)."""
    return np.array([rank_rho(predicted[pairs.group == g], pairs.delta[pairs.group == g]) for g in range(groups)])


def score(predicted, pairs: Pairs, groups: int) -> float:
    """S: the mean over the groups of Spearman rho (NaN when any group's rho is undefined)."""
    return float(np.mean(group_rhos(predicted, pairs, groups)))


# --- Cross-validation --------------------------------------------------------------------------------------

def cv_predictions(variant: str, study: Study, solver: str) -> tuple[Pairs, np.ndarray]:
    """Leave-one-control-rig-out out-of-fold predictions of the calibration pairs: (pairs, predicted (m,))."""
    rows, cols = calibration_pairs(study)
    pairs = expand(study, rows, cols)
    predicted = np.full(len(pairs.delta), np.nan)
    for left_out in study.control_index:
        keep = (pairs.row != left_out) & (pairs.col != left_out)
        model = fit(variant, study, _take(pairs, keep), solver)
        mine = pairs.row == left_out
        predicted[mine] = model.predict(study, _take(pairs, mine))
    if np.any(np.isnan(predicted)):
        raise RigoptError(f"{variant}: a calibration pair was not predicted out of fold")
    return pairs, predicted


def _take(pairs: Pairs, mask) -> Pairs:
    return Pairs(pairs.group[mask], pairs.row[mask], pairs.col[mask], pairs.delta[mask])


def choose(scores: Mapping[str, float], baseline: str = BASELINE) -> str:
    """V*: the candidate with the highest score (ties to 3 decimals: fewer features, then table order),
    provided it exceeds the baseline's score; else the baseline. NaN scores are never chosen."""
    candidates = [v for v in scores if v != baseline and np.isfinite(scores[v])]
    if not candidates:
        return baseline
    best = max(round(scores[v], 3) for v in candidates)
    tied = [v for v in candidates if round(scores[v], 3) == best]
    order = list(scores)
    chosen = min(tied, key=lambda v: (len(VARIANTS.get(v, ())), order.index(v)))
    base = scores[baseline]
    return chosen if not np.isfinite(base) or scores[chosen] > base else baseline


# --- Held-out, rig bootstrap, jackknife --------------------------------------------------------------------

def heldout(variant: str, study: Study, solver: str, control_draws=None, all_draws=None
            ) -> tuple[Model, Pairs, np.ndarray]:
    """Fit on the calibration pairs among ``control_draws`` and predict the held-out pairs among
    ``all_draws`` (defaults: every rig once): (model, held-out pairs, predictions)."""
    model = fit(variant, study, expand(study, *calibration_pairs(study, control_draws)), solver)
    pairs = expand(study, *heldout_pairs(study, all_draws))
    return model, pairs, model.predict(study, pairs)


def rig_draws(study: Study, resamples: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """``resamples`` (control draws, all draws): the control rigs and the other rigs each drawn with
    replacement, as many as there are (all draws = control draws then other draws)."""
    rng = np.random.default_rng(seed)
    control, other = study.control_index, study.other_index
    out = []
    for _ in range(resamples):
        c = rng.choice(control, len(control), replace=True)
        o = rng.choice(other, len(other), replace=True)
        out.append((c, np.concatenate([c, o])))
    return out


def bootstrap_rhos(variant: str, study: Study, solver: str, draws) -> np.ndarray:
    """(B, D) held-out rho per group of ``variant`` refitted on each resample of ``draws`` (rig_draws)."""
    return np.array([group_rhos(heldout(variant, study, solver, c, a)[2],
                                expand(study, *heldout_pairs(study, a)), len(study.groups))
                     for c, a in draws])


def percentile_interval(values) -> tuple[float, float]:
    """95 % percentile interval of the finite ``values``; (nan, nan) when none."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    if len(values) == 0:
        return float("nan"), float("nan")
    low, high = np.percentile(values, [2.5, 97.5])
    return float(low), float(high)


def bootstrap_scores(rhos) -> np.ndarray:
    """(B,) S of each resample from (B, D) rhos; NaN where any group's rho is undefined."""
    return np.asarray(rhos, dtype=float).mean(axis=1)


def paired_interval(rhos_a, rhos_b) -> tuple[tuple[float, float], int]:
    """95 % interval of S(a) - S(b) over the resamples where both are defined, and how many those are."""
    d = bootstrap_scores(rhos_a) - bootstrap_scores(rhos_b)
    return percentile_interval(d), int(np.isfinite(d).sum())


def jackknife_scores(variant: str, study: Study, solver: str) -> np.ndarray:
    """(R,) held-out S with each rig left out (a control rig left out is also left out of the fit)."""
    out = []
    everyone = np.arange(len(study.rigs))
    for k in everyone:
        keep = everyone[everyone != k]
        control = keep[study.control[keep]]
        _, pairs, predicted = heldout(variant, study, solver, control, keep)
        out.append(score(predicted, pairs, len(study.groups)))
    return np.array(out)


def jackknife_interval(estimate: float, replicates) -> tuple[float, float]:
    """estimate +- 1.96 jackknife standard errors of ``replicates`` (n,) (NaN when any is undefined)."""
    r = np.asarray(replicates, dtype=float)
    se = np.sqrt((len(r) - 1) / len(r) * np.sum((r - r.mean()) ** 2))
    return float(estimate - 1.96 * se), float(estimate + 1.96 * se)
