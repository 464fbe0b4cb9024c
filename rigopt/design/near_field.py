"""The near-field stage: surround-view fisheyes that see the regulation fields and the blind near field.

Production rigs separate two jobs. Perception cameras (windscreen, B-pillars, a truck's high mirror arm) feed
the detector and are matched to the reference; near-field cameras (grille, mirrors, tailgate, cab corners),
wide fisheyes looking down, serve the close-proximity fields of the regulations and the ground right around
the body. This stage chooses the near_field cameras of a design, given its perception cameras:

    minimise   sum_c (1 + w m_c) x_c            (the fewest cameras, then the cheapest mounts; w < 1 / n)
    subject to sum_c sees_cq x_c >= 1            every required point q: each field point at each of its
                                                 test-object heights, and the near ring around the body
               at most one camera per mount point and per clashing pair (a fisheye at a perception camera's
               mount shares its housing: the two are one camera module), and of two that would duplicate
               each other (the same lens, close and looking the same way: mounting practice's rule)
               x_c = x_mirror(c)                 (symmetric designs: mirrored pairs or the centreline)
               x binary

Candidates are the catalogue's fisheyes (default :func:`fisheye_190`: 190 deg, equidistant Kannala-Brandt) on
the vehicle's mount points (never on a windscreen's or rear window's outside), facing every NEAR_FIELD_YAW_STEP
deg of yaw at NEAR_FIELD_PITCHES_DEG (down to straight down), whose central cone (a CLEAR_CONE_DEG pinhole) is
clear of the body: a surround-view fisheye sees its own body at its edges, which is why it is mounted at the
outermost points. ``m_c`` is the relative mounting cost (:func:`near_field_costs`): the zone's and the tyre
spray's, plus one panel's off the places production surround view uses (mirrors, grille, tailgate, rear roof
line), so that of the fewest fisheyes that see what is asked, those at production spots are chosen. The MILP has a work limit, never a clock. Afterwards the
fields are checked densely (every ``DENSE_SPACING`` m) and unseen points join the requirements of another round.
The near ring is asked only where some candidate sees it (a body without mounts at its rear cannot see behind
it); its other points are reported (``NearFieldDesign.ring_unseeable``).
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sparse
from scipy.spatial import cKDTree

from rigopt.camera import Lens
from rigopt.coverage.regulations import RegionPreset, required_mask
from rigopt.coverage.visibility import no_pixel_demand, resolved_by
from rigopt.design.candidates import CandidateSet, build_candidates
from rigopt.design.defaults import DEFAULT_MAX_NODES
from rigopt.design.requirements import DENSE_SPACING, REGION_SPACING, field_labels
from rigopt.design.selection import (
    DesignInfeasible,
    _gap,
    _mount_groups,
    essential_requirements,
)
from rigopt.design.settings import CatalogueCamera
from rigopt.errors import RigoptError
from rigopt.mounting.features import GLASS_ZONES
from rigopt.mounting.practice import as_modules, mounting_costs
from rigopt.mounting.records import MountPractice, MountRules
from rigopt.mounting.shapes import NEAR_FIELD_CLEAR_CONE_DEG
from rigopt.quiet import HIGHS_OPTIONS, quiet_highs
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle

#: The default near-field camera: horizontal FOV (deg) and image size (px) of an equidistant fisheye.
FISHEYE_HFOV_DEG = 190.0
FISHEYE_IMAGE_SIZE = (1280, 800)
#: Pitches (deg, > 0 up) and yaw step (deg) of the near-field candidates' orientations.
NEAR_FIELD_PITCHES_DEG = (-90.0, -60.0, -45.0, -30.0, -15.0, 0.0)
NEAR_FIELD_YAW_STEP = 45.0
#: The central cone (a pinhole of this horizontal FOV, deg) that must be clear of the body: the mount rules'.
CLEAR_CONE_DEG = NEAR_FIELD_CLEAR_CONE_DEG
#: Largest share of a near-field camera's image that may show the ego body.
MAX_BODY_FRACTION = 0.4
#: The near ring: distances (m) from the body's footprint and heights (m) that must be seen all around.
NEAR_RING_DISTANCES = (0.5, 1.0)
NEAR_RING_HEIGHTS = (0.0, 0.8)
NEAR_RING_SECTORS = 36
#: Largest mount point spacing (m) of the near-field candidates (finer than the perception stage's on big bodies:
#: the ground right behind a bumper is seen only from a few places).
NEAR_FIELD_SPACING = 0.2
#: Farthest a near-field camera counts as seeing (m).
NEAR_FIELD_RANGE = 35.0
#: Mount points closer than this (m) may not both hold a camera, nor sit this close to a perception camera.
CLASH_DISTANCE = 0.10
#: Rounds of the dense field check.
DENSE_ROUNDS = 3
#: Where production surround view mounts its fisheyes: the mirror bases or arms, the grille or badge, the tailgate
#: or number plate, the rear roof line (zone names, as the built-in vehicles and ``vehicle add`` name them).
SURROUND_VIEW_ZONES = ("mirror", "bumper_front", "bumper_rear", "roof_rear")
#: Extra mounting cost of a near-field fisheye anywhere else, in units of an ordinary panel's (1): with the fewest
#: cameras first, it decides between mounts that see as much.
OFF_SPOT_COST = 1.0


def fisheye_190() -> CatalogueCamera:
    """A 190-degree surround-view fisheye, 1280 x 800 px, equidistant (Kannala-Brandt with zero coefficients)."""
    width, height = FISHEYE_IMAGE_SIZE
    focal = (width / 2) / np.radians(FISHEYE_HFOV_DEG / 2)
    lens = Lens(width, height, focal, focal, width / 2, height / 2, "fisheye", (0.0, 0.0, 0.0, 0.0))
    return CatalogueCamera(f"fisheye {FISHEYE_HFOV_DEG:g} deg {width}x{height} (equidistant)", lens)


@dataclass(frozen=True)
class NearFieldPoints:
    """What the near-field cameras must see: ``points`` (q, 3) m, vehicle frame, ``labels`` (q,) and
    ``pixel_demand`` (q, 2) float, each point's test object height m and the pixels its image must span (the near
    ring's: nothing, in view is enough; a field's: its test object's)."""

    points: np.ndarray
    labels: tuple[str, ...]
    pixel_demand: np.ndarray

    def extended(self, points: np.ndarray, labels, pixel_demand: np.ndarray) -> "NearFieldPoints":
        return NearFieldPoints(np.concatenate([self.points, points]), self.labels + tuple(labels),
                               np.concatenate([self.pixel_demand, pixel_demand]))

    def subset(self, keep: np.ndarray) -> "NearFieldPoints":
        """The points where ``keep`` (q,) bool holds."""
        return NearFieldPoints(self.points[keep], tuple(label for label, k in zip(self.labels, keep) if k),
                               self.pixel_demand[keep])

    @property
    def on_ring(self) -> np.ndarray:
        """(q,) bool: the near ring's points (the rest are field points)."""
        return np.array([label.startswith("near ring") for label in self.labels], dtype=bool)


