"""RigCD+: candidate rig-distance terms beyond the published RigCD, for the study in this folder.

The published RigCD (``rigopt/metrics/rigcd.py``) sees camera poses and FOVs only. The terms here also use what the vehicle
does to the cameras' views. Every term is a number per ordered pair of rigs (A, B), A the reference
(training) rig, B the other (test) rig; units in brackets. ``N_A``, ``N_B`` cameras, ``M = min(N_A, N_B)``
matched pairs (p = 1 .. M, camera ``a_p`` of A with ``b_p`` of B).

Matching (*ours*, switchable): the minimum-cost assignment of RigCD with cost
``lt ||t_i - t_j|| + lr dR + lf |f_i - f_j|`` and ``PlusSettings.match_lambdas`` = (lt, lr, lf), default
(1, 1, 1): exactly the published unit-weight matching (the same solver, so the same choice among ties).
When a lambda is 0, ties of the weighted cost are broken by the unit-weight cost (every lambda is raised by
``rigcd.TIE_BREAK`` times the largest, ``rigcd.tie_broken_lambdas``), so that a rig against itself is always matched camera to itself.
All matched terms of one call use that one matching.

Published features, under the matching:
    t [m]      mean ||t_a - t_b||            r [rad]  mean geodesic angle      f [deg]  mean |fov_a - fov_b|
    count [-]  |N_A - N_B| / max(N_A, N_B)   (no matching)
1. height and planar translation (replace t):
    dz [m]     mean |z_a - z_b|              dxy [m]  mean ||(x, y)_a - (x, y)_b||
2. focal length (replaces f): f_px = (W / 2) / tan(fov / 2) pixels, pixels per metre at depth Z = f_px / Z, so
   the depth-independent relative difference is
    focal [-]  mean |ln(f_px,a / f_px,b)| = mean |ln(tan(fov_b / 2) / tan(fov_a / 2))|
   with a common W (``focal_width="common"``, default: the detector resizes every image alike) or with each
   camera's own image width (``"own"``: adds |ln(W_a / W_b)| where widths differ).
3. coverage state: each rig on its own vehicle, the sector points of ``rigopt.coverage.matrix`` (every ring
   distance, measured from that vehicle's footprint outline, x every ring height x ``sectors`` azimuths from
   -pi: the same layout for both rigs, so points correspond by (ring, sector)); a point is *covered* when at
   least one camera sees it (frustum, range and body occlusion):
    cover [-]  mean over rings of the fraction of sectors whose covered state differs between A and B
   (every ring has the same number of sectors, so this is also the fraction of all sector points).
4. overlap structure: the same with "seen by at least two cameras":  overlap [-].
5. self-occlusion: per camera, the fraction of a grid of pixel rays (``CoverageSettings.image_grid``) that
   hit its own body within ``max_range`` (as ``coverage.measures``):
    selfocc [-]  mean |o_a - o_b| over the matched pairs
6. calibrated-weight matching: t, r, f (and every other matched term) under ``match_lambdas`` set to a
   calibration's lambdas; see :func:`features_under_matching`. The fit / rematch / refit loop is the study's.
7. coverage-weighted matching: the share of camera i of rig A in A's covered sector points,
   ``s_i = (1 / |Q_cov|) sum_{q in Q_cov} seen_iq / count_q`` (a point seen by k cameras gives 1/k to each;
   sum_i s_i = 1; uniform 1/N_A when A covers nothing); the weights of the matched pairs are
   ``w_p = s_{a_p} / sum_p s_{a_p}`` (uniform 1/M when the matched cameras have no share), sum_p w_p = 1:
    cw_t [m], cw_r [rad], cw_f [deg]  sum_p w_p * (t, r, f)_p

Every term is 0 for a rig against itself. Symmetric: every term but cw_t, cw_r, cw_f (weighted by A's
cameras). The matched terms t, r, f, dz, dxy, focal, selfocc are symmetric up to the choice among tied
optimal matchings, exactly as the published components; cover, overlap and count are exactly symmetric.
Values are rounded to ``PlusSettings.decimals`` (default 10, as the calibration's features) so that pairs of
identical geometry tie exactly.

Cost: the matched geometric terms need only the rigs. cover, overlap, cw_* need each rig's coverage matrix
and selfocc its pixel rays on its vehicle: computed once per rig by :func:`rig_profile` (and once per distinct
rig object inside :func:`term_matrices`); pass :class:`RigProfile` objects to reuse them across calls.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from rigopt.camera import CameraModel, focal_from_fov
from rigopt.coverage.matrix import rig_coverage_matrix
from rigopt.coverage.measures import CoverageSettings
from rigopt.errors import RigoptError
from rigopt.geometry import rotation_angle
from rigopt.metrics.calibration import FEATURE_DECIMALS
from rigopt.metrics.rigcd import DEFAULT_ALPHA, RigBatch, check_weights, match_pairs, tie_broken_lambdas
from rigopt.rig.model import Rig
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.model import Vehicle

#: Every term, in a fixed order.
TERMS = ("t", "r", "f", "count", "dz", "dxy", "focal", "cover", "overlap", "selfocc", "cw_t", "cw_r", "cw_f")
#: Terms that depend on which rig is the reference (the first).
ASYMMETRIC_TERMS = ("cw_t", "cw_r", "cw_f")
#: Terms computed over the matched camera pairs.
MATCHED_TERMS = ("t", "r", "f", "dz", "dxy", "focal", "selfocc", "cw_t", "cw_r", "cw_f")
COVERAGE_TERMS = ("cover", "overlap", "cw_t", "cw_r", "cw_f")
SELF_OCCLUSION_TERMS = ("selfocc",)
FOCAL_WIDTHS = ("common", "own")


def _default_coverage() -> CoverageSettings:
    return CoverageSettings()


@dataclass(frozen=True)
class PlusSettings:
    """Parameters of the RigCD+ terms.

    ``coverage``: the ring distances (m from the body outline), heights (m), ``sectors``, ``max_range`` (m),
    ``image_grid`` (pixel rays per camera, width x height) and ray ``backend`` used by cover, overlap, cw_*
    and selfocc (the other CoverageSettings fields are unused); ``match_lambdas`` (1/m, 1/rad, 1/deg): the
    matching cost's weights; ``focal_width``: "common" or "own" (see the module); ``decimals``: rounding
    of the returned values, None for none.
    """

    coverage: CoverageSettings = field(default_factory=_default_coverage)
    match_lambdas: tuple[float, float, float] = (1.0, 1.0, 1.0)
    focal_width: str = "common"
    decimals: int | None = FEATURE_DECIMALS

    def __post_init__(self):
        if not isinstance(self.coverage, CoverageSettings):
            raise RigoptError(f"PlusSettings.coverage must be a CoverageSettings, got {type(self.coverage).__name__}")
        try:
            _, lambdas = check_weights(DEFAULT_ALPHA, self.match_lambdas)
        except TypeError:
            raise RigoptError(f"match_lambdas must be three numbers (t, r, f), got {self.match_lambdas!r}") from None
        object.__setattr__(self, "match_lambdas", lambdas)
        if self.focal_width not in FOCAL_WIDTHS:
            raise RigoptError(f"focal_width must be one of {', '.join(FOCAL_WIDTHS)}, got {self.focal_width!r}")
        if self.decimals is not None and (isinstance(self.decimals, bool) or not isinstance(self.decimals, int)):
            raise RigoptError(f"decimals must be an integer or None, got {self.decimals!r}")
        _check_coverage_settings(self.coverage)


def _check_coverage_settings(c: CoverageSettings) -> None:
    if len(c.ring_distances) == 0 or len(c.ring_heights) == 0:
        raise RigoptError("coverage settings need at least one ring distance and one ring height")
    values = np.array([*c.ring_distances, *c.ring_heights, c.max_range], dtype=float)
    if not np.all(np.isfinite(values)) or min(c.ring_distances) < 0 or c.max_range <= 0:
        raise RigoptError("ring distances must be finite and >= 0 m, heights finite, max_range > 0 m; got "
                          f"{c.ring_distances}, {c.ring_heights}, {c.max_range}")
    if int(c.sectors) < 1:
        raise RigoptError(f"sectors must be a positive integer, got {c.sectors}")
    grid = tuple(c.image_grid)
    if len(grid) != 2 or any(int(g) < 1 for g in grid):
        raise RigoptError(f"image_grid must be two positive integers (width, height), got {c.image_grid}")


# --- Per-rig profile: the expensive, vehicle-dependent facts, computed once -------------------------------

@dataclass(frozen=True, eq=False)
class RigProfile:
    """A rig with what its own vehicle does to its cameras.

    ``rig``; ``vehicle`` the vehicle's name; ``coverage_settings`` those it was computed with;
    ``sees`` (N, Q) bool: camera i sees sector point q (None when not computed); ``ring`` (Q,) int ring index
    (heights outermost, then distances) and ``sector`` (Q,) int of each sector point; ``self_occlusion``
    (N,) float in [0, 1]: fraction of each camera's pixel rays hitting its own body (None when not computed).
    """

    rig: Rig
    vehicle: str
    coverage_settings: CoverageSettings
    sees: np.ndarray | None
    ring: np.ndarray | None
    sector: np.ndarray | None
    self_occlusion: np.ndarray | None

    @property
    def counts(self) -> np.ndarray:
        """(Q,) int: cameras seeing each sector point."""
        return self._needs_coverage().sum(axis=0)

    def state(self, min_cameras: int = 1) -> np.ndarray:
        """(Q,) bool: sector points seen by at least ``min_cameras`` cameras."""
        return self.counts >= int(min_cameras)

    @property
    def shares(self) -> np.ndarray:
        """(N,) float: each camera's share of the covered sector points (see the module, term 7); sums to 1."""
        return coverage_shares(self._needs_coverage())

    def _needs_coverage(self) -> np.ndarray:
        if self.sees is None:
            raise RigoptError(f"the profile of rig {self.rig.name!r} was built without coverage; "
                              "build it with rig_profile(..., coverage=True)")
        return self.sees


