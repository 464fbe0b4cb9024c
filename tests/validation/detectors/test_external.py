"""The detector contract (rigopt/validation/detectors/external.py): a packed model exported to TorchScript detects
what the model does, ``validate --detector`` gives ``--model lss``'s drops, an entry point is taken as a file is,
and a detector that breaks the contract gets one error line naming what it returned. On the tiny packed models
(conftest.packed): renderings of one 4-frame scene at 64 x 36 px."""

from __future__ import annotations

import dataclasses
import json
import os
import textwrap

import numpy as np
import pytest
from console import run_console

torch = pytest.importorskip("torch")

from rigopt.validation.detectors import external, shipped  # noqa: E402
from rigopt.validation.detectors.data import RigSplit  # noqa: E402
from rigopt.validation.detectors.inference import predict  # noqa: E402
from rigopt.validation.detectors.layers import lens_cells, pixel_rays  # noqa: E402
from rigopt.errors import DataError  # noqa: E402

SIZE = (64, 36)


@pytest.fixture(scope="module")
def exported(packed, tmp_path_factory):
    """(TorchScript file of the tiny packed seed 0 at 64 x 36 px, its pack)."""
    detector = shipped.shipped_detector("lss", "R1", packed[1])
    path = tmp_path_factory.mktemp("exported") / "lss-R1-seed0.pt"
    external.export_torchscript(detector.checkpoint(0), path, SIZE)
    return path, detector


@pytest.fixture(scope="module")
def home(packed, tmp_path_factory):
    """The environment of a validate run on the packed models: their folder, a cache of its own (shared by the
    tests here: the reference is rendered once), this folder's entry points on PYTHONPATH, one torch thread."""
    entry_points = tmp_path_factory.mktemp("entry_points")
    (entry_points / "contract_cases.py").write_text(CONTRACT_CASES)
    return {**os.environ, "OMP_NUM_THREADS": "1", "RIGOPT_DETECTORS": str(packed[1]),
            "RIGOPT_HOME": str(tmp_path_factory.mktemp("home")),
            "PYTHONPATH": os.pathsep.join(filter(None, [str(entry_points), os.environ.get("PYTHONPATH")]))}


def test_an_exported_model_detects_what_the_model_does_at_any_camera_count_and_batch(exported, tiny_data):
    """Traced with 3 cameras in batches of 2, the file runs R1 (8 cameras) and R5 (4): in batches of 16, as
    rigopt runs its own models (the card's batch size), exactly the model's detections; in batches of 3 the
    same detections to float rounding (another batch size sums the convolutions in another order)."""
    path, detector = exported
    model = shipped._loaded_model(detector.checkpoint(0), "lss")
    loaded = external.load_detector(str(path))
    assert loaded.card["image_size"] == list(SIZE) and loaded.card["trained_on"] == "R1"
    assert loaded.batch_size == 16
    for rig in ("R1", "R5"):
        split = RigSplit(tiny_data, rig, "test", None, depths=False)
        own = predict(model, split)
        for batch, tolerance in ((16, 0.0), (3, 1e-4)):
            theirs = external.predict(dataclasses.replace(loaded, card={**loaded.card, "batch_size": batch}), split)
            assert [p.token for p in theirs] == [p.token for p in own]
            for a, b in zip(theirs, own):
                assert len(b.scores) > 0 and np.array_equal(a.classes, b.classes)
                assert np.allclose(a.centers, b.centers, rtol=0, atol=tolerance)
                assert np.allclose(a.scores, b.scores, rtol=0, atol=tolerance)


