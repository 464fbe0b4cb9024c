"""Validating a designed rig: does a reference-trained detector lose on it what RigCD predicts?

The test split of the reference rig is rendered again, the same scenes and image size, under the design,
the benchmark's hand-designed rigs for the design's vehicle and the naive transfer of the reference
(each reference camera moved to the nearest valid mount facing its way). The detector trained on the
reference is evaluated on each; the measured relative drop (mAP(ref -> ref) - mAP(ref -> rig)) /
mAP(ref -> ref) stands beside the drop that the calibrated RigCD predicts. The test scenes are resampled
whole (paired across rigs: frames of one scene see nearly the same objects, so the scene is the unit) for a
95 % interval of each drop and of the design's drop minus each other rig's: the noise of the test scenes,
not of training.

mAP is the fixed-set score (every rig is scored against the same objects, so a blind zone costs what
it misses); the visible-only mAP and its drop (``mAP_visible``, ``measured_drop_visible``) stand beside
it, so that the loss from coverage (the gap between the two) and from viewpoint can be told apart.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Callable

import numpy as np

from rigopt.validation.detectors.data import RigSplit, split_root
from rigopt.validation.synthetic.evaluation import interval, relative_drops, resampled_maps, sample_blocks
from rigopt.validation.detectors.protocol import TEST_SPLIT, match_on_rigs, run_folder
from rigopt.errors import DataError, RigFileError
from rigopt.metrics.calibration import Calibration
from rigopt.metrics.reliability import DEFAULT_BOOTSTRAP, DEFAULT_SEED, finite_or_none
from rigopt.mounting.candidates import rig_body_share
from rigopt.rig.library import load_rig
from rigopt.rig.model import Rig

#: Roles of the rows a rig with near_field cameras is measured in: the cameras the detector is fed, and the whole
#: rig, near_field cameras included, for the record.
PERCEPTION_ROLE, WHOLE_ROLE = "perception cameras", "whole rig"


def fed_rigs(rig: Rig, role: str, family: str) -> tuple[list[tuple[str, Rig]], dict | None]:
    """The rows ``rig`` is measured in, (role, rig), and the record of what they hold (None for a rig of
    perception cameras only: one row, ``role``, the rig itself).

    A rig with near_field cameras feeds the detector its perception cameras (:meth:`Rig.perception`), row
    :data:`PERCEPTION_ROLE`, named ``<rig>_perception``; the drops, measured and predicted, that stand for the
    rig are that row's. The whole rig, named ``<rig>_whole``, is measured too for the record (row
    :data:`WHOLE_ROLE`) where the ``family`` takes every camera's lens (:func:`families.takes_lenses`, or no
    lens is distorted). The suffixes keep the two renderings (a folder per rig name under ``--data``) apart from
    each other and from any made of the rig under its own name. The record: ``perception_cameras``, ``near_field_cameras`` (ids), ``whole_rig`` (``rig``, ``n_cameras``,
    ``measured``, ``reason`` when not) and ``note``, a line for the user.
    """
    if not rig.near_field_count:
        return [(role, rig)], None
    from rigopt.validation.detectors.families import takes_lenses

    perception = dataclasses.replace(rig.perception(), name=f"{rig.name}_perception")
    whole = dataclasses.replace(rig, name=f"{rig.name}_whole")
    rows = [(PERCEPTION_ROLE, perception)]
    distorted = [c.id for c in rig.cameras if c.lens.is_distorted]
    reason = None
    if distorted and not takes_lenses(family):
        reason = (f"{len(distorted)} of its cameras have distorted lenses ({', '.join(distorted[:3])}"
                  f"{', ...' if len(distorted) > 3 else ''}) and {family} detectors take pinholes only")
    else:
        rows.append((WHOLE_ROLE, whole))
    near_field = [c.id for c in rig.cameras if c.role == "near_field"]
    note = (f"{rig.name}: {len(near_field)} near_field camera(s) are not fed to the detector: measured on its "
            f"{len(perception)} perception cameras" + (f"; not measured whole: {reason}" if reason else
                                                        f", and whole ({len(rig)} cameras) for the record"))
    return rows, {"perception_cameras": [c.id for c in perception.cameras], "near_field_cameras": near_field,
                  "whole_rig": {"rig": whole.name, "n_cameras": len(whole), "measured": reason is None,
                                "reason": reason},
                  "note": note}


def load_design(path) -> Rig:
    """A rig from a rig file, a design report (``report.json`` beside its ``rig.json``) or a library rig's name;
    a file named rig.json or report.json takes its folder's name (e.g. ``firetruck_from_R1``)."""
    from rigopt.rig.library import rig_names

    path = Path(path)
    if not path.exists() and str(path) in rig_names():
        return load_rig(str(path))
    if not path.is_file():
        raise RigFileError(f"{path}: no such design file; pass a rig file or the report.json of rigopt design")
    rig_path = path
    if path.name == "report.json":
        rig_path = path.with_name("rig.json")
        if not rig_path.is_file():
            try:
                rig_path = path.parent / json.loads(path.read_text())["rig_file"]  # relative to the report
            except (json.JSONDecodeError, UnicodeDecodeError, KeyError, TypeError):
                raise RigFileError(f"{path}: a report without rig_file and no rig.json beside it") from None
    rig = load_rig(rig_path)
    if rig_path.stem in ("rig", "report"):
        rig = dataclasses.replace(rig, name=rig_path.parent.resolve().name)
    return rig