def self_occlusion_fractions(rig: Rig, vehicle: Vehicle, coverage: CoverageSettings | None = None) -> np.ndarray:
    """(N,) float in [0, 1]: per camera of ``rig``, the fraction of its ``coverage.image_grid`` pixel rays
    (cell centres, its own FOV and image size) that hit ``vehicle``'s body within ``coverage.max_range`` m
    (default CoverageSettings()). Every camera's rays are cast in one call."""
    coverage = CoverageSettings() if coverage is None else coverage
    rays, origins, owner = [], [], []
    for k, camera in enumerate(rig.cameras):
        r = CameraModel.of_camera(camera).grid_rays(coverage.image_grid) @ camera.rotation.T
        rays.append(r)
        origins.append(np.repeat(camera.position[None], len(r), axis=0))
        owner.append(np.full(len(r), k))
    owner = np.concatenate(owner)
    hits = vehicle.caster(coverage.backend).first_hit_distance(np.concatenate(origins), np.concatenate(rays))
    blocked = np.bincount(owner, weights=(hits <= coverage.max_range).astype(float), minlength=len(rig.cameras))
    return blocked / np.bincount(owner, minlength=len(rig.cameras))


def coverage_shares(sees) -> np.ndarray:
    """(N,) float: camera i's share ``s_i = (1/|Q_cov|) sum_{q covered} sees_iq / count_q`` of the covered
    sector points, from ``sees`` (N, Q) bool; sums to 1 (uniform 1/N when nothing is covered)."""
    sees = np.asarray(sees, dtype=bool)
    if sees.ndim != 2 or sees.shape[0] < 1:
        raise RigoptError(f"sees must be an (N, Q) boolean array with N >= 1, got shape {sees.shape}")
    counts = sees.sum(axis=0)
    covered = counts > 0
    if not covered.any():
        return np.full(sees.shape[0], 1.0 / sees.shape[0])
    return (sees[:, covered] / counts[covered]).sum(axis=1) / covered.sum()


