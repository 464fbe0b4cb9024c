"""Design results as data and files: the report JSON, the rig file, the pictures."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rigopt.background import INLINE, Background
from rigopt.design.result import DesignResult, RigSummary
from rigopt.report.json_values import json_ready
from rigopt.rig.model import Rig
from rigopt.rig.pccr_format import write_rig
from rigopt.vehicle.symmetry import rig_symmetry

if TYPE_CHECKING:
    from rigopt.metrics.rigcd import RigCDBreakdown


def prediction_extras(p) -> dict:
    """What qualifies a predicted drop: its interval and whether it says anything (``interval_informative``:
    false when it spans the range a drop can take), the linear prediction, the extrapolation flags (null
    when the pair lies within the calibration pairs) and whether the calibration is a fallback."""
    return {key: value for key, value in p.to_dict().items()
            if key in ("interval", "interval_informative", "linear_drop", "extrapolation", "fallback", "predictor")}


def summary_dict(summary: RigSummary, vehicle=None) -> dict:
    """A rig's worst predicted transfer over the references, its coverage, each reference's prediction, and
    with the ``vehicle`` its relative mounting cost (the sum over its cameras, see ``mounting_costs``)."""
    p = summary.prediction
    out = {"name": summary.rig.name, "predicted_drop": p.predicted_drop, **prediction_extras(p), "rigcd": p.rigcd,
           "t": p.t, "r": p.r, "f": p.f, "count": p.count, "n_cameras": len(summary.rig), "coverage": summary.coverage,
           "meets_coverage_requirements": summary.meets_requirements,
           "per_reference": [{"reference": q.reference, "predicted_drop": q.predicted_drop, "rigcd": q.rigcd}
                             for q in summary.predictions]}
    if vehicle is not None:
        out["mounting_cost"] = rig_mounting_cost(summary.rig, vehicle)
    return out


def rig_mounting_cost(rig: Rig, vehicle) -> float:
    """The relative mounting cost of ``rig`` on ``vehicle``: the sum of its cameras' (zone cost + spray)."""
    from rigopt.mounting.practice import mounting_costs

    return float(mounting_costs(vehicle, [c.zone for c in rig.cameras], rig.positions).sum())


def camera_rows(rig: Rig, reference: Rig, pairs, vehicle=None, stand_ins=()) -> list[dict]:
    """Each designed camera for an engineer: id (where it is mounted and looks), zone, lens, its pose in the
    report's frame (``position`` m and ``yaw_pitch_roll_deg``: ISO 8855, x forward, y left, z up, measured
    from the ground below the rear axle's centre, :func:`rigopt.coverage.packaging.report_origin`, or from the
    vehicle centre without a ``vehicle``; yaw > 0 turns left, pitch > 0 tilts up), and the reference camera
    it is matched to by RigCD (unit weights) with that pair's t (m), r (rad), f (deg) (``pairs``:
    RigCDBreakdown.pairs, (reference id, rig id), of the perception cameras, :func:`perception_breakdown`: a
    near-field camera has none); with the ``vehicle``, its zone's mounting ``zone_cost`` and
    its tyre ``spray`` exposure (high / low). ``stand_ins``: (camera id, reference id) of the designer's own
    pairing (:attr:`rigopt.design.result.DesignResult.stand_ins`); each such camera's ``stands_in_for`` gives the
    reference camera and how far its pose is from it: height above the ground, pitch, yaw (wrapped to +-180) and
    FOV, this camera's minus the reference's, and the lenses' distance apart, each in its own vehicle's centre
    frame. ``rig`` is in the vehicle-centre frame (the design's); CARLA's frame appears only in the rig file."""
    from rigopt.coverage.packaging import report_origin
    from rigopt.geometry import yaw_pitch_roll_from_rotation
    from rigopt.metrics.rigcd import camera_costs
    from rigopt.mounting.practice import mounting_costs, spray_exposure

    partner = {b: a for a, b in pairs}
    designed_for = dict(stand_ins)
    by_id = {c.id: c for c in reference.cameras}
    origin = report_origin(vehicle).point if vehicle is not None else np.zeros(3)
    angles = np.rad2deg(np.stack(yaw_pitch_roll_from_rotation(rig.rotations), axis=-1))
    spray = spray_exposure(vehicle, rig.positions) if vehicle is not None else None
    mounting = mounting_costs(vehicle, [c.zone for c in rig.cameras], rig.positions) if vehicle is not None else None
    rows = []
    for k, camera in enumerate(rig.cameras):
        row = {"id": camera.id, "zone": camera.zone, "role": camera.role, "fov": camera.fov,
               "position": (camera.position - origin).tolist(), "yaw_pitch_roll_deg": angles[k].tolist(),
               "lens": camera.lens.summary(), "matched_reference_camera": None}
        if vehicle is not None:
            costs = {z.name: z.cost for z in vehicle.zones}
            row["zone_cost"] = costs.get(camera.zone)
            row["spray"] = spray[k]
            row["mounting_cost"] = float(mounting[k])
        if camera.id in partner:
            ref = by_id[partner[camera.id]]
            t, r, f = (float(v.item()) for v in camera_costs(ref.position[None], ref.rotation[None], [ref.fov],
                                                     camera.position[None], camera.rotation[None], [camera.fov]))
            row["matched_reference_camera"] = {"id": ref.id, "t_m": t, "r_rad": r, "f_deg": f}
        if camera.id in designed_for:
            row["stands_in_for"] = _pose_apart(camera, by_id[designed_for[camera.id]])
        rows.append(row)
    return rows


