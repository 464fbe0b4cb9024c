"""The catalogue of bad inputs: every command with each option or file it takes, given something wrong.

Each case is (class, arguments, fragment): the command line after ``rigopt`` ({tmp} is a scratch folder
that :func:`make_fixtures` fills, {repo} the checkout), and a piece of the one ``rigopt: error: ...`` line it must print. The
table in docs/errors.md is written from these by ``run.py`` (through the installed console script), and
tests/cli/test_bad_inputs.py runs each in-process and checks that the table says what rigopt says.

WARNINGS holds the inputs a command takes but flags: it does its work, exits 0 and prints one ``rigopt: warning:
...`` line holding the fragment (docs/errors.md's second table).
"""

from __future__ import annotations

import json
from pathlib import Path

NOT_UTF8 = b"\xff\xfe\x00 not text \xe9"
RIG = '{"vehicle_type": "vehicle.audi.tt", "cameras": [{"id": "C", "location": LOC, "rotation": [0, 0, 0], "fov": 60}]}'
WEIGHTS = {"K": 1, "alpha": 0.5, "lambda_t": 1, "lambda_r": 1, "lambda_f": 1}
CSV_HEADER = "model,train_rig,test_rig,mAP\n"
CAMERA = '[[cameras]]\nname = "cam"\nwidth = 1280\nheight = 960\nfx = 1000\nfy = 1000\ncx = 640\ncy = 480\n'
#: A URDF with one camera (90 deg: fx 640 on 1280 px); HFOV, LENS and EXTRA are filled per case.
URDF = ("<robot name='r'><link name='base_link'/><link name='cam'/>EXTRA<joint name='cam_joint' type='fixed'>"
        "<parent link='PARENT'/><child link='cam'/><origin xyz='1 0 1.5' rpy='0 0 0'/></joint>"
        "<gazebo reference='cam'><sensor type='camera' name='cam'><camera><horizontal_fov>HFOV</horizontal_fov>"
        "<image><width>1280</width><height>720</height></image>LENS</camera></sensor></gazebo></robot>\n")
URDF_LENS = "<lens><intrinsics><fx>640</fx><fy>640</fy><cx>640</cx><cy>360</cy><s>0</s></intrinsics></lens>"


def one_error_line(lines: list[str]) -> bool:
    """The answer to a bad input: stderr's lines hold one ``rigopt: error:`` line, the last; any before it are
    the command's indented progress lines (an error found after some work, such as a design with no feasible
    point)."""
    return bool(lines) and lines[-1].startswith("rigopt: error: ") and all(line.startswith("  ") for line in lines[:-1])


def urdf(hfov="1.5708", lens="", parent="base_link", extra=""):
    """The one-camera URDF with its field of view (rad), lens block, camera joint's parent and extra elements."""
    return URDF.replace("HFOV", hfov).replace("LENS", lens).replace("PARENT", parent).replace("EXTRA", extra)


def fixed_joint(name, parent, child):
    return f"<joint name='{name}' type='fixed'><parent link='{parent}'/><child link='{child}'/></joint>"


def nuscenes_sample_data(width, height):
    """sample_data.json of the nuscenes_two tables' camera record c0 with the image size given."""
    return json.dumps([{"token": "sd0", "calibrated_sensor_token": "c0", "sample_token": "", "width": width,
                        "height": height}])


