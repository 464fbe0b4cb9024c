"""Shipped detectors (rigopt/validation/detectors/shipped.py) and ``rigopt validate`` without ``--data``, on tiny models:
packing, the cache, agreement with the --data path, the command's output and its errors."""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from console import run_console
from in_process import run_rigopt

torch = pytest.importorskip("torch")

from rigopt.validation.detectors import shipped  # noqa: E402
from rigopt.cli import INPUT_ERROR, run  # noqa: E402
from rigopt.rig.library import load_rig  # noqa: E402
from rigopt.errors import DataError  # noqa: E402

SIZE, FRAMES = (64, 36), 4  # the packed fixture's test split (conftest.packed)


@pytest.mark.slow
def test_pack_writes_half_weights_and_a_card_with_the_packed_models_own_scores(use_packed):
    from rigopt.validation.detectors.protocol import evaluate_on

    data, _ = use_packed
    detector = shipped.shipped_detector("lss", "R1")
    assert shipped.shipped_names() == ["lss-R1"] and detector.seeds == [0, 1]
    state = torch.load(detector.checkpoint(0), weights_only=True)
    assert "optimizer" not in state and all(v.dtype == torch.float16 for v in state["model"].values()
                                            if v.is_floating_point())
    card = detector.card
    assert card["test_data"] == {"split": "test", "scenes": 1, "frames": FRAMES, "seed_offset": 0,
                                 "image_size": list(SIZE), "samples": FRAMES}
    for seed in (0, 1):
        own = evaluate_on(detector.checkpoint(seed), data, "R1", family="lss")
        assert card["seeds"][str(seed)]["mAP"] == pytest.approx(own["mAP"], abs=1e-12)
        assert np.load(detector.folder / "bootstrap.npz")[f"seed{seed}_mAP_visible"].shape == (200,)
    assert card["size_bytes"] == detector.size_bytes() > 0


@pytest.mark.slow
def test_the_reference_measured_against_itself_loses_nothing_and_a_rerun_renders_nothing(use_packed, tmp_path):
    detector = shipped.shipped_detector("lss", "R1")
    messages = []
    first = shipped.measure([load_rig("R1")], detector, tmp_path / "cache", progress=messages.append)[0]
    for seed in ("0", "1"):
        assert first["seeds"][seed]["drop"] == pytest.approx(0, abs=1e-12)
        assert first["seeds"][seed]["drop_ci"] == pytest.approx([0, 0], abs=1e-12)
    assert first["drop"] == pytest.approx(0, abs=1e-12)
    messages.clear()
    again = shipped.measure([load_rig("R1")], detector, tmp_path / "cache", progress=messages.append)[0]
    assert any("done before, skipped" in m for m in messages) and not any("rendered" in m for m in messages)
    assert shipped.without_resamples(again) == shipped.without_resamples(first)
    for seed, entry in first["seeds"].items():
        assert np.array_equal(entry["resampled_drops"], again["seeds"][seed]["resampled_drops"])


@pytest.mark.slow
def test_under_the_quick_protocol_the_reference_loses_nothing_and_scores_are_kept(use_packed, tmp_path):
    """The pack's quick denominators (taken by weight from the full matching) equal the scores of a rendering of
    the quick frames alone; a second call reads every score from the cache."""
    from rigopt.validation.detectors.measuring import QUICK

    detector = shipped.shipped_detector("lss", "R1")
    assert detector.card["protocols"]["quick"]["samples"] == 1  # frame 0 of the one 4-frame scene
    first = shipped.measure([load_rig("R1"), load_rig("R5")], detector, tmp_path / "cache", protocol=QUICK)
    assert first[0]["protocol"] == "quick" and first[0]["cache"].endswith("-quick-64x36")  # not 160 x 90: named
    for seed in ("0", "1"):
        assert first[0]["seeds"][seed]["drop"] == pytest.approx(0, abs=1e-12)
    kept = sorted((Path(first[1]["cache"]) / shipped.SCORES).glob("*.npz"))
    assert len(kept) == 2
    stamps = [path.stat().st_mtime_ns for path in kept]
    again = shipped.measure([load_rig("R5")], detector, tmp_path / "cache", protocol=QUICK)[0]
    assert [path.stat().st_mtime_ns for path in kept] == stamps  # read, not scored and written again
    assert shipped.without_resamples(again) == shipped.without_resamples(first[1])


