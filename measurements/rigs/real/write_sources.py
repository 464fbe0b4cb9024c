"""Write the four dataset rigs in their datasets' own calibration formats (the source folders beside this file).

    python measurements/rigs/real/write_sources.py

The values below are the datasets' documented calibrations where they are published, and chosen values
where they are not; README.md (beside this file) says which is which and where each documented value comes
from. ``rigopt import`` turns each folder into the rig file ``<dataset>.json`` (the commands are in README.md).

Frames: every dataset's ego frame has ISO 8855 axes (x forward, y left, z up), metres. nuScenes, Argoverse 2
and DGP give each camera's pose as ``R_ego_optical`` (optical frame: z forward, x right, y down); Waymo gives
the camera-to-vehicle transform of its camera frame (x forward along the axis, y left, z up).
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.feather as feather
import pyarrow.parquet as parquet

HERE = Path(__file__).resolve().parent

#: Optical-frame directions (columns: x right, y down, z forward) in a forward-looking camera's body frame.
OPTICAL_IN_BODY = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])

# ------------------------------------------------------------------------------------------------ nuScenes
# Documented: the calibrated_sensor records of the six cameras of nuScenes v1.0 log n015-2018-07-24-11-22-45+0800
# (Singapore, vehicle n015): translation (m, ego frame), rotation (w, x, y, z of R_ego_optical) and
# camera_intrinsic. Images 1600 x 900, rectified (no distortion).
NUSCENES = {  # channel: (translation, rotation, (fx, cx, cy)); fy = fx
    "CAM_FRONT": ((1.70079118954, 0.0159456324149, 1.51095763913),
                  (0.4998015430569128, -0.5030316162024876, 0.4997798114386805, -0.49737083824542755),
                  (1266.417203046554, 816.2670197447984, 491.50706579294757)),
    "CAM_FRONT_LEFT": ((1.52387798135, 0.494631336551, 1.50932822144),
                       (0.6757265034669446, -0.6736266522251881, 0.21214015046209478, -0.21122827103904068),
                       (1272.5979470598488, 826.6154927353808, 479.75165386361925)),
    "CAM_FRONT_RIGHT": ((1.5508477543, -0.493404796419, 1.49574800619),
                        (0.2060347966337182, -0.2026940577919598, 0.6824507824531167, -0.6713610884174485),
                        (1260.8474446004698, 807.968244525554, 495.3344268742088)),
    "CAM_BACK": ((0.0283260309358, 0.00345136761476, 1.57910346144),
                 (0.5037872666382278, -0.49740249788611096, -0.4941850223835201, 0.5045496097725578),
                 (809.2209905677063, 829.2196003259838, 481.77842384512485)),
    "CAM_BACK_LEFT": ((1.03569100218, 0.484795032713, 1.59097014818),
                      (0.6924185592174665, -0.7031619420114925, -0.11648342771943819, 0.11203317912370753),
                      (1256.7414812095406, 792.1125740759628, 492.7757465151356)),
    "CAM_BACK_RIGHT": ((1.0148780988, -0.480568219723, 1.56239545128),
                       (0.12280980120078765, -0.132400842670559, -0.7004305821388234, 0.690496031265798),
                       (1259.5137405846733, 807.2529053838625, 501.19579884916527)),
}

# ---------------------------------------------------------------------------------------------- Argoverse 2
# Documented (the av2 API's sensor dataset guide, log 54bc6dbc-ebfb-3fba-b5b3-57f88b4b79ca): the seven ring
# cameras' poses (qw, qx, qy, qz, tx_m, ty_m, tz_m) and their fx_px = fy_px, cx_px, k2, k3, height_px, width_px.
# Chosen (the guide elides those columns): cy_px at the image's middle and k1 = -0.26 (not applied: the imagery
# is undistorted). The stereo cameras are left out.
AV2_POSES = {
    "ring_front_center": (0.502809, -0.499689, 0.500147, -0.497340, 1.631216, -0.000779, 1.432780),
    "ring_front_left": (0.635526, -0.671957, 0.275463, -0.262107, 1.550015, 0.197539, 1.431329),
    "ring_front_right": (0.264354, -0.278344, 0.671740, -0.633567, 1.554057, -0.194171, 1.430575),
    "ring_rear_left": (0.600598, -0.603227, -0.371096, 0.371061, 1.104117, 0.124369, 1.446070),
    "ring_rear_right": (-0.368149, 0.369885, 0.603626, -0.602733, 1.103432, -0.128317, 1.428135),
    "ring_side_left": (0.684152, -0.724938, -0.058345, 0.054735, 1.310427, 0.267904, 1.433233),
    "ring_side_right": (-0.053810, 0.056105, 0.727113, -0.682103, 1.310236, -0.273345, 1.435529),
}
AV2_INTRINSICS = {  # fx_px (= fy_px), cx_px, k2, k3
    "ring_front_center": (1773.504272, 775.826693, -0.212167, 0.328694),
    "ring_front_left": (1682.010713, 1025.068254, -0.136984, 0.209330),
    "ring_front_right": (1684.834479, 1024.373455, -0.133341, 0.208709),
    "ring_rear_left": (1686.494558, 1025.655905, -0.129761, 0.202326),
    "ring_rear_right": (1683.375120, 1024.381124, -0.129331, 0.201599),
    "ring_side_left": (1684.902403, 1027.822264, -0.124561, 0.196519),
    "ring_side_right": (1682.936559, 1024.948976, -0.109515, 0.179383),
}
AV2_CHOSEN_K1 = -0.26

# --------------------------------------------------------------------------------------------------- Waymo
# Documented: the five cameras (camera_name 1 FRONT ... 5 SIDE_RIGHT), images 1920 x 1280 (FRONT, FRONT_LEFT,
# FRONT_RIGHT) and 1920 x 886 (SIDE_LEFT, SIDE_RIGHT). Chosen: a 50.4 deg horizontal FOV (f = 2040 px), centred
# principal points, no distortion, and poses: roof-dome cameras 2.10 m up at yaws 0, +-45, +-90 deg, level.
WAYMO_SEGMENT = "waymo_documented_layout"
WAYMO_CAMERAS = {  # camera_name: (name, yaw deg, (x, y, z) m, (width, height))
    1: ("FRONT", 0.0, (1.55, 0.00, 2.10), (1920, 1280)),
    2: ("FRONT_LEFT", 45.0, (1.50, 0.10, 2.10), (1920, 1280)),
    3: ("FRONT_RIGHT", -45.0, (1.50, -0.10, 2.10), (1920, 1280)),
    4: ("SIDE_LEFT", 90.0, (1.40, 0.12, 2.10), (1920, 886)),
    5: ("SIDE_RIGHT", -90.0, (1.40, -0.12, 2.10), (1920, 886)),
}
WAYMO_FOCAL_PX = 2040.0

# ---------------------------------------------------------------------------------------------------- DDAD
# Documented: six cameras CAMERA_01, 05, 06, 07, 08, 09, 1936 x 1216, at 60 deg intervals; origin on the
# ground below the rear axle's centre. Chosen: which name looks where (01 front, 05/06 front left/right, 07/08
# rear left/right, 09 rear), focal lengths (front 2181.5 px, others 1061.0 px), centred principal points, no
# distortion, and a level roof ring of radius 0.35 m about (1.25, 0) m, 1.75 m up.
DDAD_CAMERAS = {"CAMERA_01": 0.0, "CAMERA_05": 60.0, "CAMERA_06": -60.0, "CAMERA_07": 120.0, "CAMERA_08": -120.0,
                "CAMERA_09": 180.0}  # name: yaw deg
DDAD_SIZE = (1936, 1216)
DDAD_FOCAL_PX = {"CAMERA_01": 2181.5}
DDAD_OTHER_FOCAL_PX = 1061.0
DDAD_RING_CENTRE, DDAD_RING_RADIUS, DDAD_HEIGHT = (1.25, 0.0), 0.35, 1.75


def yaw_matrix(yaw_deg: float) -> np.ndarray:
    """(3, 3) rotation about +z by ``yaw_deg`` (counter-clockwise seen from above)."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def quaternion_wxyz(rotation: np.ndarray) -> tuple[float, float, float, float]:
    """Scalar-first unit quaternion of a proper rotation (3, 3) (w >= 0; exact for the yaw rotations here)."""
    r = rotation
    w = math.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2.0
    x = math.copysign(math.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2.0, r[2, 1] - r[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] + r[1, 1] - r[2, 2])) / 2.0, r[0, 2] - r[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] - r[1, 1] + r[2, 2])) / 2.0, r[1, 0] - r[0, 1])
    return w, x, y, z