def make_fixtures(tmp: Path) -> dict[str, str]:
    """Write the files the cases refer to under ``tmp``; returns the environment the cases run in."""
    from rigopt.cli import run
    from rigopt.rig.formats.tfrecord import tfrecord_record
    from rigopt.vehicle.library import load_vehicle

    tmp.mkdir(parents=True, exist_ok=True)
    files = {
        "file.txt": "just a file\n",
        "model.onnx": "not really ONNX\n",
        "rig_not_utf8.json": NOT_UTF8,
        "rig_malformed.json": '{"vehicle_type": "x", "cameras": [',
        "rig_nan.json": RIG.replace("LOC", "[0, NaN, 1]"),
        "rig_far.json": RIG.replace("LOC", "[1e308, 0, 1]"),
        "rig_escape_id.json": RIG.replace("LOC", "[2.1, 0, 0.6]").replace('"id": "C"', '"id": "C\\u001b[31mRED"'),
        "rig_null_id.json": RIG.replace("LOC", "[2.1, 0, 0.6]").replace('"id": "C"', '"id": null'),
        "rig_no_cameras.json": '{"vehicle_type": "v", "cameras": []}',
        "rig_fov_200.json": RIG.replace("LOC", "[0, 0, 1]").replace('"fov": 60', '"fov": 200'),
        "rig_one_camera.json": RIG.replace("LOC", "[2.36, 0, 0.68]"),
        "rig_list.json": "[1, 2, 3]",
        "rig_nested.json": "[" * 100000 + "]" * 100000,
        "rig_beyond_float.json": RIG.replace("LOC", "[1e400, 0, 1]"),
        "weights_huge_lambda.json": json.dumps({**WEIGHTS, "lambda_t": 1e300}),
        "weights_nested.json": '{"K": ' + "[" * 5000 + "]" * 5000 + "}",
        "weights_not_utf8.json": NOT_UTF8,
        "weights_beta_text.json": json.dumps({**WEIGHTS, "beta": {"t": "abc"}}),
        "weights_beta_null.json": json.dumps({**WEIGHTS, "beta": {"r": None}}),
        "weights_beta_list.json": json.dumps({**WEIGHTS, "beta": [1, 2]}),
        "weights_missing_k.json": json.dumps({k: v for k, v in WEIGHTS.items() if k != "K"}),
        "weights_alpha_2.json": json.dumps({**WEIGHTS, "alpha": 2}),
        "weights_negative.json": json.dumps({**WEIGHTS, "lambda_t": -1}),
        "weights_plus.json": json.dumps({**WEIGHTS, "metric": "rigcd+"}),
        "weights_bad_json.json": "{",
        "weights.txt": "K = 1",
        "diagonal.csv": CSV_HEADER + "M,R1,R1,0.3\nM,R6,R6,0.3\n",
        "not_utf8.csv": NOT_UTF8,
        "bad_header.csv": "a,b,c,d\nM,R1,R1,0.3\n",
        "three_fields.csv": CSV_HEADER + "M,R1,0.3\n",
        "map_2.csv": CSV_HEADER + "M,R1,R1,2\n",
        "map_text.csv": CSV_HEADER + "M,R1,R1,abc\n",
        "twice.csv": CSV_HEADER + "M,R1,R1,0.3\nM,R1,R1,0.3\n",
        "empty.csv": "",
        "no_control.csv": CSV_HEADER + "M,R5,R5,0.3\nM,R5,R6,0.2\nM,R6,R6,0.3\n",
        "zones_not_utf8.toml": NOT_UTF8,
        "zones_bad.toml": "[[zones]\n",
        "zones_none.toml": 'name = "nothing"\n',
        "zones_no_max.toml": '[[zones]]\nname = "nose"\nmin = [1, -1, 0]\nnormal = [1, 0, 0]\ncone_deg = 30\n',
        "garbage.pt": b"this is not a checkpoint",
        "nuscenes_not_utf8/sensor.json": NOT_UTF8,
        "nuscenes_not_utf8/calibrated_sensor.json": NOT_UTF8,
        "camchain_bad.yaml": "cam0: [unclosed\n",
        "camchain_no_cam0.yaml": "camera_model: pinhole\n",
        "camchain_fov.yaml": "cam0:\n  intrinsics: [400.0, 400.0, 320.0, 240.0]\n  resolution: [640, 480]\n"
                             "  distortion_model: omni\n",
        "robot.urdf": "<robot name='r'><link name='base_link'/></robot>\n",
        "robot_broken.urdf": "<robot name='r'><link name='base_link'>\n",
        "carla_no_sensors.json": json.dumps({"rig": "x", "vehicle": "vehicle.audi.tt"}),
        "carla_huge_image.json": json.dumps({"sensors": [{"id": "C", "attributes": {"image_size_x": "99999",
                                             "image_size_y": "480", "fov": "90"},
                                             "transform": {"location": {"x": 2, "y": 0, "z": 1.5},
                                                           "rotation": {"pitch": 0, "yaw": 0, "roll": 0}}}]}),
        "camchain_gap.yaml": "cam0:\n  intrinsics: [400.0, 400.0, 320.0, 240.0]\n  resolution: [640, 480]\n"
                             "  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n"
                             "camera_left:\n  intrinsics: [400.0, 400.0, 320.0, 240.0]\n  resolution: [640, 480]\n",
        "camchain_far_centre.yaml": "cam0:\n  intrinsics: [400.0, 400.0, 5320.0, 240.0]\n  resolution: [640, 480]\n"
                                    "  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n",
        "carla_fov_text.json": json.dumps({"sensors": [{"id": "C", "attributes": {"image_size_x": "640", "image_size_y":
                                           "480", "fov": "wide"}, "transform": {}}]}),
        "dgp/calibration/c.json": json.dumps({"names": ["CAMERA_01"], "intrinsics": [{"fx": 1000.0, "skew": 2.0}],
                                              "extrinsics": [{}]}),
        "av2/calibration/intrinsics.feather": "not a feather table",
        "av2/calibration/egovehicle_SE3_sensor.feather": "not a feather table",
        "waymo/camera_calibration.parquet": "not a parquet file",
        "av1/vehicle_calibration_info.json": json.dumps({"camera_data_": [{"key": "image_raw_roof_camera",
                                                                           "value": {}}]}),
        "waymo_v1_text.tfrecord": "a text file, not a TFRecord\n",
        "waymo_v1_truncated.tfrecord": tfrecord_record(b"\x0a" * 100)[:40],
        "waymo_v1_bad_crc.tfrecord": tfrecord_record(b"frame")[:-4] + b"\x00\x00\x00\x00",
        "waymo_v1_no_cameras.tfrecord": tfrecord_record(b""),
        # Frame.context (1) -> camera_calibrations (2) -> name (1) = 9, not a CameraName
        "waymo_v1_camera_9.tfrecord": tfrecord_record(b"\x0a\x04\x12\x02\x08\x09"),
        "nuscenes_two/sensor.json": json.dumps([{"token": "s", "channel": "CAM_FRONT", "modality": "camera"}]),
        "waymo_v1_empty.tfrecord": b"",
        "urdf_fov_0.urdf": urdf(hfov="0"),
        "urdf_fov_4.urdf": urdf(hfov="4", lens=URDF_LENS),
        "urdf_fov_disagrees.urdf": urdf(hfov="1.0", lens=URDF_LENS),
        "urdf_undeclared_parent.urdf": urdf(parent="chassis"),
        "urdf_loop.urdf": urdf(extra="<link name='a'/><link name='b'/>" + fixed_joint("ab", "a", "b")
                               + fixed_joint("ba", "b", "a")),
        "urdf_two_parents.urdf": urdf(extra="<link name='mast'/>" + fixed_joint("mast_joint", "base_link", "mast")
                                      + fixed_joint("cam_on_mast", "mast", "cam")),
        "nuscenes_two/calibrated_sensor.json": json.dumps([
            {"token": f"c{k}", "sensor_token": "s", "translation": [1.0 + k, 0.0, 1.5], "rotation": [0.5, -0.5, 0.5, -0.5],
             "camera_intrinsic": [[1266.4, 0.0, 800.0], [0.0, 1266.4, 450.0], [0.0, 0.0, 1.0]]} for k in range(2)]),
        "results_bad/M/trained_on_R1.json": "{",
        "results_no_diagonal/M/trained_on_R1.json": json.dumps({"results": {"R6": {"metrics": {"mAP": 0.2}}}}),
        "full/x.txt": "occupied folder",
        "cameras_not_utf8.toml": NOT_UTF8,
        "cameras_bad.toml": "[[cameras]\n",
        "cameras_empty.json": '{"cameras": []}',
        "cameras_no_fx.toml": CAMERA.replace("fx = 1000\n", ""),
        "cameras_bad_model.toml": CAMERA + 'distortion = "kb8"\ncoefficients = [0.1]\n',
        "cameras_coefficients.toml": CAMERA + 'distortion = "radtan"\ncoefficients = [0.1]\n',
        "cameras_folding.toml": CAMERA.replace("fx = 1000", "fx = 300").replace("fy = 1000", "fy = 300")
        + 'distortion = "fisheye"\ncoefficients = [0.05, -0.01, 0, 0]\n',
        "cameras_twice.toml": CAMERA + CAMERA,
    }
    for folder, (width, height) in {"nuscenes_size_0": (0, 0), "nuscenes_size_fraction": (1600.5, 900)}.items():
        for table in ("sensor.json", "calibrated_sensor.json"):
            files[f"{folder}/{table}"] = files[f"nuscenes_two/{table}"]
        files[f"{folder}/sample_data.json"] = nuscenes_sample_data(width, height)
    for name, content in files.items():
        path = tmp / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
    for folder in ("emptydir", "dir.png", "dir.json", "dir.urdf"):
        (tmp / folder).mkdir(exist_ok=True)
    _write_empty_waymo_table(tmp / "waymo_empty" / "camera_calibration.parquet")
    _write_inward_rig(tmp / "rig_inward.json")
    _write_sky_rig(tmp / "rig_sky.json")
    load_vehicle("tt").mesh.export(tmp / "car.stl")
    _write_posed_meshes(load_vehicle("tt").mesh, tmp)
    env = {"RIGOPT_HOME": str(tmp / "home")}
    wreck = tmp / "home" / "vehicles" / "wreck"
    wreck.mkdir(parents=True, exist_ok=True)
    (wreck / "vehicle.toml").write_text("name = [unclosed\n")
    odd = tmp / "home" / "vehicles" / "oddcategory"
    odd.mkdir(parents=True, exist_ok=True)
    (odd / "vehicle.toml").write_text('name = "oddcategory"\ncategory = "truck"\n[[solids]]\ntype = "box"\n'
                                      'center = [0, 0, 1]\nsize = [4, 2, 1.5]\n')
    if not (tmp / "home" / "vehicles" / "mycar").is_dir():
        from rigopt.vehicle.user import add_user_vehicle
        import os

        previous = os.environ.get("RIGOPT_HOME")
        os.environ["RIGOPT_HOME"] = env["RIGOPT_HOME"]
        try:
            add_user_vehicle("mycar", tmp / "car.stl")
        finally:
            if previous is None:
                del os.environ["RIGOPT_HOME"]
            else:
                os.environ["RIGOPT_HOME"] = previous
    if not (tmp / "bench" / "R1" / "mini").is_dir():
        code = run(["bench", "generate", "--rigs", "R1", "--scenes", "1", "--frames", "1", "--size", "16x9",
                    "--out", str(tmp / "bench")])
        assert code == 0, "bench generate of the fixture failed"
    images = sorted((tmp / "bench" / "R1" / "mini" / "samples").rglob("*.png"))
    (tmp / "bench_missing").mkdir(exist_ok=True)
    if not (tmp / "bench_missing" / "R1").is_dir():
        import shutil

        shutil.copytree(tmp / "bench" / "R1", tmp / "bench_missing" / "R1")
        (tmp / "bench_missing" / "R1" / "mini" / images[0].relative_to(tmp / "bench" / "R1" / "mini")).unlink()
    return env