def rig_profile(rig: Rig, vehicle: Vehicle | None = None, settings: PlusSettings | None = None,
                coverage: bool = True, self_occlusion: bool = True,
                vehicle_lookup: Callable[[str], Vehicle] = load_vehicle) -> RigProfile:
    """The profile of ``rig`` on ``vehicle`` (default: ``vehicle_lookup(rig.vehicle)``, the library's vehicle).

    ``coverage`` computes the (N, Q) sector-point visibility (cover, overlap, cw_*), ``self_occlusion``
    the per-camera body fractions (selfocc). Cost: one coverage matrix and N * grid pixel rays.
    """
    if not isinstance(rig, Rig):
        raise RigoptError(f"rig_profile needs a Rig, got {type(rig).__name__}")
    settings = PlusSettings() if settings is None else settings
    if not isinstance(settings, PlusSettings):
        raise RigoptError(f"settings must be a PlusSettings, got {type(settings).__name__}")
    if vehicle is None:
        try:
            vehicle = vehicle_lookup(rig.vehicle)
        except RigoptError as error:
            raise type(error)(f"rig {rig.name!r}: {error}") from None
    if not isinstance(vehicle, Vehicle):
        raise RigoptError(f"the vehicle of rig {rig.name!r} must be a rigopt Vehicle, got {type(vehicle).__name__}")
    cov = settings.coverage
    sees = ring = sector = occlusion = None
    if coverage:
        matrix = rig_coverage_matrix(rig, vehicle, cov)
        sees = np.asarray(matrix.sees, dtype=bool)
        ring = np.repeat(np.arange(len(cov.ring_heights) * len(cov.ring_distances)), int(cov.sectors))
        sector = np.asarray(matrix.sector, dtype=int)
        for array in (sees, ring, sector):
            array.flags.writeable = False
    if self_occlusion:
        occlusion = self_occlusion_fractions(rig, vehicle, cov)
        occlusion.flags.writeable = False
    return RigProfile(rig, vehicle.name, cov, sees, ring, sector, occlusion)


