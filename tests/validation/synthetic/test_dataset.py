"""The benchmark's nuScenes layout: written by generate_split, read back by read_dataset."""

import json
from dataclasses import dataclass

import numpy as np
import pytest

from rigopt.validation.synthetic import generate as generate_module
from rigopt.validation.synthetic.dataset import read_dataset, visibility_token
from rigopt.validation.synthetic.generate import generate_split
from rigopt.validation.synthetic.scene_model import SAMPLE_INTERVAL_US, Boxes, Frame, Road, Scene
from rigopt.errors import DataError, RigoptError
from rigopt.geometry import R_CAM_OPTICAL, rot_z
from rigopt.rig.library import load_rig


@dataclass(frozen=True)
class FakeRendered:
    rgb: np.ndarray
    depth: np.ndarray
    intrinsics: np.ndarray
    object_id: np.ndarray


def fake_render_rig(scene, k, rig, ego, size):
    w, h = size
    k_matrix = np.array([[w / 2, 0, w / 2], [0, w / 2, h / 2], [0, 0, 1.0]])
    return {c.id: FakeRendered(np.full((h, w, 3), 10 * k, np.uint8), np.full((h, w), np.inf, np.float32), k_matrix,
                               np.full((h, w), -1, np.int32)) for c in rig.cameras}


def pose(x, y, yaw):
    T = np.eye(4)
    T[:3, :3] = rot_z(yaw)
    T[:3, 3] = [x, y, 0.0]
    return T


@pytest.fixture
def scene():
    road = Road("straight", (np.array([[-100, -7.0], [100, -7.0], [100, 7.0], [-100, 7.0]]),), np.zeros((0, 2, 2)),
                0.15, np.zeros((0, 2, 2)))
    static = Boxes(np.array([[30.0, 10.0, 5.0], [5.0, -6.0, 3.0]]), np.array([[10.0, 8.0, 10.0], [0.3, 0.3, 6.0]]),
                   np.array([0.0, 0.0]), np.array([-1, -1]), np.array([100, 101]))
    frames = []
    for k in range(3):
        agents = Boxes(np.array([[12.0 + k, 1.5, 0.85], [200.0, 0.0, 0.85]]), np.array([[4.5, 1.9, 1.7]] * 2),
                       np.array([0.3, 0.0]), np.array([0, 1]), np.array([1, 2]))
        frames.append(Frame(1_000_000 + k * SAMPLE_INTERVAL_US, pose(k * 1.0, 0.5, 0.1), agents))
    return Scene("scene-test-0000", 7, "mini", road, static, tuple(frames))


@pytest.fixture
def all_visible(monkeypatch):
    monkeypatch.setattr(generate_module, "visible_fractions", lambda boxes, *a: np.full(len(boxes), 0.7))


def test_round_trip_gives_the_scene_boxes_in_the_ego_frame(tmp_path, scene, all_visible):
    rig = load_rig("R1")
    (root,) = generate_split([rig], [scene], tmp_path, (32, 18), fake_render_rig, lambda r: None)
    samples = read_dataset(root)
    assert [s.timestamp_us for s in samples] == [f.timestamp_us for f in scene.frames]
    for sample, frame in zip(samples, scene.frames):
        # Only the annotated agent within 80 m: instance 1 (the other is 200 m away; static ones are class -1).
        assert sample.classes.tolist() == [0]
        T_ego_world = np.linalg.inv(frame.T_world_ego)
        expected = T_ego_world[:3, :3] @ frame.agents.centers[0] + T_ego_world[:3, 3]
        np.testing.assert_allclose(sample.centers[0], expected, atol=1e-6)
        np.testing.assert_allclose(sample.sizes[0], frame.agents.sizes[0], atol=1e-9)
        assert sample.yaws[0] == pytest.approx(0.3 - 0.1, abs=1e-9)
        assert sample.visibility.tolist() == ["3"]
        assert sample.visible_fractions.tolist() == [0.7]
        np.testing.assert_allclose(sample.T_world_ego, frame.T_world_ego, atol=1e-9)


def test_cameras_round_trip_their_pose_and_intrinsics(tmp_path, scene, all_visible):
    rig = load_rig("R1")
    (root,) = generate_split([rig], [scene], tmp_path, (32, 18), fake_render_rig, lambda r: None)
    sample = read_dataset(root)[0]
    assert sorted(sample.images) == sorted(c.id for c in rig.cameras)
    for camera in rig.cameras:
        T = sample.T_ego_cam[camera.id]
        np.testing.assert_allclose(T[:3, :3], camera.rotation @ R_CAM_OPTICAL, atol=1e-9)
        np.testing.assert_allclose(T[:3, 3], camera.position, atol=1e-9)
        assert sample.intrinsics[camera.id][0, 2] == pytest.approx(16.0)
        assert sample.images[camera.id].is_file()


def test_generation_resumes_by_skipping_finished_scenes(tmp_path, scene, all_visible):
    rig = load_rig("R1-c6")
    messages = []
    generate_split([rig], [scene], tmp_path, (16, 9), fake_render_rig, lambda r: None, messages.append)
    generate_split([rig], [scene], tmp_path, (16, 9), fake_render_rig, lambda r: None, messages.append)
    assert any("rendering" in m for m in messages[:1]) and any("skipped" in m for m in messages[1:])
    assert len(read_dataset(tmp_path / "R1-c6" / "mini")) == 3