def predicted_transfers(reference: Rig, rigs, calibration: Calibration, drop_model=None) -> list:
    """``metrics.ranking.predict_transfer`` of ``rigs`` from ``reference`` (one Prediction each), the rigs first
    brought to one origin: an imported reference measures from its rear axle, designs from the vehicle's centre."""
    from rigopt.metrics.ranking import predict_transfer
    from rigopt.vehicle.placement import comparable_rigs

    placed, _ = comparable_rigs([reference, *rigs])
    return predict_transfer(placed[0], placed[1:], calibration, drop_model, rig_body_share)


def comparison_rigs(design: Rig, reference: Rig, calibration: Calibration | None = None) -> list[tuple[str, Rig]]:
    """(role, rig): the design, the library's hand-designed rigs for its vehicle, the naive transfer (with the
    ``calibration``, refined as a design is: ``designer.refine_comparison``, the same continuous stage,
    keeping what it sees of the reference's coverage, so that the comparison credits the design's objective
    and not its extra refinement) and the height-matched transfer (each camera at the mount nearest its
    height: does matching heights alone explain the design's gain?). A hand-designed rig that is the design or the
    reference itself (a rig on the reference's own vehicle) is not compared again."""
    from rigopt.design.designer import default_spacing, mount_candidates, naive_transfer, refine_comparison
    from rigopt.design.problem import ReferenceRig, benchmark_rigs
    from rigopt.design.requirements import design_requirements
    from rigopt.design.settings import DesignSettings
    from rigopt.vehicle.library import load_vehicle
    from rigopt.vehicle.placement import in_vehicle_frame

    vehicle = load_vehicle(design.vehicle)
    reference = in_vehicle_frame(reference)[0]  # from its vehicle's centre, as designs are (an import: its rear axle)
    settings = DesignSettings(symmetric=False, require="none")
    rigs = [("design", design)] + [("hand-designed", rig) for rig in benchmark_rigs(vehicle)
                                   if rig.name not in (design.name, reference.name)]
    candidates = mount_candidates(vehicle, settings)
    naive = naive_transfer(vehicle, reference, candidates, settings)
    if naive is not None and calibration is not None:
        requirements = design_requirements([ReferenceRig.on_own_vehicle(reference)], vehicle, settings)
        naive, _ = refine_comparison(naive, vehicle, reference, calibration, requirements,
                                     default_spacing(vehicle, settings), settings)
    if naive is not None:
        rigs.append(("naive transfer", naive))
    height_matched = naive_transfer(vehicle, reference, candidates, settings, match="height")
    if height_matched is not None:
        rigs.append(("height-matched transfer", height_matched))
    return rigs