# --- Pieces of the terms ------------------------------------------------------------------------------------

def pixels_per_metre(fov_deg, width_px, depth_m):
    """Pixels spanned by one metre (fronto-parallel) at depth ``depth_m``: f_px / Z with
    f_px = (W / 2) / tan(fov / 2). fov_deg (deg), width_px (px), depth_m (m): broadcastable -> px/m."""
    depth = np.asarray(depth_m, dtype=float)
    if np.any(~np.isfinite(depth)) or np.any(depth <= 0):
        raise RigoptError("depth must be finite and > 0 m")
    return focal_from_fov(fov_deg, width_px) / depth


def focal_log_ratio(fovs_a, fovs_b, widths_a=None, widths_b=None) -> np.ndarray:
    """|ln(f_px,a / f_px,b)| elementwise; fovs (deg) broadcastable, each in (0, 180). Without widths, a common
    image width: |ln(tan(fov_b / 2) / tan(fov_a / 2))|. With widths (px): f_px = (W / 2) / tan(fov / 2)."""
    fa, fb = np.asarray(fovs_a, dtype=float), np.asarray(fovs_b, dtype=float)
    for fov in (fa, fb):
        if np.any(~np.isfinite(fov)) or np.any(fov <= 0) or np.any(fov >= 180):
            raise RigoptError("FOVs must be in (0, 180) degrees")
    ratio = np.log(np.tan(np.deg2rad(fb) / 2.0)) - np.log(np.tan(np.deg2rad(fa) / 2.0))
    if (widths_a is None) != (widths_b is None):
        raise RigoptError("give the image widths of both sides or of neither")
    if widths_a is not None:
        wa, wb = np.asarray(widths_a, dtype=float), np.asarray(widths_b, dtype=float)
        if np.any(~np.isfinite(wa)) or np.any(~np.isfinite(wb)) or np.any(wa <= 0) or np.any(wb <= 0):
            raise RigoptError("image widths must be finite and > 0 px")
        ratio = ratio + np.log(wa) - np.log(wb)
    return np.abs(ratio)