def _pose_apart(camera, reference) -> dict:
    """How far ``camera``'s pose is from ``reference``'s (each in its own vehicle's centre frame, z up from the
    ground): the reference's id, height (m), pitch, yaw (wrapped to +-180) and FOV (deg) of the camera minus the
    reference's, and the lenses' distance apart (m)."""
    from rigopt.geometry import yaw_pitch_roll_from_rotation

    (yaw, pitch, _), (ref_yaw, ref_pitch, _) = (np.rad2deg(np.ravel(yaw_pitch_roll_from_rotation(r)))
                                                for r in (camera.rotation, reference.rotation))
    return {"id": reference.id, "height_m": float(camera.position[2] - reference.position[2]),
            "pitch_deg": float(pitch - ref_pitch), "yaw_deg": float((yaw - ref_yaw + 180.0) % 360.0 - 180.0),
            "fov_deg": float(camera.fov - reference.fov),
            "lenses_apart_m": float(np.linalg.norm(camera.position - reference.position))}


def packaging_rows(rig: Rig, vehicle, lifted=()) -> list[dict]:
    """Each camera's packaging sheet (:mod:`rigopt.coverage.packaging`: body feature, surface normal and
    bracket wedge angle, protrusion, nearest visible ground, ground resolution, people's heights in pixels,
    blocked shares: the body's, and each keep-out's in force but those ``lifted``) with its bracket sheet under
    ``bracket`` (:mod:`rigopt.coverage.bracket`: bracket angles,
    housing and depth behind the skin, clearances, harness, exposure) as JSON values, positions measured from the report's datum
    (:func:`rigopt.coverage.packaging.report_origin`). ``rig`` may be measured from any origin the vehicle
    can place."""
    from rigopt.coverage.bracket import rig_brackets
    from rigopt.coverage.packaging import report_origin, rig_packaging

    origin = report_origin(vehicle).point
    return [{**sheet.to_dict(origin), "bracket": bracket.to_dict(origin)}
            for sheet, bracket in zip(rig_packaging(rig, vehicle, lifted=lifted), rig_brackets(rig, vehicle))]


def frame_dict(vehicle) -> dict:
    """The report's frame: its name (``frame``) and where its origin lies from the vehicle's centre, the
    rig file's origin (``origin_from_vehicle_centre_m``: subtract it from a rig file position, after turning
    CARLA's y right into ISO's y left, to get the report's)."""
    from rigopt.coverage.packaging import report_origin

    return report_origin(vehicle).to_dict()


def breakdown_dict(b) -> dict:
    """A RigCDBreakdown's values: rigcd, match, count, t m, r rad, f deg."""
    return {"rigcd": b.rigcd, "match": b.match, "count": b.count, "t_m": b.t, "r_rad": b.r, "f_deg": b.f}