def validate_design(design: Rig, reference: str, family: str, data, calibration: Calibration, runs=None,
                    device: str = "cpu", progress: Callable[[str], None] = lambda message: None,
                    resamples: int = DEFAULT_BOOTSTRAP, seed: int = DEFAULT_SEED, drop_model=None) -> dict:
    """Measured and predicted drops of the reference-trained ``family`` detector on the design and its
    comparison rigs. Renders missing test splits into ``data``; returns a JSON-ready dict.

    Each measured drop has a 95 % interval from resampling whole test scenes (the same draw for every rig);
    ``bootstrap.measured_drops`` keeps each rig's resampled drops (the same draws, in the same order, for
    every validation of this test split and seed); ``design_minus`` holds the design's drop minus each other rig's,
    with its paired interval (below 0: the design loses less).

    A design with near_field cameras is measured as :func:`fed_rigs` says: the detector is fed its perception
    cameras (the row that stands for the design, in ``design_minus`` too), the whole design is kept for the
    record where the family takes its lenses; ``near_field`` holds what was measured (absent without them).
    The predicted drops are ``drop_model``'s where one is given (:mod:`rigopt.metrics.drop_model`), else RigCD's
    under ``calibration``; ``predicted_by`` names which.
    """
    from rigopt.validation.synthetic.generate import ego_body_lookup, generate_split, split_layout
    from rigopt.validation.synthetic.render import render_rig

    reference_rig = load_rig(reference)
    runs = Path(runs) if runs is not None else Path(data) / "runs"
    checkpoint = run_folder(runs, family, reference_rig.name) / "checkpoint.pt"
    if not checkpoint.is_file():
        raise DataError(f"{checkpoint}: no {family} model trained on {reference_rig.name}; train it first with "
                        f"rigopt bench train --data {data} --rig {reference_rig.name} --model {family}")
    scenes, size = split_layout(split_root(data, reference_rig.name, TEST_SPLIT))
    fed, near_field = fed_rigs(design, "design", family)
    rigs = fed + comparison_rigs(design, reference_rig, calibration)[1:]
    names = [rig.name for _, rig in rigs]
    if len(set(names)) != len(names) or reference_rig.name in names:
        raise DataError(f"rig names must differ from each other and from the reference: {names}")
    progress(f"rendering the {len(scenes)}-scene test split under {', '.join(names)} (finished ones are kept)")
    generate_split([rig for _, rig in rigs], scenes, data, size, render_rig, ego_body_lookup(progress))

    progress(f"evaluating the {family} model trained on {reference_rig.name}")
    test_rigs = [reference_rig.name, *names]
    matched = match_on_rigs(checkpoint, data, test_rigs, device, family)
    maps = np.array([matched[name].evaluation().map for name in test_rigs])
    maps_visible = np.array([matched[name].evaluation(visible_only=True).map for name in test_rigs])
    blocks = sample_blocks(RigSplit(data, reference_rig.name, TEST_SPLIT).samples)
    progress(f"bootstrapping the drops over the {len(blocks)} test scenes")
    runs_matched = [matched[name] for name in test_rigs]
    resampled = resampled_maps(runs_matched, blocks, resamples, seed)
    resampled_visible = resampled_maps(runs_matched, blocks, resamples, seed, visible_only=True)
    drops, resampled_drops = relative_drops(maps), relative_drops(resampled)
    drops_visible, resampled_drops_visible = relative_drops(maps_visible), relative_drops(resampled_visible)
    predictions = predicted_transfers(reference_rig, [rig for _, rig in rigs], calibration, drop_model)
    entries = []
    for k, ((role, rig), prediction) in enumerate(zip(rigs, predictions), start=1):
        predicted = prediction.to_dict()
        entries.append({"role": role, "rig": rig.name, "n_cameras": len(rig), "mAP": finite_or_none(maps[k]),
                        "mAP_visible": finite_or_none(maps_visible[k]),
                        "measured_drop": finite_or_none(drops[k]), "measured_drop_ci": interval(resampled_drops[:, k]),
                        "measured_drop_visible": finite_or_none(drops_visible[k]),
                        "measured_drop_visible_ci": interval(resampled_drops_visible[:, k]),
                        "predicted_drop": prediction.predicted_drop,
                        "predicted_interval": predicted["interval"],
                        "interval_informative": predicted["interval_informative"],
                        "extrapolation": predicted["extrapolation"],
                        "rigcd": prediction.rigcd})
    others = [k for k in range(2, len(test_rigs)) if rigs[k - 1][0] != WHOLE_ROLE]  # the design's own rows aside
    design_minus = [{"rig": names[k - 1], "role": rigs[k - 1][0], "difference": finite_or_none(drops[1] - drops[k]),
                     "ci": interval(resampled_drops[:, 1] - resampled_drops[:, k])} for k in others]
    result = {"reference": reference_rig.name, "model": family, "checkpoint": str(checkpoint),
              "metric": calibration.metric, "weights": calibration.name, "predicted_by": predictions[0].predictor,
              "reference_mAP": finite_or_none(maps[0]),
              "reference_mAP_visible": finite_or_none(maps_visible[0]),
              "test_scenes": len(scenes), "image_size": list(size), "rigs": entries,
              "design_minus": design_minus,
              "bootstrap": {"resamples": resamples, "seed": seed, "unit": "scene", "blocks": len(blocks),
                            "measured_drops": {name: [round(float(v), 4) if np.isfinite(v) else None
                                                      for v in column]
                                               for name, column in zip(names, resampled_drops[:, 1:].T)}}}
    if near_field is not None:
        result["near_field"] = near_field
    return result