def _write_empty_waymo_table(path: Path) -> None:
    """A Waymo v2 camera_calibration Parquet file with the columns rigopt reads and no row."""
    import pyarrow as pa
    import pyarrow.parquet as parquet

    from rigopt.rig.formats.datasets import WAYMO_COLUMNS

    path.parent.mkdir(parents=True, exist_ok=True)
    texts = {"key.segment_context_name": pa.string(), "key.camera_name": pa.int8()}
    parquet.write_table(pa.table({c: pa.array([], type=texts.get(c, pa.float64())) for c in WAYMO_COLUMNS}), path)


def _write_inward_rig(path: Path) -> None:
    """R1 with every camera turned to face the way it came: into the etron's body (it sees nothing)."""
    from dataclasses import replace

    import numpy as np

    from rigopt.geometry import rot_z
    from rigopt.rig.library import load_rig
    from rigopt.rig.model import Rig
    from rigopt.rig.pccr_format import write_rig

    r1 = load_rig("R1")
    write_rig(Rig("R1_inward", r1.vehicle, tuple(replace(c, rotation=c.rotation @ rot_z(np.pi)) for c in r1.cameras)),
              path)


def _write_sky_rig(path: Path) -> None:
    """R1 with every camera pitched 80 degrees up: it sees the sky, none of what R1 sees."""
    from dataclasses import replace

    import numpy as np

    from rigopt.geometry import rot_y
    from rigopt.rig.library import load_rig
    from rigopt.rig.model import Rig
    from rigopt.rig.pccr_format import write_rig

    r1 = load_rig("R1")
    up = rot_y(-np.radians(80.0))  # about the camera's y (left): a negative angle lifts its optical axis
    write_rig(Rig("R1_sky", r1.vehicle, tuple(replace(c, rotation=c.rotation @ up) for c in r1.cameras)), path)


def _write_posed_meshes(mesh, tmp: Path) -> None:
    """The tt's mesh in centimetres, turned by 90 degrees, facing backwards and with y up (for vehicle add)."""
    import numpy as np

    from rigopt.geometry import rot_x, rot_z

    def write(name, matrix):
        posed = mesh.copy()
        posed.apply_transform(matrix)
        posed.export(tmp / name)

    def turn(rotation):
        transform = np.eye(4)
        transform[:3, :3] = rotation
        return transform

    write("car_cm.stl", np.diag([100.0, 100.0, 100.0, 1.0]))
    write("car_turned.stl", turn(rot_z(np.pi / 2)))
    write("car_backwards.stl", turn(rot_z(np.pi)))
    write("car_y_up.stl", turn(rot_x(-np.pi / 2)))


T = "{tmp}"
SHIPPED = "{repo}/metrics/pccr_transfer.csv"
DESIGN = ["design", "--vehicle", "tt", "--ref", "R1"]
CAL = ["calibrate", "--results"]
SHOW = ["vehicle", "show", "tt", "--out"]
BENCH = ["bench", "generate", "--rigs", "R1", "--out", f"{T}/gen"]