def token(text: str) -> str:
    """A nuScenes-style 32-hex-digit token derived from ``text``."""
    return hashlib.md5(text.encode()).hexdigest()


def write_json(path: Path, data) -> str:
    text = json.dumps(data, indent=1) + "\n"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return text


def write_nuscenes(folder: Path) -> None:
    sensors = [{"token": token(f"sensor/{c}"), "channel": c, "modality": "camera"} for c in NUSCENES]
    records = [{"token": token(f"calibrated_sensor/n015/{c}"), "sensor_token": token(f"sensor/{c}"),
                "translation": list(t), "rotation": list(q),
                "camera_intrinsic": [[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]]}
               for c, (t, q, (f, cx, cy)) in NUSCENES.items()]
    sample_data = [{"token": token(f"sample_data/n015/{c}"), "sample_token": "", "ego_pose_token": "",
                    "calibrated_sensor_token": token(f"calibrated_sensor/n015/{c}"), "timestamp": 0,
                    "fileformat": "jpg", "is_key_frame": True, "height": 900, "width": 1600,
                    "filename": f"samples/{c}/", "prev": "", "next": ""} for c in NUSCENES]
    write_json(folder / "sensor.json", sensors)
    write_json(folder / "calibrated_sensor.json", records)
    write_json(folder / "sample_data.json", sample_data)  # one image record per camera: its size


