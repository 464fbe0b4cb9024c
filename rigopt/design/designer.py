"""The design pipeline: candidates -> coverage requirements -> MILP selection -> validated rig.

``design_rig`` proposes a rig on ``vehicle`` that minimises the calibrated RigCD to the reference rig
(the objective of :mod:`rigopt.design.selection`) while every ring sector the reference sees on its own
vehicle stays seen (plus optional stricter requirements), and every camera passes the mount checks.
With several reference rigs (a fleet) it minimises the largest RigCD over them and meets the union of
their coverage requirements; the continuous refinement then stays off.
A selected camera that fails the python-fcl checks is removed from the candidates and the MILP solved
again, so a returned design is always valid. With a height tolerance, the refined perception cameras then move to
the mounts nearest their reference cameras' heights (:mod:`rigopt.design.heights`), and a two-role design's
near-field stage adds its fisheyes.

The stages are functions of the records before them (``FieldPlan``, ``Selected``, ``Perception``,
``NearFieldResult``; :func:`design_rig` lists them in order), each record carrying the settings its stage used.
Every input is explicit: the references come with the vehicles they were designed on and the rigs to
compare with are passed in (:mod:`rigopt.design.problem` builds the usual ones); the result
(:mod:`rigopt.design.result`) carries everything the reports show.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from functools import reduce
from typing import Callable, Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

from rigopt.background import INLINE, Background
from rigopt.camera import CameraModel
from rigopt.design.naming import mount_name, unique
from rigopt.mounting.practice import as_modules, mounting_costs
from rigopt.mounting.records import RigCheck
from rigopt.mounting.rules import check_rig, check_unassembled
from rigopt.coverage.matrix import rig_coverage_matrix
from rigopt.coverage.visibility import resolved_by
from rigopt.design.candidates import CandidateSet, build_candidates
from rigopt.design.heights import search_heights
from rigopt.design.problem import ReferenceRig
from rigopt.design.refine import (RefineProblem, duty_points, free_radii, frustum_margins, project_to_surface,
                                  refine)
from rigopt.coverage.regulations import region_coverage
from rigopt.design.near_field import NEAR_FIELD_SPACING, NearFieldChoice, choose_near_field, with_near_field
from rigopt.design.requirements import (DENSE_SPACING, Requirements, design_requirements, explain_uncoverable,
                                       field_labels, required_presets)
from rigopt.design.result import Comparisons, DesignResult, MilpStage, RefinementReport, RigSummary
from rigopt.design.selection import DesignInfeasible, Selection, prune, select_cameras
from rigopt.design.settings import DesignSettings
from rigopt.design.tolerance import (OUT_OF_TOLERANCE_COST, matched_widening, tolerance_gaps, tolerance_penalty,
                                     tolerance_text, tolerated)
from rigopt.errors import RigoptError
from rigopt.metrics.calibration import Calibration, load_weights
from rigopt.metrics.drop_model import FEATURES as DROP_MODEL_FEATURES, DropModel
from rigopt.metrics.lifting import pair_terms
from rigopt.metrics.ranking import predict_transfer
from rigopt.metrics.rigcd import camera_costs
from rigopt.rig.library import load_rig
from rigopt.rig.model import Rig
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.symmetry import camera_mirrors

#: Mount points closer than this (m) may not both hold a camera (8 cm housings plus a margin).
CLASH_DISTANCE = 0.10
#: Rounds of the dense field check of the MILP's rig: unseen field points become requirements and the MILP is
#: solved again.
MAX_FIELD_ROUNDS = 3
#: At most this many unseen points of one field are added per round.
MAX_NEW_FIELD_POINTS = 200
#: How many validation rounds (re-solves after removing cameras that fail the fcl checks) at most.
MAX_REPAIRS = 10


def no_progress(message: str) -> None:
    """A progress callback that shows nothing."""
    return None


def default_spacing(vehicle: Vehicle, settings: DesignSettings) -> float:
    """A spacing (m) that puts about ``target_mounts`` mount points on the allowed zones (at least 0.1 m)."""
    zones = vehicle.fine_face_zones
    allowed = np.array([z is not None and (not settings.zones or z in settings.zones) for z in zones])
    area = float(vehicle.fine_mesh.area_faces[allowed].sum())
    return max(0.1, float(np.sqrt(area / settings.target_mounts)))


def _coverage_pool(candidates: CandidateSet, references: list[Rig], settings: DesignSettings) -> np.ndarray:
    """Candidates offered for coverage: on a coarse subset of mount points (about ``coverage_mounts``, and
    the centreline's in a symmetric design), every clear orientation with the reference's lenses and the
    widest lens; with their mirror images in a symmetric design."""
    points = candidates.mount_points
    step = max(1, len(points) // settings.coverage_mounts)
    order = np.lexsort((points[:, 1], points[:, 0]))
    chosen_mounts = set(order[::step].tolist())
    fovs = {float(f) for rig in references for f in np.round(rig.fovs, 6)} | {float(candidates.fovs.max())}
    mounts = np.isin(candidates.mount, list(chosen_mounts))
    if candidates.mirror is not None:  # every centreline camera too: the few that face straight ahead or back
        mounts |= candidates.mirror == np.arange(len(candidates))
    mask = mounts & np.isin(np.round(candidates.fovs, 6), list(fovs))
    return candidates.mirror_closed(np.flatnonzero(mask))


@dataclass(frozen=True)
class Prepared:
    """What every MILP of one design problem shares: the candidates, their matching costs to each
    reference (n, R_k), the requirement points (q, 3) m (``Requirements.points``), the coverage pool (p,) int
    and what it resolves (p, q; at each point's ``Requirements.pixel_demand``), the mount spacing (m) and each
    candidate's relative mounting cost (n,)."""

    references: tuple[Rig, ...]
    candidates: CandidateSet
    costs: tuple[np.ndarray, ...]
    points: np.ndarray
    pool: np.ndarray
    sees_pool: np.ndarray
    spacing: float
    mount_cost: np.ndarray


def prepare(vehicle: Vehicle, references: Sequence[Rig], calibration: Calibration, settings: DesignSettings,
            requirements: Requirements, progress: Callable[[str], None] = no_progress) -> Prepared:
    """Candidates, costs and the coverage of the ``requirements``' points by the candidates worth
    considering."""
    spacing = settings.spacing or default_spacing(vehicle, settings)
    progress(f"sampling mount candidates on {vehicle.name} (spacing {spacing:.2f} m)")
    candidates, points = mount_candidates(vehicle, settings, spacing), requirements.points
    model = candidates.model()
    raw = tuple(calibrated_costs(candidates.positions, candidates.rotations, candidates.fovs, rig, calibration,
                                 None, model, drop_model=settings.drop_model) for rig in references)
    gaps = tuple(tolerance_gaps(candidates.positions, candidates.rotations, candidates.fovs, rig, settings)
                 for rig in references)
    # beyond the tolerance a camera costs EXCESS_COST per tolerance: chosen only where the body offers no mount
    # within it, at the nearest pose it allows
    costs = tuple(r + tolerance_penalty(g) for r, g in zip(raw, gaps))
    no_sees, no_needs = np.zeros((len(candidates), 0), bool), np.zeros(0, int)
    pool = reduce(np.union1d, [prune(c, no_sees, no_needs, settings.keep_per_reference, 0) for c in costs],
                  _coverage_pool(candidates, list(references), settings))
    pool = candidates.mirror_closed(pool)
    progress(f"coverage of {len(points)} requirement points by {len(pool)} of {len(candidates)} candidates")
    sees_pool = _pool_sees(vehicle, candidates, pool, points, requirements.demands, settings)
    per_mount = mounting_costs(vehicle, candidates.mount_zones, candidates.mount_points)
    return Prepared(tuple(references), candidates, costs, points, pool, sees_pool, spacing, per_mount[candidates.mount])


def _pool_sees(vehicle: Vehicle, candidates: CandidateSet, pool: np.ndarray, points: np.ndarray,
               pixel_demand: np.ndarray, settings: DesignSettings) -> np.ndarray:
    """(p, q) bool: which of ``points`` (q, 3) m each pool candidate resolves (``pixel_demand`` (q, 2): each
    point's test object height m and the pixels its image must span)."""
    return resolved_by(vehicle.caster(settings.coverage.backend), candidates.model(pool), candidates.positions[pool],
                       candidates.rotations[pool], points, pixel_demand, settings.coverage.max_range)


def with_points(prepared: Prepared, vehicle: Vehicle, points: np.ndarray, pixel_demand: np.ndarray,
                settings: DesignSettings) -> Prepared:
    """``prepared`` with the requirement ``points`` (k, 3) m appended (their coverage by the pool computed, at
    ``pixel_demand`` (k, 2))."""
    more = _pool_sees(vehicle, prepared.candidates, prepared.pool, points, pixel_demand, settings)
    return replace(prepared, points=np.concatenate([prepared.points, points]),
                   sees_pool=np.concatenate([prepared.sees_pool, more], axis=1))


def mount_candidates(vehicle: Vehicle, settings: DesignSettings, spacing: float | None = None) -> CandidateSet:
    """Every valid (mount point, orientation, lens) of ``vehicle`` on the settings' grid; ``spacing`` (m)
    defaults to the settings' or one sized from the vehicle."""
    spacing = spacing or settings.spacing or default_spacing(vehicle, settings)
    yaws = np.arange(-180.0, 180.0, settings.yaw_step_deg)
    return build_candidates(vehicle, settings.lenses, spacing, yaws, settings.pitches_deg, settings.zones,
                            settings.rules, settings.max_body_fraction, settings.is_symmetric_on(vehicle))


def select_valid(prepared: Prepared, vehicle: Vehicle, calibration: Calibration, requirements: Requirements,
                 counts: tuple[int, int], settings: DesignSettings, progress: Callable[[str], None] = no_progress
                 ) -> MilpStage:
    """The best selection meeting ``requirements`` (its points are ``prepared.points``) whose cameras all pass
    the mount checks.

    Raises DesignInfeasible with the uncoverable points, or when repairs run out.
    """
    needed = requirements.needed
    seen = np.minimum(prepared.sees_pool.sum(axis=0), needed.max(initial=1))
    if np.any(seen < needed):
        raise DesignInfeasible(explain_uncoverable(requirements, seen))
    pool, candidates = prepared.pool, prepared.candidates
    field = slice(requirements.n_sector, None)
    kept = [prune(c[pool], prepared.sees_pool, needed, settings.keep_per_reference, settings.keep_per_sector)
            for c in prepared.costs]
    kept.append(_best_coverers(prepared.sees_pool[:, field], needed[field], settings.keep_coverers))
    offered = candidates.mirror_closed(pool[reduce(np.union1d, kept)])
    sees = prepared.sees_pool[np.searchsorted(pool, offered)]
    excluded: set[int] = set()
    for repairs in range(MAX_REPAIRS + 1):
        keep = np.array([k for k, c in enumerate(offered) if c not in excluded], dtype=int)
        best = _best_selection([c[offered[keep]] for c in prepared.costs], sees[keep], needed,
                               candidates.mount[offered[keep]], candidates.mount_points, counts,
                               milp_alpha(calibration, settings),
                               settings, progress, local_mirror(candidates, offered[keep]),
                               prepared.mount_cost[offered[keep]])
        chosen = offered[keep][best.chosen]
        paired = best.matched >= 0
        if np.any(prepared.costs[0][chosen[paired], best.matched[paired]] >= OUT_OF_TOLERANCE_COST):
            raise DesignInfeasible(f"no selection keeps every perception camera within {tolerance_text(settings)} "
                                   "of its matched reference camera and meets the requirements; widen the tolerance "
                                   "(--match-height, --match-pitch, --match-yaw, --match-fov), add pitches (--pitch) "
                                   "or allow more zones")
        rig = _rig_from(candidates.subset(chosen), best.matched, prepared.references[0], vehicle)
        check = check_unassembled(rig, vehicle, settings.rules)
        failed = [(chosen[k], c) for k, c in enumerate(check.cameras) if not c.valid]
        if not failed:
            return MilpStage(rig, check, best, len(candidates), len(offered), repairs)
        progress(f"{len(failed)} camera(s) failed the mount checks; solving again without them")
        for index, camera_check in failed:
            # A view problem belongs to the orientation; any other to the mount point and all its candidates.
            if all("view" in problem for problem in camera_check.problems):
                excluded.add(int(index))
            else:
                excluded.update(int(c) for c in offered[candidates.mount[offered] == candidates.mount[index]])
        excluded = set(candidates.mirror_closed(sorted(excluded)).tolist())  # a pair goes as a whole
    problems = "; ".join(f"{c.id}: {', '.join(c.problems)}" for c in check.cameras if not c.valid)
    raise DesignInfeasible(f"after {MAX_REPAIRS} repairs the design still fails the mount checks ({problems})")


def design_rig(vehicle: Vehicle | str, references: ReferenceRig | Sequence[ReferenceRig] | str,
               calibration: Calibration | None = None, settings: DesignSettings | None = None,
               compare_with: Sequence[Rig] = (), progress: Callable[[str], None] = no_progress,
               background: Background = INLINE) -> DesignResult:
    """Design a rig on ``vehicle`` (a Vehicle or its name) for a detector trained on the reference (one rig, or a
    fleet of rigs, each on its own vehicle; a library rig's name or a rig file is placed on its own vehicle; see
    the module docstring), judged beside the naive transfer and ``compare_with`` (e.g.
    ``problem.benchmark_rigs(vehicle)``), under ``calibration`` (None: the joint weights) and ``settings`` (None:
    ``DesignSettings.preset()``, what ``rigopt design`` does by default). With a ``background`` worker the near-field stage (which needs
    nothing of the perception cameras until they share housings) runs there while the perception cameras are
    designed and refined here, and the naive transfer refined: the same design.

    The stages, each a function of the records before it: the fields' plan (who sees the regulation fields) ->
    requirements -> selection (the MILP, down the fallback ladder) -> validation (pose tolerance, coverage) ->
    refinement (casadi + IPOPT) -> height search -> the naive transfer -> near field -> result."""
    start = time.perf_counter()
    vehicle, references, calibration = by_name(vehicle, references, calibration)
    settings = DesignSettings.preset() if settings is None else settings
    references = checked_references(references)
    rigs = [r.rig for r in references]
    progress(f"coverage requirements from {', '.join(r.name for r in rigs)} and the required fields")
    fields = plan_fields(vehicle, settings, background)
    requirements = design_requirements(references, vehicle, fields.perception)
    selected = select_stage(vehicle, rigs, calibration, fields.perception, requirements, progress)
    refines = (selected.settings.refine and len(rigs) == 1 and calibration.lifting is None
               and selected.settings.drop_model is None)
    perception = validate_stage(selected, vehicle, rigs, calibration, progress)
    perception = refine_stage(perception, selected, vehicle, rigs, calibration, refines, progress)
    perception = height_stage(perception, selected, vehicle, rigs, calibration, progress)
    naive, naive_refinement = naive_stage(selected, vehicle, rigs[0], calibration, refines, progress)
    near = near_field_result(perception.design, selected, fields, vehicle, rigs, calibration, progress)
    regions = field_coverage(near.design.rig, vehicle, near.presets or required_fields(near.requirements, near.settings)
                             or required_presets(vehicle, near.settings, "default"), near.settings)
    reference_coverage = rig_coverage_matrix(rigs[0], references[0].vehicle,
                                             near.settings.coverage).sees.any(axis=0).mean()
    comparisons = Comparisons(
        summarise(naive, vehicle, rigs, calibration, near.requirements, near.settings) if naive else None,
        tuple(summarise(rig, vehicle, rigs, calibration, near.requirements, near.settings) for rig in compare_with),
        naive_refinement)
    widened = tuple((rigs[0].cameras[k].id, float(perception.widen[k])) for k in np.flatnonzero(perception.widen > 1.0))
    stand_ins = tuple((camera.id, rigs[0].cameras[r].id)
                      for camera, r in zip(perception.design.rig.cameras, perception.matched))
    return DesignResult(near.design, selected.milp, perception.refinement, comparisons, float(reference_coverage),
                        vehicle, references, calibration, near.settings, time.perf_counter() - start,
                        selected.symmetry_fallback, regions, near.fields_fallback, near.stage, widened,
                        near.settings.near_field and selected.near_field_mirrored, perception.height_moves,
                        stand_ins=stand_ins)


def by_name(vehicle, references, calibration):
    """(Vehicle, references, Calibration) from what a caller may give by name: a vehicle's name, one reference
    rig's name or file (placed on its own vehicle), no calibration (the joint weights)."""
    vehicle = load_vehicle(vehicle) if isinstance(vehicle, str) else vehicle
    if isinstance(references, str):
        references = ReferenceRig.on_own_vehicle(load_rig(references))
    return vehicle, references, load_weights("joint") if calibration is None else calibration


def checked_references(references: ReferenceRig | Sequence[ReferenceRig]) -> tuple[ReferenceRig, ...]:
    """The reference rigs as a tuple; none, or one measured from another origin than its vehicle's centre, is an
    error."""
    references = (references,) if isinstance(references, ReferenceRig) else tuple(references)
    if not references:
        raise RigoptError("a design needs at least one reference rig")
    off_centre = [r.rig.name for r in references if not r.rig.origin.is_benchmark]
    if off_centre:
        raise RigoptError(f"reference rig(s) {', '.join(off_centre)} measure positions from another origin than the "
                          "vehicle centre the design uses; build them with ReferenceRig.on_own_vehicle (or "
                          "rigopt.vehicle.placement.place_rig), which converts them")
    return references


@dataclass(frozen=True)
class FieldPlan:
    """Who sees the regulation fields. ``presets``: the near-field stage's fields (a two-role design; () else);
    ``user_require``: the user's ``require``; ``perception``: the settings the perception cameras are designed
    under (no fields asked of them in a two-role design); ``job``: the near-field choice computed ahead in a
    background worker, or None."""

    presets: tuple
    user_require: str | None
    perception: DesignSettings
    job: object | None


def plan_fields(vehicle: Vehicle, settings: DesignSettings, background: Background) -> FieldPlan:
    """The fields' plan: in a two-role design the fields are the near-field cameras' job, started in the
    ``background`` worker when there is one (for the symmetry the first rung asks for: checked when taken)."""
    if not settings.near_field:
        return FieldPlan((), settings.require, settings, None)
    presets = required_presets(vehicle, settings) if settings.require != "none" else ()
    perception = replace(settings, require="none")
    job = (background.submit(near_field_stage_choice, vehicle, presets, perception, settings.require)
           if background.parallel else None)
    return FieldPlan(presets, settings.require, perception, job)


@dataclass(frozen=True)
class Rung:
    """One rung of the fallback ladder: the perception cameras in mirrored pairs or not, the category's fields
    required of them or not."""

    symmetric: bool
    with_fields: bool


def fallback_ladder(vehicle: Vehicle, settings: DesignSettings, requirements: Requirements) -> tuple[Rung, ...]:
    """What the design must have, and what it gives up, in this order, when nothing meets it: mirrored pairs
    (unless asked for or refused), then the category's fields (unless named)."""
    first = Rung(settings.perception_mirrored_on(vehicle), True)
    rungs = [first] + [Rung(False, True)] * auto_symmetry(vehicle, settings)
    if auto_fields(settings, requirements):
        rungs += [Rung(r.symmetric, False) for r in rungs]
    return tuple(rungs)


def auto_symmetry(vehicle: Vehicle, settings: DesignSettings) -> bool:
    """Whether mirrored pairs are the vehicle's default rather than asked for (so they may be given up)."""
    return settings.symmetric is None and settings.perception_mirrored_on(vehicle)


def auto_fields(settings: DesignSettings, requirements: Requirements) -> bool:
    """Whether the fields required are the category's rather than named (so they may be given up)."""
    return settings.require is None and bool(requirements.presets)


@dataclass(frozen=True)
class Selected:
    """The selection stage: the first rung of the ladder with a valid MILP selection. ``settings`` and
    ``requirements`` are that rung's (its symmetry and fields, the dense check's field points added);
    ``near_field_mirrored``: whether the near-field cameras come in mirrored pairs."""

    prepared: Prepared
    requirements: Requirements
    milp: MilpStage
    settings: DesignSettings
    symmetry_fallback: str | None
    fields_fallback: str | None
    near_field_mirrored: bool


def select_stage(vehicle: Vehicle, rigs: Sequence[Rig], calibration: Calibration, settings: DesignSettings,
                 requirements: Requirements, progress: Callable[[str], None]) -> Selected:
    """Down the fallback ladder until a rung has a valid selection (the last rung's failure is raised)."""
    rungs, prepared_for, reasons = fallback_ladder(vehicle, settings, requirements), {}, []
    for k, rung in enumerate(rungs):
        tried = replace(settings, symmetric=rung.symmetric, require=settings.require if rung.with_fields else "none")
        needs = requirements if rung.with_fields else requirements.sector_only()
        counts = settings.cameras or default_counts(len(rigs[0]), rung.with_fields and bool(requirements.presets))
        try:
            if rung.symmetric not in prepared_for:
                prepared_for[rung.symmetric] = prepare(vehicle, rigs, calibration, tried, requirements, progress)
            prepared, needs, milp = _select_seeing_fields(prepared_for[rung.symmetric], vehicle, calibration, needs,
                                                          counts, tried, progress)
            break
        except DesignInfeasible as error:
            if k == len(rungs) - 1:
                raise
            reasons.append(str(error))
            progress(f"no design with{'' if rung.symmetric else 'out'} mirrored pairs"
                     f"{' seeing the fields' if rung.with_fields else ''} ({error}); trying with less")
    symmetry_fallback = (f"no symmetric design meets the requirements ({reasons[0]}); designed without symmetry"
                         if auto_symmetry(vehicle, settings) and not rung.symmetric else None)
    fields_fallback = (f"no design sees all of the vehicle category's fields "
                       f"{', '.join(p.key for p in needs.presets)} ({reasons[-1]}); they are reported, not "
                       "required" if auto_fields(settings, requirements) and not rung.with_fields else None)
    return Selected(prepared, needs, milp, tried, symmetry_fallback, fields_fallback,
                    settings.is_symmetric_on(vehicle) and symmetry_fallback is None)


@dataclass(frozen=True)
class Perception:
    """The perception cameras after a stage. ``design``: the rig's summary; ``matched`` (m,) int: the reference
    cameras matched, in the order of the rig's first m cameras; ``widen`` (R,) float: each reference camera's
    pose tolerance widened by (1: as set; inf: matched without it, `matched_widening`); ``refinement``: the
    continuous stage's report; ``height_moves``: what the height search moved."""

    design: RigSummary
    matched: np.ndarray
    widen: np.ndarray
    refinement: RefinementReport
    height_moves: tuple = ()


def validate_stage(selected: Selected, vehicle: Vehicle, rigs: Sequence[Rig], calibration: Calibration,
                   progress: Callable[[str], None]) -> Perception:
    """The MILP's rig checked: its pose tolerance (widened where no mount keeps it, said so) and its coverage
    recomputed."""
    progress("validating the design: mount checks, coverage, RigCD")
    milp, reference, settings = selected.milp, rigs[0], selected.settings
    matched = np.sort(milp.selection.matched[milp.selection.matched >= 0])  # the rig's cameras come in this order
    gaps = tolerance_gaps(milp.rig.positions[:len(matched)], milp.rig.rotations[:len(matched)],
                          milp.rig.fovs[:len(matched)], reference, settings)
    widen = matched_widening(gaps, matched)
    for k in np.flatnonzero(widen > 1.0):
        progress(f"no mount keeps {reference.cameras[k].id} within {tolerance_text(settings)}: "
                 + (f"the nearest pose the body allows, {widen[k]:.2f}x the tolerance" if np.isfinite(widen[k])
                    else "matched without the tolerance"))
    design = summarise(milp.rig, vehicle, rigs, calibration, selected.requirements, settings, milp.check)
    if not design.meets_requirements:
        raise DesignInfeasible("the selected rig does not meet the coverage requirements when recomputed; "
                               "this should not happen: please report it")
    return Perception(design, matched, widen, RefinementReport(refinement_off(calibration, settings, len(rigs))))


def refinement_off(calibration: Calibration, settings: DesignSettings, n_references: int) -> str:
    """Why the continuous stage does not run (its objective has RigCD's terms only), or "off"."""
    if calibration.lifting is not None:
        return f"off ({calibration.metric}: the continuous stage weighs RigCD's terms only)"
    if settings.drop_model is not None:
        return "off (the MILP minimised a drop model; the continuous stage weighs RigCD's terms only)"
    return "off" if n_references == 1 else "off (fleet design)"


def refine_stage(perception: Perception, selected: Selected, vehicle: Vehicle, rigs: Sequence[Rig],
                 calibration: Calibration, refines: bool, progress: Callable[[str], None]) -> Perception:
    """The continuous refinement, its rig taken when accepted and within the (widened) pose tolerance."""
    if not refines:
        return perception
    progress("continuous refinement (casadi + IPOPT)")
    settings = selected.settings
    refinement = _refined(perception.design, vehicle, rigs[0], calibration, selected.requirements,
                          selected.prepared.spacing, settings)
    outside = (pose_violations(refinement.refined.rig, rigs[0], calibration, settings, perception.widen)
               if refinement.accepted else [])
    if outside:  # the continuous stage may slide and tilt a camera out of the tolerance: keep the MILP's rig
        refinement = replace(refinement, accepted=False,
                             status=f"rejected: moves {', '.join(outside)} out of {tolerance_text(settings)}")
    design = refinement.refined if refinement.accepted else perception.design
    return replace(perception, design=design, refinement=refinement)


def height_stage(perception: Perception, selected: Selected, vehicle: Vehicle, rigs: Sequence[Rig],
                 calibration: Calibration, progress: Callable[[str], None]) -> Perception:
    """With a height tolerance and free perception cameras of one reference: each perception camera moved to the
    mount nearest its reference camera's height (:func:`rigopt.design.heights.search_heights`), the coverage kept;
    what moved is in ``height_moves``."""
    settings, requirements = selected.settings, selected.requirements
    if not (settings.height_search_m > 0 and settings.match_height_m is not None and len(rigs) == 1
            and not settings.perception_mirrored_on(vehicle)):
        return perception
    progress("moving each perception camera to the mount nearest its reference camera's height")
    matched = perception.matched
    rig, moves = search_heights(
        perception.design.rig, matched, rigs[0], vehicle, settings.height_search_m, settings,
        lambda trial: bool(np.all(requirements.counts(trial, vehicle, settings) >= requirements.needed)))
    if not moves:
        return perception
    design = summarise(rig, vehicle, rigs, calibration, requirements, settings,
                       check_unassembled(rig, vehicle, settings.rules))
    gaps = tolerance_gaps(rig.positions[:len(matched)], rig.rotations[:len(matched)], rig.fovs[:len(matched)],
                          rigs[0], settings)
    return replace(perception, design=design, widen=matched_widening(gaps, matched), height_moves=moves)


def naive_stage(selected: Selected, vehicle: Vehicle, reference: Rig, calibration: Calibration, refines: bool,
                progress: Callable[[str], None]) -> tuple[Rig | None, str]:
    """The naive transfer (None when some camera finds no mount) and, when the design was refined, the same
    refinement of it (so that the comparison credits the design's objective, not its extra stage): (rig, the
    refinement's status)."""
    naive = naive_transfer(vehicle, reference, selected.prepared.candidates, selected.settings)
    if naive is None or not refines:
        return naive, "off"
    progress("refining the naive transfer as the design")
    return refine_comparison(naive, vehicle, reference, calibration, selected.requirements, selected.prepared.spacing,
                             selected.settings)


@dataclass(frozen=True)
class NearFieldResult:
    """The design after the near-field stage (the perception design as it was without one): its summary, the
    stage (None without), the fields its cameras see, the fallback note, and the requirements and settings the
    whole design is reported under (the near-field fields and the user's ``require``)."""

    design: RigSummary
    stage: object | None
    presets: tuple
    fields_fallback: str | None
    requirements: Requirements
    settings: DesignSettings


def near_field_result(design: RigSummary, selected: Selected, fields: FieldPlan, vehicle: Vehicle,
                      rigs: Sequence[Rig], calibration: Calibration, progress: Callable[[str], None]) -> NearFieldResult:
    """A two-role design's near-field fisheyes added to the perception cameras (:func:`_near_field_stage`)."""
    settings, requirements = selected.settings, selected.requirements
    if not settings.near_field:
        grouped = as_modules(design.rig, settings.rules.practice)  # housings closer than a module's size: one
        if grouped is not design.rig:
            design = summarise(grouped, vehicle, rigs, calibration, requirements, settings,
                               check_rig(grouped, vehicle, settings.rules))
        return NearFieldResult(design, None, fields.presets, selected.fields_fallback, requirements, settings)
    stage, presets, fallback = _near_field_stage(
        vehicle, design.rig, fields.presets, selected.prepared.spacing,
        replace(settings, symmetric=selected.near_field_mirrored), fields.user_require, progress, fields.job)
    design = summarise(stage.rig, vehicle, rigs, calibration, requirements, settings,
                       check_rig(stage.rig, vehicle, settings.rules))
    return NearFieldResult(design, stage, presets, fallback, replace(requirements, presets=presets),
                           replace(settings, require=fields.user_require if presets else "none"))


def near_field_stage_choice(vehicle: Vehicle, presets: tuple, settings: DesignSettings, user_require: str | None,
                            spacing: float | None = None) -> tuple[NearFieldChoice, tuple, str | None, bool,
                                                                   tuple[str, ...]]:
    """The near-field stage's choice (:func:`rigopt.design.near_field.choose_near_field`) for a design under
    ``settings``: (the choice, the presets its cameras see, the fallback note or None, whether it was designed
    in mirrored pairs, its progress messages). The category's fields (``user_require`` None) that no near-field
    cameras see are dropped with a note, the near ring still designed; named fields are strict. ``spacing``
    (m): the design's mount spacing (default: the settings', else sized to the vehicle); the stage's is at most
    NEAR_FIELD_SPACING. A module-level function of picklable values: it may run in a background worker."""
    messages: list[str] = []
    spacing = spacing or settings.spacing or default_spacing(vehicle, settings)
    symmetric = settings.is_symmetric_on(vehicle)

    def choice_for(required):
        return choose_near_field(vehicle, required, min(spacing, NEAR_FIELD_SPACING), symmetric, settings.rules,
                                 zones=settings.zones, max_nodes=settings.max_nodes,
                                 lifted=settings.rules.practice.lifted, progress=messages.append)

    fallback = None
    try:
        choice = choice_for(presets)
    except DesignInfeasible as error:
        if user_require is not None or not presets:
            raise
        fallback = (f"no near-field cameras see all of the vehicle category's fields "
                    f"{', '.join(p.key for p in presets)} ({error}); they are reported, not required")
        messages.append(fallback)
        choice, presets = choice_for(()), ()
    return choice, presets, fallback, symmetric, tuple(messages)


def _near_field_stage(vehicle: Vehicle, perception: Rig, presets: tuple, spacing: float, settings: DesignSettings,
                      user_require: str | None, progress, job=None) -> tuple:
    """The near-field stage of a two-role design: (NearFieldDesign, the presets its cameras see, the fallback note
    or None); see :func:`near_field_stage_choice`. ``job``: that choice computed ahead (in a background worker),
    taken when it was designed with the symmetry of ``settings``."""
    progress("near-field cameras for the fields and the near ring")
    outcome = job.result() if job is not None else None
    if outcome is None or outcome[3] != settings.is_symmetric_on(vehicle):
        outcome = near_field_stage_choice(vehicle, presets, settings, user_require, spacing)
    choice, presets, fallback, _, messages = outcome
    for message in messages:
        progress(message)
    if choice.status == "node_limit" and not settings.accept_gap:
        raise RigoptError(f"the near-field MILP stopped at its work limit of {settings.max_nodes} branch-and-bound "
                          f"nodes {choice.gap:.1%} from proven best; raise --max-nodes (e.g. --max-nodes "
                          f"{4 * settings.max_nodes}), or take the best found within it with --accept-gap")
    return with_near_field(perception, choice, settings.rules.practice), presets, fallback


#: Cameras beyond the reference's count a design with required fields may use by default (near-field cameras).
FIELD_EXTRA_CAMERAS = 4


def default_counts(n_reference: int, with_fields: bool) -> tuple[int, int]:
    """The (min, max) camera count of a design without ``--cameras``: the reference's, up to
    FIELD_EXTRA_CAMERAS more when regulation fields are required (a truck's near field needs cameras of its
    own: the count term of RigCD weighs them against the matching)."""
    return n_reference, n_reference + (FIELD_EXTRA_CAMERAS if with_fields else 0)


def required_fields(requirements: Requirements, settings: DesignSettings) -> tuple:
    """The regulation presets a design must see: the requirements' fields, none when ``settings`` says so
    (``require="none"``, also after the category's fields were dropped)."""
    return requirements.presets if settings.require != "none" else ()


def field_coverage(rig: Rig, vehicle: Vehicle, presets, settings: DesignSettings):
    """The dense coverage (every DENSE_SPACING m) of the required fields ``presets`` by ``rig``."""
    return region_coverage(rig, vehicle, presets, DENSE_SPACING, settings.coverage.backend,
                           settings.coverage.max_range, settings.rules.practice.lifted)


def _spread(points: np.ndarray, most: int) -> np.ndarray:
    """At most ``most`` of ``points`` (k, 3), evenly through their order."""
    if len(points) <= most:
        return points
    return points[np.linspace(0, len(points) - 1, most).round().astype(int)]


def refine_comparison(rig: Rig, vehicle: Vehicle, reference: Rig, calibration: Calibration,
                      requirements: Requirements, spacing: float, settings: DesignSettings) -> tuple[Rig, str]:
    """``rig`` (the naive transfer) through the design's continuous stage, so that a comparison credits the
    design's objective and not its extra refinement: the same moves, matching and acceptance, keeping the
    sector points ``rig`` already sees (none added, no pairing, no fields). Returns (the refined rig
    when accepted, else ``rig``; the refinement's status line)."""
    counts = requirements.counts(rig, vehicle, settings)
    sectors = requirements.sector_only()
    own = replace(sectors, needed=np.minimum(sectors.needed, counts), presets=())
    free = replace(settings, symmetric=False, require="none")
    summary = summarise(rig, vehicle, [reference], calibration, own, free, check_unassembled(rig, vehicle, free.rules))
    report = _refined(summary, vehicle, reference, calibration, own, spacing, free)
    return (report.refined.rig if report.accepted else rig), report.status


def _best_coverers(sees: np.ndarray, needed: np.ndarray, count: int) -> np.ndarray:
    """(k,) int: the ``count`` pool candidates (rows of ``sees`` (p, q), the field points) that see the most
    required points, so that wide requirements (a regulation field's hundreds of points) are offered cameras
    that cover much of them at once, not only each point's cheapest in RigCD."""
    seen = sees[:, needed > 0].sum(axis=1)
    return np.flatnonzero(seen > 0)[np.argsort(-seen[seen > 0], kind="stable")[:count]]


def _select_seeing_fields(prepared: Prepared, vehicle: Vehicle, calibration: Calibration, requirements: Requirements,
                          counts: tuple[int, int], settings: DesignSettings, progress: Callable[[str], None]):
    """The valid MILP selection meeting ``requirements``, its required fields checked densely: unseen field
    points become requirements and the MILP is solved again (MAX_FIELD_ROUNDS). Returns (Prepared,
    Requirements, MilpStage), both extended by the points added."""
    milp = select_valid(prepared, vehicle, calibration, requirements, counts, settings, progress)
    presets = required_fields(requirements, settings)
    for round in range(MAX_FIELD_ROUNDS + 1):
        regions = field_coverage(milp.rig, vehicle, presets, settings)
        unseen = [(r.key, _spread(r.unseen, MAX_NEW_FIELD_POINTS), p)
                  for r, p in zip(regions, presets) if len(r.unseen)]
        if not unseen:
            break
        if round == MAX_FIELD_ROUNDS:
            raise DesignInfeasible(f"after {MAX_FIELD_ROUNDS} rounds the design still misses field points in the "
                                   f"dense check ({', '.join(f'{k}: {len(u)}' for k, u, _ in unseen)}); allow more "
                                   "cameras (--cameras), zones or pitch angles, or fewer fields (--require)")
        points = np.concatenate([u for _, u, _ in unseen])
        demands = np.concatenate([preset.pixel_demands(len(u)) for _, u, preset in unseen])
        progress(f"{len(points)} field points unseen in the dense check; solving again with them required")
        requirements = requirements.extended(points, [label for key, u, _ in unseen for label in field_labels(key, u)],
                                             demands)
        prepared = with_points(prepared, vehicle, points, demands, settings)
        milp = select_valid(prepared, vehicle, calibration, requirements, counts, settings, progress)
    return prepared, requirements, milp


def _refined(design: RigSummary, vehicle: Vehicle, reference: Rig, calibration: Calibration,
             requirements: Requirements, spacing: float, settings: DesignSettings) -> RefinementReport:
    """Refine the MILP ``design``; the refined rig is accepted when it validates, meets the requirements and
    lowers the calibrated RigCD, and the report says why not otherwise."""
    rig = design.rig
    points, sees = requirements.points, requirements.counts_matrix(rig, vehicle, settings)
    mirror = camera_mirrors(rig.positions, rig.rotations, rig.fovs) if settings.is_symmetric_on(vehicle) else None
    normals = vehicle.surface(rig.positions).normal
    radii = free_radii(rig, normals, vehicle, spacing, settings.rules)
    if mirror is not None:  # a pair slides as far as both of its cameras may
        radii = np.minimum(radii, radii[np.where(mirror >= 0, mirror, np.arange(len(rig)))])
    problem = RefineProblem(
        rig, reference, calibrated_matching(rig, reference, calibration), normals,
        duty_points(sees, requirements.needed, frustum_margins(rig, points), points), points, calibration.alpha, calibration.lambdas,
        (float(np.deg2rad(min(settings.pitches_deg))), float(np.deg2rad(max(settings.pitches_deg)))),
        settings.fov_range, radii, mirror)
    outcome = refine(problem)
    if outcome.rig is None:
        return RefinementReport(f"rejected: IPOPT {outcome.status}", solver_status=outcome.status)
    refined_rig = project_to_surface(Rig(rig.name, rig.vehicle, outcome.rig.cameras), vehicle, settings.rules)
    check = check_unassembled(refined_rig, vehicle, settings.rules)
    moved = len(rig)
    if not check.valid:  # keep the MILP pose of the cameras whose refined pose fails (with their mirrors), once
        keep = np.array([not c.valid for c in check.cameras])
        if mirror is not None:
            keep |= np.array([m >= 0 and keep[m] for m in mirror])
        cameras = tuple(old if k else new for new, old, k in zip(refined_rig.cameras, rig.cameras, keep))
        moved = int((~keep).sum())
        refined_rig = Rig(rig.name, rig.vehicle, cameras)
        check = check_unassembled(refined_rig, vehicle, settings.rules)
    if not check.valid or moved == 0:
        return RefinementReport(f"rejected: IPOPT {outcome.status}, refined cameras fail the mount checks",
                                solver_status=outcome.status)
    refined = summarise(refined_rig, vehicle, [reference], calibration, requirements, settings, check)
    if not refined.meets_requirements:
        return RefinementReport(f"rejected: IPOPT {outcome.status}, refined rig loses required coverage",
                                solver_status=outcome.status, cameras_moved=moved, refined=refined)
    lost = [r.key for r in field_coverage(refined_rig, vehicle, required_fields(requirements, settings), settings)
            if not r.covered]
    if lost:
        return RefinementReport(f"rejected: IPOPT {outcome.status}, refined rig loses part of the field(s) "
                                f"{', '.join(lost)}", solver_status=outcome.status, cameras_moved=moved, refined=refined)
    if refined.prediction.rigcd >= design.prediction.rigcd:
        return RefinementReport(f"rejected: IPOPT {outcome.status}, no improvement", solver_status=outcome.status,
                                cameras_moved=moved, refined=refined)
    return RefinementReport(f"accepted: IPOPT {outcome.status}, {moved} of {len(rig)} cameras moved, RigCD "
                            f"{design.prediction.rigcd:.4f} -> {refined.prediction.rigcd:.4f}", accepted=True,
                            solver_status=outcome.status, cameras_moved=moved, refined=refined)


def local_mirror(candidates: CandidateSet, index: np.ndarray) -> np.ndarray | None:
    """(k,) int: the mirror of each of the candidates ``index`` (k,) (sorted, mirror-closed) as a position in
    ``index``; None for a set without mirrors."""
    if candidates.mirror is None:
        return None
    return np.searchsorted(index, candidates.mirror[index])


def _best_selection(costs, sees, needed, mount, mount_points, counts, alpha, settings, progress,
                    mirror=None, mount_cost=None) -> Selection:
    """The best selection over the camera ``counts`` (low, high): one MILP for a range at or above every
    reference's count (the count a variable), else one per count."""
    clashes = cKDTree(mount_points).query_pairs(CLASH_DISTANCE, output_type="ndarray")
    n_ref = max(c.shape[1] for c in costs)
    ranges = [counts] if counts[0] >= n_ref and counts[0] < counts[1] else [(n, n) for n in range(counts[0],
                                                                                                   counts[1] + 1)]
    best = None
    for low, high in ranges:
        progress(f"MILP: {low if low == high else f'{low}-{high}'} cameras from {len(costs[0])} candidates")
        try:
            selection = select_cameras(costs, sees, needed, mount, (low, high), alpha, clashes, settings.max_nodes,
                                       settings.mip_gap, mirror, mount_cost, settings.cost_weight)
        except DesignInfeasible:
            if high == counts[1] and best is None:
                raise
            continue
        if selection.status == "node_limit" and not settings.accept_gap:
            raise RigoptError(f"the selection MILP ({low if low == high else f'{low}-{high}'} cameras) stopped at its "
                              f"work limit of {settings.max_nodes} branch-and-bound nodes {selection.gap:.1%} from "
                              "proven best; raise --max-nodes (e.g. "
                              f"--max-nodes {4 * settings.max_nodes}), or take the best selection found within it with "
                              "--accept-gap (reported with its gap)")
        if best is None or selection.objective + selection.cost_term < best.objective + best.cost_term:
            best = selection
    return best


def _rig_from(chosen: CandidateSet, matched: np.ndarray, reference: Rig, vehicle: Vehicle) -> Rig:
    """A rig of the chosen candidates, in the order of the reference cameras they match; each named after
    where it is mounted and where it looks (:mod:`rigopt.design.naming`)."""
    cameras = [chosen.camera(k, f"CAM_{k}") for k in range(len(chosen))]
    order = np.argsort([m if m >= 0 else len(reference) + k for k, m in enumerate(matched)])
    cameras = [cameras[k] for k in order]
    names = unique([mount_name(c.zone, c.position, c.forward) for c in cameras])
    return Rig(f"design_{vehicle.name}_from_{reference.name}", vehicle.blueprint,
               tuple(replace(c, id=name) for c, name in zip(cameras, names)))


def summarise(rig: Rig, vehicle: Vehicle, references: Sequence[Rig], calibration: Calibration,
              requirements: Requirements, settings: DesignSettings, check: RigCheck | None = None) -> RigSummary:
    """Predicted transfer from each reference (of the rig's perception cameras, the ones a detector is fed),
    coverage fraction (of the sector points, by every camera) and requirement check of ``rig``."""
    counts = requirements.counts(rig, vehicle, settings)
    predictions = tuple(predict_transfer(reference, [rig.perception()], calibration)[0] for reference in references)
    return RigSummary(rig, predictions, float(np.mean(counts[:requirements.n_sector] >= 1)),
                      bool(np.all(counts >= requirements.needed)), check)


def calibrated_matching(rig: Rig, reference: Rig, calibration: Calibration) -> np.ndarray:
    """(k,) int: the reference camera each camera of ``rig`` is matched to by the calibrated RigCD's optimal
    assignment (-1 for cameras beyond the reference's count)."""
    rows, cols = linear_sum_assignment(rig_costs(rig, reference, calibration))
    matched = np.full(len(rig), -1, dtype=int)
    matched[rows] = cols
    return matched


def pose_violations(rig: Rig, reference: Rig, calibration: Calibration, settings: DesignSettings,
                    widen: np.ndarray | None = None) -> list[str]:
    """The ids of ``rig``'s perception cameras that no matching to the reference (the calibrated cost's
    cheapest among those within the tolerance, as the MILP's) keeps within the pose tolerance (widened per reference
    camera by ``widen`` (R,), `matched_widening`)."""
    perception = rig.perception()
    if not settings.tolerances:
        return []
    costs = rig_costs(perception, reference, calibration, settings, widen)
    rows, cols = linear_sum_assignment(costs)
    return [perception.cameras[k].id for k, m in zip(rows, cols) if costs[k, m] >= OUT_OF_TOLERANCE_COST]


def calibrated_costs(positions: np.ndarray, rotations: np.ndarray, fovs: np.ndarray, reference: Rig,
                     calibration: Calibration, settings: DesignSettings | None = None,
                     model: CameraModel | None = None, widen: np.ndarray | None = None,
                     drop_model: DropModel | None = None) -> np.ndarray:
    """(n, R) float: the calibrated raw-unit cost of matching each camera (positions (n, 3) m, vehicle frame;
    rotations (n, 3, 3); fovs (n,) deg; lenses ``model`` of batch (n,), needed by a lifting metric's depth
    prior and a drop model) to each reference camera, or ``drop_model``'s pair cost when one is given;
    OUT_OF_TOLERANCE_COST for the pairs outside ``settings``' pose tolerance (None: no tolerance), widened per
    reference camera by ``widen`` (R,) (see `matched_widening`)."""
    if drop_model is not None:
        costs = drop_model.pair_costs(positions, rotations, model, reference)
        return tolerated(costs, positions, rotations, fovs, reference, settings, widen)
    lt, lr, lf = calibration.lambdas
    t, r, f = camera_costs(positions, rotations, fovs, reference.positions, reference.rotations, reference.fovs)
    costs = lt * t + lr * r + lf * f
    if calibration.lifting is not None:
        if model is None:
            raise ValueError(f"calibrated_costs under {calibration.metric} needs the cameras' lenses (model)")
        costs = costs + pair_terms(positions, rotations, model, reference) @ np.asarray(calibration.lifting)
    return tolerated(costs, positions, rotations, fovs, reference, settings, widen)


def rig_costs(rig: Rig, reference: Rig, calibration: Calibration, settings: DesignSettings | None = None,
              widen: np.ndarray | None = None) -> np.ndarray:
    """(len(rig), R) float: :func:`calibrated_costs` of ``rig``'s cameras to the reference's."""
    return calibrated_costs(rig.positions, rig.rotations, rig.fovs, reference, calibration, settings,
                            CameraModel.of_cameras(rig.cameras), widen,
                            drop_model=settings.drop_model if settings is not None else None)


def milp_alpha(calibration: Calibration, settings: DesignSettings) -> float:
    """The MILP's weight of the mean matched cost against the count term: the calibration's alpha, or under a
    drop model 1 / (1 + its count weight), so that the MILP's objective is the model's score over 1 + that weight
    (the same minimiser)."""
    if settings.drop_model is None:
        return calibration.alpha
    return 1.0 / (1.0 + float(settings.drop_model.weights[DROP_MODEL_FEATURES.index("count")]))


#: Heights (m) closer than this count as the same for the height-matched transfer.
HEIGHT_STEP = 0.05


def naive_transfer(vehicle: Vehicle, reference: Rig, candidates: CandidateSet, settings: DesignSettings,
                   match: str = "position") -> Rig | None:
    """Each reference camera moved to the nearest mount point where it can face the same way (its yaw and
    pitch on the grid, nearest catalogue lens; where no mount allows its yaw, e.g. straight back past a
    trailer, the nearest yaw some mount allows), one camera per mount point; None if some camera finds none.

    ``match`` "position": nearest in 3D (the naive transfer); "height": the mount closest to the camera's
    height (in steps of HEIGHT_STEP m), then nearest in plan (the height-matched transfer, which keeps
    what RigCD's translation term weighs most on a taller vehicle and nothing else).
    """
    cameras = []
    used: set[int] = set()
    fovs = np.unique(candidates.fovs)
    for camera in reference.cameras:
        yaw = np.arctan2(camera.forward[1], camera.forward[0])
        pitch = np.arcsin(np.clip(camera.forward[2], -1.0, 1.0))
        fov = fovs[np.argmin(np.abs(fovs - camera.fov))]
        yaw_gap = np.where(candidates.fovs == fov, np.abs(np.angle(np.exp(1j * (candidates.yaws - yaw)))), np.inf)
        yaw_gap = np.maximum(yaw_gap, np.deg2rad(settings.yaw_step_deg) / 2)  # the grid's nearest yaws are all "same"
        same_way = yaw_gap <= yaw_gap.min(initial=np.inf) + 1e-9
        pitch_gap = np.abs(candidates.pitches - pitch)
        same_way &= pitch_gap <= pitch_gap[same_way].min(initial=np.inf) + 1e-9
        options = np.flatnonzero(same_way & ~np.isin(candidates.mount, list(used)))
        if len(options) == 0:
            return None
        offsets = candidates.positions[options] - camera.position
        if match == "height":
            best = options[np.lexsort((np.linalg.norm(offsets[:, :2], axis=1), np.round(np.abs(offsets[:, 2]) / HEIGHT_STEP)))[0]]
        else:
            best = options[np.argmin(np.linalg.norm(offsets, axis=1))]
        used.add(int(candidates.mount[best]))
        cameras.append(candidates.camera(best, camera.id))
    prefix = "naive" if match == "position" else "height_matched"
    return Rig(f"{prefix}_{vehicle.name}_from_{reference.name}", vehicle.blueprint, tuple(cameras))