#: (class, arguments, fragment of the error line)
CASES: list[tuple[str, list[str], str]] = [
    # --- usage: commands, options, values (click, at parse time) ---
    ("unknown command", ["desgn"], "Did you mean 'design'"),
    ("unknown option", ["rigs", "--jsn"], "--json"),
    ("extra argument", ["rigs", "R1"], "unexpected extra argument"),
    ("missing argument", ["rigv"], "Missing argument"),
    ("missing option", ["design", "--ref", "R1"], "--vehicle"),
    ("option without its value", ["rigcd", "R1", "R5", "--weights"], "requires an argument"),
    ("not a number", [*DESIGN, "--yaw-step", "abc"], "--yaw-step"),
    ("not an integer", [*DESIGN, "--min-coverage", "1.5"], "--min-coverage"),
    # --- rigs given by name or file ---
    ("unknown rig name", ["rigcd", "R1", "R99"], "valid names"),
    ("rig file missing", ["rigv", f"{T}/nofile.json"], "no such rig file"),
    ("rig file is a folder", ["rigv", f"{T}/emptydir"], "emptydir"),
    ("rig file not UTF-8", ["rigv", f"{T}/rig_not_utf8.json"], "not UTF-8"),
    ("rig file not JSON", ["rigv", f"{T}/rig_malformed.json"], "not valid JSON"),
    ("rig file not an object", ["rigv", f"{T}/rig_list.json"], "JSON object"),
    ("rig with NaN", ["rigv", f"{T}/rig_nan.json"], "NaN"),
    ("rig file nested past the parser's limit", ["rigv", f"{T}/rig_nested.json"], "nested too deeply"),
    ("rig number beyond float range", ["rigv", f"{T}/rig_beyond_float.json"], "NaN or inf"),
    ("rig coordinates of 1e308", ["rigv", f"{T}/rig_far.json"], "1000 m"),
    ("rig coordinates of 1e308 (rigcd)", ["rigcd", f"{T}/rig_far.json", "R1"], "1000 m"),
    ("rig coordinates of 1e308 (coverage)", ["coverage", f"{T}/rig_far.json"], "1000 m"),
    ("rig without cameras", ["rigcd", f"{T}/rig_no_cameras.json", "R1"], "non-empty list"),
    ("rig with fov 200", ["rigv", f"{T}/rig_fov_200.json"], "(0, 180)"),
    ("unknown rank candidate", ["rank", "R5", "R77", "--ref", "R1"], "R77"),
    ("unknown rank reference", ["rank", "R5", "--ref", "R77"], "R77"),
    # --- weights and metric ---
    ("unknown weights name", ["rigcd", "R1", "R6", "--weights", "YOLO"], "joint"),
    ("weights file missing", ["rigcd", "R1", "R6", "--weights", f"{T}/nothere.json"], "no such weights file"),
    ("weights file a folder", ["rigcd", "R1", "R6", "--weights", f"{T}/dir.json"], "is a folder"),
    ("weights not UTF-8", ["rigcd", "R1", "R6", "--weights", f"{T}/weights_not_utf8.json"], "not UTF-8"),
    ("weights not JSON", ["rigv", "R1", "--weights", f"{T}/weights_bad_json.json"], "not valid JSON"),
    ("weights not a JSON file", ["rigv", "R1", "--weights", f"{T}/weights.txt"], "not valid JSON"),
    ("weights beta not a number", ["rigcd", "R1", "R6", "--weights", f"{T}/weights_beta_text.json"], "beta.t"),
    ("weights beta null", ["rank", "R6", "--ref", "R1", "--weights", f"{T}/weights_beta_null.json"], "beta.r"),
    ("weights beta a list", ["rigcd", "R1", "R6", "--weights", f"{T}/weights_beta_list.json"], "beta must be"),
    ("weights without K", ["rigcd", "R1", "R6", "--weights", f"{T}/weights_missing_k.json"], "needs the keys"),
    ("weights alpha 2", ["rigcd", "R1", "R6", "--weights", f"{T}/weights_alpha_2.json"], "alpha"),
    ("weights negative lambda", ["rigcd", "R1", "R6", "--weights", f"{T}/weights_negative.json"], "lambda_t"),
    ("weights lambda of 1e300", ["rigcd", "R1", "R6", "--weights", f"{T}/weights_huge_lambda.json"], "from 0 to 1e+06"),
    ("weights file nested past the parser's limit", ["rigcd", "R1", "R6", "--weights", f"{T}/weights_nested.json"],
     "nested too deeply"),
    ("weights of the other metric", ["rigcd", "R1", "R6", "--weights", f"{T}/weights_plus.json"], "--metric rigcd+"),
    ("unknown metric", ["rigcd", "R1", "R6", "--metric", "cd"], "valid names"),
    ("rigcd+ without weights", ["rigcd", "R1", "R6", "--metric", "rigcd+"], "--weights"),
    ("unknown metric (rank)", ["rank", "R6", "--ref", "R1", "--metric", "x"], "valid names"),
    # --- calibrate ---
    ("results missing", [*CAL, f"{T}/no_results"], "no such results"),
    ("results only the diagonal", [*CAL, f"{T}/diagonal.csv"], "only the diagonal"),
    ("results without control pairs", [*CAL, f"{T}/no_control.csv"], "--control"),
    ("results CSV not UTF-8", [*CAL, f"{T}/not_utf8.csv"], "not UTF-8"),
    ("results CSV header", [*CAL, f"{T}/bad_header.csv"], "header"),
    ("results CSV empty", [*CAL, f"{T}/empty.csv"], "header"),
    ("results CSV field count", [*CAL, f"{T}/three_fields.csv"], "3 fields"),
    ("results mAP above 1", [*CAL, f"{T}/map_2.csv"], "[0, 1]"),
    ("results mAP not a number", [*CAL, f"{T}/map_text.csv"], "mAP must be a number"),
    ("results pair twice", [*CAL, f"{T}/twice.csv"], "twice"),
    ("results folder not JSON", [*CAL, f"{T}/results_bad"], "not valid JSON"),
    ("results folder without diagonal", [*CAL, f"{T}/results_no_diagonal"], "diagonal"),
    ("results folder empty", [*CAL, f"{T}/emptydir"], "no transfer results"),
    ("calibrate --bootstrap -1", [*CAL, SHIPPED, "--bootstrap", "-1"], "--bootstrap"),
    ("calibrate --seed -1", [*CAL, SHIPPED, "--seed", "-1"], "--seed"),
    ("calibrate --metric", [*CAL, SHIPPED, "--metric", "x"], "valid names"),
    ("calibrate --out is a file", [*CAL, SHIPPED, "--out", f"{T}/file.txt"], "is a file"),
    ("calibrate --out under a file", [*CAL, SHIPPED, "--out", f"{T}/file.txt/x"],
     "is a file, not a folder"),
    ("calibrate --out not empty", [*CAL, SHIPPED, "--out", f"{T}/full"], "--force"),
    ("calibrate --out empty name", [*CAL, SHIPPED, "--out", ""], "a name of its own"),
    # --- check, vehicles ---
    ("check unknown rig", ["check", "R99"], "R99"),
    ("check unknown vehicle", ["check", "R1", "--vehicle", "nosuchcar"], "nosuchcar"),
    ("check broken user vehicle", ["check", "R1", "--vehicle", "wreck"], "user vehicle 'wreck' cannot be read"),
    ("check rig file not UTF-8", ["check", f"{T}/rig_not_utf8.json"], "not UTF-8"),
    # --- vehicle show / export / add ---
    ("show unknown vehicle", ["vehicle", "show", "nosuchcar", "--out", f"{T}/x.png"], "nosuchcar"),
    ("show picture extension .txt", [*SHOW, f"{T}/x.txt"], ".txt is not a format"),
    ("show without extension", [*SHOW, f"{T}/cov07"], "no extension"),
    ("show --out is a folder", [*SHOW, f"{T}/emptydir"], "no extension"),
    ("show --out folder named .png", [*SHOW, f"{T}/dir.png"], "is a folder"),
    ("show --out under a file", [*SHOW, f"{T}/file.txt/x.png"], "is a file, not a folder"),
    ("show --out empty", [*SHOW, ""], "no extension"),
    ("show unknown rig", [*SHOW, f"{T}/x.png", "--rig", "R99"], "R99"),
    ("export unknown format", ["vehicle", "export", "tt", "--out", f"{T}/x.xyz"], ".ply"),
    ("export unknown frame", ["vehicle", "export", "tt", "--out", f"{T}/x.ply", "--frame", "enu"], "--frame"),
    ("export unknown vehicle", ["vehicle", "export", "nosuchcar", "--out", f"{T}/x.ply"], "nosuchcar"),
    ("export --out under a file", ["vehicle", "export", "tt", "--out", f"{T}/file.txt/x.ply"], "is a file"),
    ("add name with spaces", ["vehicle", "add", "my car", "--mesh", f"{T}/car.stl"], "letters, digits"),
    ("add built-in name", ["vehicle", "add", "etron", "--mesh", f"{T}/car.stl"], "built-in"),
    ("add built-in alias", ["vehicle", "add", "SUV", "--mesh", f"{T}/car.stl"], "built-in"),
    ("add existing name", ["vehicle", "add", "mycar", "--mesh", f"{T}/car.stl"], "--force"),
    ("add existing name in capitals", ["vehicle", "add", "MYCAR", "--mesh", f"{T}/car.stl"], "ignore case"),
    ("add broken name without force", ["vehicle", "add", "wreck", "--mesh", f"{T}/car.stl"], "--force"),
    ("add mesh missing", ["vehicle", "add", "x", "--mesh", f"{T}/none.stl"], "no such mesh"),
    ("add mesh named with ESC and BEL", ["vehicle", "add", "x", "--mesh", f"{T}/car\x1b[31m\x07.stl"], "\\x1b[31m\\x07"),
    ("add mesh not a mesh", ["vehicle", "add", "x", "--mesh", f"{T}/file.txt"], "cannot read"),
    ("add unknown frame", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--frame", "enu"], "--frame"),
    ("add unknown category", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--category", "truck"],
     "not a UN vehicle category"),
    ("coverage --no-trailer with a value", ["coverage", "R9", "--no-trailer", "yes"], "unexpected extra argument"),
    ("add zones not UTF-8", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--zones", f"{T}/zones_not_utf8.toml"],
     "not UTF-8"),
    ("add zones not TOML", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--zones", f"{T}/zones_bad.toml"],
     "not valid TOML"),
    ("add zones without zones", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--zones", f"{T}/zones_none.toml"],
     "[[zones]]"),
    ("add zone without max", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--zones", f"{T}/zones_no_max.toml"],
     "zones_no_max.toml"),
    ("add zones file missing", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--zones", f"{T}/nozones.toml"],
     "cannot read"),
    ("add mesh in centimetres", ["vehicle", "add", "x", "--mesh", f"{T}/car_cm.stl"], "add --scale 0.01"),
    ("add mesh turned by 90 degrees", ["vehicle", "add", "x", "--mesh", f"{T}/car_turned.stl"], "add --forward +y"),
    ("add mesh facing backwards", ["vehicle", "add", "x", "--mesh", f"{T}/car_backwards.stl"], "add --forward -x"),
    ("add mesh with y up", ["vehicle", "add", "x", "--mesh", f"{T}/car_y_up.stl"], "add --up +y"),
    ("add unknown --forward", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--forward", "ahead"], "--forward"),
    ("add --forward along --up", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--forward", "+z"],
     "different axes"),
    ("add --scale zero", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--scale", "0"], "--scale"),
    ("add --axles not numbers", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--axles", "front,rear"],
     "--axles"),
    ("add --axles off the mesh", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--axles", "9,-1"],
     "outside the mesh"),
    ("add --roof-rack negative", ["vehicle", "add", "x", "--mesh", f"{T}/car.stl", "--roof-rack", "-1"],
     "--roof-rack"),
    ("add mesh of unknown format", ["vehicle", "add", "x", "--mesh", f"{T}/file.txt"], "not a mesh format"),
    # --- coverage ---
    ("coverage unknown rig", ["coverage", "R99"], "R99"),
    ("coverage unknown vehicle", ["coverage", "R1", "--vehicle", "nosuchcar"], "nosuchcar"),
    ("coverage unknown --compare", ["coverage", "R1", "--compare", "R99"], "R99"),
    ("coverage --out is a file", ["coverage", "R1", "--out", f"{T}/file.txt"], "is a file"),
    ("coverage --out under a file", ["coverage", "R1", "--out", f"{T}/file.txt/sub"], "is a file, not a folder"),
    ("coverage --out not empty", ["coverage", "R1", "--out", f"{T}/full"], "--force"),
    ("coverage --out empty name", ["coverage", "R1", "--out", ""], "needs a folder name"),
    ("coverage --require unknown preset", ["coverage", "R1", "--require", "r158,r999"], "r999"),
    ("coverage --require unknown traffic side", ["coverage", "R1", "--require", "r151:uk"], ":lht"),
    ("coverage --require none with others", ["coverage", "R1", "--require", "none,r158"], "stands alone"),
    ("coverage --field-pixels negative", ["coverage", "R1", "--require", "r158", "--field-pixels", "-1"],
     "--field-pixels"),
    ("coverage --articulation without a trailer", ["coverage", "R1", "--require", "r158", "--articulation", "30"],
     "drop --articulation"),
    ("coverage --articulation beyond 90 deg", ["coverage", "R9", "--vehicle", "hgv", "--require", "r151",
                                               "--articulation", "120"], "--articulation"),
    ("calibrate --test-on missing", ["calibrate", "--results", "{repo}/metrics/pccr_transfer.csv", "--test-on",
                                     "{tmp}/no-such-results"], "no-such-results"),
    ("calibrate --null without --test-on", ["calibrate", "--results", "{repo}/metrics/pccr_transfer.csv", "--null",
                                            "5"], "--test-on"),
    ("calibrate --test-control without --test-on", ["calibrate", "--results", "{repo}/metrics/pccr_transfer.csv",
                                                    "--test-control", "R1,R1-r"], "--test-on"),
    ("design --require unknown preset", ["design", "--vehicle", "firetruck", "--ref", "R1", "--require", "r15",
                                         "--out", "{tmp}/d-require"], "r15"),
    ("design --cost-weight negative", ["design", "--vehicle", "firetruck", "--ref", "R1", "--cost-weight", "-1",
                                       "--out", "{tmp}/d-cost"], "--cost-weight"),
    ("user vehicle of an unknown category", ["coverage", "R4", "--vehicle", "oddcategory"], "'category'"),
    ("coverage --out the current folder", ["coverage", "R1", "--out", "."], "a name of its own"),
    ("coverage --out unwritable", ["coverage", "R1", "--out", "/proc/rigopt-out"], "/proc/rigopt-out"),
    # --- design ---
    ("design unknown vehicle", ["design", "--vehicle", "nosuchcar", "--ref", "R1"], "nosuchcar"),
    ("design unknown ref", ["design", "--vehicle", "tt", "--ref", "R99"], "R99"),
    ("design empty ref", ["design", "--vehicle", "tt", "--ref", ","], "--ref"),
    ("design unknown weights", [*DESIGN, "--weights", "nosuchweights"], "joint"),
    ("design weights beta text", [*DESIGN, "--weights", f"{T}/weights_beta_text.json"], "beta.t"),
    ("design unknown metric", [*DESIGN, "--metric", "x"], "valid names"),
    ("design --cameras 0", [*DESIGN, "--cameras", "0"], "--cameras"),
    ("design --cameras reversed", [*DESIGN, "--cameras", "9-3"], "--cameras"),
    ("design --cameras text", [*DESIGN, "--cameras", "many"], "--cameras"),
    ("design --fov outside (0, 180)", [*DESIGN, "--fov", "0,200"], "(0, 180)"),
    ("design --fov text", [*DESIGN, "--fov", "wide"], "--fov"),
    ("design --fov reversed range", [*DESIGN, "--fov", "120-60"], "--fov"),
    ("design --fov empty", [*DESIGN, "--fov", ","], "--fov"),
    ("design --image-size text", [*DESIGN, "--image-size", "big"], "--image-size"),
    ("design --image-size 0x720", [*DESIGN, "--image-size", "0x720"], "--image-size"),
    ("design --image-size 1x1", [*DESIGN, "--image-size", "1x1"], "each side 16 to"),
    ("design --cameras-file missing", [*DESIGN, "--cameras-file", f"{T}/nosuch.toml"], "no such camera catalogue"),
    ("design --cameras-file a folder", [*DESIGN, "--cameras-file", f"{T}/dir.json"], "is a folder"),
    ("design --cameras-file not UTF-8", [*DESIGN, "--cameras-file", f"{T}/cameras_not_utf8.toml"], "UTF-8"),
    ("design --cameras-file bad TOML", [*DESIGN, "--cameras-file", f"{T}/cameras_bad.toml"], "not valid TOML"),
    ("design --cameras-file no cameras", [*DESIGN, "--cameras-file", f"{T}/cameras_empty.json"], "'cameras'"),
    ("design --cameras-file camera without fx", [*DESIGN, "--cameras-file", f"{T}/cameras_no_fx.toml"], "no fx"),
    ("design --cameras-file unknown distortion", [*DESIGN, "--cameras-file", f"{T}/cameras_bad_model.toml"],
     "'distortion' must be one of"),
    ("design --cameras-file too few coefficients", [*DESIGN, "--cameras-file",
                                                    f"{T}/cameras_coefficients.toml"], "needs 5"),
    ("design --cameras-file lens folding back", [*DESIGN, "--cameras-file", f"{T}/cameras_folding.toml"],
     "folds back"),
    ("design --cameras-file name twice", [*DESIGN, "--cameras-file", f"{T}/cameras_twice.toml"], "used twice"),
    ("design --cameras-file with --fov", [*DESIGN, "--cameras-file", f"{T}/cameras_twice.toml", "--fov", "90"],
     "leave out --fov"),
    ("design --pitch text", [*DESIGN, "--pitch", "abc"], "--pitch"),
    ("design --pitch 200", [*DESIGN, "--pitch", "200"], "[-90, 90]"),
    ("design --yaw-step 0", [*DESIGN, "--yaw-step", "0"], "--yaw-step"),
    ("design --yaw-step -5", [*DESIGN, "--yaw-step", "-5"], "--yaw-step"),
    ("design --yaw-step 400", [*DESIGN, "--yaw-step", "400"], "--yaw-step"),
    ("design --yaw-step nan", [*DESIGN, "--yaw-step", "nan"], "--yaw-step"),
    ("design --max-nodes text", [*DESIGN, "--max-nodes", "many"], "--max-nodes"),
    ("design --max-nodes above 10 million", [*DESIGN, "--max-nodes", "20000000"], "--max-nodes"),
    ("design --min-height negative", [*DESIGN, "--min-height", "-0.5"], "--min-height"),
    ("check --min-height too high", ["check", "R1", "--min-height", "12"], "--min-height"),
    ("design --spacing 0", [*DESIGN, "--spacing", "0"], "--spacing"),
    ("design --spacing -1", [*DESIGN, "--spacing", "-1"], "--spacing"),
    ("design --spacing 1e-4", [*DESIGN, "--spacing", "1e-4"], "half a housing"),
    ("design --spacing wider than the zones", [*DESIGN, "--spacing", "100"], "--spacing"),
    ("design --cost-weight inf", [*DESIGN, "--cost-weight", "inf"], "--cost-weight"),
    ("design --max-nodes 0", [*DESIGN, "--max-nodes", "0"], "--max-nodes"),
    ("design --min-height above every mount point", [*DESIGN, "--min-height", "5"], "--min-height"),
    ("design --pareto with no feasible point", [*DESIGN, "--pareto", "--cameras", "1", "--out", f"{T}/pareto"],
     "no frontier"),
    ("coverage of a rig that sees only its body", ["coverage", f"{T}/rig_inward.json"], "sees nothing"),
    ("camera id with a terminal escape", ["check", f"{T}/rig_escape_id.json"], "control characters"),
    ("camera id null", ["check", f"{T}/rig_null_id.json"], "'id' must be a non-empty string"),
    ("design --min-coverage -1", [*DESIGN, "--min-coverage", "-1"], "--min-coverage"),
    ("design --min-overlap -1", [*DESIGN, "--min-overlap", "-1"], "--min-overlap"),
    ("design --out is a file", [*DESIGN, "--out", f"{T}/file.txt"], "is a file"),
    ("design --out under a file", [*DESIGN, "--out", f"{T}/file.txt/d"], "is a file, not a folder"),
    ("design --out not empty", [*DESIGN, "--out", f"{T}/full"], "--force"),
    ("design --out unwritable", [*DESIGN, "--out", "/proc/rigopt-design"], "/proc/rigopt-design"),
    ("design --pareto --out not empty", [*DESIGN, "--pareto", "--out", f"{T}/full"], "--force"),
    ("design --pareto with --near-field", [*DESIGN, "--pareto", "--near-field", "--out", f"{T}/pareto2"],
     "--pareto sweeps one camera set"),
    # --- import nuscenes ---
    ("import missing folder", ["import", "nuscenes", f"{T}/none", "--out", f"{T}/r.json"], "no such folder"),
    ("import tables not UTF-8", ["import", "nuscenes", f"{T}/nuscenes_not_utf8", "--out", f"{T}/r.json"],
     "not UTF-8"),
    ("import --out not .json", ["import", "nuscenes", f"{T}/none", "--out", f"{T}/r.txt"], ".json"),
    ("import --out under a file", ["import", "nuscenes", f"{T}/none", "--out", f"{T}/file.txt/r.json"],
     "is a file"),
    ("import --image-size text", ["import", "nuscenes", f"{T}/none", "--out", f"{T}/r.json", "--image-size",
                                  "1280by720"], "1280by720"),
    ("import --image-size 0x0", ["import", "nuscenes", f"{T}/none", "--out", f"{T}/r.json", "--image-size", "0x0"],
     "WIDTHxHEIGHT"),
    ("import nuscenes two calibrations", ["import", "nuscenes", f"{T}/nuscenes_two", "--out", f"{T}/r.json"],
     "--calibration K"),
    ("import nuscenes --calibration 5", ["import", "nuscenes", f"{T}/nuscenes_two", "--out", f"{T}/r.json",
                                         "--calibration", "5"], "out of range"),
    ("import nuscenes --log without log tables", ["import", "nuscenes", f"{T}/nuscenes_two", "--out", f"{T}/r.json",
                                                  "--log", "n015"], "--calibration K instead"),
    ("import --out exists", ["import", "nuscenes", f"{T}/nuscenes_two", "--out", f"{T}/carla_no_sensors.json"],
     "--force"),
    ("import --vehicle unknown", ["import", "carla", f"{T}/carla_no_sensors.json", "--out", f"{T}/r.json",
                                  "--vehicle", "batmobile"], "batmobile"),
    ("import --origin unknown", ["import", "carla", f"{T}/carla_no_sensors.json", "--out", f"{T}/r.json",
                                 "--origin", "roof"], "--origin"),
    ("import argoverse2 not feather", ["import", "argoverse2", f"{T}/av2", "--out", f"{T}/r.json"],
     "not a readable"),
    ("import argoverse2 missing folder", ["import", "argoverse2", f"{T}/none", "--out", f"{T}/r.json"],
     "no such folder"),
    ("import --origin custom without offset", ["import", "carla", f"{T}/carla_no_sensors.json", "--out",
                                               f"{T}/r.json", "--origin", "custom"], "--origin-offset X,Y,Z"),
    ("import --origin-offset without custom", ["import", "carla", f"{T}/carla_no_sensors.json", "--out",
                                               f"{T}/r.json", "--origin-offset", "1,0,0"], "--origin custom"),
    ("import --origin-offset of 1e9 m", ["import", "carla", f"{T}/carla_no_sensors.json", "--out", f"{T}/r.json",
                                         "--origin", "custom", "--origin-offset", "1e9,0,0"], "within 100 m"),
    ("import --origin-offset malformed", ["import", "carla", f"{T}/carla_no_sensors.json", "--out", f"{T}/r.json",
                                          "--origin", "custom", "--origin-offset", "1;0;0"], "three numbers"),
    ("import unknown format", ["import", "kitti", f"{T}/none", "--out", f"{T}/r.json"], "unknown format 'kitti'"),
    ("import an option of another format", ["import", "carla", f"{T}/carla_no_sensors.json", "--out", f"{T}/r.json",
                                            "--log", "x"], "--log: not an option of carla"),
    ("import dgp per-channel image size", ["import", "dgp", f"{T}/none", "--out", f"{T}/r.json", "--image-size",
                                           "100x100,CAMERA_01=200x200"], "one WIDTHxHEIGHT"),
    ("export a format rigopt only reads", ["export", "R1", "--format", "waymo", "--out", f"{T}/w"],
     "one rigopt reads but does not write"),
    ("import argoverse1 missing file", ["import", "argoverse1", f"{T}/none", "--out", f"{T}/r.json"],
     "no such Argoverse 1 calibration file"),
    ("import argoverse1 unknown camera", ["import", "argoverse1", f"{T}/av1", "--out", f"{T}/r.json"],
     "not an Argoverse 1 camera"),
    ("import argoverse1 --cameras unknown", ["import", "argoverse1", f"{T}/av1", "--out", f"{T}/r.json",
                                             "--cameras", "stereo"], "--cameras"),
    ("import argoverse1 --axle-height with --origin", ["import", "argoverse1", f"{T}/av1", "--out", f"{T}/r.json",
                                                       "--origin", "rear_axle", "--axle-height", "0.3"],
     "--axle-height"),
    ("import argoverse1 --axle-height -1", ["import", "argoverse1", f"{T}/av1", "--out", f"{T}/r.json",
                                            "--axle-height", "-1"], "--axle-height"),
    ("import dgp skew", ["import", "dgp", f"{T}/dgp", "--out", f"{T}/r.json"], "skew"),
    ("import waymo not parquet", ["import", "waymo", f"{T}/waymo", "--out", f"{T}/r.json"], "not a readable"),
    ("import waymo v1 not a TFRecord", ["import", "waymo", f"{T}/waymo_v1_text.tfrecord", "--out", f"{T}/r.json"],
     "not a TFRecord"),
    ("import waymo v1 truncated record", ["import", "waymo", f"{T}/waymo_v1_truncated.tfrecord", "--out",
                                          f"{T}/r.json"], "truncated"),
    ("import waymo v1 bad CRC", ["import", "waymo", f"{T}/waymo_v1_bad_crc.tfrecord", "--out", f"{T}/r.json"],
     "CRC"),
    ("import waymo v1 no camera calibrations", ["import", "waymo", f"{T}/waymo_v1_no_cameras.tfrecord", "--out",
                                                f"{T}/r.json"], "no camera calibrations"),
    ("import waymo v1 unknown camera", ["import", "waymo", f"{T}/waymo_v1_camera_9.tfrecord", "--out",
                                        f"{T}/r.json"], "camera name 9"),
    ("import opencv bad YAML", ["import", "opencv", f"{T}/camchain_bad.yaml", "--out", f"{T}/r.json"],
     "not valid YAML"),
    ("import opencv no cam0", ["import", "opencv", f"{T}/camchain_no_cam0.yaml", "--out", f"{T}/r.json"], "cam0"),
    ("import opencv unknown distortion", ["import", "opencv", f"{T}/camchain_fov.yaml", "--out", f"{T}/r.json"],
     "omni"),
    ("import urdf without cameras", ["import", "urdf", f"{T}/robot.urdf", "--out", f"{T}/r.json"], "camera"),
    ("import urdf broken XML", ["import", "urdf", f"{T}/robot_broken.urdf", "--out", f"{T}/r.json"],
     "not valid XML"),
    ("import carla without sensors", ["import", "carla", f"{T}/carla_no_sensors.json", "--out", f"{T}/r.json"],
     "'sensors'"),
    ("import carla fov text", ["import", "carla", f"{T}/carla_fov_text.json", "--out", f"{T}/r.json"], "wide"),
    ("import carla image 99999 px wide", ["import", "carla", f"{T}/carla_huge_image.json", "--out", f"{T}/r.json"],
     "from 1 to 20000"),
    ("import opencv block not named camN", ["import", "opencv", f"{T}/camchain_gap.yaml", "--out", f"{T}/r.json"],
     "camera_left not read"),
    ("import opencv principal point outside the image", ["import", "opencv", f"{T}/camchain_far_centre.yaml", "--out",
                                                        f"{T}/r.json"], "outside its 640 x 480 image"),
    # --- export ---
    ("export --format unknown", ["export", "R1", "--format", "kitti", "--out", f"{T}/x"], "kitti"),
    ("export --out wrong extension", ["export", "R1", "--format", "urdf", "--out", f"{T}/x.json"], ".urdf"),
    ("export --out exists", ["export", "R1", "--format", "carla", "--out", f"{T}/carla_no_sensors.json"],
     "--force"),
    ("export nuscenes --out not empty", ["export", "R1", "--format", "nuscenes", "--out", f"{T}/full"], "--force"),
    ("export unknown rig", ["export", "R99", "--format", "carla", "--out", f"{T}/x.json"], "R99"),
    # --- bench generate / show ---
    ("generate --size 20000x20000", [*BENCH, "--size", "20000x20000"], "GiB"),
    ("generate --size 100000x100000", [*BENCH, "--size", "100000x100000"], "each side 1 to 20000"),
    ("generate --size text", [*BENCH, "--size", "big"], "WIDTHxHEIGHT"),
    ("generate --seed -5", [*BENCH, "--seed", "-5"], "--seed"),
    ("generate --scenes 0", [*BENCH, "--scenes", "0"], "--scenes"),
    ("generate --frames 0", [*BENCH, "--frames", "0"], "--frames"),
    ("generate unknown split", [*BENCH, "--split", "dev"], "dev"),
    ("generate unknown rig", ["bench", "generate", "--rigs", "R99", "--out", f"{T}/gen"], "R99"),
    ("generate --out is a file", ["bench", "generate", "--rigs", "R1", "--out", f"{T}/file.txt"], "is a file"),
    ("generate --out under a file", ["bench", "generate", "--rigs", "R1", "--out", f"{T}/file.txt/g"], "is a file"),
    ("show missing folder", ["bench", "show", f"{T}/none", "--rig", "R1", "--out", f"{T}/s.png"], "no such folder"),
    ("show sample out of range", ["bench", "show", f"{T}/bench", "--rig", "R1", "--sample", "99", "--out",
                                  f"{T}/s.png"], "--sample"),
    ("show missing image", ["bench", "show", f"{T}/bench_missing", "--rig", "R1", "--out", f"{T}/s.png"],
     "lacks its image"),
    ("bench show picture extension .txt", ["bench", "show", f"{T}/bench", "--rig", "R1", "--out", f"{T}/s.txt"],
     ".txt is not a format"),
    # --- bench train / evaluate / matrix, validate (torch) ---
    ("train unknown model", ["bench", "train", "--data", f"{T}/bench", "--rig", "R1", "--model", "yolo"], "yolo"),
    ("train missing split", ["bench", "train", "--data", f"{T}/bench", "--rig", "R1", "--model", "lss"],
     "no train split"),
    ("train unknown size", ["bench", "train", "--data", f"{T}/bench", "--rig", "R1", "--model", "lss", "--size",
                            "huge"], "huge"),
    ("train unknown device", ["bench", "train", "--data", f"{T}/bench", "--rig", "R1", "--model", "lss",
                              "--device", "tpu"], "tpu"),
    ("evaluate garbage checkpoint", ["bench", "evaluate", "--data", f"{T}/bench", "--rig", "R1", "--model", "lss",
                                     "--split", "mini", "--checkpoint", f"{T}/garbage.pt"], "not a readable"),
    ("evaluate missing checkpoint", ["bench", "evaluate", "--data", f"{T}/bench", "--rig", "R1", "--model", "lss",
                                     "--split", "mini"], "no such checkpoint"),
    ("matrix --out is a file", ["bench", "matrix", "--data", f"{T}/bench", "--rigs", "R1", "--model", "lss",
                                "--out", f"{T}/file.txt"], "is a file"),
    ("matrix unknown model", ["bench", "matrix", "--data", f"{T}/bench", "--rigs", "R1", "--model", "yolo",
                              "--out", f"{T}/m"], "yolo"),
    ("validate missing design", ["validate", f"{T}/none.json", "--ref", "R1", "--model", "lss", "--data",
                                 f"{T}/bench"], "no such design"),
    ("validate --out not .json", ["validate", f"{T}/rig_nan.json", "--ref", "R1", "--model", "lss", "--data",
                                  f"{T}/bench", "--out", f"{T}/v.txt"], ".json"),
    # --- import, export, calibrate, bench, validate edges (issue 29, parts 10-11) ---
    ("import waymo v2 table without rows", ["import", "waymo", f"{T}/waymo_empty", "--out", f"{T}/r.json"],
     "no rows"),
    ("import waymo v1 TFRecord without records", ["import", "waymo", f"{T}/waymo_v1_empty.tfrecord", "--out",
                                                  f"{T}/r.json"], "holds no records"),
    ("import urdf horizontal_fov 0", ["import", "urdf", f"{T}/urdf_fov_0.urdf", "--out", f"{T}/r.json"],
     "(0, pi)"),
    ("import urdf horizontal_fov 4 with intrinsics", ["import", "urdf", f"{T}/urdf_fov_4.urdf", "--out",
                                                      f"{T}/r.json"], "(0, pi)"),
    ("import urdf horizontal_fov against intrinsics", ["import", "urdf", f"{T}/urdf_fov_disagrees.urdf", "--out",
                                                       f"{T}/r.json"], "disagrees with <lens><intrinsics>"),
    ("import urdf joint to an undeclared link", ["import", "urdf", f"{T}/urdf_undeclared_parent.urdf", "--out",
                                                 f"{T}/r.json"], "'chassis' is not a declared <link>"),
    ("import urdf joint loop", ["import", "urdf", f"{T}/urdf_loop.urdf", "--out", f"{T}/r.json"], "loop"),
    ("import urdf link with two parents", ["import", "urdf", f"{T}/urdf_two_parents.urdf", "--out", f"{T}/r.json"],
     "two parents"),
    ("import urdf given a folder", ["import", "urdf", f"{T}/emptydir", "--out", f"{T}/r.json"],
     "is a folder; give the URDF file itself"),
    ("import nuscenes image width 0", ["import", "nuscenes", f"{T}/nuscenes_size_0", "--out", f"{T}/r.json"],
     "record 0 (token 'sd0')"),
    ("import nuscenes image width 1600.5", ["import", "nuscenes", f"{T}/nuscenes_size_fraction", "--out",
                                            f"{T}/r.json"], "positive whole pixels"),
    ("import nuscenes given a file", ["import", "nuscenes", f"{T}/file.txt", "--out", f"{T}/r.json"],
     "is a file; give the folder holding"),
    ("import --image-size 99999x99999", ["import", "nuscenes", f"{T}/nuscenes_two", "--out", f"{T}/r.json",
                                         "--image-size", "99999x99999"], "each side 16 to 20000"),
    ("design --image-size 99999x99999", [*DESIGN, "--image-size", "99999x99999"], "each side 16 to 20000"),
    ("rig file .json that is a folder", ["rigv", f"{T}/dir.json"], "is a folder; give the rig file itself"),
    ("export --out a folder for a file", ["export", "R1", "--format", "urdf", "--out", f"{T}/dir.urdf"],
     "is a folder; give the name of the file"),
    ("calibrate --rigs missing", [*CAL, SHIPPED, "--rigs", f"{T}/no_rigs"], "--rigs"),
    ("calibrate --rigs a file", [*CAL, SHIPPED, "--rigs", f"{T}/file.txt"], "is a file; give the folder holding"),
    ("calibrate results naming a rig outside the library", [*CAL, "{repo}/measurements/transfer"],
     "give --rigs FOLDER"),
    ("calibrate --rigs without the results' rig", [*CAL, "{repo}/measurements/transfer", "--rigs", f"{T}/emptydir"],
     "add --rigs"),
    ("calibrate --results one model's JSON", [*CAL, f"{T}/results_no_diagonal/M/trained_on_R1.json"],
     "is a JSON file"),
    ("train --data missing", ["bench", "train", "--data", f"{T}/none", "--rig", "R1", "--model", "lss"],
     "none: no such folder"),
    ("evaluate --data missing", ["bench", "evaluate", "--data", f"{T}/none", "--rig", "R1", "--model", "lss"],
     "none: no such folder"),
    ("matrix --data missing", ["bench", "matrix", "--data", f"{T}/none", "--rigs", "R1", "--model", "lss", "--out",
                               f"{T}/m"], "none: no such folder"),
    ("validate --data missing", ["validate", f"{T}/rig_nan.json", "--ref", "R1", "--model", "lss", "--data",
                                 f"{T}/none"], "none: no such folder"),
    ("train --data a file", ["bench", "train", "--data", f"{T}/file.txt", "--rig", "R1", "--model", "lss"],
     "is a file; give the folder holding"),
    ("evaluate --checkpoint a folder", ["bench", "evaluate", "--data", f"{T}/bench", "--rig", "R1", "--model", "lss",
                                        "--checkpoint", f"{T}/emptydir"], "is a folder; give the checkpoint file"),
    ("validate design a folder", ["validate", f"{T}/emptydir", "--ref", "R1", "--model", "lss", "--data",
                                  f"{T}/bench"], "is a folder; give the design file"),
    ("bench show data a file", ["bench", "show", f"{T}/file.txt", "--rig", "R1", "--out", f"{T}/s.png"],
     "is a file; give the folder holding"),
    # --- measurement protocols, several rigs, design --measure (issue 42) ---
    ("validate unknown --protocol", ["validate", "R5", "--ref", "R1", "--model", "lss", "--protocol", "fast"],
     "unknown measurement protocol"),
    ("validate --protocol with --data", ["validate", "R5", "--ref", "R1", "--model", "lss", "--protocol", "quick",
                                         "--data", f"{T}/bench"], "--protocol is for the shipped models"),
    ("validate --ray with --data", ["validate", "R5", "--ref", "R1", "--model", "lss", "--ray", "local",
                                    "--data", f"{T}/bench"], "--ray is for the shipped models"),
    ("validate several rigs with --compare", ["validate", "R5", "R4", "--ref", "R1", "--model", "lss", "--compare"],
     "--compare validates one rig at a time"),
    # --- your own detector, models for any reference (issue 45) ---
    ("validate --model and --detector", ["validate", "R5", "--ref", "R1", "--model", "lss", "--detector",
                                         f"{T}/file.txt"], "not both"),
    ("validate --detector missing", ["validate", "R5", "--ref", "R1", "--detector", f"{T}/none.pt"],
     "no such file, nor an entry point"),
    ("validate --detector not TorchScript", ["validate", "R5", "--ref", "R1", "--detector", f"{T}/file.txt"],
     "not a TorchScript file"),
    ("validate --detector an ONNX file", ["validate", "R5", "--ref", "R1", "--detector", f"{T}/model.onnx"],
     "ONNX files are not read"),
    ("validate --detector entry point not importable", ["validate", "R5", "--ref", "R1", "--detector",
                                                        "no_such_package.models:factory"], "cannot import it"),
    ("validate --detector with --data", ["validate", "R5", "--ref", "R1", "--detector", f"{T}/file.txt", "--data",
                                         f"{T}/bench"], "--detector is scored on"),
    ("validate --detectors missing", ["validate", "R5", "--ref", "R1", "--model", "lss", "--detectors",
                                      f"{T}/none"], "--detectors"),
    ("validate --detectors without a pack of the reference", ["validate", "R5", "--ref", "R2", "--model", "lss",
                                                              "--detectors", f"{T}/emptydir"],
     "no lss models trained on R2"),
    ("detectors export without --ref or --checkpoint", ["detectors", "export", "--out", f"{T}/e.pt"],
     "give --ref"),
    ("detectors export --seed not in the pack", ["detectors", "export", "--out", f"{T}/e.pt", "--ref", "R1",
                                                 "--seed", "7"], "--seed 7"),
    ("detectors export --out not .pt", ["detectors", "export", "--out", f"{T}/e.txt", "--ref", "R1"], "--out"),
    ("detectors train repeated --seeds", ["detectors", "train", "--ref", "R1", "--out", f"{T}/packs", "--seeds",
                                          "0,0"], "--seeds"),
    ("detectors train unknown --model", ["detectors", "train", "--ref", "R1", "--out", f"{T}/packs", "--model",
                                         "yolo"], "unknown model family"),
    ("detectors train --out a file", ["detectors", "train", "--ref", "R1", "--out", f"{T}/file.txt"], "is a file"),
    ("design --measure with --pareto", ["design", "--vehicle", "tt", "--ref", "R1", "--measure", "--pareto", "--out",
                                        f"{T}/dm"], "--measure measures one design"),
    ("design --measure unknown --protocol", ["design", "--vehicle", "tt", "--ref", "R1", "--measure", "--protocol",
                                             "fast", "--out", f"{T}/dm"], "unknown measurement protocol"),
    ("design --measure from a reference without shipped models", ["design", "--vehicle", "tt", "--ref", "R6",
                                                                  "--measure", "--out", f"{T}/dm"],
     "--measure needs the shipped lss models trained on R6"),
    # --- predictors and the drop-model objective (issue 42) ---
    ("rank unknown --predictor", ["rank", "R6", "--ref", "R1", "--predictor", "nope"], "unknown predictor 'nope'"),
    ("rank --predictor of another reference", ["rank", "R1", "--ref", "R2", "--predictor", "lss-R1"],
     "predicts transfers from R1"),
    ("design --objective missing file", [*DESIGN, "--objective", f"{T}/none.json", "--out", f"{T}/dobj"],
     "no such drop model file"),
    ("design --objective not a model", [*DESIGN, "--objective", f"{T}/weights_beta_null.json", "--out", f"{T}/dobj"],
     "not a drop model file"),
    ("design --objective of another reference", ["design", "--vehicle", "tt", "--ref", "R2", "--objective", "lss-R1",
                                                 "--out", f"{T}/dobj"], "fitted from R1"),
]

#: (class, arguments, fragment of the one warning line): inputs a command takes, exit 0, but flags.
WARNINGS = [
    # --- a candidate that sees little of what the reference sees (issue 44) ---
    ("rank a rig whose cameras look at the sky", ["rank", "R3", f"{T}/rig_sky.json", "--ref", "R1"],
     "see 0 % of what R1's see"),
    ("rank a rig of one camera", ["rank", "R3", f"{T}/rig_one_camera.json", "--ref", "R1", "--predictor", "rigcd"],
     "of what R1's see; the predictors were not calibrated on such rigs"),
    ("rigcd a rig whose cameras look at the sky", ["rigcd", "R1", f"{T}/rig_sky.json", "--json"],
     "see 0 % of what R1's see"),
]