@pytest.mark.slow
def test_a_protocol_on_named_scenes_is_added_to_a_pack_as_its_frames_score_there(packed, tmp_path, monkeypatch):
    """add_protocol's path for a protocol with its own scenes (rendered under the protocol, scored as it is), here
    pointed at the card's own scenes (seed offset 0) with quick's frames: the same reference scores as quick's,
    which the pack took by weight from the full matching; the reference then loses nothing under it. The tiny
    models detect nothing on really new scenes, which is refused."""
    from rigopt.validation.detectors.measuring import QUICK, QUICK_NEW_SCENES, Protocol

    root = tmp_path / "detectors"
    shutil.copytree(packed[1], root)
    monkeypatch.setenv("RIGOPT_DETECTORS", str(root))
    named = Protocol("quick-s0", 4, scene_offset=0)
    detector = shipped.shipped_detector("lss", "R1")
    with pytest.raises(DataError, match="no reference scores for protocol quick-s0"):
        shipped.measure([load_rig("R5")], detector, tmp_path / "cache", protocol=named)
    detector = shipped.add_protocol(detector, named, tmp_path / "cache")
    assert shipped.shipped_detector("lss", "R1").card == detector.card  # written to the pack
    assert detector.card["protocols"]["quick-s0"]["scene_offset"] == 0
    for seed, own in detector.card["protocols"]["quick"]["seeds"].items():
        assert detector.card["protocols"]["quick-s0"]["seeds"][seed] == pytest.approx(own, abs=1e-12)
    reference = shipped.measure([load_rig("R1")], detector, tmp_path / "cache", protocol=named)[0]
    assert reference["drop"] == pytest.approx(0, abs=1e-12) and reference["cache"].endswith("-quick-s0-64x36")
    with pytest.raises(DataError, match="scores mAP 0 on R1's quick-s1 scenes"):
        shipped.add_protocol(detector, QUICK_NEW_SCENES, tmp_path / "cache")
    assert "quick-s1" not in shipped.shipped_detector("lss", "R1").card["protocols"]
    assert QUICK.scene_offset is None


@pytest.mark.slow
def test_scoring_the_seeds_in_two_processes_gives_what_one_gives(use_packed, tmp_path):
    detector = shipped.shipped_detector("lss", "R1")
    rig = load_rig("R5")
    messages = []
    parallel = shipped.measure([rig], detector, tmp_path / "cache", workers=2, progress=messages.append)[0]
    assert any("in 2 processes" in m for m in messages)
    serial = shipped.measure([rig], detector, tmp_path / "cache", workers=1)[0]
    assert shipped.without_resamples(parallel) == shipped.without_resamples(serial) and parallel["drop"] > 0


@pytest.mark.slow
def test_a_rig_scores_as_the_data_path_scores_it(use_packed, tmp_path):
    """The cache path and ``--data``'s (render the rig beside the reference, evaluate the checkpoint) agree."""
    from rigopt.validation.detectors.protocol import evaluate_on_rigs
    from rigopt.validation.synthetic.generate import ego_body_lookup, generate_split, split_layout
    from rigopt.validation.synthetic.render import render_rig

    data, _ = use_packed
    detector = shipped.shipped_detector("lss", "R1")
    rig = load_rig("R5")
    from rigopt.validation.detectors.measuring import FULL

    measured = shipped.measure([rig], detector, tmp_path / "cache", protocol=FULL)[0]
    copy = tmp_path / "data"
    shutil.copytree(data / "R1", copy / "R1")
    scenes, size = split_layout(copy / "R1" / "test")
    generate_split([rig], scenes, copy, size, render_rig, ego_body_lookup())
    for seed in (0, 1):
        metrics = evaluate_on_rigs(detector.checkpoint(seed), copy, ["R1", "R5"], family="lss")
        own, other = metrics["R1"]["mAP"], metrics["R5"]["mAP"]
        assert measured["seeds"][str(seed)]["mAP"] == pytest.approx(other, abs=1e-12)
        assert measured["seeds"][str(seed)]["drop"] == pytest.approx((own - other) / own, abs=1e-12)