def near_field_points(vehicle: Vehicle, presets: tuple[RegionPreset, ...], lifted=()) -> NearFieldPoints:
    """The near ring around the footprint and every field point of ``presets`` (each at its heights), less the
    points inside the footprint or a keep-out in force (a coupled trailer)."""
    footprint = vehicle.footprint
    azimuths = np.linspace(-np.pi, np.pi, NEAR_RING_SECTORS, endpoint=False)
    parts, labels, demands = [], [], []
    for height in NEAR_RING_HEIGHTS:
        for distance in NEAR_RING_DISTANCES:
            parts.append(footprint.ring_points(azimuths, distance, height))
            demands.append(no_pixel_demand(len(azimuths)))
            labels += [f"near ring {distance:g} m at height {height:g} m, azimuth {np.rad2deg(a):+.0f} deg"
                       for a in azimuths]
    for preset in presets:
        mine = preset.points(vehicle, REGION_SPACING)
        parts.append(mine)
        demands.append(preset.pixel_demands(len(mine)))
        labels += field_labels(preset.key, mine)
    points = np.concatenate(parts)
    keep = required_mask(vehicle, points, lifted)
    return NearFieldPoints(points[keep], tuple(label for label, k in zip(labels, keep) if k),
                           np.concatenate(demands)[keep])