def test_ray_maps_are_the_detectors_own_rays_for_pinholes_and_fisheyes():
    """Every 8th pixel of the contract's ray maps is a feature cell's ray: a pinhole's as pixel_rays computes it
    from the intrinsics (the same numbers), a fisheye's as lens_cells does, with no ray beyond 90 degrees."""
    from rigopt.camera import CameraModel, Lens
    from rigopt.validation.detectors.data import Batch

    w, h = 64, 36
    k = torch.tensor([[[30.0, 0, 31.0], [0, 29.0, 17.5], [0, 0, 1]]]).repeat(1, 2, 1, 1)
    batch = Batch(torch.zeros(1, 2, 3, h, w), k, torch.eye(4).repeat(1, 2, 1, 1), [], [])
    rays = external.pixel_ray_maps(batch)
    assert rays.shape == (1, 2, h, w, 3)
    _, directions = pixel_rays(k, torch.eye(4).repeat(1, 2, 1, 1), (5, 8), 8)
    assert torch.equal(rays[:, :, ::8, ::8], directions)
    fisheye = Lens(w, h, 14.0, 14.0, 32.0, 18.0, "fisheye", (0.0, 0.0, 0.0, 0.0))  # 150 degrees off axis at a corner
    lenses = CameraModel.of_lenses([fisheye, fisheye])
    rays = external.pixel_ray_maps(dataclasses.replace(batch, lenses=lenses))
    cells, in_front = lens_cells(lenses, (5, 8), 8)
    assert torch.allclose(rays[0, :, ::8, ::8], cells, rtol=0, atol=1e-6)
    assert bool((rays[0, :, ::8, ::8][..., 2] > 0).eq(in_front).all()) and not bool(in_front.all())


@pytest.mark.parametrize("case, message", [
    ("wrong_shape", "returned shapes ((1, 5, 6), (1, 5), (1, 5)); the contract expects (boxes (B, K, 7)"),
    ("nan_boxes", "returned NaN or infinite boxes or scores"),
    ("camera_frame", "returned boxes at a median height of 20.0 m; the contract expects the ego frame"),
    ("score_above_one", "returned score 3; the contract expects scores in [0, 1]"),
    ("label_out_of_range", "returned label 9; its card names 2 classes"),
    ("not_a_pair", "the factory returned str; the contract expects a (detector, card) pair"),
    ("unknown_class", "classes ['car', 'tram']; the contract expects a list of names from car, truck"),
    ("no_tuple", "returned a Tensor; the contract expects three tensors"),
])
def test_a_detector_that_breaks_the_contract_gets_one_error_line(home, case, message):
    done = run_console("validate", "R1", "--ref", "R1", "--detector", f"contract_cases:{case}", "--workers", "1",
                       env=home)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert lines[-1].startswith("rigopt: error: ") and message in lines[-1], done.stderr
    assert "Traceback" not in done.stderr and done.stdout == ""


def test_validate_with_the_exported_file_or_an_entry_point_gives_the_models_drops(exported, home, tmp_path):
    """The acceptance of the contract on the tiny pack: R5 from R1 with --detector FILE equals --model lss's seed 0
    (drop, visible-only drop, interval), and an entry point wrapping the file equals the file."""
    path, _ = exported
    results = {}
    for name, how in (("model", ["--model", "lss"]), ("file", ["--detector", path]),
                      ("entry", ["--detector", "contract_cases:from_file"])):
        done = run_console("validate", "R5", "--ref", "R1", *how, "--workers", "1", "--json",
                           env={**home, "CONTRACT_FILE": str(path)})
        assert done.returncode == 0, done.stderr
        results[name] = json.loads(done.stdout)
    model = results["model"]["rigs"][0]["seeds"]["0"]
    for name in ("file", "entry"):
        theirs = results[name]
        assert theirs["models"] == "yours" and theirs["seeds"] == [0] and theirs["image_size"] == list(SIZE)
        seed = theirs["rigs"][0]["seeds"]["0"]
        for key in ("drop", "drop_visible", "reference_mAP", "mAP"):
            assert seed[key] == pytest.approx(model[key], rel=0, abs=1e-6), key
        assert seed["drop_ci"] == pytest.approx(model["drop_ci"], abs=1e-6)
    assert results["model"]["rigs"][0]["drop"] != pytest.approx(0, abs=1e-3)  # a drop to agree on, not two zeros


def test_a_detector_at_another_image_size_is_scored_on_renderings_of_that_size(exported, home, tmp_path):
    path, detector = exported
    bigger = tmp_path / "bigger.pt"
    external.export_torchscript(detector.checkpoint(0), bigger, (96, 54))
    done = run_console("validate", "R1", "--ref", "R1", "--detector", bigger, "--workers", "1", "--json", env=home)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["image_size"] == [96, 54] and result["rigs"][0]["cache"].endswith("-96x54")
    assert result["rigs"][0]["drop"] == pytest.approx(0, abs=1e-12)  # the reference against itself


