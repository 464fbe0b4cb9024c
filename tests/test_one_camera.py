"""One camera, one form: a rig camera is a pose and a Lens, a catalogue entry a named Lens, and the benchmark's
image size is written once (rigopt/benchmark.py)."""

from __future__ import annotations

import dataclasses
import pickle
import re
from pathlib import Path

import numpy as np
import pytest

from rigopt.benchmark import BENCHMARK_IMAGE_SIZE
from rigopt.camera import CameraModel, Lens
from rigopt.design.near_field import fisheye_190
from rigopt.design.settings import CatalogueCamera, DesignSettings, catalogue_of, pinhole_catalogue
from rigopt.errors import RigFileError
from rigopt.rig.model import Camera

PACKAGE = Path(__file__).resolve().parents[1] / "rigopt"


def test_a_camera_stores_a_pose_and_a_lens_and_nothing_beside_it():
    names = [f.name for f in dataclasses.fields(Camera)]
    assert names == ["id", "position", "rotation", "lens", "zone", "module", "role"]
    assert "fov" not in names and "image_size" not in names


def test_fov_and_image_size_are_read_from_the_lens():
    camera = Camera("FISH", [1.0, 0.0, 1.0], np.eye(3), fisheye_190().lens)
    assert camera.fov == camera.lens.hfov and camera.image_size == camera.lens.image_size == (1280, 800)
    pinhole = Camera.pinhole("P", [1.0, 0.0, 1.0], np.eye(3), 70.0, (1600, 900))
    assert pinhole.lens == Lens.pinhole(70.0, (1600, 900)) and pinhole.image_size == (1600, 900)
    with pytest.raises(AttributeError):
        pinhole.fov = 60.0


def test_the_pinhole_keeps_the_stated_fov_to_the_bit():
    rng = np.random.default_rng(0)
    fovs = np.concatenate([rng.uniform(1e-3, 180.0, 500), rng.uniform(59.0, 121.0, 500), [65.0, 90.0, 0.1]])
    for fov in fovs.tolist():
        assert fov not in (0.0, 180.0)
        camera = Camera.pinhole("C", [0.0, 0.0, 1.0], np.eye(3), fov)
        assert camera.fov == fov and type(camera.fov) is float
        assert Lens.pinhole(fov).hfov == fov and CatalogueCamera.pinhole(fov).fov == fov
    # the FOV derived back from the focal length through atan is not always the stated float
    assert any(Lens.pinhole(f).derived_hfov != f for f in fovs.tolist())


def test_a_pinhole_camera_pickles_and_compares_as_itself():
    camera = Camera.pinhole("C", [0.5, 0.0, 1.0], np.eye(3), 64.99999999999999, zone="front")
    back = pickle.loads(pickle.dumps(camera))
    assert back.fov == camera.fov and back.lens == camera.lens and back.same_as(camera)
    assert back.lens.stated_hfov == camera.lens.stated_hfov


def test_an_ideal_pinhole_given_as_intrinsics_becomes_the_benchmarks_pinhole_of_its_fov():
    stated = Lens.pinhole(65.0)
    bare = Lens(1280, 720, stated.fx, stated.fy, stated.cx, stated.cy)
    camera = Camera("C", [0.0, 0.0, 1.0], np.eye(3), bare)
    assert camera.lens.stated_hfov == bare.derived_hfov == camera.fov
    model = CameraModel.of_cameras([camera, Camera.pinhole("D", [0.0, 0.0, 1.0], np.eye(3), 65.0)])
    np.testing.assert_array_equal(model.fx, CameraModel.from_fov([camera.fov, 65.0], [(1280, 720)] * 2).fx)


@pytest.mark.parametrize("fov", [0.0, 180.0, -1.0, float("nan"), "wide", None])
def test_a_pinhole_fov_outside_0_180_is_refused(fov):
    with pytest.raises(RigFileError, match="camera 'C' fov"):
        Camera.pinhole("C", [0.0, 0.0, 1.0], np.eye(3), fov)


@pytest.mark.parametrize("lens", [65.0, None, "pinhole", (1280, 720)])
def test_a_camera_without_a_lens_is_refused(lens):
    with pytest.raises(RigFileError, match="must be a rigopt.camera.Lens"):
        Camera("C", [0.0, 0.0, 1.0], np.eye(3), lens)


def test_a_stated_fov_far_from_the_intrinsics_is_refused():
    lens = Lens.pinhole(65.0)
    with pytest.raises(Exception, match="disagrees"):
        Lens(1280, 720, lens.fx, lens.fy, lens.cx, lens.cy, stated_hfov=66.0)


def test_catalogue_entries_are_named_lenses():
    assert [f.name for f in dataclasses.fields(CatalogueCamera)] == ["name", "lens"]
    entries = (*pinhole_catalogue((60.0, 90.0)), *catalogue_of([fisheye_190().lens, 75.0]),
               *DesignSettings().lenses)
    for entry in entries:
        assert isinstance(entry.lens, Lens) and entry.fov == entry.lens.hfov
        camera = entry.camera("C", [1.0, 0.0, 1.0], np.eye(3))
        assert camera.lens == entry.lens and camera.fov == entry.fov
    with pytest.raises(Exception, match="rigopt.camera.Lens"):
        CatalogueCamera("bare FOV", 65.0)


def test_the_benchmark_image_size_is_written_once():
    assert BENCHMARK_IMAGE_SIZE == (1280, 720) and Lens.pinhole(60.0).image_size == BENCHMARK_IMAGE_SIZE
    pattern = re.compile(r"1280\s*,\s*720")
    files = sorted(PACKAGE.rglob("*.py"))
    assert len(files) > 50
    writers = [str(p.relative_to(PACKAGE)) for p in files if pattern.search(p.read_text())]
    assert writers == ["benchmark.py"], f"(1280, 720) written outside rigopt/benchmark.py: {writers}"