def coverage_difference(profile_a: RigProfile, profile_b: RigProfile, min_cameras: int = 1) -> np.ndarray:
    """(R,) float: per ring (heights outermost, then distances), the fraction of sectors whose state
    "seen by >= min_cameras cameras" differs between the two rigs, each on its own vehicle."""
    _same_layout(profile_a, profile_b)
    differs = profile_a.state(min_cameras) != profile_b.state(min_cameras)
    rings = int(profile_a.ring.max()) + 1
    return np.bincount(profile_a.ring, weights=differs.astype(float), minlength=rings) / np.bincount(
        profile_a.ring, minlength=rings)


def _same_layout(profile_a: RigProfile, profile_b: RigProfile) -> None:
    if profile_a.coverage_settings != profile_b.coverage_settings:
        raise RigoptError(f"the profiles of {profile_a.rig.name!r} and {profile_b.rig.name!r} were computed with "
                          "different coverage settings; build both with the same PlusSettings")
    profile_a._needs_coverage(), profile_b._needs_coverage()


def matched_weights(shares_a, rows) -> np.ndarray:
    """(M,) float: weights of the matched pairs from the reference cameras' shares ``shares_a`` (N_A,) and
    their indices ``rows`` (M,): ``s[rows] / sum s[rows]``, uniform when that sum is 0; sums to 1."""
    picked = np.asarray(shares_a, dtype=float)[np.asarray(rows, dtype=int)]
    if len(picked) == 0:
        raise RigoptError("no matched pairs to weight")
    total = picked.sum()
    return picked / total if total > 0 else np.full(len(picked), 1.0 / len(picked))


def matching(rig_a: Rig, rig_b: Rig, match_lambdas: Sequence[float] = (1.0, 1.0, 1.0)):
    """The matching of the terms: (rows (M,), cols (M,)) int camera indices of A and B."""
    settings = PlusSettings(match_lambdas=tuple(match_lambdas))
    zero = np.zeros(1, dtype=int)
    _, assignments = match_pairs(RigBatch.from_rigs([rig_a]), zero, RigBatch.from_rigs([rig_b]), zero,
                                  DEFAULT_ALPHA, tie_broken_lambdas(settings.match_lambdas), keep_assignment=True)
    return assignments[0]


# --- The terms of many pairs -------------------------------------------------------------------------------

def _check_terms(terms) -> tuple[str, ...]:
    if isinstance(terms, str):
        terms = (terms,)
    terms = tuple(terms)
    unknown = [t for t in terms if t not in TERMS]
    if not terms or unknown:
        raise RigoptError(f"unknown RigCD+ terms {unknown}; use some of {', '.join(TERMS)}" if unknown
                          else "no terms requested")
    return terms


def _as_entries(items, what: str) -> list:
    if isinstance(items, (Rig, RigProfile)):
        raise RigoptError(f"{what} must be a sequence of rigs or profiles, not a single one")
    items = list(items)
    if not items:
        raise RigoptError(f"{what} is empty; pass at least one rig")
    for item in items:
        if not isinstance(item, (Rig, RigProfile)):
            raise RigoptError(f"{what} must hold Rig or RigProfile objects, got {type(item).__name__}")
    return items