def test_the_cache_key_follows_the_geometry_not_the_name():
    r1 = load_rig("R1")
    renamed = dataclasses.replace(r1, name="another")
    moved = dataclasses.replace(r1, cameras=(dataclasses.replace(
        r1.cameras[0], position=r1.cameras[0].position + np.array([0.001, 0, 0])), *r1.cameras[1:]))
    assert shipped.rig_key(renamed) == shipped.rig_key(r1) != shipped.rig_key(moved)
    assert shipped.cache_name(dataclasses.replace(r1, name="a b/c")).startswith("a_b_c-")


@pytest.mark.slow
def test_validate_without_data_through_the_console_script(packed, tmp_path):
    """The installed script in a real process: stdout is JSON only."""
    _, root = packed
    env = {**os.environ, "RIGOPT_DETECTORS": str(root), "RIGOPT_HOME": str(tmp_path / "home")}
    process = run_console("validate", "R5", "--ref", "R1", "--model", "lss", "--json", "--workers", "1", env=env,
                          timeout=600)
    assert process.returncode == 0, process.stderr
    result = json.loads(process.stdout)
    assert result["models"] == "shipped" and result["seeds"] == [0, 1]
    entry = result["rigs"][0]
    assert entry["rig"] == "R5" and entry["role"] == "rig" and set(entry["seeds"]) == {"0", "1"}
    assert entry["drop"] == pytest.approx(np.mean([s["drop"] for s in entry["seeds"].values()]))
    assert entry["predicted_drop"] is not None
    assert Path(entry["cache"]).parent == tmp_path / "home" / "cache" / "validate"
    off = abs(entry["drop"] - entry["predicted_drop"]) > 0.15 and not entry["interval_informative"]
    assert (f"R5: predicted {entry['predicted_drop']:.3f}, measured {entry['drop']:.3f}: the prediction is off by "
            f"{abs(entry['drop'] - entry['predicted_drop']):.3f}" in result["contradictions"]) == off


@pytest.mark.slow
def test_validate_several_rigs_in_one_call_gives_what_separate_calls_give(use_packed, tmp_path):
    home = {"RIGOPT_HOME": str(tmp_path / "home")}
    both = run_rigopt("validate", "R5", "R4", "--ref", "R1", "--model", "lss", "--protocol", "quick", "--json",
                      "--workers", "1", env=home)
    assert both.returncode == 0, both.stderr
    result = json.loads(both.stdout)
    assert [e["rig"] for e in result["rigs"]] == ["R5", "R4"] and result["protocol"]["name"] == "quick"
    for name, entry in zip(("R5", "R4"), result["rigs"]):
        alone = run_rigopt("validate", name, "--ref", "R1", "--model", "lss", "--protocol", "quick", "--json",
                           "--workers", "1", env={"RIGOPT_HOME": str(tmp_path / f"home-{name}")})
        assert json.loads(alone.stdout)["rigs"][0]["seeds"] == entry["seeds"]


@pytest.mark.slow
def test_design_measure_through_the_console_script(packed, tmp_path):
    """rigopt design --measure: the design and the two copies measured under the named protocol beside their
    predictions, in report.json and the JSON printed; stdout JSON only."""
    _, root = packed
    env = {**os.environ, "RIGOPT_DETECTORS": str(root), "RIGOPT_HOME": str(tmp_path / "home")}
    process = run_console("design", "--vehicle", "tt", "--ref", "R1", "--measure", "--out", str(tmp_path / "d"),
                          "--json", env=env, timeout=900)
    assert process.returncode == 0, process.stderr
    measured = json.loads(process.stdout)["measured"]
    assert [r["role"] for r in measured["rigs"]] == ["design", "naive transfer", "height-matched transfer"]
    assert measured["protocol"].startswith("protocol quick") and measured["detector"] == "lss-R1"
    for entry, rig in zip(measured["measured"], measured["rigs"]):
        assert rig["measured_drop"] == pytest.approx(entry["drop"]) and entry["protocol"] == "quick"
    assert isinstance(measured["contradictions"], list)
    assert json.loads((tmp_path / "d" / "report.json").read_text())["measured"] == measured
    assert "Measured with the shipped detectors" in (tmp_path / "d" / "report.html").read_text()


