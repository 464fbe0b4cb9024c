"""``rigopt detectors train`` (rigopt/validation/detectors/reference_models.py): models for a reference given as a
rig file, packed so that ``validate --detectors`` uses them; killed half-way and rerun, it resumes and makes the
same models. Tiny models on 64 x 36 px renderings, one training and one test scene of 4 frames, 60 epochs (seconds).

A tiny model trained for seconds detects nothing on scenes it has not seen (mAP 0, which packing rightly refuses),
so here its training scene is the test scene: a ``sitecustomize`` on the command's PYTHONPATH gives the train split
the test split's scene seeds. What these tests check is the command (rendering, training, resuming, packing, the
pack's use), not learning.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time

import numpy as np
import pytest
from console import console_script, run_console

torch = pytest.importorskip("torch")

#: One torch thread in the commands' processes, as in the tests' own (conftest): a tiny model's OpenMP threads spin
#: against any other load on a shared machine.
ONE_THREAD = {**os.environ, "OMP_NUM_THREADS": "1"}
TRAIN = ["--size", "tiny", "--seeds", "0,1", "--scenes", "1", "--test-scenes", "1", "--frames", "4",
         "--image-size", "64x36", "--epochs", "60", "--workers", "1"]
SAME_SCENES = """
import rigopt.validation.synthetic.scenes as scenes

_seeds = scenes.split_seeds
scenes.split_seeds = lambda split, count: _seeds("test" if split == "train" else split, count)
"""


@pytest.fixture(scope="module")
def trains_on_its_test_scene(tmp_path_factory):
    """The environment of a ``detectors train`` whose training scenes are its test scenes (module docstring)."""
    folder = tmp_path_factory.mktemp("same_scenes")
    (folder / "sitecustomize.py").write_text(SAME_SCENES)
    return {**ONE_THREAD, "PYTHONPATH": os.pathsep.join(filter(None, [str(folder), os.environ.get("PYTHONPATH")]))}


@pytest.fixture(scope="module")
def reference_file(tmp_path_factory):
    """R5's cameras in a rig file of its own name (``myref``): a reference rigopt ships no models for."""
    from rigopt.rig.library import load_rig
    from rigopt.rig.pccr_format import rig_to_dict

    path = tmp_path_factory.mktemp("reference") / "myref.json"
    path.write_text(json.dumps(rig_to_dict(load_rig("R5"))))
    return path


@pytest.fixture(scope="module")
def trained(reference_file, trains_on_its_test_scene, tmp_path_factory):
    """(packs folder, the command's result) of one uninterrupted run."""
    out = tmp_path_factory.mktemp("packs")
    done = run_console("detectors", "train", "--ref", reference_file, "--out", out, *TRAIN,
                       env={**trains_on_its_test_scene, "RIGOPT_HOME": str(out / "home")})
    return out, done


def test_the_pack_records_its_recipe_and_own_scores_and_validate_uses_it(reference_file, trained):
    out, done = trained
    assert done.returncode == 0, done.stderr
    assert "packed 2 lss model(s) trained on myref" in done.stdout
    card = json.loads((out / "lss-myref" / "card.json").read_text())
    assert card["reference"] == "myref" and card["recipe"]["preset"] == "tiny" and card["recipe"]["epochs"] == 60
    assert card["recipe"]["command"].startswith("rigopt detectors train --ref myref --model lss --size tiny")
    assert card["train_data"] == {"split": "train", "scenes": 1, "frames": 4, "seed_offset": 0,
                                  "image_size": [64, 36], "samples": 4}
    assert card["test_data"]["scenes"] == 1 and card["test_data"]["image_size"] == [64, 36]
    assert all(card["seeds"][seed]["mAP"] > 0 for seed in ("0", "1"))
    assert set(card["protocols"]) == {"quick"}
    assert (out / "lss-myref" / "rig.json").is_file()  # the reference travels with its pack: --ref myref finds it
    home = {**ONE_THREAD, "RIGOPT_HOME": str(out / "home")}
    measured = run_console("validate", reference_file, "R1", "--ref", "myref", "--model", "lss",
                           "--detectors", out, "--workers", "1", "--json", env=home)
    assert measured.returncode == 0, measured.stderr
    result = json.loads(measured.stdout)
    assert result["models"] == "packed" and result["seeds"] == [0, 1]
    for seed in ("0", "1"):
        assert result["reference_mAP"][seed] == card["protocols"]["quick"]["seeds"][seed]["mAP"]
    itself, other = result["rigs"]
    assert itself["drop"] == pytest.approx(0, abs=1e-12) and other["rig"] == "R1" and other["n_cameras"] == 8
    exported = run_console("detectors", "export", "--ref", "myref", "--detectors", out, "--seed", "1", "--out",
                           out / "mine.pt", env=home)
    assert exported.returncode == 0, exported.stderr
    yours = run_console("validate", "R1", "--ref", "myref", "--detector", out / "mine.pt", "--detectors", out,
                        "--workers", "1", "--json", env=home)
    assert yours.returncode == 0, yours.stderr
    assert json.loads(yours.stdout)["rigs"][0]["drop"] == pytest.approx(other["seeds"]["1"]["drop"], abs=1e-6)
    unknown = run_console("validate", "R1", "--ref", "theirs", "--model", "lss", "--detectors", out, env=home)
    assert unknown.returncode == 2 and "or a packed reference: myref" in unknown.stderr