def near_field_candidates(vehicle: Vehicle, spacing: float, symmetric: bool, rules: MountRules = MountRules(),
                          catalogue=None, zones=None) -> CandidateSet:
    """The near-field candidates on ``vehicle``'s mount points (see the module docstring), on ``zones`` (None: every
    zone the perception cameras may use) less the glass (GLASS_ZONES)."""
    yaws = np.arange(-180.0, 180.0, NEAR_FIELD_YAW_STEP)
    catalogue = catalogue or (fisheye_190(),)
    # the cone the mount check clears (rigopt.mounting.shapes.checked_model) has each camera's image aspect: the
    # tallest catalogue image's clears them all
    tallest = max((c.lens.image_size for c in catalogue), key=lambda size: size[1] / size[0])
    return build_candidates(vehicle, catalogue, spacing, yaws, NEAR_FIELD_PITCHES_DEG,
                            near_field_zones(vehicle, zones), rules, MAX_BODY_FRACTION, symmetric,
                            clear_lens=Lens.pinhole(CLEAR_CONE_DEG, tallest))


def near_field_zones(vehicle: Vehicle, zones=None) -> tuple[str, ...]:
    """The zones a near-field fisheye may sit on: ``zones`` (None: the vehicle's zones that are sampled without being
    named, those on the body's surface) less the glass (GLASS_ZONES: a surround-view camera behind a windscreen would
    see the dashboard; on it, it sits in the wipers' sweep)."""
    asked = zones if zones is not None else [z.name for z in vehicle.zones if not z.raised_max]
    allowed = tuple(name for name in dict.fromkeys(asked) if name not in GLASS_ZONES)
    if not allowed:
        raise RigoptError(f"the zones {sorted(set(asked))} of {vehicle.name} are glass, where no near-field fisheye "
                          "is mounted; allow a zone of the body (--zones), or design without near-field cameras")
    return allowed


def near_field_costs(vehicle: Vehicle, zones, points) -> np.ndarray:
    """(n,) float: the mounting cost of a near-field fisheye at each of ``points`` (n, 3) m in ``zones`` (n,): the
    zone's and the tyre spray's (:func:`rigopt.mounting.practice.mounting_costs`) plus OFF_SPOT_COST off the
    places production surround view uses (SURROUND_VIEW_ZONES)."""
    off_spot = ~np.isin(np.asarray(zones, dtype=str), SURROUND_VIEW_ZONES)
    return mounting_costs(vehicle, zones, points) + OFF_SPOT_COST * off_spot


@dataclass(frozen=True)
class NearFieldDesign:
    """``rig``: the perception cameras followed by the chosen near-field cameras (role near_field; one that sits at
    a perception camera's mount shares its housing, the pair one camera module); the candidates' count, the
    points required (``n_points``, after the dense rounds), the MILP's ``status`` and ``gap``, and ``seconds``."""

    rig: Rig
    n_candidates: int
    n_points: int
    status: str
    gap: float
    seconds: float
    rounds: int
    ring_unseeable: tuple[str, ...] = ()
    """The near ring's points no candidate sees (the body allows no mount that sees them): reported, not asked."""