def _resolve_profiles(entries: list, settings: PlusSettings, need_cov: bool, need_occ: bool,
                      vehicles, vehicle_lookup) -> list:
    """One profile per distinct object of ``entries`` (None where nothing vehicle-dependent is needed)."""
    if not (need_cov or need_occ):
        return [None] * len(entries)
    cache: dict[int, RigProfile] = {}
    out = []
    for entry in entries:
        if isinstance(entry, RigProfile):
            if entry.coverage_settings != settings.coverage:
                raise RigoptError(f"the profile of {entry.rig.name!r} was computed with other coverage settings "
                                  "than the settings given")
            if (need_cov and entry.sees is None) or (need_occ and entry.self_occlusion is None):
                raise RigoptError(f"the profile of {entry.rig.name!r} lacks the coverage or self-occlusion the "
                                  "requested terms need; build it with both")
            out.append(entry)
            continue
        if id(entry) not in cache:
            vehicle = None
            if vehicles is not None:
                vehicle = vehicles.get(entry.vehicle) if isinstance(vehicles, Mapping) else None
            cache[id(entry)] = rig_profile(entry, vehicle, settings, need_cov, need_occ, vehicle_lookup)
        out.append(cache[id(entry)])
    return out


def term_matrices(rigs_a: Iterable[Rig | RigProfile], rigs_b: Iterable[Rig | RigProfile],
                  terms: Sequence[str] = TERMS, settings: PlusSettings | None = None,
                  vehicles: Mapping[str, Vehicle] | None = None,
                  vehicle_lookup: Callable[[str], Vehicle] = load_vehicle) -> dict[str, np.ndarray]:
    """Every requested term of every pair (rigs_a[i], rigs_b[j]): {term: (len(rigs_a), len(rigs_b)) float}.

    Either side holds Rig or RigProfile objects. Vehicles (for the vehicle-dependent terms) come from
    ``vehicles`` (by ``rig.vehicle``) or else ``vehicle_lookup``; profiles are built once per distinct rig
    object across both sides. Raises RigoptError on bad input or a non-finite result.
    """
    terms = _check_terms(terms)
    settings = PlusSettings() if settings is None else settings
    if not isinstance(settings, PlusSettings):
        raise RigoptError(f"settings must be a PlusSettings, got {type(settings).__name__}")
    side_a, side_b = _as_entries(rigs_a, "rigs_a"), _as_entries(rigs_b, "rigs_b")
    need_cov = any(t in COVERAGE_TERMS for t in terms)
    need_occ = any(t in SELF_OCCLUSION_TERMS for t in terms)
    profiles = _resolve_profiles(side_a + side_b, settings, need_cov, need_occ, vehicles, vehicle_lookup)
    prof_a, prof_b = profiles[:len(side_a)], profiles[len(side_a):]
    rig_a = [e.rig if isinstance(e, RigProfile) else e for e in side_a]
    rig_b = [e.rig if isinstance(e, RigProfile) else e for e in side_b]

    shape = (len(rig_a), len(rig_b))
    out = {t: np.zeros(shape) for t in terms}
    ia, ib = (g.ravel() for g in np.meshgrid(np.arange(shape[0]), np.arange(shape[1]), indexing="ij"))
    if any(t in MATCHED_TERMS or t == "count" for t in terms):
        matched, assignments = match_pairs(RigBatch.from_rigs(rig_a), ia, RigBatch.from_rigs(rig_b), ib,
                                            DEFAULT_ALPHA, tie_broken_lambdas(settings.match_lambdas),
                                            keep_assignment=True)
        for key in ("t", "r", "f", "count"):
            if key in out:
                out[key][ia, ib] = matched[key]
        per_pair = [t for t in terms if t in MATCHED_TERMS and t not in ("t", "r", "f")]
        if per_pair:
            shares = {}
            for p, (i, j) in enumerate(zip(ia, ib)):
                values = _pair_matched_terms(rig_a[i], rig_b[j], *assignments[p], per_pair, settings,
                                             prof_a[i], prof_b[j], shares)
                for key, value in values.items():
                    out[key][i, j] = value
    for key, min_cameras in (("cover", 1), ("overlap", 2)):
        if key in out:
            states_a = np.stack([p.state(min_cameras) for p in prof_a]).astype(float)  # (A, Q)
            states_b = np.stack([p.state(min_cameras) for p in prof_b]).astype(float)
            if len({p.coverage_settings for p in prof_a + prof_b}) != 1:
                raise RigoptError("the profiles were computed with different coverage settings")
            # fraction of differing points = mean over rings (all rings have the same number of sectors)
            out[key] = (states_a @ (1 - states_b).T + (1 - states_a) @ states_b.T) / states_a.shape[1]

    for key, values in out.items():
        if not np.all(np.isfinite(values)):
            raise RigoptError(f"RigCD+ term {key!r} is not finite for some pair; check the rigs' cameras")
        if settings.decimals is not None:
            out[key] = np.round(values, settings.decimals) + 0.0
    return out


