"""Ground truth that does not depend on the rig (issue 18): the same annotations under every rig, each
with the rig's visible fraction, and an evaluation that counts an object in a blind zone as missed.

One real scene (2 frames, 64 x 36, ego bodies) is rendered under R1 (8 cameras all round), R6 and
"R1-front", R1 keeping only its three forward-looking cameras: it sees nothing behind the ego.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from rigopt.validation.synthetic.dataset import read_dataset
from rigopt.validation.synthetic.evaluation import Detections, GroundTruth, SamplePrediction, evaluate
from rigopt.validation.synthetic.generate import generate_split
from rigopt.validation.synthetic.render import EgoBody
from rigopt.errors import DataError
from rigopt.rig.library import load_rig

SIZE = (64, 36)


def front_only(rig):
    """``rig`` with only the cameras whose optical axis points forward (within 60 degrees of ego x)."""
    cameras = tuple(c for c in rig.cameras if c.rotation[0, 0] > 0.5)
    return dataclasses.replace(rig, name=f"{rig.name}-front", cameras=cameras)


@pytest.fixture(scope="module")
def roots(tmp_path_factory):
    """{rig name: split root} of one 2-frame scene under R1, R6 and R1-front."""
    from rigopt.validation.synthetic.render import render_rig
    from rigopt.validation.synthetic.scenes import generate_scene
    from rigopt.vehicle.library import load_vehicle

    rigs = [load_rig("R1"), load_rig("R6"), front_only(load_rig("R1"))]
    assert len(rigs[2]) == 3
    out = tmp_path_factory.mktemp("fixed_truth")
    found = generate_split(rigs, [generate_scene(11, "mini", n_frames=2)], out, SIZE, render_rig,
                           lambda r: EgoBody(load_vehicle(r.vehicle).mesh))
    return {rig.name: root for rig, root in zip(rigs, found)}


def annotation_table(root):
    return json.loads(next(root.glob("v1.0-*/sample_annotation.json")).read_text())


def test_every_rig_gets_the_same_annotations(roots):
    """The same records (token, instance, box) under every rig; only the visibility fields differ."""
    rig_fields = {"visibility_token", "visible_fraction"}
    tables = {name: sorted(annotation_table(root), key=lambda r: r["token"]) for name, root in roots.items()}
    fixed = {name: [{k: v for k, v in r.items() if k not in rig_fields} for r in records]
             for name, records in tables.items()}
    assert len(fixed["R1"]) > 20
    assert fixed["R1"] == fixed["R6"] == fixed["R1-front"]
    fractions = {name: np.array([r["visible_fraction"] for r in records]) for name, records in tables.items()}
    assert not np.array_equal(fractions["R1"], fractions["R1-front"])
    assert (fractions["R1-front"] == 0).sum() > (fractions["R1"] == 0).sum()


def test_the_same_boxes_in_the_ego_frame_under_every_rig(roots):
    samples = {name: read_dataset(root) for name, root in roots.items()}
    for a, b in zip(samples["R1"], samples["R1-front"]):
        assert a.token == b.token
        np.testing.assert_array_equal(a.instances, b.instances)
        for field in ("centers", "sizes", "yaws", "classes"):
            np.testing.assert_allclose(getattr(a, field), getattr(b, field), atol=1e-9)


def seen_objects_found(samples):
    """A perfect detector of what the rig sees: every seen object of an evaluated class, exactly, score 1."""
    predictions = []
    for s in samples:
        keep = s.visible & (s.classes >= 0)
        predictions.append(SamplePrediction(s.token, s.centers[keep], s.classes[keep], np.ones(int(keep.sum()))))
    return Detections.from_predictions(p.within() for p in predictions)


def test_a_front_only_rig_loses_the_objects_behind_the_ego(roots):
    scores = {}
    for name in ("R1", "R1-front"):
        samples = read_dataset(roots[name])
        truth = GroundTruth.from_samples(samples).within()
        behind = truth.xy[:, 0] < -3.0
        scores[name] = (evaluate(seen_objects_found(samples), truth),
                        evaluate(seen_objects_found(samples), truth, visible_only=True),
                        behind.sum(), (behind & truth.visible).sum())
    front_fixed, front_visible, behind, front_sees_behind = scores["R1-front"]
    full_fixed, full_visible, _, full_sees_behind = scores["R1"]
    assert behind >= 5 and front_sees_behind == 0 and full_sees_behind >= behind / 2
    assert front_visible.map == pytest.approx(1.0) and full_visible.map == pytest.approx(1.0)
    assert front_fixed.map < full_fixed.map < 1.0  # occluded objects are missed by any rig
    assert front_fixed.n_ground_truth.sum() == full_fixed.n_ground_truth.sum()  # the same objects counted
    assert front_visible.n_ground_truth.sum() < full_visible.n_ground_truth.sum()


def test_a_dataset_without_visible_fractions_reads_as_all_visible(roots, tmp_path):
    """rigopt's data made before the field (and the real benchmark's) annotate only seen objects."""
    import shutil

    old = tmp_path / "old"
    shutil.copytree(roots["R1"], old)
    table = next(old.glob("v1.0-*/sample_annotation.json"))
    records = [r for r in json.loads(table.read_text()) if r["visible_fraction"] > 0]
    for record in records:
        del record["visible_fraction"]
    table.write_text(json.dumps(records))
    samples = read_dataset(old)
    assert sum(len(s.classes) for s in samples) == len(records)
    assert all(np.isnan(s.visible_fractions).all() and s.visible.all() for s in samples)
    truth = GroundTruth.from_samples(samples).within()
    assert truth.visible.all()
    found = seen_objects_found(samples)
    assert evaluate(found, truth).map == evaluate(found, truth, visible_only=True).map == pytest.approx(1.0)


def test_a_bad_visible_fraction_is_refused(roots, tmp_path):
    import shutil

    bad = tmp_path / "bad"
    shutil.copytree(roots["R6"], bad)
    table = next(bad.glob("v1.0-*/sample_annotation.json"))
    records = json.loads(table.read_text())
    records[0]["visible_fraction"] = "high"
    table.write_text(json.dumps(records))
    with pytest.raises(DataError, match="visible_fraction must be a number"):
        read_dataset(bad)
