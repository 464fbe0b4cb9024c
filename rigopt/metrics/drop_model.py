"""A model of a shipped detector's measured transfer drop from the geometry of the reference and the candidate rig.

RigCD weighs every camera offset alike and was calibrated on the benchmark's hand-designed rigs; a lifting
detector instead depends on what each camera's image rows mean in depth (its height and pitch), less on where
in plan it sits. This model's terms follow that, and it is fitted on drops measured with the shipped detectors
(studies/predictor/: pre-registered, leave-one-vehicle-out).

Terms of a matched camera pair (reference camera r, candidate camera c; ``PAIR_FEATURES``), both rigs measured
from their vehicle's centre on the ground (ISO 8855; :func:`rigopt.vehicle.placement.in_vehicle_frame`):

- ``depth_prior`` (log-m): the mean |ln d_c - ln d_r| over a grid of image places, d the optical-axis depth at
  which that place's ray meets the ground (:func:`rigopt.metrics.lifting.ground_depths`);
- ``raise``, ``lower`` (m): the height difference z_c - z_r where positive, z_r - z_c where positive;
- ``tilt_down``, ``tilt_up`` (rad): the pitch difference, c pitched more down than r, or more up;
- ``roll``, ``yaw`` (rad): |roll difference|, |yaw difference| (wrapped);
- ``plan`` (m): the horizontal distance of the two lenses;
- ``zoom``: |ln(tan(hfov_c / 2) / tan(hfov_r / 2))|, the lens's scale change;
- ``centre``: |cx_c / w_c - cx_r / w_r| + |cy_c / h_c - cy_r / h_r|, the principal point's move (image fractions);
- ``body``: max(b_c - b_r, 0), b the share of the camera's image that shows its own vehicle's body (the renderer
  draws the ego body; a camera that sees it sees less of the scene). The body is a vehicle's, which this layer
  does not know: callers pass a ``body_share(rig, grid)`` function (:func:`rigopt.mounting.candidates.rig_body_share`).

Terms of the whole rig (``RIG_FEATURES``): ``count`` = |N_c - N_r| / max(N_c, N_r) and ``uncovered``, the share
of the reference's horizontal view (1-degree sectors of azimuth round the vehicle, each camera's horizontal FOV
about its yaw) that no candidate camera's covers.

A model names the terms it was fitted with (``DropModel.features``, a subset of FEATURES in their order; the
first shipped model has no ``body`` term); the others weigh exactly 0. The score of a candidate is s = w . x, x the pair terms averaged over the matched pairs (min(N_r, N_c) of them,
the assignment minimising the sum of the pair costs w_pair . phi) followed by the rig terms, w >= 0; the
predicted drop is 1 - exp(-s). The pair cost is a sum over matched pairs plus terms of the whole rig, so the
score can stand as a MILP's objective (the link is monotone).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from scipy.optimize import least_squares, linear_sum_assignment

from rigopt.camera import CameraModel
from rigopt.errors import DataError, RigoptError, json_loads, not_utf8, unknown_name
from rigopt.geometry import yaw_pitch_roll_from_rotation
from rigopt.metrics.lifting import depths_on_ground
from rigopt.rig.model import Rig

#: ``body_share(rig, grid)``: (N,) float, the share of each camera's image (estimated on a (columns, rows) grid)
#: that shows the rig's vehicle's body; rig from the vehicle's centre on the ground.
BodyShare = Callable[[Rig, tuple[int, int]], np.ndarray]
PAIR_FEATURES = ("depth_prior", "raise", "lower", "tilt_down", "tilt_up", "roll", "yaw", "plan", "zoom", "centre",
                 "body")
RIG_FEATURES = ("count", "uncovered")
FEATURES = PAIR_FEATURES + RIG_FEATURES
#: Rounds of fit -> rematch -> refit at most (the fit stops early when the matching no longer changes).
FIT_ROUNDS = 5
#: Starting weights of the least-squares fit (every term alike).
START_WEIGHT = 0.1
#: A term whose largest value over the fitting rigs is at most this is not fitted (weight 0).
INFORMATIVE = 1e-6
#: The widest horizontal FOV (deg) the terms read: a fisheye of 180 deg or more counts as this (tan(hfov / 2) has
#: no value at 180 deg); no fitting rig came near it, so its zoom term is flagged as beyond them.
WIDEST_HFOV = 179.0
#: Image grid (columns, rows) on which a camera's share of ego body is estimated for the ``body`` term.
BODY_GRID = (16, 9)


@dataclass(frozen=True, eq=False)
class CameraGeometry:
    """What the terms read of N cameras, vehicle frame from the centre on the ground.

    plan : (N, 2) float m; height : (N,) float m; yaw, pitch, roll : (N,) float rad (ISO 8855);
    depths : (N, G) float ln m of the ground depth grid; half_tan : (N,) float tan(min(hfov, WIDEST_HFOV) / 2);
    centre : (N, 2) float principal point over image size; body : (N,) float share of the image showing the ego
    body (zeros when not given).
    """

    plan: np.ndarray
    height: np.ndarray
    yaw: np.ndarray
    pitch: np.ndarray
    roll: np.ndarray
    depths: np.ndarray
    half_tan: np.ndarray
    centre: np.ndarray
    body: np.ndarray

    @classmethod
    def of(cls, rig: Rig, body_share: BodyShare | None = None) -> CameraGeometry:
        """The rig's cameras; their ego-body shares from ``body_share(rig, BODY_GRID)`` (zeros without it)."""
        body = None if body_share is None else body_share(rig, BODY_GRID)
        return cls.of_cameras(rig.positions, rig.rotations, CameraModel.of_cameras(rig.cameras), body)

    @classmethod
    def of_cameras(cls, positions: np.ndarray, rotations: np.ndarray, model: CameraModel,
                   body: np.ndarray | None = None) -> CameraGeometry:
        """N cameras given as positions (N, 3) m, rotations (N, 3, 3) (body to vehicle frame), their lenses
        ``model`` (batch (N,)) and their ego-body shares ``body`` (N,) (zeros when None)."""
        positions = np.asarray(positions, dtype=float)
        yaw, pitch, roll = yaw_pitch_roll_from_rotation(rotations)
        hfov = np.minimum(np.broadcast_to(np.asarray(model.hfov, dtype=float), len(positions)), WIDEST_HFOV)
        return cls(positions[:, :2], positions[:, 2], yaw, pitch, roll,
                   depths_on_ground(model, rotations, positions[:, 2]), np.tan(np.radians(hfov) / 2),
                   np.stack([np.asarray(model.cx) / np.asarray(model.width),
                             np.asarray(model.cy) / np.asarray(model.height)], axis=-1)
                   * np.ones((len(positions), 1)),
                   np.zeros(len(positions)) if body is None else np.asarray(body, dtype=float).reshape(len(positions)))