def _pair_matched_terms(rig_a: Rig, rig_b: Rig, rows, cols, keys, settings: PlusSettings,
                        profile_a, profile_b, shares_cache: dict) -> dict[str, float]:
    pa, pb = rig_a.positions[rows], rig_b.positions[cols]
    out = {}
    if "dz" in keys:
        out["dz"] = float(np.mean(np.abs(pa[:, 2] - pb[:, 2])))
    if "dxy" in keys:
        out["dxy"] = float(np.mean(np.linalg.norm(pa[:, :2] - pb[:, :2], axis=1)))
    if "focal" in keys:
        widths = (None, None)
        if settings.focal_width == "own":
            widths = ([rig_a.cameras[i].image_size[0] for i in rows], [rig_b.cameras[j].image_size[0] for j in cols])
        out["focal"] = float(np.mean(focal_log_ratio(rig_a.fovs[rows], rig_b.fovs[cols], *widths)))
    if "selfocc" in keys:
        out["selfocc"] = float(np.mean(np.abs(profile_a.self_occlusion[rows] - profile_b.self_occlusion[cols])))
    if any(k.startswith("cw_") for k in keys):
        if id(profile_a) not in shares_cache:
            shares_cache[id(profile_a)] = profile_a.shares
        w = matched_weights(shares_cache[id(profile_a)], rows)
        t = np.linalg.norm(pa - pb, axis=1)
        r = rotation_angle(np.swapaxes(rig_a.rotations[rows], -1, -2) @ rig_b.rotations[cols])
        f = np.abs(rig_a.fovs[rows] - rig_b.fovs[cols])
        for key, values in (("cw_t", t), ("cw_r", r), ("cw_f", f)):
            if key in keys:
                out[key] = float(w @ values)
    return out


def pair_terms(rig_a: Rig | RigProfile, rig_b: Rig | RigProfile, terms: Sequence[str] = TERMS,
               settings: PlusSettings | None = None, vehicles: Mapping[str, Vehicle] | None = None,
               vehicle_lookup: Callable[[str], Vehicle] = load_vehicle) -> dict[str, float]:
    """The requested terms of one pair (A = reference, B) as {term: float}; arguments as :func:`term_matrices`."""
    matrices = term_matrices([rig_a], [rig_b], terms, settings, vehicles, vehicle_lookup)
    return {key: float(value[0, 0]) for key, value in matrices.items()}


def features_under_matching(rigs_a, rigs_b, match_lambdas: Sequence[float],
                            settings: PlusSettings | None = None) -> np.ndarray:
    """(len(rigs_a), len(rigs_b), 3) float: the features (t m, r rad, f deg) over the matching that minimises
    ``lt t + lr r + lf f`` with ``match_lambdas`` (term 6). Unit lambdas give the published features."""
    settings = replace(PlusSettings() if settings is None else settings, match_lambdas=tuple(match_lambdas))
    matrices = term_matrices(rigs_a, rigs_b, ("t", "r", "f"), settings)
    return np.stack([matrices["t"], matrices["r"], matrices["f"]], axis=-1)
