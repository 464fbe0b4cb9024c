"""Bad input at the import edges is refused with one clear RigFileError, never a traceback or a silently wrong
rig: Waymo tables and TFRecords without rows or records, URDF FOVs outside (0, pi) or disagreeing with the
intrinsics, URDF joints that do not form one tree, nuScenes image sizes of 0, and image sizes beyond any camera."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ElementTree

import numpy as np
import pyarrow as pa
import pyarrow.parquet as parquet
import pytest

from in_process import refused, run_rigopt
from rigopt.errors import RigFileError, RigoptError
from rigopt.rig.formats.datasets import WAYMO_COLUMNS, read_waymo
from rigopt.rig.formats.nuscenes import SAMPLE_DATA_FILE, nuscenes_token, read_nuscenes, write_nuscenes_calibration
from rigopt.rig.formats.urdf import FOV_AGREEMENT_DEG, export_urdf, read_urdf
from rigopt.rig.library import load_rig


# --------------------------------------------------------------------------------------------------- Waymo


def test_a_waymo_v2_table_without_rows_is_refused(tmp_path):
    """The right columns (Waymo's v2 camera_calibration names) and no row: no camera, said as such."""
    path = tmp_path / "camera_calibration.parquet"
    types = {"key.segment_context_name": pa.string(), "key.camera_name": pa.int8(),
             "[CameraCalibrationComponent].extrinsic.transform": pa.list_(pa.float64()),
             "[CameraCalibrationComponent].width": pa.int32(), "[CameraCalibrationComponent].height": pa.int32()}
    parquet.write_table(pa.table({c: pa.array([], type=types.get(c, pa.float64())) for c in WAYMO_COLUMNS}), path)
    with pytest.raises(RigFileError, match=r"camera_calibration\.parquet: the Waymo v2 camera_calibration table has "
                                           r"its columns but no rows"):
        read_waymo(path)
    out = tmp_path / "r.json"
    refused(run_rigopt("import", "waymo", path, "--out", out), "no rows")
    assert not out.exists()
    refused(run_rigopt("import", "waymo", path, "--list"), "no rows")


def test_a_waymo_v1_tfrecord_without_records_is_refused(tmp_path):
    path = tmp_path / "segment-empty.tfrecord"
    path.write_bytes(b"")
    with pytest.raises(RigFileError, match=r"segment-empty\.tfrecord: the TFRecord file holds no records"):
        read_waymo(path)
    out = tmp_path / "r.json"
    refused(run_rigopt("import", "waymo", tmp_path, "--out", out), "holds no records")  # its folder too
    assert not out.exists()


# ---------------------------------------------------------------------------------------------------- URDF


def r1_urdf() -> ElementTree.Element:
    """R1 as rigopt exports it: every camera with <horizontal_fov> and <lens><intrinsics>."""
    return ElementTree.fromstring(export_urdf(load_rig("R1")).files[""].split("\n", 1)[1])


def write(tmp_path, robot: ElementTree.Element):
    path = tmp_path / "robot.urdf"
    path.write_text(ElementTree.tostring(robot, encoding="unicode"))
    return path


def first_camera(robot):
    return robot.find("gazebo/sensor/camera")


def drop_intrinsics(robot) -> None:
    for camera in robot.iter("camera"):
        camera.remove(camera.find("lens"))


@pytest.mark.parametrize("with_intrinsics", [True, False])
@pytest.mark.parametrize("fov", ["0", "4", "-1", "3.1415926536"])
def test_a_horizontal_fov_outside_0_pi_is_refused_with_or_without_intrinsics(tmp_path, fov, with_intrinsics):
    robot = r1_urdf()
    if not with_intrinsics:
        drop_intrinsics(robot)
    first_camera(robot).find("horizontal_fov").text = fov
    with pytest.raises(RigFileError, match=r"<horizontal_fov> must be in \(0, pi\) radians"):
        read_urdf(write(tmp_path, robot))


def test_without_intrinsics_the_fov_gives_the_centred_pinhole(tmp_path):
    robot = r1_urdf()
    drop_intrinsics(robot)
    first_camera(robot).find("horizontal_fov").text = repr(math.radians(70.0))
    camera = read_urdf(write(tmp_path, robot)).rig.cameras[0]
    assert camera.fov == pytest.approx(70.0, abs=1e-9)
    assert camera.lens.cx == camera.image_size[0] / 2


def test_intrinsics_and_a_disagreeing_fov_are_refused(tmp_path):
    robot = r1_urdf()
    intrinsics = first_camera(robot).find("lens/intrinsics")
    fx, width = float(intrinsics.find("fx").text), int(first_camera(robot).find("image/width").text)
    from_intrinsics = 2.0 * math.atan(width / 2.0 / fx)
    first_camera(robot).find("horizontal_fov").text = repr(from_intrinsics + math.radians(2 * FOV_AGREEMENT_DEG))
    with pytest.raises(RigFileError, match=r"<horizontal_fov> .* disagrees with <lens><intrinsics>.*rigopt takes the "
                                           r"intrinsics"):
        read_urdf(write(tmp_path, robot))


def test_intrinsics_win_over_a_fov_that_agrees_within_rounding(tmp_path):
    robot = r1_urdf()
    intrinsics = first_camera(robot).find("lens/intrinsics")
    fx, width = float(intrinsics.find("fx").text), int(first_camera(robot).find("image/width").text)
    rounded = round(2.0 * math.atan(width / 2.0 / fx), 3)  # a hand-written FOV: three decimals
    first_camera(robot).find("horizontal_fov").text = repr(rounded)
    camera = read_urdf(write(tmp_path, robot)).rig.cameras[0]
    assert camera.lens.fx == fx  # the intrinsics give the lens, not the rounded FOV
    assert camera.fov == pytest.approx(load_rig("R1").cameras[0].fov, abs=1e-9)


def test_a_joint_to_an_undeclared_link_is_refused_naming_both(tmp_path):
    robot = r1_urdf()
    joint = robot.find("joint")
    joint.find("parent").set("link", "chassis")
    with pytest.raises(RigFileError, match=rf"joint {joint.get('name')!r}: its parent link 'chassis' is not a declared "
                                           r"<link>"):
        read_urdf(write(tmp_path, robot))
    robot = r1_urdf()
    joint = robot.find("joint")
    robot.remove(robot.find(f"link[@name='{joint.find('child').get('link')}']"))
    with pytest.raises(RigFileError, match=rf"joint {joint.get('name')!r}: its child link .* is not a declared <link>"):
        read_urdf(write(tmp_path, robot))


def test_a_link_with_two_parents_is_refused_naming_both_joints(tmp_path):
    robot = r1_urdf()
    first, second = robot.findall("joint")[0], robot.findall("joint")[2]  # two cameras' body joints
    second.find("child").set("link", first.find("child").get("link"))
    with pytest.raises(RigFileError, match=rf"has two parents \(joint {first.get('name')!r} gives it 'base_link', this "
                                           r"one 'base_link'\)"):
        read_urdf(write(tmp_path, robot))


def test_a_joint_loop_is_refused_even_away_from_the_cameras(tmp_path):
    robot = r1_urdf()
    for name in ("a", "b"):
        ElementTree.SubElement(robot, "link", name=name)
    for name, parent, child in (("ab", "a", "b"), ("ba", "b", "a")):
        joint = ElementTree.SubElement(robot, "joint", name=name, type="fixed")
        ElementTree.SubElement(joint, "parent", link=parent)
        ElementTree.SubElement(joint, "child", link=child)
    with pytest.raises(RigFileError, match=r"the joints form a loop: (a -> b -> a|b -> a -> b)"):
        read_urdf(write(tmp_path, robot))


def test_a_link_declared_twice_is_refused(tmp_path):
    robot = r1_urdf()
    ElementTree.SubElement(robot, "link", name="base_link")
    with pytest.raises(RigFileError, match=r"link 'base_link' is declared twice"):
        read_urdf(write(tmp_path, robot))


def test_the_urdf_command_writes_nothing_for_a_bad_fov(tmp_path):
    robot = r1_urdf()
    first_camera(robot).find("horizontal_fov").text = "0"
    out = tmp_path / "r.json"
    refused(run_rigopt("import", "urdf", write(tmp_path, robot), "--out", out), "<horizontal_fov>")
    assert not out.exists()


# ------------------------------------------------------------------------------------------------ nuScenes


def tables_with_sizes(tmp_path, sizes: dict) -> tuple:
    """R1's nuScenes tables and a sample_data.json with one record per camera: ``sizes`` maps a camera to the
    record's extra keys (width, height); the others get 1920 x 1080."""
    rig = load_rig("R1")
    folder = write_nuscenes_calibration(rig, tmp_path / "tables")
    records = [{"token": f"sd-{c.id}", "calibrated_sensor_token": nuscenes_token("calibrated_sensor", c.id),
                **sizes.get(c.id, {"width": 1920, "height": 1080})} for c in rig.cameras]
    (folder / SAMPLE_DATA_FILE).write_text(json.dumps(records))
    return folder, rig.cameras[0].id


@pytest.mark.parametrize("width, height", [(0, 0), (0, 900), (-1600, 900), (1600.5, 900), ("1600", 900),
                                           (1600, None), (True, 900)])
def test_a_camera_image_size_that_is_not_positive_whole_pixels_is_refused(tmp_path, width, height):
    folder, first = tables_with_sizes(tmp_path, {})
    folder, first = tables_with_sizes(tmp_path, {first: {"width": width, "height": height}})
    with pytest.raises(RigFileError, match=rf"sample_data\.json: record 0 \(token 'sd-{first}'\) .* width and height "
                                           r"must be positive whole pixels"):
        read_nuscenes(folder)


def test_a_camera_record_without_a_size_takes_the_default(tmp_path):
    folder, first = tables_with_sizes(tmp_path, {})
    folder, first = tables_with_sizes(tmp_path, {first: {}})
    rig = read_nuscenes(folder, image_size=(1280, 960)).rig
    assert rig.cameras[0].image_size == (1280, 960)
    assert rig.cameras[1].image_size == (1920, 1080)


def test_the_nuscenes_command_names_the_record_and_writes_nothing(tmp_path):
    folder, first = tables_with_sizes(tmp_path, {})
    folder, first = tables_with_sizes(tmp_path, {first: {"width": 0, "height": 0}})
    out = tmp_path / "r.json"
    refused(run_rigopt("import", "nuscenes", folder, "--out", out), "record 0")
    assert not out.exists()


# ---------------------------------------------------------------------------------------------- image sizes


@pytest.mark.parametrize("args, option", [
    (["import", "nuscenes", "{tmp}/tables", "--out", "{tmp}/r.json", "--image-size", "99999x99999"], "--image-size"),
    (["import", "dgp", "{tmp}/dgp", "--out", "{tmp}/r.json", "--image-size", "20001x10"], "--image-size"),
    (["design", "--vehicle", "tt", "--ref", "R1", "--image-size", "99999x99999"], "--image-size"),
    (["bench", "generate", "--rigs", "R1", "--out", "{tmp}/g", "--size", "99999x99999"], "--size"),
])
def test_image_sizes_beyond_any_camera_are_refused_with_one_message(tmp_path, args, option):
    line = refused(run_rigopt(*(a.format(tmp=tmp_path) for a in args)), option)
    smallest = 1 if option == "--size" else 16  # a rendering size may be tiny, a camera's image may not
    assert line.endswith(f"{option} must be WIDTHxHEIGHT in whole pixels, each side {smallest} to 20000, e.g. "
                         f"1600x900; got {args[-1]!r}")
    assert list(tmp_path.iterdir()) == []


def test_the_largest_image_size_is_taken(tmp_path):
    from rigopt.cli.parsing import MAX_IMAGE_SIDE, MIN_IMAGE_SIDE, parse_image_size

    assert parse_image_size(f"{MAX_IMAGE_SIDE}x{MIN_IMAGE_SIDE}") == (MAX_IMAGE_SIDE, MIN_IMAGE_SIDE)
    assert parse_image_size("16x9", "--size", smallest=1) == (16, 9)  # a rendering size may be tiny
    with pytest.raises(RigoptError, match="each side 16 to 20000"):
        parse_image_size("1x1")  # a camera's may not
    np.testing.assert_array_equal(parse_image_size(" 1600 X 900 "), (1600, 900))