def test_same_scene_gets_the_same_sample_tokens_under_two_rigs(tmp_path, scene, all_visible):
    roots = generate_split([load_rig("R1"), load_rig("R6")], [scene], tmp_path, (16, 9), fake_render_rig,
                           lambda r: None)
    tokens = [[s.token for s in read_dataset(root)] for root in roots]
    assert tokens[0] == tokens[1]


def test_unseen_boxes_are_kept_with_fraction_zero(tmp_path, scene, monkeypatch):
    monkeypatch.setattr(generate_module, "visible_fractions", lambda boxes, *a: np.zeros(len(boxes)))
    (root,) = generate_split([load_rig("R1")], [scene], tmp_path, (16, 9), fake_render_rig, lambda r: None)
    for sample in read_dataset(root):
        assert sample.classes.tolist() == [0]  # annotated all the same: evaluation counts it
        assert sample.visible_fractions.tolist() == [0.0] and sample.visible.tolist() == [False]
        assert sample.visibility.tolist() == ["1"]


@pytest.mark.parametrize("fraction, token", [(0.0, "1"), (0.39, "1"), (0.4, "2"), (0.79, "3"), (1.0, "4")])
def test_visibility_levels(fraction, token):
    assert visibility_token(fraction) == token


def test_bad_sizes_are_refused(tmp_path, scene):
    with pytest.raises(RigoptError, match="image size"):
        generate_split([load_rig("R1")], [scene], tmp_path, (0, 9), fake_render_rig, lambda r: None)


def test_reading_a_folder_without_tables_is_a_clear_error(tmp_path):
    (tmp_path / "v1.0-mini").mkdir()
    with pytest.raises(DataError, match="missing table"):
        read_dataset(tmp_path)


def test_a_rear_axle_rig_is_rendered_from_its_vehicle_centre(tmp_path, scene, all_visible):
    """An imported rig (rear-axle origin) is moved to its vehicle's centre, the ego frame of the renders and
    the tables; one on an unknown vehicle is rendered from its own origin; both say so."""
    from dataclasses import replace

    from rigopt.rig.model import Rig, RigOrigin

    base = load_rig("R1")
    cameras = tuple(replace(c, position=c.position + np.array([1.43, 0.0, 0.0])) for c in base.cameras)
    on_axle = Rig("axle", "etron", cameras, RigOrigin("rear_axle"))  # etron's rear axle: x = -1.43 m
    unknown = Rig("unknown", "lab_car", cameras, RigOrigin("rear_axle"))
    seen, notes = {}, []

    def recording_render(scene, k, rig, ego, size):
        seen[rig.name] = rig
        return fake_render_rig(scene, k, rig, ego, size)

    generate_split([on_axle, unknown], [scene], tmp_path, (16, 9), recording_render, lambda r: None,
                   note=notes.append)
    assert seen["axle"].origin.is_benchmark
    np.testing.assert_allclose([c.position for c in seen["axle"].cameras], [c.position for c in base.cameras],
                               atol=1e-12)
    assert seen["unknown"].same_as(unknown)
    assert notes == ["axle: positions converted from the rear axle to the vehicle centre of etron (x -1.430 m)",
                     "unknown: positions are measured from the rear axle of 'lab_car', which rigopt does not know; "
                     "kept with that point as the ego origin"]
    tables = tmp_path / "axle" / "mini" / "v1.0-mini"
    sensor = {s["token"]: s["channel"] for s in json.loads((tables / "sensor.json").read_text())}
    written = {sensor[r["sensor_token"]]: r["translation"]
               for r in json.loads((tables / "calibrated_sensor.json").read_text())}
    for camera in base.cameras:  # the tables are in the same frame as the renders
        np.testing.assert_allclose(written[camera.id], camera.position, atol=1e-9)


@pytest.mark.slow
def test_generation_on_ray_writes_what_generation_here_writes(tmp_path):
    """`rigopt bench generate --ray local`: each (rig, scene) pair a task of a local Ray instance (with the
    command's own ego-mesh lookup and console), the same tables, images and depth maps as rendering here."""
    ray = pytest.importorskip("ray")
    if ray.is_initialized():
        pytest.skip("a Ray instance is already running in this process")
    from tests.in_process import run_rigopt

    common = ["bench", "generate", "--rigs", "R5", "R1-c6", "--split", "mini", "--scenes", "1", "--frames", "1",
              "--size", "24x14"]
    assert run_rigopt(*common, "--out", tmp_path / "here").returncode == 0
    try:
        outcome = run_rigopt(*common, "--out", tmp_path / "ray", "--ray", "local")
    finally:
        ray.shutdown()
    assert outcome.returncode == 0, outcome.stderr
    for rig in ("R5", "R1-c6"):
        a, b = tmp_path / "here" / rig / "mini", tmp_path / "ray" / rig / "mini"
        files = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
        assert files and files == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
        assert any(str(f).startswith("depth/") for f in files)
        for name in files:
            assert (a / name).read_bytes() == (b / name).read_bytes(), name