def perception_breakdown(reference: Rig, rig: Rig) -> tuple[RigCDBreakdown, dict]:
    """The unit-weight RigCD of ``reference`` to ``rig`` as ``rigopt rigcd`` gives it: of their perception cameras
    only (the detector's; near-field cameras are left out). Returns the RigCDBreakdown (its ``pairs`` match each
    perception camera of ``rig`` to a reference camera) and its JSON values: :func:`breakdown_dict` with the
    cameras compared, ``reference_cameras`` and ``design_cameras``."""
    from rigopt.metrics.rigcd import rigcd

    reference, perception = reference.perception(), rig.perception()
    breakdown = rigcd(reference, perception)
    return breakdown, {**breakdown_dict(breakdown), "reference_cameras": len(reference),
                       "design_cameras": len(perception)}


def symmetry_dict(result: DesignResult) -> dict:
    """The design's mirror symmetry: whether it was asked for, the vehicle's, and the pairs it has."""
    symmetry = rig_symmetry(result.design.rig)
    asked = result.settings.is_symmetric_on(result.vehicle)
    free_perception = result.near_field_mirrored and not asked
    describe = (symmetry.describe() if asked else result.symmetry_fallback
                or (f"perception cameras placed freely, near-field cameras in mirrored pairs ({symmetry.describe()})"
                    if free_perception else f"symmetry not required ({symmetry.describe()})"))
    return {"required": asked, "vehicle": result.vehicle.symmetry.describe(), **symmetry.to_dict(),
            "near_field_mirrored": result.near_field_mirrored, "fallback": result.symmetry_fallback,
            "describe": describe}


def design_dict(result: DesignResult, rig_file: Path | None) -> dict:
    """The ``rigopt design --json`` object (and the body of report.json). Positions are in one frame, named by
    ``frame`` (ISO 8855 from the ground below the rear axle's centre, :func:`frame_dict`): the cameras'
    poses and the ``packaging`` sheets (:func:`packaging_rows`); CARLA's frame is only the rig file's."""
    from rigopt.coverage.regulations import category_dict
    from rigopt.report.coverage_tables import regions_dict

    design, milp, comparisons = result.design, result.milp, result.comparisons
    reference = result.references[0].rig
    breakdown, breakdown_values = perception_breakdown(reference, design.rig)  # the matching each camera reports
    summary = {
        "rig_file": str(rig_file) if rig_file else None,
        "vehicle": design.rig.vehicle,
        "vehicle_category": category_dict(result.vehicle),
        **frame_dict(result.vehicle),
        "reference": ",".join(r.rig.name for r in result.references),
        "metric": result.calibration.metric,
        "weights": result.calibration.name,
        "predictor_evidence": result.drop_model.study if result.drop_model is not None else None,
        "predictor_detector": result.drop_model.detector if result.drop_model is not None else None,
        "predicted_drop": design.prediction.predicted_drop,
        **prediction_extras(design.prediction),
        "rigcd": design.prediction.rigcd,
        "n_cameras": len(design.rig),
        "per_reference": summary_dict(design)["per_reference"],
        "coverage": design.coverage,
        "reference_coverage": result.reference_coverage,
        "mounting_cost": rig_mounting_cost(design.rig, result.vehicle),
        "cost_weight": result.settings.cost_weight,
        "objective": ("rigcd" if result.settings.drop_model is None
                      else f"{result.settings.drop_model.name} drop model ({result.settings.drop_model.study})"),
        "pose_tolerance": {"height_m": result.settings.match_height_m, "pitch_deg": result.settings.match_pitch_deg,
                           "yaw_deg": result.settings.match_yaw_deg, "fov_deg": result.settings.match_fov_deg,
                           "lifted_for": [k for k, f in result.tolerance_widened if not np.isfinite(f)],
                           "widened_by": {k: f for k, f in result.tolerance_widened if np.isfinite(f)},
                           "height_search_m": result.settings.height_search_m,
                           "height_moves": [move.to_dict() for move in result.height_moves]},
        "perception_range_m": result.settings.perception_range_m,
        "solver": {"milp_status": milp.status, "milp_gap": milp.gap, "milp_seconds": milp.selection.seconds,
                   "refine_status": result.refinement.status, "candidates": milp.n_candidates,
                   "offered_to_milp": milp.n_offered, "repairs": milp.repairs, "seconds": result.seconds,
                   "near_field": near_field_dict(result.near_field)},
        "cameras": camera_rows(design.rig, reference, breakdown.pairs, result.vehicle, result.stand_ins),
        "packaging": packaging_rows(design.rig, result.vehicle, result.settings.rules.practice.lifted),
        "symmetry": symmetry_dict(result),
        "roles": {"perception": len(design.rig) - design.rig.near_field_count,
                  "near_field": design.rig.near_field_count},
        "regions_required": result.settings.require != "none",
        "regions_fallback": result.fields_fallback,
        "regions": regions_dict(result.regions),
        "rigcd_breakdown": breakdown_values,
        "comparisons": {
            "naive_transfer": ({**summary_dict(comparisons.naive_transfer, result.vehicle),
                                "refinement": comparisons.naive_refinement} if comparisons.naive_transfer else None),
            "benchmark_rig": summary_dict(comparisons.best_rig, result.vehicle) if comparisons.best_rig else None,
            "benchmark_rigs": [summary_dict(s, result.vehicle) for s in comparisons.rigs],
        },
    }
    summary["notes"] = comparison_notes(summary)
    return summary