@pytest.mark.parametrize("args, message", [
    (["validate", "R5", "--ref", "R1", "--model", "lss", "--detector", "x.pt"], "or --detector (your own"),
    (["validate", "R5", "--ref", "R1", "--detector", "{tmp}/none.pt"], "no such file, nor an entry point"),
    (["validate", "R5", "--ref", "R1", "--detector", "{tmp}/model.onnx"], "ONNX files are not read"),
    (["validate", "R5", "--ref", "R1", "--detector", "{tmp}/model.pt"], "not a TorchScript file torch can load"),
    (["validate", "R5", "--ref", "R1", "--detector", "x.pt", "--data", "{tmp}"], "--detector is scored on the"),
    (["validate", "R5", "--ref", "R1", "--model", "lss", "--detectors", "{tmp}/none"], "--detectors"),
    (["detectors", "export", "--out", "{tmp}/a.pt"], "give --ref (a packed model"),
    (["detectors", "export", "--out", "{tmp}/a.pt", "--ref", "R1", "--seed", "7"], "--seed 7: the pack"),
    (["detectors", "export", "--out", "{tmp}/a.txt", "--ref", "R1"], "--out"),
    (["detectors", "train", "--ref", "R1", "--out", "{tmp}/p", "--seeds", "0,0"], "--seeds '0,0': give distinct"),
])
def test_bad_detector_options_get_one_error_line(args, message, tmp_path):
    (tmp_path / "model.onnx").write_bytes(b"onnx")
    (tmp_path / "model.pt").write_bytes(b"not torchscript")
    done = run_console(*(a.replace("{tmp}", str(tmp_path)) for a in args))
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rigopt: error: ") and message in lines[0], done.stderr


def test_a_card_without_the_contract_is_refused(tmp_path):
    module = torch.jit.trace(torch.nn.Identity(), torch.zeros(1))
    torch.jit.save(module, str(tmp_path / "bare.pt"))
    with pytest.raises(DataError, match="carries no rigopt.json"):
        external.load_detector(str(tmp_path / "bare.pt"))
    torch.jit.save(module, str(tmp_path / "old.pt"), _extra_files={"rigopt.json": json.dumps({"contract": 0})})
    with pytest.raises(DataError, match="card says contract 0; this rigopt reads contract 1"):
        external.load_detector(str(tmp_path / "old.pt"))


#: Entry points for the tests: detectors that break the contract one way each, and one that keeps it by loading
#: the exported file named in $CONTRACT_FILE.
CONTRACT_CASES = textwrap.dedent('''
    import os
    import torch

    CARD = {"contract": 1, "image_size": [64, 36], "classes": ["car", "adult"], "batch_size": 4}


    def answer(boxes=None, scores=None, labels=None):
        def detector(images, intrinsics, cam_to_ego, rays):
            b = images.shape[0]
            box = torch.tensor([[10.0, 0.0, 0.8, 4.0, 1.8, 1.5, 0.0]]).repeat(b, 5, 1)
            return (box if boxes is None else boxes(box), torch.full((b, 5), 0.5) if scores is None else scores(b),
                    torch.zeros(b, 5, dtype=torch.long) if labels is None else labels(b))
        return detector


    def wrong_shape():
        return answer(boxes=lambda box: box[..., :6]), CARD


    def nan_boxes():
        return answer(boxes=lambda box: box.index_fill(2, torch.tensor([1]), float("nan"))), CARD


    def camera_frame():
        return answer(boxes=lambda box: box.index_fill(2, torch.tensor([2]), 20.0)), CARD


    def score_above_one():
        return answer(scores=lambda b: torch.full((b, 5), 3.0)), CARD


    def label_out_of_range():
        return answer(labels=lambda b: torch.full((b, 5), 9, dtype=torch.long)), CARD


    def not_a_pair():
        return "detector"


    def unknown_class():
        return answer(), {**CARD, "classes": ["car", "tram"]}


    def no_tuple():
        return (lambda *inputs: torch.zeros(1)), CARD


    def from_file():
        import json
        extra = {"rigopt.json": ""}
        module = torch.jit.load(os.environ["CONTRACT_FILE"], _extra_files=extra)
        return module, json.loads(extra["rigopt.json"])
''')