def pair_features(reference: CameraGeometry, candidate: CameraGeometry) -> np.ndarray:
    """(N_r, N_c, len(PAIR_FEATURES)) float: every term between each reference and each candidate camera."""
    r, c = np.s_[:, None], np.s_[None, :]
    dz = candidate.height[c] - reference.height[r]
    dpitch = candidate.pitch[c] - reference.pitch[r]
    wrap = lambda angle: np.abs(np.angle(np.exp(1j * angle)))  # noqa: E731
    return np.stack([
        np.abs(candidate.depths[None, :, :] - reference.depths[:, None, :]).mean(axis=-1),
        np.maximum(dz, 0.0), np.maximum(-dz, 0.0),
        np.maximum(-dpitch, 0.0), np.maximum(dpitch, 0.0),
        wrap(candidate.roll[c] - reference.roll[r]), wrap(candidate.yaw[c] - reference.yaw[r]),
        np.linalg.norm(candidate.plan[c] - reference.plan[r], axis=-1),
        np.abs(np.log(candidate.half_tan[c] / reference.half_tan[r])),
        np.abs(candidate.centre[c] - reference.centre[r]).sum(axis=-1),
        np.maximum(candidate.body[c] - reference.body[r], 0.0)], axis=-1)


def azimuth_cover(geometry: CameraGeometry, sectors: int = 360) -> np.ndarray:
    """(sectors,) bool: the 1-degree sectors of azimuth (from 0 = ahead, counter-clockwise) inside some camera's
    horizontal FOV about its yaw."""
    centres = (np.arange(sectors) + 0.5) * 2 * np.pi / sectors
    half = np.arctan(geometry.half_tan)
    gap = np.abs(np.angle(np.exp(1j * (centres[None, :] - geometry.yaw[:, None]))))
    return (gap <= half[:, None]).any(axis=0)


