"""Validating a designed rig: does a reference-trained detector lose on it what RigCD predicts?

The test split of the reference rig is rendered again, the same scenes and image size, under the design,
the benchmark's hand-designed rigs for the design's vehicle and the naive transfer of the reference
(each reference camera moved to the nearest valid mount facing its way). The detector trained on the
reference is evaluated on each; the measured relative drop (mAP(ref -> ref) - mAP(ref -> rig)) /
mAP(ref -> ref) stands beside the drop that the calibrated RigCD predicts.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Callable

from rigopt.baselines.protocol import TEST_SPLIT, evaluate_on_rigs, run_folder
from rigopt.errors import DataError, RigFileError
from rigopt.metrics.calibration import Calibration
from rigopt.rig.library import load_rig
from rigopt.rig.model import Rig


def load_design(path) -> Rig:
    """A rig from a rig file or a design report (``report.json`` beside its ``rig.json``); a file named
    rig.json or report.json takes its folder's name (e.g. ``firetruck_from_R1``)."""
    path = Path(path)
    if not path.is_file():
        raise RigFileError(f"{path}: no such design file; pass a rig file or the report.json of rigopt design")
    rig_path = path
    if path.name == "report.json":
        rig_path = path.with_name("rig.json")
        if not rig_path.is_file():
            try:
                rig_path = Path(json.loads(path.read_text())["rig_file"])
            except (json.JSONDecodeError, KeyError, TypeError):
                raise RigFileError(f"{path}: a report without rig_file and no rig.json beside it") from None
    rig = load_rig(rig_path)
    if rig_path.stem in ("rig", "report"):
        rig = dataclasses.replace(rig, name=rig_path.parent.resolve().name)
    return rig


def comparison_rigs(design: Rig, reference: Rig) -> list[tuple[str, Rig]]:
    """(role, rig): the design, the library's hand-designed rigs for its vehicle, the naive transfer."""
    from rigopt.design.designer import DesignSettings, benchmark_rigs, mount_candidates, naive_transfer
    from rigopt.vehicle.library import load_vehicle

    vehicle = load_vehicle(design.vehicle)
    settings = DesignSettings()
    rigs = [("design", design)] + [("hand-designed", rig) for rig in benchmark_rigs(vehicle)]
    naive = naive_transfer(vehicle, reference, mount_candidates(vehicle, settings), settings)
    if naive is not None:
        rigs.append(("naive transfer", naive))
    return rigs


def validate_design(design: Rig, reference: str, family: str, data, calibration: Calibration, runs=None,
                    device: str = "cpu", progress: Callable[[str], None] = lambda message: None) -> dict:
    """Measured and predicted drops of the reference-trained ``family`` detector on the design and its
    comparison rigs. Renders missing test splits into ``data``; returns a JSON-ready dict."""
    from rigopt.baselines.data import split_root
    from rigopt.bench.generate import ego_mesh_lookup, generate_split, split_layout
    from rigopt.bench.render import render_rig
    from rigopt.metrics.ranking import predict_transfer

    reference_rig = load_rig(reference)
    runs = Path(runs) if runs is not None else Path(data) / "runs"
    checkpoint = run_folder(runs, family, reference_rig.name) / "checkpoint.pt"
    if not checkpoint.is_file():
        raise DataError(f"{checkpoint}: no {family} model trained on {reference_rig.name}; train it first with "
                        f"rigopt bench train --data {data} --rig {reference_rig.name} --model {family}")
    scenes, size = split_layout(split_root(data, reference_rig.name, TEST_SPLIT))
    rigs = comparison_rigs(design, reference_rig)
    names = [rig.name for _, rig in rigs]
    if len(set(names)) != len(names) or reference_rig.name in names:
        raise DataError(f"rig names must differ from each other and from the reference: {names}")
    progress(f"rendering the {len(scenes)}-scene test split under {', '.join(names)} (finished ones are kept)")
    generate_split([rig for _, rig in rigs], scenes, data, size, render_rig, ego_mesh_lookup(progress))

    progress(f"evaluating the {family} model trained on {reference_rig.name}")
    metrics = evaluate_on_rigs(checkpoint, data, [reference_rig.name, *names], device, family)
    own = metrics[reference_rig.name]["mAP"]
    predictions = predict_transfer(reference_rig, [rig for _, rig in rigs], calibration)
    entries = []
    for (role, rig), prediction in zip(rigs, predictions):
        measured = metrics[rig.name]["mAP"]
        drop = (own - measured) / own if own and measured is not None else None
        entries.append({"role": role, "rig": rig.name, "n_cameras": len(rig), "mAP": measured,
                        "measured_drop": drop, "predicted_drop": prediction.predicted_drop,
                        "rigcd": prediction.rigcd})
    return {"reference": reference_rig.name, "model": family, "checkpoint": str(checkpoint),
            "metric": calibration.metric, "weights": calibration.name, "reference_mAP": own, "test_scenes": len(scenes),
            "image_size": list(size), "rigs": entries}