def near_field_dict(stage) -> dict | None:
    """The near-field stage's MILP in the summary (None for a one-set design)."""
    if stage is None:
        return None
    return {"status": stage.status, "gap": stage.gap, "cameras": stage.rig.near_field_count,
            "candidates": stage.n_candidates, "points": stage.n_points, "dense_rounds": stage.rounds,
            "near_ring_unseeable": len(stage.ring_unseeable), "seconds": stage.seconds}


#: What the designs measured with the shipped detectors showed of RigCD's predictions (studies/validation/designs).
RIGCD_ON_DESIGNS = ("The predicted drops are RigCD's, calibrated on the benchmark's hand-designed rigs; on the "
                    "designs measured with rigopt's shipped detectors it ordered design and naive copy the wrong way "
                    "(design and naive copy, fire truck: predicted 0.809 and 0.615, measured 0.136 and 0.660; hgv: "
                    "predicted 0.893 and 0.833, measured 0.283 and 0.633; studies/validation/designs): --measure "
                    "measures this design and its copies")


def comparison_notes(summary: dict) -> list[str]:
    """Lines a reader of the comparison table needs: what RigCD's predictions are worth on designs, and why the
    design is predicted to lose more than the naive transfer when it is (``summary`` is :func:`design_dict`
    without its notes)."""
    if summary["predictor_evidence"] is not None:
        notes = [f"The predicted drops are the {summary['predictor']}'s, a model of the measured drop of "
                 f"{summary['predictor_detector']} ({summary['predictor_evidence']}); RigCD is in its column"]
    else:
        notes = [RIGCD_ON_DESIGNS] if summary["metric"].startswith("rigcd") else []
    naive = summary["comparisons"]["naive_transfer"]
    if naive is None or naive["predicted_drop"] >= summary["predicted_drop"]:
        return notes
    lower = (f"The naive transfer is predicted to lose less than the design ({naive['predicted_drop']:.3f} against "
             f"{summary['predicted_drop']:.3f})")
    if naive["meets_coverage_requirements"]:
        return notes + [f"{lower} and meets every coverage requirement; the designer keeps each perception camera "
                        "at the pose nearest its reference camera's, which the measurements above favour over the "
                        "prediction: compare the two in report.html or measure them (--measure)"]
    one_set = summary["solver"]["near_field"] is None  # two roles: the fields are the near-field cameras' job
    fields = [r["key"] for r in summary["regions"]] if summary["regions_required"] and one_set else []
    needs = "the reference's ring sectors" + (f" and the required fields ({', '.join(fields)})" if fields else "")
    return notes + [f"{lower} but misses what the design must see: {needs}; it sees {naive['coverage']:.1%} of the "
                    f"ring sectors (the design {summary['coverage']:.1%})"
                    + ("; --require none designs without the fields" if fields else "")]