def rig_features(reference: CameraGeometry, candidate: CameraGeometry) -> np.ndarray:
    """(len(RIG_FEATURES),) float: the count term and the uncovered share of the reference's view."""
    n_r, n_c = len(reference.height), len(candidate.height)
    seen = azimuth_cover(reference)
    uncovered = float((seen & ~azimuth_cover(candidate)).sum() / max(seen.sum(), 1))
    return np.array([abs(n_r - n_c) / max(n_r, n_c), uncovered])


def match(pairs: np.ndarray, pair_weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols): the min(N_r, N_c) matched pairs minimising the summed pair cost ``pairs @ pair_weights``."""
    return linear_sum_assignment(pairs @ pair_weights)


def matched_features(pairs: np.ndarray, rig_terms: np.ndarray, pair_weights: np.ndarray) -> np.ndarray:
    """(len(FEATURES),) float: the pair terms averaged over the matching under ``pair_weights``, then the rig terms."""
    rows, cols = match(pairs, pair_weights)
    return np.concatenate([pairs[rows, cols].mean(axis=0), rig_terms])


@dataclass(frozen=True)
class PairTerms:
    """One (reference, candidate) pair's terms before matching: ``pairs`` (N_r, N_c, len(PAIR_FEATURES)) and
    ``rig`` (len(RIG_FEATURES),)."""

    pairs: np.ndarray
    rig: np.ndarray

    @classmethod
    def of(cls, reference: Rig, candidate: Rig, body_share: BodyShare | None = None) -> PairTerms:
        """Both rigs measured from their vehicle's centre on the ground (the callers' job:
        :func:`rigopt.vehicle.placement.in_vehicle_frame`); the body term 0 without ``body_share``."""
        a, b = CameraGeometry.of(reference, body_share), CameraGeometry.of(candidate, body_share)
        return cls(pair_features(a, b), rig_features(a, b))


def link(score: np.ndarray) -> np.ndarray:
    """Predicted drop of a score s >= 0: 1 - exp(-s)."""
    return -np.expm1(-np.asarray(score, dtype=float))


def fit_weights(terms: Sequence[PairTerms], drops: np.ndarray, features: Sequence[str] = FEATURES,
                rounds: int = FIT_ROUNDS) -> np.ndarray:
    """(len(FEATURES),) float >= 0: the weights whose predicted drops best fit ``drops`` (least squares on the
    drop scale, scipy's bounded trust-region solver from START_WEIGHT), fit -> rematch -> refit until the
    matchings stop changing or ``rounds`` fits are done. Only ``features`` are fitted (the others weigh 0 and do
    not enter the matching). The first matching is under unit weights of the fitted pair terms. A term no fitting
    rig has (at most INFORMATIVE everywhere) gets weight 0."""
    drops = np.asarray(drops, dtype=float)
    fitted = np.isin(FEATURES, features)
    pair_weights = fitted[:len(PAIR_FEATURES)].astype(float)
    weights, matched = None, None
    for _ in range(rounds):
        matchings = [match(t.pairs, pair_weights) for t in terms]
        key = [tuple(map(tuple, m)) for m in matchings]
        if key == matched:
            break
        matched = key
        x = np.array([np.concatenate([t.pairs[m].mean(axis=0), t.rig]) for t, m in zip(terms, matchings)])
        # a term that no fitting rig has (rounding noise at most) carries no information: its weight is 0, not
        # whatever the solver drifts it to (a huge weight on 1e-16 noise would blow up on a rig that has it)
        used = fitted & (x.max(axis=0) > INFORMATIVE)
        start = np.full(used.sum(), START_WEIGHT) if weights is None else weights[used]
        solution = least_squares(lambda w: link(x[:, used] @ w) - drops, start, bounds=(0.0, np.inf), method="trf")
        weights = np.zeros(x.shape[1])
        weights[used] = solution.x
        pair_weights = matching_weights(weights, features)
    return weights


def matching_weights(weights: np.ndarray, features: Sequence[str] = FEATURES) -> np.ndarray:
    """(len(PAIR_FEATURES),) float: the pair weights the matching is made under, each of ``features`` raised by
    1e-9 so that a term of weight 0 still breaks ties between matchings the others leave equal."""
    return (np.asarray(weights[:len(PAIR_FEATURES)], dtype=float)
            + 1e-9 * np.isin(PAIR_FEATURES, features))


def predict(weights: np.ndarray, terms: Sequence[PairTerms], features: Sequence[str] = FEATURES) -> np.ndarray:
    """(P,) float: the predicted drops of ``terms`` under ``weights`` (a model of ``features``)."""
    pair_weights = matching_weights(weights, features)
    return link(np.array([matched_features(t.pairs, t.rig, pair_weights) @ weights for t in terms]))


#: Upper edges of the predicted-drop bins whose intervals are set apart (the last bin is open above).
INTERVAL_BINS = (0.15, 0.4)
INTERVAL_LEVEL = 0.9


def interval_bin(predicted: np.ndarray) -> np.ndarray:
    """(P,) int: the bin of each predicted drop (0: below 0.15, 1: below 0.4, 2: the rest)."""
    return np.searchsorted(np.asarray(INTERVAL_BINS), np.asarray(predicted, dtype=float), side="right")


def interval_halfwidths(predicted: np.ndarray, measured: np.ndarray, level: float = INTERVAL_LEVEL) -> np.ndarray:
    """(len(INTERVAL_BINS) + 1,) float: per bin of predicted drop, the split-conformal half-width at ``level`` from
    held-out predictions: the ceil((n + 1) level)-th smallest |measured - predicted| of the n in the bin (inf where
    n is too small for that rank)."""
    predicted, measured = np.asarray(predicted, dtype=float), np.asarray(measured, dtype=float)
    bins = interval_bin(predicted)
    widths = np.full(len(INTERVAL_BINS) + 1, np.inf)
    for b in range(len(widths)):
        residuals = np.sort(np.abs(measured - predicted)[bins == b])
        rank = int(np.ceil((len(residuals) + 1) * level))
        if 0 < rank <= len(residuals):
            widths[b] = residuals[rank - 1]
    return widths


#: Units of the terms, for the notes that flag a prediction beyond the fitting rigs.
FEATURE_UNITS = {"depth_prior": "ln m", "raise": "m", "lower": "m", "tilt_down": "rad", "tilt_up": "rad",
                 "roll": "rad", "yaw": "rad", "plan": "m", "zoom": "-", "centre": "-", "body": "-", "count": "-",
                 "uncovered": "-"}
#: How far a reference's cameras may lie from the model's reference and still count as it (m, rad, deg).
SAME_REFERENCE = {"position": 1e-3, "angle": 1e-4, "hfov": 1e-3}
#: The folder of the shipped models, under the metrics data folder.
MODELS_FOLDER = "drop_models"


@dataclass(frozen=True, eq=False)
class DropModel:
    """A fitted model of one detector's measured drop from one reference rig (shipped under ``metrics/drop_models``).

    name : what the outputs call it (e.g. "lss-R1"); detector : the detector models whose measured drops it was
    fitted on (their pack and the commit that shipped them); reference : the reference rig's name; reference_cameras : (N, 7) float, :func:`camera_table` of the
    reference's perception cameras, vehicle frame from the centre on the ground; features : the terms it was
    fitted with (FEATURES in order; the model file lists them); weights : (len(FEATURES),) float >= 0, 0 outside
    ``features``; halfwidths : (len(INTERVAL_BINS) + 1,) float, the 90 % interval's half-width per predicted-drop
    bin; ranges : (len(FEATURES), 2) float, each term's range over the fitting rigs; default : whether its study
    found it better than RigCD, so that commands print it by default; study : where its evidence is (one line).
    """

    name: str
    detector: str
    reference: str
    reference_cameras: np.ndarray
    weights: np.ndarray
    halfwidths: np.ndarray
    ranges: np.ndarray
    default: bool
    study: str
    level: float = INTERVAL_LEVEL
    features: tuple[str, ...] = FEATURES

    @classmethod
    def from_dict(cls, data: dict) -> DropModel:
        features = tuple(map(str, data["features"]))
        if [f for f in FEATURES if f in features] != list(features) or list(data["interval"]["bins"]) != list(INTERVAL_BINS):
            raise ValueError(f"the model's terms must be some of {', '.join(FEATURES)} in that order, and its "
                             f"interval bins {list(INTERVAL_BINS)}")
        weights, ranges = np.array(data["weights"], float), np.array(data["ranges"], float)
        n = len(features)
        if (weights.shape != (n,) or not np.all(np.isfinite(weights)) or np.any(weights < 0)
                or ranges.shape != (n, 2)):
            raise ValueError(f"weights must be {n} finite numbers >= 0 and ranges {n} pairs, one per term")
        fitted = np.isin(FEATURES, features)
        all_weights, all_ranges = np.zeros(len(FEATURES)), np.zeros((len(FEATURES), 2))
        all_weights[fitted], all_ranges[fitted] = weights, ranges
        model = cls(str(data["name"]), str(data["detector"]), str(data["reference"]),
                    np.array(data["reference_cameras"], float), all_weights,
                    np.array(data["interval"]["halfwidths"], float), all_ranges,
                    bool(data["default"]), str(data["study"]), float(data["interval"]["level"]), features)
        if (model.reference_cameras.ndim != 2 or model.reference_cameras.shape[1] != 7
                or model.halfwidths.shape != (len(INTERVAL_BINS) + 1,)):
            raise ValueError(f"reference_cameras must be rows of 7 and halfwidths {len(INTERVAL_BINS) + 1} numbers")
        return model

    def to_dict(self) -> dict:
        fitted = np.isin(FEATURES, self.features)
        return {"name": self.name, "detector": self.detector, "reference": self.reference,
                "reference_cameras": self.reference_cameras.tolist(), "features": list(self.features),
                "weights": self.weights[fitted].tolist(), "ranges": self.ranges[fitted].tolist(),
                "default": self.default, "study": self.study,
                "interval": {"level": self.level, "bins": list(INTERVAL_BINS), "halfwidths": self.halfwidths.tolist()}}

    @property
    def needs_body(self) -> bool:
        """Whether the model weighs the ``body`` term (its predictions then need a ``body_share`` function)."""
        return bool(self.weights[FEATURES.index("body")] > 0)

    def applies_to(self, reference: Rig) -> bool:
        """Whether ``reference`` (its perception cameras, from its vehicle's centre on the ground) is the model's
        reference: the same cameras in the same order within SAME_REFERENCE."""
        return _same_cameras(camera_table(reference), self.reference_cameras)

    def terms(self, reference: Rig, candidates: Sequence[Rig], body_share: BodyShare | None = None) -> np.ndarray:
        """(P, len(FEATURES)) float: each candidate's terms under the model's matching; ``body_share`` gives the
        ego-body shares, required when the model weighs them (:attr:`needs_body`)."""
        if self.needs_body and body_share is None:
            raise ValueError(f"the {self.name} drop model weighs the ego body each camera sees: pass body_share")
        body_share = body_share if self.needs_body else None  # no rays cast for a term the model does not weigh
        a = CameraGeometry.of(reference, body_share)
        pair_weights = matching_weights(self.weights, self.features)
        return np.array([matched_features(pair_features(a, b), rig_features(a, b), pair_weights)
                         for b in (CameraGeometry.of(c, body_share) for c in candidates)]
                        ).reshape(len(candidates), len(FEATURES))

    def pair_costs(self, positions: np.ndarray, rotations: np.ndarray, model: CameraModel, reference: Rig,
                   chunk: int = 4096) -> np.ndarray:
        """(n, R) float: the model's cost w_pair . phi of matching each of n cameras (positions (n, 3) m, rotations
        (n, 3, 3), lenses ``model`` of batch (n,); from the vehicle's centre on the ground) to each camera of
        ``reference``: the pair part of its score, whose mean over the matched pairs plus the rig terms is the
        score (a designer's MILP objective). Computed ``chunk`` cameras at a time. The ``body`` term is left out:
        a designer bounds each candidate's share of ego body instead (``DesignSettings.max_body_fraction``)."""
        ref = CameraGeometry.of(reference)
        pair_weights = np.where(np.equal(PAIR_FEATURES, "body"), 0.0, self.weights[:len(PAIR_FEATURES)])
        out = np.empty((len(positions), len(reference)))
        for start in range(0, len(positions), chunk):
            part = slice(start, start + chunk)
            geometry = CameraGeometry.of_cameras(positions[part], rotations[part], model.take(part))
            out[part] = (pair_features(ref, geometry) @ pair_weights).T
        return out

    def predict(self, reference: Rig, candidates: Sequence[Rig], body_share: BodyShare | None = None
                ) -> tuple[np.ndarray, np.ndarray, list[dict]]:
        """Predicted drops (P,), interval half-widths (P,) and, per candidate, {term: (value, low, high)} of the
        terms beyond the fitting rigs' range (empty inside). Rigs from their vehicle's centre on the ground;
        ``body_share`` as in :meth:`terms`."""
        x = self.terms(reference, candidates, body_share)
        drops = link(x @ self.weights)
        weighted = self.weights > 0  # a term the model gives no weight cannot carry it beyond its data
        beyond = [{name: (float(v), float(lo), float(hi))
                   for name, v, (lo, hi), used in zip(FEATURES, row, self.ranges, weighted) if used and v > hi + 1e-9}
                  for row in x]
        return drops, self.halfwidths[interval_bin(drops)], beyond


def camera_table(rig: Rig) -> np.ndarray:
    """(N, 7) float: x, y, z (m), yaw, pitch, roll (rad), hfov (deg) of each camera, in the rig's frame."""
    yaw, pitch, roll = yaw_pitch_roll_from_rotation(rig.rotations)
    hfov = np.asarray(CameraModel.of_cameras(rig.cameras).hfov, dtype=float)
    return np.column_stack([rig.positions, yaw, pitch, roll, hfov])


def _same_cameras(a: np.ndarray, b: np.ndarray) -> bool:
    if a.shape != b.shape:
        return False
    turn = np.abs(np.angle(np.exp(1j * (a[:, 3:6] - b[:, 3:6]))))
    return bool(np.all(np.abs(a[:, :3] - b[:, :3]) <= SAME_REFERENCE["position"])
                and np.all(turn <= SAME_REFERENCE["angle"])
                and np.all(np.abs(a[:, 6] - b[:, 6]) <= SAME_REFERENCE["hfov"]))


def shipped_drop_models() -> list[str]:
    """Names of the shipped drop models."""
    from rigopt.resources import data_dir

    folder = data_dir("metrics") / MODELS_FOLDER
    return sorted(p.stem for p in folder.glob("*.json")) if folder.is_dir() else []


def load_drop_model(name_or_path) -> DropModel:
    """The shipped drop model of that name (case-insensitive) or a drop model JSON file (``DropModel.to_dict``)."""
    from pathlib import Path

    from rigopt.resources import data_dir

    text = str(name_or_path)
    by_lower = {n.lower(): n for n in shipped_drop_models()}
    if text.lower() in by_lower:
        path = data_dir("metrics") / MODELS_FOLDER / f"{by_lower[text.lower()]}.json"
    elif text.lower().endswith(".json"):
        path = Path(text)
        if not path.is_file():
            raise DataError(f"{path}: no such drop model file; give a shipped name ({', '.join(by_lower.values())}) "
                            "or a drop model JSON file")
    else:
        raise unknown_name("drop model", text, sorted(by_lower.values()))
    try:
        return DropModel.from_dict(json_loads(path.read_text()))
    except UnicodeDecodeError as error:
        raise not_utf8(path, "drop model file", error) from None
    except KeyError as error:
        raise DataError(f"{path}: not a drop model file (no {error} key); rigopt writes them as "
                        "studies/predictor/ship.py does") from None
    except (OSError, ValueError, TypeError) as error:
        raise DataError(f"{path}: not a drop model file ({error}); rigopt writes them as "
                        "studies/predictor/ship.py does") from None


#: ``--predictor`` values besides a model's name: the default model where it applies (RigCD elsewhere), RigCD.
AUTO, RIGCD = "auto", "rigcd"


def choose_model(option: str, reference: Rig, weights_given: bool = False) -> DropModel | None:
    """The drop model that predicts transfers from ``reference`` (perception cameras, from its vehicle's centre on
    the ground) under ``--predictor option``; None means RigCD's calibrated prediction.

    ``auto``: the shipped model marked default whose reference ``reference`` is, unless RigCD weights were named
    (``weights_given``: the user asked for RigCD under them); ``rigcd``: None; a model's name: that model, refused
    for a reference it was not fitted from."""
    key = option.lower()
    if key == RIGCD:
        return None
    if key == AUTO:
        if weights_given:
            return None
        models = (load_drop_model(name) for name in shipped_drop_models())
        return next((m for m in models if m.default and m.applies_to(reference)), None)
    if key not in {name.lower() for name in shipped_drop_models()}:
        raise unknown_name("predictor", option, [AUTO, RIGCD, *shipped_drop_models()])
    model = load_drop_model(option)
    if not model.applies_to(reference):
        raise RigoptError(f"the {model.name} drop model predicts transfers from {model.reference} (its detector's "
                          f"training rig), and {reference.name} is another rig: pass --ref {model.reference} or "
                          f"--predictor {RIGCD}")
    return model