def select_near_field(sees: np.ndarray, mount: np.ndarray, mount_points: np.ndarray, mount_cost: np.ndarray,
                      mirror: np.ndarray | None = None, max_nodes: int = DEFAULT_MAX_NODES,
                      labels=None, duplicates: np.ndarray | None = None) -> tuple[np.ndarray, str, float]:
    """The MILP of the module docstring: (chosen (k,) int, status, relative gap). sees (n, q) bool; mount (n,) int
    into mount_points (m, 3) m; mount_cost (n,) float; mirror (n,) int or None; duplicates (d, 2) int pairs of
    candidates of which at most one may be chosen (:func:`duplicate_pairs`), or None. Raises DesignInfeasible when
    some point no candidate sees, or no selection meets every point."""
    import cvxpy as cp

    n = sees.shape[0]
    unseen = np.flatnonzero(~sees.any(axis=0))
    if len(unseen):
        named = "; ".join(labels[q] for q in unseen[:6]) if labels is not None else ""
        raise DesignInfeasible(f"{len(unseen)} near-field point(s) no near-field candidate sees"
                               f"{': ' + named if named else ''}{' and more' if len(unseen) > 6 and named else ''}; "
                               "allow more zones or a finer --spacing")
    x = cp.Variable(n, boolean=True)
    needed = essential_requirements(sees, np.ones(sees.shape[1], dtype=int))
    constraints = [sparse.csr_matrix(sees[:, needed].T.astype(float)) @ x >= 1]
    clashes = cKDTree(mount_points).query_pairs(CLASH_DISTANCE, output_type="ndarray")
    groups = _mount_groups(mount, clashes)
    if groups.shape[0]:
        constraints.append(groups @ x <= 1)
    if duplicates is not None and len(duplicates):
        rows = np.repeat(np.arange(len(duplicates)), 2)
        pairs = sparse.csr_matrix((np.ones(rows.size), (rows, np.ravel(duplicates))), shape=(len(duplicates), n))
        constraints.append(pairs @ x <= 1)
    if mirror is not None:
        first = np.flatnonzero(np.arange(n) < mirror)
        if len(first):
            constraints.append(x[first] == x[mirror[first]])
    cost = np.asarray(mount_cost, dtype=float)
    weight = 1.0 / (n * max(float(cost.max(initial=1.0)), 1.0) + 1.0)  # the count first, the cost breaks ties
    problem = cp.Problem(cp.Minimize(cp.sum(x) + weight * (cost @ x)), constraints)
    quiet_highs()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        problem.solve(solver=cp.HIGHS, **{**HIGHS_OPTIONS, "mip_rel_gap": 1e-6, "mip_max_nodes": int(max_nodes)})
    if problem.status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE) or x.value is None:
        raise DesignInfeasible("no choice of near-field cameras sees every near-field point with its housing clear "
                               "of the others; allow more zones or a finer --spacing")
    status = "optimal" if problem.status == cp.OPTIMAL else "node_limit"
    return np.flatnonzero(x.value > 0.5), status, _gap(problem)


def duplicate_pairs(candidates: CandidateSet, index: np.ndarray, practice) -> np.ndarray:
    """(d, 2) int positions in ``index`` of the candidate pairs that would duplicate each other by mounting practice
    (:func:`rigopt.mounting.practice.duplicates`: the same lens, lenses within ``practice.duplicate_distance`` m and
    optical axes within ``practice.duplicate_angle_deg``); none when the practice's feature rules are off."""
    if not practice.feature_rules:
        return np.zeros((0, 2), dtype=int)
    positions = candidates.positions[index]
    pairs = cKDTree(positions).query_pairs(practice.duplicate_distance, output_type="ndarray")
    if not len(pairs):
        return np.zeros((0, 2), dtype=int)
    i, j = pairs[:, 0], pairs[:, 1]
    forwards = candidates.rotations[index][:, :, 0]
    lenses = candidates.lens[index]
    apart = np.linalg.norm(positions[i] - positions[j], axis=1)
    angle = np.rad2deg(np.arccos(np.clip(np.einsum("ij,ij->i", forwards[i], forwards[j]), -1.0, 1.0)))
    same = (lenses[i] == lenses[j]) & (apart <= practice.duplicate_distance) & (angle <= practice.duplicate_angle_deg)
    return pairs[same]


@dataclass(frozen=True)
class NearFieldChoice:
    """The near-field cameras chosen on a vehicle, before they join a rig: ``cameras`` (role near_field, named
    CAM_NEAR_FIELD_k), and the stage's facts as :class:`NearFieldDesign` gives them."""

    cameras: tuple[Camera, ...]
    n_candidates: int
    n_points: int
    status: str
    gap: float
    seconds: float
    rounds: int
    ring_unseeable: tuple[str, ...] = ()