def write_design_pictures(vehicle, reference, design: Rig, naive: Rig | None, regions, out_dir,
                          lifted=()) -> dict[str, Path]:
    """The design's pictures in ``out_dir``: design.png, reference.png (``reference``, a ReferenceRig, on its own
    vehicle), naive_transfer.png (``naive``, when there is one), coverage.png (the design's rings beside the
    reference's) and, with ``regions`` (RegionCoverage), fields.png (the regulation fields over the near-field
    blind zones). Positions are drawn in the tables' frame (:func:`frame_dict`: from the datum of
    :func:`rigopt.coverage.packaging.report_origin`), the reference on its own vehicle from that vehicle's datum.
    ``lifted``: the optional keep-outs the design lifted (``MountPractice.lifted``), which hide nothing on the
    design's rings. Returns {picture name: path}. A module-level function of picklable values: it may run in a
    background worker."""
    from rigopt.coverage.measures import CoverageSettings, ring_report
    from rigopt.coverage.packaging import report_origin
    from rigopt.report.coverage_figures import write_regions_figure, write_rings_figure
    from rigopt.report.vehicle_figures import write_vehicle_figure

    out_dir = Path(out_dir)
    datum = report_origin(vehicle)
    pictures = {"design": write_vehicle_figure(vehicle, out_dir / "design.png", design, datum),
                "reference": write_vehicle_figure(reference.vehicle, out_dir / "reference.png", reference.rig,
                                                  report_origin(reference.vehicle))}
    if naive is not None:
        pictures["naive_transfer"] = write_vehicle_figure(vehicle, out_dir / "naive_transfer.png", naive, datum)
    design_coverage = ring_report(design, vehicle, CoverageSettings(lifted=tuple(lifted)))
    reference_coverage = ring_report(reference.rig, reference.vehicle)
    pictures["coverage"] = write_rings_figure(design_coverage, out_dir / "coverage.png", compare=reference_coverage)
    if regions:
        pictures["fields"] = write_regions_figure(regions, design_coverage, out_dir / "fields.png", design, datum)
    return pictures


def write_design_report(result: DesignResult, out_dir, background: Background = INLINE,
                        measured: dict | None = None) -> tuple[list[Path], dict]:
    """Write rig.json (benchmark format), report.json, the pictures (:func:`write_design_pictures`, in the
    ``background`` worker when there is one, while the report and the 3D view are written here) and report.html
    (with the interactive 3D view of the design on its vehicle, the fields on the ground and the reference rig in
    grey when it sits on the same vehicle) into ``out_dir``. Returns (the files, the report's :func:`design_dict`).
    ``measured``: the design and its copies measured (:func:`rigopt.validation.designs.measure_design`), kept as
    report.json's ``measured`` and shown beside the predictions.
    The reports name the rig file relative to their folder (``rig.json``), so that a report holds no machine
    path and stays valid where the folder is moved.
    """
    from rigopt.report.design_html import write_design_html
    from rigopt.report.scene_3d import scene_html

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    vehicle, naive = result.vehicle, result.comparisons.naive_transfer
    pictures = background.submit(write_design_pictures, vehicle, result.references[0], result.design.rig,
                                 naive.rig if naive is not None else None, result.regions, out_dir,
                                 result.settings.rules.practice.lifted)
    rig_file = write_rig(result.design.rig, out_dir / "rig.json", say_frame=True)
    summary = design_dict(result, Path(rig_file.name))  # named relative to the report's folder: no machine paths
    if measured is not None:
        summary["measured"] = measured
    report = out_dir / "report.json"
    report.write_text(json.dumps(json_ready(summary), indent=2) + "\n")
    compared = next((r.rig for r in result.references if r.vehicle.name == vehicle.name), None)
    outlines = [(r.key, np.asarray(r.polygon.exterior.coords)[:, :2]) for r in result.regions
                if r.polygon.geom_type == "Polygon"]
    scene = scene_html(vehicle, result.design.rig, compare=compared, lifted=result.settings.rules.practice.lifted,
                       regions=outlines, datum="rear_axle")
    drawn = pictures.result()
    page = write_design_html(summary, out_dir, drawn, scene, compared.name if compared is not None else None)
    return [rig_file, report, *drawn.values(), page], summary


def write_design_outputs(result: DesignResult, out_dir, background: Background = INLINE) -> list[Path]:
    """The files of :func:`write_design_report`."""
    return write_design_report(result, out_dir, background)[0]
