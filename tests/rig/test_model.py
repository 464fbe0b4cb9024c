"""rigopt.rig.model: Camera and Rig validation and their frozen, read-only arrays."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rigopt.errors import RigFileError, RigoptError
from rigopt.geometry import rot_z
from rigopt.benchmark import BENCHMARK_IMAGE_SIZE
from rigopt.rig.model import Camera, Rig


def _camera(**overrides):
    fields = dict(id="CAM_FRONT", position=[1.0, 0.0, 1.5], rotation=np.eye(3), fov=60.0)
    fields.update(overrides)
    return Camera.pinhole(**fields)


# --- valid cameras --------------------------------------------------------------------------------------


def test_camera_defaults_and_conversions():
    camera = _camera(fov=65)
    assert camera.image_size == BENCHMARK_IMAGE_SIZE == (1280, 720)
    assert camera.zone is None
    assert isinstance(camera.fov, float) and camera.fov == 65.0
    assert camera.position.dtype == float and camera.position.shape == (3,)
    assert camera.rotation.dtype == float and camera.rotation.shape == (3, 3)


def test_camera_accepts_numpy_integer_image_size():
    camera = _camera(image_size=(np.int64(1920), np.int32(1080)))
    assert camera.image_size == (1920, 1080)
    assert all(type(v) is int for v in camera.image_size)


def test_camera_forward_is_the_first_rotation_column():
    camera = _camera(rotation=rot_z(math.pi / 2))
    np.testing.assert_allclose(camera.forward, [0.0, 1.0, 0.0], atol=1e-15)


def test_camera_copies_its_inputs():
    position, rotation = np.array([1.0, 2.0, 3.0]), np.eye(3)
    camera = _camera(position=position, rotation=rotation)
    position[0] = 99.0
    rotation[0, 0] = -1.0
    np.testing.assert_array_equal(camera.position, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(camera.rotation, np.eye(3))


@pytest.mark.parametrize("attribute", ["position", "rotation"])
def test_camera_arrays_are_read_only(attribute):
    array = getattr(_camera(), attribute)
    with pytest.raises(ValueError):
        array[0] = 5.0


def test_camera_fields_cannot_be_reassigned():
    camera = _camera()
    with pytest.raises(AttributeError):
        camera.fov = 90.0


# --- invalid cameras ------------------------------------------------------------------------------------

INVALID_CAMERAS = {
    "NaN position": dict(position=[float("nan"), 0.0, 0.0]),
    "inf position": dict(position=[0.0, float("inf"), 0.0]),
    "position of length 2": dict(position=[0.0, 0.0]),
    "position of length 4": dict(position=[0.0, 0.0, 0.0, 0.0]),
    "position as a matrix": dict(position=np.zeros((3, 1))),
    "scalar position": dict(position=1.0),
    "rotation 2x2": dict(rotation=np.eye(2)),
    "rotation 3x4": dict(rotation=np.eye(3, 4)),
    "flat rotation": dict(rotation=np.eye(3).ravel()),
    "NaN rotation": dict(rotation=np.full((3, 3), float("nan"))),
    "reflection": dict(rotation=np.diag([1.0, -1.0, 1.0])),
    "scaled rotation": dict(rotation=2.0 * np.eye(3)),
    "sheared rotation": dict(rotation=[[1.0, 0.2, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
    "zero rotation": dict(rotation=np.zeros((3, 3))),
    "fov 0": dict(fov=0.0),
    "fov 180": dict(fov=180.0),
    "negative fov": dict(fov=-30.0),
    "NaN fov": dict(fov=float("nan")),
    "inf fov": dict(fov=float("inf")),
    "fov not a number (str)": dict(fov="wide"),
    "fov not a number (None)": dict(fov=None),
    "fov not a number (list)": dict(fov=[60.0]),
    "image_size zero width": dict(image_size=(0, 720)),
    "image_size negative": dict(image_size=(1280, -720)),
    "image_size one value": dict(image_size=(1280,)),
    "image_size three values": dict(image_size=(1280, 720, 3)),
    "image_size floats": dict(image_size=(1280.0, 720.0)),
    "image_size strings": dict(image_size=("1280", "720")),
    "empty id": dict(id=""),
    "id not a string": dict(id=7),
    "id None": dict(id=None),
    "id with a terminal escape": dict(id="CAM\x1b[31mRED"),
    "id with a newline": dict(id="CAM\nFRONT"),
    "id with a NUL": dict(id="CAM\x00"),
    "zone with a control character": dict(zone="roof\x07"),
    "module empty": dict(module=""),
    "module not a string": dict(module=3),
    "position 1000 km away": dict(position=[1.0e6, 0.0, 1.0]),
}


@pytest.mark.parametrize("overrides", list(INVALID_CAMERAS.values()), ids=list(INVALID_CAMERAS))
def test_invalid_camera_raises_rig_file_error(overrides):
    with pytest.raises(RigFileError):
        _camera(**overrides)


# Inputs numpy or tuple() cannot even convert escape as plain ValueError / TypeError instead of the
# RigFileError (a RigoptError) the model promises for every malformed value.
UNCONVERTIBLE_CAMERAS = {
    "non-numeric position": dict(position=["x", 0.0, 0.0]),
    "ragged rotation": dict(rotation=[[1.0, 0.0, 0.0], [0.0, 1.0], [0.0, 0.0, 1.0]]),
    "image_size an int": dict(image_size=1280),
    "image_size None": dict(image_size=None),
}


@pytest.mark.parametrize("overrides", list(UNCONVERTIBLE_CAMERAS.values()), ids=list(UNCONVERTIBLE_CAMERAS))
def test_unconvertible_camera_value_raises_rig_file_error(overrides):
    with pytest.raises(RigFileError):
        _camera(**overrides)


def test_rig_file_error_is_a_rigopt_error_and_a_value_error():
    with pytest.raises(RigoptError):
        _camera(fov=0.0)
    with pytest.raises(ValueError):
        _camera(fov=0.0)


def test_invalid_camera_message_names_the_camera():
    with pytest.raises(RigFileError, match="CAM_LEFT"):
        _camera(id="CAM_LEFT", fov=200.0)


@given(fov=st.floats(1e-300, 180.0, exclude_max=True))
def test_every_fov_strictly_between_0_and_180_is_accepted(fov):
    assert _camera(fov=fov).fov == fov  # (below 1e-300 deg the focal length overflows: no pinhole there)


@given(angle=st.floats(1e-4, 0.1))
def test_a_visibly_non_orthonormal_rotation_is_rejected(angle):
    rotation = rot_z(0.3).copy()
    rotation[:, 0] *= 1.0 + angle
    with pytest.raises(RigFileError):
        _camera(rotation=rotation)


# --- rigs -----------------------------------------------------------------------------------------------


def test_rig_without_cameras_raises():
    with pytest.raises(RigFileError, match="no cameras"):
        Rig("empty", "vehicle.test", ())
    with pytest.raises(RigFileError):
        Rig("empty", "vehicle.test")


def test_rig_with_duplicate_ids_raises_and_names_the_id():
    with pytest.raises(RigFileError, match="CAM_FRONT"):
        Rig("dup", "vehicle.test", (_camera(), _camera(position=[0.0, 1.0, 1.0])))


def test_rig_accepts_a_list_and_stores_a_tuple():
    cameras = [_camera(id="A"), _camera(id="B")]
    rig = Rig("two", "vehicle.test", cameras)
    assert isinstance(rig.cameras, tuple)
    assert [c.id for c in rig.cameras] == ["A", "B"] and len(rig) == 2


@given(rig=st.from_type(Rig))
def test_rig_array_shapes_and_values(rig):
    n = len(rig)
    assert rig.positions.shape == (n, 3)
    assert rig.rotations.shape == (n, 3, 3)
    assert rig.fovs.shape == (n,)
    for k, camera in enumerate(rig.cameras):
        np.testing.assert_array_equal(rig.positions[k], camera.position)
        np.testing.assert_array_equal(rig.rotations[k], camera.rotation)
        assert rig.fovs[k] == camera.fov


@pytest.mark.parametrize("attribute, index", [("positions", (0, 0)), ("rotations", (0, 0, 0)), ("fovs", (0,))])
def test_rig_arrays_are_read_only(attribute, index):
    rig = Rig("two", "vehicle.test", (_camera(id="A"), _camera(id="B")))
    array = getattr(rig, attribute)
    with pytest.raises(ValueError):
        array[index] = 1.0


# --- same_as --------------------------------------------------------------------------------------------


@given(rig=st.from_type(Rig))
def test_rig_is_same_as_itself(rig):
    assert rig.same_as(rig)


@pytest.mark.parametrize(
    "change",
    [dict(position=[1.0, 0.0, 1.5 + 1e-6]), dict(rotation=rot_z(1e-6)), dict(fov=60.0 + 1e-6),
     dict(image_size=(1920, 1080)), dict(zone="roof"), dict(id="CAM_OTHER")],
    ids=["position", "rotation", "fov", "image_size", "zone", "id"],
)
def test_same_as_sees_every_field(change):
    assert not _camera().same_as(_camera(**change))
    assert _camera().same_as(_camera(**change), atol=1e-3) == ("position" in change or "rotation" in change
                                                               or "fov" in change)


def test_rig_same_as_compares_name_vehicle_and_count():
    rig = Rig("r", "vehicle.a", (_camera(id="A"), _camera(id="B")))
    assert rig.same_as(Rig("r", "vehicle.a", (_camera(id="A"), _camera(id="B"))))
    assert not rig.same_as(Rig("other", "vehicle.a", rig.cameras))
    assert not rig.same_as(Rig("r", "vehicle.b", rig.cameras))
    assert not rig.same_as(Rig("r", "vehicle.a", rig.cameras[:1]))
    assert not rig.same_as(Rig("r", "vehicle.a", rig.cameras[::-1]))


def test_printable_names_in_any_script_are_accepted():
    """Printable text is not only ASCII: accented and non-Latin names are fine."""
    camera = _camera(id="Kamera vorn ü 前", zone="dach", module="roof cluster")
    assert camera.id == "Kamera vorn ü 前" and camera.module == "roof cluster"