def write_argoverse2(folder: Path) -> None:
    calibration = folder / "calibration"
    calibration.mkdir(parents=True, exist_ok=True)
    names = list(AV2_POSES)
    poses = {"sensor_name": names}
    for k, column in enumerate(("qw", "qx", "qy", "qz", "tx_m", "ty_m", "tz_m")):
        poses[column] = [AV2_POSES[n][k] for n in names]
    feather.write_feather(pa.table(poses), calibration / "egovehicle_SE3_sensor.feather", compression="uncompressed")
    portrait = [n == "ring_front_center" for n in names]
    intrinsics = {
        "sensor_name": names,
        "fx_px": [AV2_INTRINSICS[n][0] for n in names],
        "fy_px": [AV2_INTRINSICS[n][0] for n in names],
        "cx_px": [AV2_INTRINSICS[n][1] for n in names],
        "cy_px": [1024.0 if p else 775.0 for p in portrait],
        "k1": [AV2_CHOSEN_K1] * len(names),
        "k2": [AV2_INTRINSICS[n][2] for n in names],
        "k3": [AV2_INTRINSICS[n][3] for n in names],
        "height_px": [2048 if p else 1550 for p in portrait],
        "width_px": [1550 if p else 2048 for p in portrait],
    }
    feather.write_feather(pa.table(intrinsics), calibration / "intrinsics.feather", compression="uncompressed")


def write_waymo(folder: Path) -> None:
    c = "[CameraCalibrationComponent]."
    rows: dict[str, list] = {k: [] for k in ("key.segment_context_name", "key.camera_name",
                                             *(f"{c}intrinsic.{k}" for k in ("f_u", "f_v", "c_u", "c_v", "k1", "k2",
                                                                              "p1", "p2", "k3")),
                                             f"{c}extrinsic.transform", f"{c}width", f"{c}height")}
    for number, (_, yaw, position, (width, height)) in WAYMO_CAMERAS.items():
        transform = np.eye(4)
        transform[:3, :3] = yaw_matrix(yaw)  # Waymo's camera frame: x along the optical axis, y left, z up
        transform[:3, 3] = position
        intrinsic = {"f_u": WAYMO_FOCAL_PX, "f_v": WAYMO_FOCAL_PX, "c_u": width / 2, "c_v": height / 2, "k1": 0.0,
                     "k2": 0.0, "p1": 0.0, "p2": 0.0, "k3": 0.0}
        rows["key.segment_context_name"].append(WAYMO_SEGMENT)
        rows["key.camera_name"].append(number)
        for key, value in intrinsic.items():
            rows[f"{c}intrinsic.{key}"].append(value)
        rows[f"{c}extrinsic.transform"].append([float(v) for v in transform.ravel()])
        rows[f"{c}width"].append(width)
        rows[f"{c}height"].append(height)
    table = pa.table({k: pa.array(v, type=pa.int8() if k == "key.camera_name" else None) for k, v in rows.items()})
    folder.mkdir(parents=True, exist_ok=True)
    parquet.write_table(table, folder / "camera_calibration.parquet", compression="none")


def write_ddad(folder: Path) -> None:
    names = list(DDAD_CAMERAS)
    intrinsics, extrinsics = [], []
    for name, yaw in DDAD_CAMERAS.items():
        f = DDAD_FOCAL_PX.get(name, DDAD_OTHER_FOCAL_PX)
        intrinsics.append({"fx": f, "fy": f, "cx": DDAD_SIZE[0] / 2, "cy": DDAD_SIZE[1] / 2})
        x = DDAD_RING_CENTRE[0] + DDAD_RING_RADIUS * math.cos(math.radians(yaw))
        y = DDAD_RING_CENTRE[1] + DDAD_RING_RADIUS * math.sin(math.radians(yaw))
        w, qx, qy, qz = quaternion_wxyz(yaw_matrix(yaw) @ OPTICAL_IN_BODY)  # R_ego_optical
        extrinsics.append({"translation": {"x": round(x, 4), "y": round(y, 4) + 0.0, "z": DDAD_HEIGHT},
                           "rotation": {"qx": qx, "qy": qy, "qz": qz, "qw": w}})
    calibration = {"names": names, "intrinsics": intrinsics, "extrinsics": extrinsics}
    key = hashlib.sha1(json.dumps(calibration, sort_keys=True).encode()).hexdigest()
    write_json(folder / "calibration" / f"{key}.json", calibration)
    scene = {"name": "ddad", "data": [
        {"id": {"name": name, "index": "0"}, "key": f"k{name}",
         "datum": {"image": {"filename": f"rgb/{name}/0.png", "width": DDAD_SIZE[0], "height": DDAD_SIZE[1],
                             "channels": 3}}} for name in names]}
    scene_key = hashlib.sha1(json.dumps(scene, sort_keys=True).encode()).hexdigest()
    write_json(folder / f"scene_{scene_key}.json", scene)


if __name__ == "__main__":
    write_nuscenes(HERE / "nuscenes")
    write_argoverse2(HERE / "argoverse2")
    write_waymo(HERE / "waymo")
    write_ddad(HERE / "ddad")