@pytest.mark.parametrize("args, message", [
    (["validate", "R5", "--ref", "R5", "--model", "lss"], "no lss models trained on R5 in "),
    (["validate", "R5", "--ref", "R5", "--model", "lss"], "(packed there: lss-R1); make them with rigopt detectors "
                                                           "train --ref R5"),
    (["validate", "R5", "--ref", "R1", "--model", "lss", "--runs", "{tmp}"], "--runs names trained runs of a --data"),
    (["validate", "R5", "--ref", "R1", "--model", "lss", "--data", "{tmp}", "--compare"], "--compare is for the shipped"),
    (["validate", "R5", "--ref", "R1", "--model", "lss", "--cache", "{file}"], "--cache"),
])
@pytest.mark.slow
def test_bad_input_exits_2_with_one_line(use_packed, tmp_path, capsys, args, message):
    (tmp_path / "file").write_text("x")
    capsys.readouterr()
    code = run([a.format(tmp=tmp_path, file=tmp_path / "file") for a in args])
    stderr = capsys.readouterr().err
    assert code == INPUT_ERROR, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rigopt: error: ") and message in lines[0]


@pytest.mark.slow
def test_near_field_cameras_are_not_fed_to_the_detector(use_packed, tmp_path, capsys):
    """A rig with near_field cameras is measured on its perception cameras, and whole for the record."""
    from rigopt.rig.pccr_format import write_rig

    r5 = load_rig("R5")
    mixed = dataclasses.replace(r5, name="mixed", cameras=(dataclasses.replace(r5.cameras[0], role="near_field"),
                                                           *r5.cameras[1:]))
    path = write_rig(mixed, tmp_path / "mixed.json")
    capsys.readouterr()
    code = run(["validate", str(path), "--ref", "R1", "--model", "lss", "--json", "--workers", "1",
                "--cache", str(tmp_path / "cache")])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    entries = json.loads(captured.out)["rigs"]
    assert [(e["role"], e["n_cameras"]) for e in entries] == [("perception cameras", 3), ("whole rig", 4)]
    assert "1 near_field camera(s) are not fed to the detector" in captured.err


@pytest.mark.slow
def test_a_rig_with_near_field_fisheyes_is_measured_whole_through_its_lenses(use_packed, tmp_path, capsys):
    """The shipped lss models lift a fisheye's cells along its lens's rays: the perception cameras are fed, the
    whole rig, fisheye included, is measured for the record."""
    from rigopt.design.near_field import fisheye_190
    from rigopt.rig.pccr_format import write_rig

    r5 = load_rig("R5")
    fisheye = dataclasses.replace(r5.cameras[0], id="FISHEYE", role="near_field", lens=fisheye_190().lens)
    path = write_rig(dataclasses.replace(r5, name="with_fisheye", cameras=(*r5.cameras, fisheye)), tmp_path / "f.json")
    capsys.readouterr()
    code = run(["validate", str(path), "--ref", "R1", "--model", "lss", "--json", "--workers", "1",
                "--cache", str(tmp_path / "cache")])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    result = json.loads(captured.out)
    assert [(e["role"], e["n_cameras"]) for e in result["rigs"]] == [("perception cameras", 4), ("whole rig", 5)]
    assert all(e["drop"] is not None for e in result["rigs"])
    assert result["near_field"]["whole_rig"]["measured"] and result["near_field"]["near_field_cameras"] == ["FISHEYE"]
    assert "and whole (5 cameras) for the record" in captured.err


