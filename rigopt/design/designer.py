"""The design pipeline: candidates -> coverage requirements -> MILP selection -> validated rig.

``design_rig`` proposes a rig on ``vehicle`` that minimises the calibrated RigCD to the reference rig
(the objective of :mod:`rigopt.design.selection`) while every ring sector the reference sees on its own
vehicle stays seen (plus optional stricter requirements), and every camera passes the mount checks.
With several reference rigs (a fleet) it minimises the largest RigCD over them and meets the union of
their coverage requirements; the continuous refinement then stays off.
A selected camera that fails the python-fcl checks is removed from the candidates and the MILP solved
again, so a returned design is always valid.

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

from rigopt.design.naming import mount_name, unique
from rigopt.mounting.practice import in_keep_outs, mounting_costs
from rigopt.mounting.rules import RigCheck, check_rig
from rigopt.coverage.footprint import Footprint
from rigopt.coverage.matrix import rig_coverage_matrix, sector_points
from rigopt.coverage.visibility import visible_by
from rigopt.design.candidates import CandidateSet, build_candidates
from rigopt.design.problem import ReferenceRig
from rigopt.design.refine import (RefineProblem, duty_points, free_radii, frustum_margins, project_to_surface,
                                  refine)
from rigopt.design.result import Comparisons, DesignResult, MilpStage, RefinementReport, RigSummary
from rigopt.design.selection import DesignInfeasible, Selection, prune, select_cameras
from rigopt.design.settings import DesignSettings
from rigopt.errors import RigoptError
from rigopt.metrics.calibration import Calibration
from rigopt.metrics.ranking import predict_transfer
from rigopt.metrics.rigcd import camera_costs
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.symmetry import camera_mirrors

#: Mount points closer than this (m) may not both hold a camera (8 cm housings plus a margin).
CLASH_DISTANCE = 0.10
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


def requirements(reference: Rig, reference_vehicle: Vehicle, settings: DesignSettings) -> np.ndarray:
    """(q,) int cameras needed at each sector point: where the reference (on its own vehicle) sees a point,
    one; where it sees it twice, ``min_overlap``; everywhere at least ``min_coverage``."""
    counts = rig_coverage_matrix(reference, reference_vehicle, settings.coverage).sees.sum(axis=0)
    needed = np.minimum(counts, 1)
    if settings.min_overlap:
        needed = np.where(counts >= 2, np.maximum(needed, settings.min_overlap), needed)
    return np.maximum(needed, settings.min_coverage).astype(int)


def _coverage_pool(candidates: CandidateSet, references: list[Rig], settings: DesignSettings) -> np.ndarray:
    """Candidates offered for coverage: on a coarse subset of mount points (about ``coverage_mounts``, and
    the centreline's in a symmetric design), every clear orientation with the reference's lenses and the
    widest lens; with their mirror images in a symmetric design."""
    points = candidates.mount_points
    step = max(1, len(points) // settings.coverage_mounts)
    order = np.lexsort((points[:, 1], points[:, 0]))
    chosen_mounts = set(order[::step].tolist())
    lenses = {float(f) for rig in references for f in np.round(rig.fovs, 6)} | {float(candidates.fovs.max())}
    mounts = np.isin(candidates.mount, list(chosen_mounts))
    if candidates.mirror is not None:  # every centreline camera too: the few that face straight ahead or back
        mounts |= candidates.mirror == np.arange(len(candidates))
    mask = mounts & np.isin(np.round(candidates.fovs, 6), list(lenses))
    return candidates.mirror_closed(np.flatnonzero(mask))


def _explain_uncoverable(needed: np.ndarray, seen: np.ndarray, distance, height, azimuth) -> str:
    bad = np.flatnonzero(seen < needed)
    lines = []
    for q in bad[:8]:
        lines.append(f"ring {distance[q]:g} m at height {height[q]:g} m, azimuth {np.rad2deg(azimuth[q]):+.0f} deg "
                     f"(needs {needed[q]} camera(s), at most {seen[q]} candidate(s) see it)")
    more = f" and {len(bad) - 8} more" if len(bad) > 8 else ""
    return ("no valid camera position covers " + "; ".join(lines) + more +
            ". To make it feasible: allow more zones, more pitch angles (e.g. --pitch -30,-20,-10,0,10), "
            "wider lenses, or lower --min-coverage / --min-overlap")


@dataclass(frozen=True)
class Prepared:
    """What every MILP of one design problem shares: the candidates, their matching costs to each
    reference (n, R_k), the sector points (q, 3) with their rings, the coverage pool (p,) int and what it
    sees (p, q), the mount spacing (m) and each candidate's relative mounting cost (n,)."""

    references: tuple[Rig, ...]
    candidates: CandidateSet
    costs: tuple[np.ndarray, ...]
    points: np.ndarray
    distance: np.ndarray
    height: np.ndarray
    azimuth: np.ndarray
    pool: np.ndarray
    sees_pool: np.ndarray
    spacing: float
    mount_cost: np.ndarray


def prepare(vehicle: Vehicle, references: Sequence[Rig], calibration: Calibration, settings: DesignSettings,
            progress: Callable[[str], None] = no_progress) -> Prepared:
    """Candidates, costs and the coverage of the candidates worth considering."""
    spacing = settings.spacing or default_spacing(vehicle, settings)
    progress(f"sampling mount candidates on {vehicle.name} (spacing {spacing:.2f} m)")
    candidates = mount_candidates(vehicle, settings, spacing)
    costs = tuple(matching_costs(candidates, rig, calibration) for rig in references)
    points, distance, height, _, azimuth = sector_points(Footprint.of_mesh(vehicle.mesh), settings.coverage)
    no_sees, no_needs = np.zeros((len(candidates), 0), bool), np.zeros(0, int)
    pool = reduce(np.union1d, [prune(c, no_sees, no_needs, settings.keep_per_reference, 0) for c in costs],
                  _coverage_pool(candidates, list(references), settings))
    pool = candidates.mirror_closed(pool)
    progress(f"coverage of {len(pool)} of {len(candidates)} candidates")
    sees_pool = visible_by(vehicle.mesh, candidates.model(pool), candidates.positions[pool],
                           candidates.rotations[pool], points, settings.coverage.max_range, settings.coverage.backend)
    per_mount = mounting_costs(vehicle, candidates.mount_zones, candidates.mount_points)
    return Prepared(tuple(references), candidates, costs, points, distance, height, azimuth, pool, sees_pool, spacing,
                    per_mount[candidates.mount])


def mount_candidates(vehicle: Vehicle, settings: DesignSettings, spacing: float | None = None) -> CandidateSet:
    """Every valid (mount point, orientation, lens) of ``vehicle`` on the settings' grid; ``spacing`` (m)
    defaults to the settings' or one sized from the vehicle."""
    spacing = spacing or settings.spacing or default_spacing(vehicle, settings)
    yaws = np.arange(-180.0, 180.0, settings.yaw_step_deg)
    return build_candidates(vehicle, settings.lenses, spacing, yaws, settings.pitches_deg, settings.zones,
                            settings.rules, settings.max_body_fraction, settings.is_symmetric_on(vehicle))


def fleet_requirements(references: Sequence[ReferenceRig], settings: DesignSettings,
                       target: Vehicle | None = None, points: np.ndarray | None = None) -> np.ndarray:
    """(q,) int: the largest requirement of any reference (on its own vehicle) at each sector point; with the
    ``target`` vehicle and its sector ``points`` (q, 3) m (``Prepared.points``), none at points inside its
    keep-outs in force (a coupled trailer fills the space behind a tractor: there is nothing there to see)."""
    needed = np.max([requirements(r.rig, r.vehicle, settings) for r in references], axis=0)
    if target is not None and settings.rules.practice.enabled:
        inside = np.array([bool(b) for b in in_keep_outs(target, points, settings.rules.practice.lifted)])
        needed = np.where(inside, 0, needed)
    return needed


def select_valid(prepared: Prepared, vehicle: Vehicle, calibration: Calibration, needed: np.ndarray,
                 counts: tuple[int, int], settings: DesignSettings, progress: Callable[[str], None] = no_progress
                 ) -> MilpStage:
    """The best selection meeting ``needed`` whose cameras all pass the mount checks.

    Raises DesignInfeasible with the uncoverable sectors, or when repairs run out.
    """
    seen = np.minimum(prepared.sees_pool.sum(axis=0), needed.max(initial=1))
    if np.any(seen < needed):
        raise DesignInfeasible(_explain_uncoverable(needed, seen, prepared.distance, prepared.height, prepared.azimuth))
    pool, candidates = prepared.pool, prepared.candidates
    offered = candidates.mirror_closed(pool[reduce(np.union1d, [
        prune(c[pool], prepared.sees_pool, needed, settings.keep_per_reference, settings.keep_per_sector)
        for c in prepared.costs])])
    sees = prepared.sees_pool[np.searchsorted(pool, offered)]
    excluded: set[int] = set()
    for repairs in range(MAX_REPAIRS + 1):
        keep = np.array([k for k, c in enumerate(offered) if c not in excluded], dtype=int)
        best = _best_selection([c[offered[keep]] for c in prepared.costs], sees[keep], needed,
                               candidates.mount[offered[keep]], candidates.mount_points, counts, calibration.alpha,
                               settings, progress, local_mirror(candidates, offered[keep]),
                               prepared.mount_cost[offered[keep]])
        chosen = offered[keep][best.chosen]
        rig = _rig_from(candidates.subset(chosen), best.matched, prepared.references[0], vehicle)
        check = check_rig(rig, vehicle, settings.rules)
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


def design_rig(vehicle: Vehicle, references: ReferenceRig | Sequence[ReferenceRig], calibration: Calibration,
               settings: DesignSettings = DesignSettings(), compare_with: Sequence[Rig] = (),
               progress: Callable[[str], None] = no_progress) -> DesignResult:
    """Design a rig on ``vehicle`` for a detector trained on the reference (one rig, or a fleet of rigs, each
    on its own vehicle; see the module docstring), judged beside the naive transfer and ``compare_with``
    (e.g. ``problem.benchmark_rigs(vehicle)``)."""
    start = time.perf_counter()
    references = (references,) if isinstance(references, ReferenceRig) else tuple(references)
    if not references:
        raise RigoptError("a design needs at least one reference rig")
    off_centre = [r.rig.name for r in references if not r.rig.origin.is_benchmark]
    if off_centre:
        raise RigoptError(f"reference rig(s) {', '.join(off_centre)} measure positions from another origin than the "
                          "vehicle centre the design uses; build them with ReferenceRig.on_own_vehicle (or "
                          "rigopt.vehicle.placement.place_rig), which converts them")
    rigs = [r.rig for r in references]
    reference = rigs[0]
    counts = settings.cameras or (len(reference), len(reference))
    symmetry_fallback = None
    try:
        prepared, needed, milp = _discrete_stage(vehicle, references, calibration, settings, counts, progress)
    except DesignInfeasible as error:
        if settings.symmetric is not None or not settings.is_symmetric_on(vehicle):
            raise
        symmetry_fallback = f"no symmetric design meets the requirements ({error}); designed without symmetry"
        progress(symmetry_fallback)
        settings = replace(settings, symmetric=False)
        prepared, needed, milp = _discrete_stage(vehicle, references, calibration, settings, counts, progress)

    progress("validating the design: mount checks, coverage, RigCD")
    design = summarise(milp.rig, vehicle, rigs, calibration, needed, settings, milp.check)
    refinement = RefinementReport("off" if len(rigs) == 1 else "off (fleet design)")
    if settings.refine and design.meets_requirements and len(rigs) == 1:
        progress("continuous refinement (casadi + IPOPT)")
        refinement = _refined(design, vehicle, reference, calibration, needed, prepared.points, prepared.spacing,
                              settings)
        if refinement.accepted:
            design = refinement.refined
    if not design.meets_requirements:
        raise DesignInfeasible("the selected rig does not meet the coverage requirements when recomputed; "
                               "this should not happen: please report it")
    reference_coverage = rig_coverage_matrix(reference, references[0].vehicle,
                                             settings.coverage).sees.any(axis=0).mean()
    naive = naive_transfer(vehicle, reference, prepared.candidates, settings)
    comparisons = Comparisons(
        summarise(naive, vehicle, rigs, calibration, needed, settings) if naive else None,
        tuple(summarise(rig, vehicle, rigs, calibration, needed, settings) for rig in compare_with))
    return DesignResult(design, milp, refinement, comparisons, float(reference_coverage), vehicle, references,
                        calibration, settings, time.perf_counter() - start, symmetry_fallback)


def _discrete_stage(vehicle, references, calibration, settings, counts, progress):
    """Candidates, requirements and the valid MILP selection: (Prepared, needed (q,) int, MilpStage)."""
    prepared = prepare(vehicle, [r.rig for r in references], calibration, settings, progress)
    progress(f"coverage requirements from {', '.join(r.rig.name for r in references)}")
    needed = fleet_requirements(references, settings, vehicle, prepared.points)
    return prepared, needed, select_valid(prepared, vehicle, calibration, needed, counts, settings, progress)


def _refined(design: RigSummary, vehicle: Vehicle, reference: Rig, calibration: Calibration, needed: np.ndarray,
             points: np.ndarray, spacing: float, settings: DesignSettings) -> RefinementReport:
    """Refine the MILP ``design``; the refined rig is accepted when it validates, meets the requirements and
    lowers the calibrated RigCD, and the report says why not otherwise."""
    rig = design.rig
    sees = rig_coverage_matrix(rig, vehicle, settings.coverage).sees
    mirror = camera_mirrors(rig.positions, rig.rotations, rig.fovs) if settings.is_symmetric_on(vehicle) else None
    normals = vehicle.surface(rig.positions).normal
    radii = free_radii(rig, normals, vehicle, spacing, settings.rules)
    if mirror is not None:  # a pair slides as far as both of its cameras may
        radii = np.minimum(radii, radii[np.where(mirror >= 0, mirror, np.arange(len(rig)))])
    problem = RefineProblem(
        rig, reference, calibrated_matching(rig, reference, calibration), normals,
        duty_points(sees, needed, frustum_margins(rig, points)), points, calibration.alpha, calibration.lambdas,
        (float(np.deg2rad(min(settings.pitches_deg))), float(np.deg2rad(max(settings.pitches_deg)))),
        settings.fov_range, radii, mirror)
    outcome = refine(problem)
    if outcome.rig is None:
        return RefinementReport(f"rejected: IPOPT {outcome.status}", solver_status=outcome.status)
    refined_rig = project_to_surface(Rig(rig.name, rig.vehicle, outcome.rig.cameras), vehicle, settings.rules)
    check = check_rig(refined_rig, vehicle, settings.rules)
    moved = len(rig)
    if not check.valid:  # keep the MILP pose of the cameras whose refined pose fails (with their mirrors), once
        keep = np.array([not c.valid for c in check.cameras])
        if mirror is not None:
            keep |= np.array([m >= 0 and keep[m] for m in mirror])
        cameras = tuple(old if k else new for new, old, k in zip(refined_rig.cameras, rig.cameras, keep))
        moved = int((~keep).sum())
        refined_rig = Rig(rig.name, rig.vehicle, cameras)
        check = check_rig(refined_rig, vehicle, settings.rules)
    if not check.valid or moved == 0:
        return RefinementReport(f"rejected: IPOPT {outcome.status}, refined cameras fail the mount checks",
                                solver_status=outcome.status)
    refined = summarise(refined_rig, vehicle, [reference], calibration, needed, settings, check)
    if not refined.meets_requirements:
        return RefinementReport(f"rejected: IPOPT {outcome.status}, refined rig loses required coverage",
                                solver_status=outcome.status, cameras_moved=moved, refined=refined)
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
    clashes = cKDTree(mount_points).query_pairs(CLASH_DISTANCE, output_type="ndarray")
    best = None
    for n_cameras in range(counts[0], counts[1] + 1):
        progress(f"MILP: {n_cameras} cameras from {len(costs[0])} candidates")
        try:
            selection = select_cameras(costs, sees, needed, mount, n_cameras, alpha, clashes, settings.time_limit,
                                       settings.mip_gap, mirror, mount_cost, settings.cost_weight)
        except DesignInfeasible:
            if n_cameras == counts[1] and best is None:
                raise
            continue
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


def summarise(rig: Rig, vehicle: Vehicle, references: Sequence[Rig], calibration: Calibration, needed: np.ndarray,
              settings: DesignSettings, check: RigCheck | None = None) -> RigSummary:
    """Predicted transfer from each reference, coverage fraction and requirement check of ``rig``."""
    counts = rig_coverage_matrix(rig, vehicle, settings.coverage).sees.sum(axis=0)
    predictions = tuple(predict_transfer(reference, [rig], calibration)[0] for reference in references)
    return RigSummary(rig, predictions, float(np.mean(counts >= 1)), bool(np.all(counts >= needed)), check)


def calibrated_matching(rig: Rig, reference: Rig, calibration: Calibration) -> np.ndarray:
    """(k,) int: the reference camera each camera of ``rig`` is matched to by the calibrated RigCD's optimal
    assignment (-1 for cameras beyond the reference's count)."""
    lt, lr, lf = calibration.lambdas
    t, r, f = camera_costs(rig.positions, rig.rotations, rig.fovs, reference.positions, reference.rotations,
                           reference.fovs)
    rows, cols = linear_sum_assignment(lt * t + lr * r + lf * f)
    matched = np.full(len(rig), -1, dtype=int)
    matched[rows] = cols
    return matched


def matching_costs(candidates: CandidateSet, reference: Rig, calibration: Calibration) -> np.ndarray:
    """(n, R) float: the calibrated raw-unit cost of matching each candidate to each reference camera."""
    lt, lr, lf = calibration.lambdas
    t, r, f = camera_costs(candidates.positions, candidates.rotations, candidates.fovs,
                           reference.positions, reference.rotations, reference.fovs)
    return lt * t + lr * r + lf * f


def naive_transfer(vehicle: Vehicle, reference: Rig, candidates: CandidateSet, settings: DesignSettings) -> Rig | None:
    """Each reference camera moved to the nearest mount point where it can face the same way (its yaw and
    pitch on the grid, nearest catalogue lens), one camera per mount point; None if some camera finds none."""
    cameras = []
    used: set[int] = set()
    lenses = np.unique(candidates.fovs)
    for camera in reference.cameras:
        yaw = np.arctan2(camera.forward[1], camera.forward[0])
        pitch = np.arcsin(np.clip(camera.forward[2], -1.0, 1.0))
        lens = lenses[np.argmin(np.abs(lenses - camera.fov))]
        same_way = (np.abs(np.angle(np.exp(1j * (candidates.yaws - yaw)))) <= np.deg2rad(settings.yaw_step_deg) / 2
                    + 1e-9) & (candidates.fovs == lens)
        pitch_gap = np.abs(candidates.pitches - pitch)
        same_way &= pitch_gap <= pitch_gap[same_way].min(initial=np.inf) + 1e-9
        options = np.flatnonzero(same_way & ~np.isin(candidates.mount, list(used)))
        if len(options) == 0:
            return None
        best = options[np.argmin(np.linalg.norm(candidates.positions[options] - camera.position, axis=1))]
        used.add(int(candidates.mount[best]))
        cameras.append(candidates.camera(best, camera.id, with_zone=False))
    return Rig(f"naive_{vehicle.name}_from_{reference.name}", vehicle.blueprint, tuple(cameras))