def test_killed_half_way_it_resumes_and_makes_the_same_models(reference_file, trained, trains_on_its_test_scene,
                                                              tmp_path):
    out = tmp_path / "packs"
    env = {**trains_on_its_test_scene, "RIGOPT_HOME": str(tmp_path / "home")}
    command = [str(console_script()), "detectors", "train", "--ref", str(reference_file), "--out", str(out), *TRAIN]
    running = subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    first_epoch = None
    deadline = time.monotonic() + 240
    while first_epoch is None and running.poll() is None and time.monotonic() < deadline:
        first_epoch = next(out.glob(".work/*/runs/seed0/lss/myref/checkpoint.pt"), None)
        time.sleep(0.02)
    running.send_signal(signal.SIGKILL)
    running.wait()
    assert first_epoch is not None and running.returncode == -signal.SIGKILL, "killed before its first epoch ended"
    assert not (out / "lss-myref").exists()
    done = run_console("detectors", "train", "--ref", reference_file, "--out", out, *TRAIN, env=env)
    assert done.returncode == 0, done.stderr
    assert "done before, skipped" in done.stderr  # the scenes rendered before the kill
    whole, resumed = trained[0] / "lss-myref", out / "lss-myref"
    for seed in ("0", "1"):
        a = torch.load(whole / f"seed{seed}.pt", weights_only=True)["model"]
        b = torch.load(resumed / f"seed{seed}.pt", weights_only=True)["model"]
        assert a.keys() == b.keys() and all(torch.equal(a[key], b[key]) for key in a)
    cards = [json.loads((folder / "card.json").read_text()) for folder in (whole, resumed)]
    assert all(cards[0]["seeds"][seed]["mAP"] == cards[1]["seeds"][seed]["mAP"] > 0 for seed in ("0", "1"))
    with np.load(whole / "bootstrap.npz") as a, np.load(resumed / "bootstrap.npz") as b:
        assert all(np.array_equal(a[key], b[key]) for key in a.files)


def test_the_defaults_are_the_shipped_recipe(monkeypatch):
    """``rigopt detectors train`` with no recipe options makes what rigopt ships: every shipped pack's card records the
    default preset, epochs, training scenes, frames and image size of ``Recipe``."""
    from rigopt.validation.detectors.reference_models import Recipe
    from rigopt.validation.detectors.shipped import shipped_detector, shipped_names

    monkeypatch.delenv("RIGOPT_DETECTORS", raising=False)
    recipe = Recipe()
    packs = [shipped_detector(*name.split("-", 1)) for name in shipped_names()]
    assert {pack.reference for pack in packs} >= {"R1", "nuscenes"}
    for pack in packs:
        card = pack.card
        assert (card["recipe"]["family"], card["recipe"]["preset"], card["recipe"]["epochs"]) == (
            recipe.family, recipe.size, recipe.epochs)
        assert (card["train_data"]["scenes"], card["train_data"]["frames"], tuple(card["train_data"]["image_size"])) == (
            recipe.train_scenes, recipe.frames, tuple(recipe.image_size))
        assert card["test_data"]["scenes"] == recipe.test_scenes