def choose_near_field(vehicle: Vehicle, presets: tuple[RegionPreset, ...], spacing: float, symmetric: bool,
                      rules: MountRules = MountRules(), catalogue=None, zones=None, max_nodes: int = DEFAULT_MAX_NODES,
                      lifted=(), progress=lambda message: None) -> NearFieldChoice:
    """The near-field cameras of ``vehicle`` that see every field of ``presets`` densely and the near ring, the
    fewest and cheapest (mount points ``spacing`` m apart); nothing here depends on the perception cameras."""
    start = time.perf_counter()
    candidates = near_field_candidates(vehicle, spacing, symmetric, rules, catalogue, zones)
    index = np.arange(len(candidates))
    mirror = candidates.mirror
    model = candidates.model(index)
    points = near_field_points(vehicle, presets, lifted)
    progress(f"near field: {len(index)} fisheye candidates, {len(points.points)} points to see")
    # The near ring is seen as far as the body allows: its points no candidate sees are reported, not asked;
    # a field point no candidate sees is an error (select_near_field names it).
    def seen_by_candidates(required: NearFieldPoints) -> np.ndarray:
        return resolved_by(vehicle.ray_caster, model, candidates.positions[index], candidates.rotations[index],
                           required.points, required.pixel_demand, NEAR_FIELD_RANGE)

    sees = seen_by_candidates(points)
    unseeable = points.on_ring & ~sees.any(axis=0)
    ring_unseeable = tuple(label for label, u in zip(points.labels, unseeable) if u)
    if ring_unseeable:
        progress(f"near field: {len(ring_unseeable)} near-ring point(s) no candidate sees are left out")
        points, sees = points.subset(~unseeable), sees[:, ~unseeable]
    cost = near_field_costs(vehicle, candidates.mount_zones[candidates.mount[index]], candidates.positions[index])
    duplicates = duplicate_pairs(candidates, index, rules.practice)
    dense = [preset.points(vehicle, DENSE_SPACING) for preset in presets]
    dense = [p[required_mask(vehicle, p, lifted)] for p in dense]
    for round_ in range(1, DENSE_ROUNDS + 1):
        if round_ > 1:  # the points the dense check added
            sees = seen_by_candidates(points)
        chosen, status, gap = select_near_field(sees, candidates.mount[index], candidates.mount_points, cost, mirror,
                                                max_nodes, points.labels, duplicates)
        picked = index[chosen]
        unseen = []
        if dense:
            chosen_model = candidates.model(picked)
            for preset, field in zip(presets, dense):
                seen = resolved_by(vehicle.ray_caster, chosen_model, candidates.positions[picked],
                                   candidates.rotations[picked], field, preset.pixel_demands(len(field)),
                                   NEAR_FIELD_RANGE).any(axis=0)
                unseen.append((preset, field[~seen]))
        missing = sum(len(u) for _, u in unseen)
        if not missing or round_ == DENSE_ROUNDS:
            break
        progress(f"near field: {missing} dense field point(s) unseen; round {round_ + 1}")
        for preset, extra in unseen:
            points = points.extended(extra, field_labels(preset.key, extra), preset.pixel_demands(len(extra)))
    if missing:
        raise DesignInfeasible(f"after {DENSE_ROUNDS} rounds the near-field cameras still miss {missing} dense field "
                               "point(s); allow more zones or a finer --spacing")
    cameras = tuple(dataclasses.replace(candidates.camera(k, f"CAM_NEAR_FIELD_{n + 1}"), role="near_field")
                    for n, k in enumerate(picked))
    return NearFieldChoice(cameras, len(index), len(points.points), status, gap, time.perf_counter() - start, round_,
                           ring_unseeable)


def with_near_field(perception: Rig, choice: NearFieldChoice, practice: MountPractice = MountPractice()
                     ) -> NearFieldDesign:
    """``perception``'s cameras followed by the ``choice``'s; cameras closer than ``practice.module_distance`` (a
    fisheye at a perception camera's mount among them) share a housing: they are one camera module
    (:func:`rigopt.mounting.practice.as_modules`)."""
    rig = as_modules(Rig(perception.name, perception.vehicle, perception.cameras + choice.cameras, perception.origin),
                     practice)
    return NearFieldDesign(rig, choice.n_candidates, choice.n_points, choice.status, choice.gap, choice.seconds,
                           choice.rounds, choice.ring_unseeable)


def design_near_field(vehicle: Vehicle, perception: Rig, presets: tuple[RegionPreset, ...], spacing: float,
                      symmetric: bool, rules: MountRules = MountRules(), catalogue=None, zones=None,
                      max_nodes: int = DEFAULT_MAX_NODES, lifted=(), progress=lambda message: None) -> NearFieldDesign:
    """The near-field cameras of a design whose perception cameras are ``perception`` (on ``vehicle``): they
    see every field of ``presets`` densely and the near ring, the fewest and cheapest
    (:func:`choose_near_field`, then :func:`with_near_field`)."""
    return with_near_field(perception, choose_near_field(vehicle, presets, spacing, symmetric, rules, catalogue,
                                                         zones, max_nodes, lifted, progress), rules.practice)