def measure_design(design: Rig, reference: Rig, calibration: Calibration, protocol, cache=None, workers: int = 1,
                   progress: Callable[[str], None] = lambda message: None, drop_model=None) -> dict:
    """A design's perception cameras, R1's naive and height-matched transfers to its vehicle
    (:func:`comparison_rigs`) measured with the shipped lss models trained on ``reference`` under ``protocol``
    (:func:`rigopt.validation.detectors.shipped.measure`), each beside its predicted drop; JSON-ready.

    ``rigs``: per rig its role, predicted drop and interval, measured drop and 95 % scene interval; ``paired``:
    the design minus each copy, per seed and on the mean, with paired intervals; ``contradictions``: a line for
    each place where the prediction and the measurement disagree (a measured drop outside an informative
    predicted interval; two rigs ordered one way by the prediction and the other by a measurement whose paired
    interval excludes 0), so that a report never shows both without saying so. The predicted drops are
    ``drop_model``'s where one is given, else RigCD's under ``calibration`` (``predicted_by``).
    """
    from rigopt.validation.detectors.shipped import measure, paired_differences, shipped_detector, without_resamples

    detector = shipped_detector("lss", reference.name)
    copies = [(role, rig) for role, rig in comparison_rigs(design, reference, calibration)[1:]
              if role in ("naive transfer", "height-matched transfer")]
    rigs = [("design", dataclasses.replace(design.perception(), name=f"{design.name}_perception"))] + copies
    measured = measure([rig for _, rig in rigs], detector, cache, "cpu", workers, progress, protocol)
    predictions = predicted_transfers(reference, [rig for _, rig in rigs], calibration, drop_model)
    rows = [{"role": role, "rig": rig.name, "n_cameras": len(rig), "predicted_drop": p.predicted_drop,
             "predicted_interval": p.to_dict()["interval"], "interval_informative": p.interval_informative,
             "measured_drop": m["drop"], "measured_drop_ci": m["drop_ci"],
             "measured_per_seed": [s["drop"] for s in m["seeds"].values()]}
            for (role, rig), p, m in zip(rigs, predictions, measured)]
    paired = [{"role": role, **paired_differences(measured[0], entry)} for (role, _), entry in zip(rigs[1:], measured[1:])]
    return {"detector": detector.folder.name, "reference": reference.name,
            "protocol": protocol.describe(detector.card["test_data"]),
            "predicted_by": predictions[0].predictor, "rigs": rows, "paired": paired,
            "contradictions": contradictions(rows, paired), "measured": [without_resamples(m) for m in measured]}


def contradictions(rows: list[dict], paired: list[dict], name: Callable[[dict], str] = lambda row: row["role"]) -> list[str]:
    """Lines saying where predicted and measured drops disagree (see :func:`measure_design`).

    rows : each with ``rig``, ``predicted_drop``, ``predicted_interval``, ``interval_informative`` and
    ``measured_drop`` (None: not measured, skipped); paired : the first row's rig minus another rig, each with
    ``rig`` (the other's name), ``difference`` and its paired ``ci``; name : how a row is called in the lines."""
    lines = []
    measured = [row for row in rows if row["measured_drop"] is not None and row["predicted_drop"] is not None]
    for row in measured:
        low, high = row["predicted_interval"] or (None, None)
        if row["interval_informative"] and low is not None and not low <= row["measured_drop"] <= high:
            lines.append(f"{name(row)}: measured {row['measured_drop']:.3f}, outside the predicted interval "
                         f"[{low:.3f}, {high:.3f}] (predicted {row['predicted_drop']:.3f})")
        elif abs(row["measured_drop"] - row["predicted_drop"]) > 0.15:
            lines.append(f"{name(row)}: predicted {row['predicted_drop']:.3f}, measured {row['measured_drop']:.3f}: "
                         f"the prediction is off by {abs(row['measured_drop'] - row['predicted_drop']):.3f}")
    first, by_rig = rows[0], {row["rig"]: row for row in rows}
    for pair in paired:
        other, (low, high) = by_rig.get(pair["rig"]), pair["ci"]
        if other is None or None in (low, high, first["predicted_drop"], other["predicted_drop"]):
            continue
        predicted = first["predicted_drop"] - other["predicted_drop"]
        if (predicted > 0 and high < 0) or (predicted < 0 and low > 0):
            lines.append(f"the prediction orders {name(first)} and {name(other)} one way ({predicted:+.3f}), the "
                         f"measurement the other ({pair['difference']:+.3f} [{low:.3f}, {high:.3f}], {name(first)} "
                         f"minus {name(other)})")
    return lines