@pytest.mark.slow
def test_the_table_says_when_the_prediction_interval_is_uninformative(use_packed, tmp_path, capsys):
    """The joint calibration's interval (RigCD's, on request) spans the whole range: the cell and a note say so,
    JSON keeps it; the default prediction from R1, the drop model's, has an informative interval."""
    capsys.readouterr()
    base = ["validate", "R5", "--ref", "R1", "--model", "lss", "--workers", "1", "--cache", str(tmp_path / "c")]
    code = run([*base, "--predictor", "rigcd"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "uninformative" in captured.out and "interval uninformative (wider than the range" in captured.err
    code = run([*base, "--predictor", "rigcd", "--json"])
    result = json.loads(capsys.readouterr().out)
    entry = result["rigs"][0]
    assert entry["interval_informative"] is False and len(entry["predicted_interval"]) == 2
    assert result["predicted_by"] == "RigCD (joint)"
    code = run([*base, "--json"])
    result = json.loads(capsys.readouterr().out)
    assert result["predicted_by"] == "lss-R1-v2 drop model" and result["rigs"][0]["interval_informative"] is True


@pytest.mark.slow
def test_compare_pairs_the_rig_with_each_yardstick_on_the_same_scene_resamples(use_packed, tmp_path, capsys):
    from rigopt.rig.pccr_format import write_rig

    path = write_rig(dataclasses.replace(load_rig("R5"), name="mine"), tmp_path / "mine.json")
    capsys.readouterr()
    code = run(["validate", str(path), "--ref", "R1", "--model", "lss", "--json", "--workers", "1", "--compare",
                "--cache", str(tmp_path / "cache")])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    result = json.loads(captured.out)
    first, others = result["rigs"][0], result["rigs"][1:]
    assert [p["rig"] for p in result["paired"]] == [o["rig"] for o in others] and others
    for paired, other in zip(result["paired"], others):
        for seed, entry in paired["seeds"].items():
            assert entry["difference"] == pytest.approx(first["seeds"][seed]["drop"] - other["seeds"][seed]["drop"],
                                                         abs=1e-12)
            assert entry["ci"][0] <= entry["ci"][1]
        assert paired["difference"] == pytest.approx(np.mean([s["difference"] for s in paired["seeds"].values()]))
    assert all("resampled_drops" not in s for r in result["rigs"] for s in r["seeds"].values())


def test_the_cache_key_changes_with_the_ego_body_drawn(monkeypatch):
    """A rig rendered while its vehicle was unknown (no ego body drawn) is not reused once the vehicle is known, nor
    after its mesh changes."""
    from rigopt.vehicle import placement

    r1 = load_rig("R1")
    with_body = shipped.rig_key(r1)
    monkeypatch.setattr(placement, "known_vehicle", lambda rig: None)
    assert shipped.rig_key(r1) != with_body
    monkeypatch.undo()
    monkeypatch.setattr(shipped, "body_digest", lambda mesh: "another mesh")
    assert shipped.rig_key(r1) != with_body


@pytest.mark.slow
def test_validate_on_a_local_ray_cluster_gives_the_figures_of_one_machine(use_packed, tmp_path):
    """R3 and R6 measured with the renderings and the (rig, seed) scorings as Ray tasks ('local') give the same
    drops, resampled drops too, as two separate runs on this machine, each into a cache of its own; so does the
    command ``rigopt validate R3 R6 --ref R1 --ray local``."""
    ray = pytest.importorskip("ray")
    detector = shipped.shipped_detector("lss", "R1")
    rigs = [load_rig("R3"), load_rig("R6")]
    alone = [shipped.measure([rig], detector, tmp_path / f"alone-{rig.name}")[0] for rig in rigs]
    try:
        clustered = shipped.measure(rigs, detector, tmp_path / "ray", ray_address="local")
        command = run_rigopt("validate", "R3", "R6", "--ref", "R1", "--model", "lss", "--ray", "local", "--json",
                             "--cache", tmp_path / "cli")
    finally:
        ray.shutdown()
    for one, other in zip(alone, clustered):
        figures = [{k: v for k, v in shipped.without_resamples(e).items() if k != "cache"} for e in (one, other)]
        assert figures[0] == figures[1] and other["cache"].startswith(str(tmp_path / "ray"))
        for seed, entry in one["seeds"].items():
            assert np.array_equal(entry["resampled_drops"], other["seeds"][seed]["resampled_drops"])
    assert command.returncode == 0, command.stderr
    assert [e["drop"] for e in json.loads(command.stdout)["rigs"]] == [e["drop"] for e in alone]


def test_both_shipped_packs_test_on_the_default_test_set_and_nuscenes_names_its_own_rig(monkeypatch):
    """The shipped packs (no $RIGOPT_DETECTORS): lss-R1 and lss-nuscenes score on the 16 x 40 test scenes a user's
    detector is scored on where no pack says otherwise, each model at own mAP 0.30 or more there, and ``--ref
    nuscenes`` is the rig inside its pack."""
    monkeypatch.delenv("RIGOPT_DETECTORS", raising=False)
    assert {"lss-R1", "lss-nuscenes"} <= set(shipped.shipped_names())
    for reference in ("R1", "nuscenes"):
        card = shipped.shipped_detector("lss", reference).card
        assert {key: card["test_data"][key] for key in shipped.DEFAULT_TEST_DATA} == shipped.DEFAULT_TEST_DATA
        assert card["bootstrap"] == shipped.DEFAULT_BOOTSTRAP
        assert {"quick", "quick-s1"} <= set(card["protocols"])
        assert all(seed["mAP"] >= 0.30 for seed in card["seeds"].values())  # the stronger detector's bar
    rig = shipped.reference_rig("nuscenes")
    assert rig.name == "nuscenes" and len(rig) == 6 and rig.origin.kind == "rear_axle"
    assert sorted(c.id for c in rig.cameras) == sorted(["CAM_FRONT", "CAM_FRONT_LEFT", "CAM_FRONT_RIGHT", "CAM_BACK",
                                                         "CAM_BACK_LEFT", "CAM_BACK_RIGHT"])
    from rigopt.vehicle.placement import known_vehicle

    assert known_vehicle(rig).name == "renault_zoe"


@pytest.mark.slow
def test_a_nuscenes_rig_is_validated_from_the_nuscenes_reference_with_its_shipped_model(tmp_path):
    """The issue's acceptance: ``rigopt validate <nuScenes rig> --ref nuscenes``, from the shipped pack alone (the
    rig as the benchmark placed it on the tt), one seed, a drop with its interval."""
    rig = Path(__file__).resolve().parents[3] / "measurements" / "rigs" / "real" / "nuscenes.json"
    env = {k: v for k, v in os.environ.items() if k != "RIGOPT_DETECTORS"}
    done = run_console("validate", rig, "--ref", "nuscenes", "--workers", "1", "--json",
                       env={**env, "RIGOPT_HOME": str(tmp_path), "OMP_NUM_THREADS": "1"}, timeout=900)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["reference"] == "nuscenes" and result["detector"] == "lss-nuscenes" and result["seeds"] == [0]
    entry = result["rigs"][0]
    assert entry["seeds"]["0"]["reference_mAP"] > 0.2 and entry["drop_ci"][0] <= entry["drop"] <= entry["drop_ci"][1]


def test_rank_and_rigcd_take_a_packed_reference_by_name():
    """``--ref nuscenes`` (the rig inside its pack) in rank, and the name as a rig in rigcd: the same rig as its file,
    so the distance between the two is 0."""
    ranked = run_console("rank", "R1", "--ref", "nuscenes", "--json")
    assert ranked.returncode == 0, ranked.stderr
    assert [(r["reference"], r["rig"]) for r in json.loads(ranked.stdout)] == [("nuscenes", "R1")]
    rig_file = Path(__file__).resolve().parents[3] / "studies" / "second_reference" / "nuscenes.json"
    distance = run_console("rigcd", "nuscenes", rig_file, "--json")
    assert distance.returncode == 0, distance.stderr
    assert json.loads(distance.stdout)["rigcd"] == pytest.approx(0, abs=1e-9)
