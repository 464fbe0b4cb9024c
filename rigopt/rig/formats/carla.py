"""CARLA camera spawn list (JSON) read into and written from :class:`Rig`.

Layout::

    {"rig": "R1", "vehicle": "vehicle.audi.etron",
     "sensors": [{"id": "CAM_FRONT", "blueprint": "sensor.camera.rgb",
                  "attributes": {"image_size_x": "1280", "image_size_y": "720", "fov": "65.0"},
                  "transform": {"location": {"x": .., "y": .., "z": ..},
                                "rotation": {"pitch": .., "yaw": .., "roll": ..}}}, ...]}

Each camera's role (perception or near_field) is written as its ``role_name`` attribute, CARLA's own attribute
for what an actor is for; a list whose ``role_name`` is anything else reads as perception.

Each sensor is what ``world.spawn_actor(blueprint, carla.Transform(...), attach_to=vehicle)`` takes:
attribute values are strings, as ``blueprint.set_attribute`` wants them; the transform is relative to the
vehicle actor, in CARLA's frame (x forward, y right, z up, left-handed; rotations in degrees), whose origin
is rigopt's vehicle centre. CARLA's camera is an ideal centred pinhole of horizontal ``fov`` (< 180 deg):
a real lens's distortion, principal point and unequal focal lengths are dropped on export (with a
warning, its horizontal FOV kept); a lens of 180 deg or more is refused.
"""

from __future__ import annotations

import json
from pathlib import Path

from rigopt.errors import RigFileError, RigoptError
from rigopt.geometry import carla_to_iso, iso_to_carla
from rigopt.rig.formats.common import (Exported, Imported, format_number, make_rig, numbers, origin_note, read_json,
                                       warn_origin, whole_number)
from rigopt.rig.model import ROLES, Camera, Rig, RigOrigin

BLUEPRINT = "sensor.camera.rgb"
FIX = "write it with rigopt export --format carla (keys rig, vehicle, sensors)"


def export_carla(rig: Rig) -> Exported:
    """The CARLA JSON of ``rig`` (key "" of the files) and warnings for what a CARLA camera cannot carry."""
    wide = [f"{c.id} ({c.fov:.1f} deg)" for c in rig.cameras if not c.fov < 180.0]
    if wide:
        near_field = any(c.role == "near_field" for c in rig.cameras if not c.fov < 180.0)
        raise RigoptError(f"CARLA's pinhole camera needs a FOV under 180 deg; {', '.join(wide)} cannot be written; "
                          + ("add --perception to write the perception cameras alone, or " if near_field else "")
                          + "export with --format opencv instead")
    sensors, approximated = [], []
    for camera in rig.cameras:
        if not camera.lens.is_ideal_pinhole:
            approximated.append(camera.id)
        location, rotation = iso_to_carla(camera.position, camera.rotation)
        width, height = camera.image_size
        sensors.append({
            "id": camera.id, "blueprint": BLUEPRINT,
            "attributes": {"image_size_x": str(width), "image_size_y": str(height), "fov": format_number(camera.fov),
                           "role_name": camera.role},
            "transform": {"location": dict(zip("xyz", (float(v) + 0.0 for v in location))),
                          "rotation": dict(zip(("pitch", "yaw", "roll"), (float(v) + 0.0 for v in rotation)))},
        })
    text = json.dumps({"rig": rig.name, "vehicle": rig.vehicle, "sensors": sensors}, indent=2) + "\n"
    warnings = []
    if approximated:
        warnings.append(f"CARLA cameras are ideal centred pinholes; {', '.join(approximated)} are written as the "
                        "pinhole of their horizontal FOV (distortion, principal point and fy dropped)")
    zoned = [c.id for c in rig.cameras if c.zone is not None]
    if zoned:
        warnings.append(f"the CARLA spawn list does not carry the mounting zones of {len(zoned)} camera(s)")
    warnings += warn_origin(rig, "CARLA", "vehicle_centre")
    return Exported({"": text}, warnings)


def read_carla(path, name: str | None = None, vehicle: str | None = None, origin: RigOrigin | None = None) -> Imported:
    """Read a CARLA spawn list; name and vehicle default to the file's ``rig`` and ``vehicle``."""
    path = Path(path)
    data = read_json(path, "CARLA camera list", FIX)
    if not isinstance(data, dict) or not isinstance(data.get("sensors"), list):
        raise RigFileError(f"{path}: a CARLA camera list is a JSON object with a 'sensors' list; {FIX}")
    cameras = []
    for k, sensor in enumerate(data["sensors"]):
        where = f"{path}: sensor {k}"
        if not isinstance(sensor, dict) or not all(key in sensor for key in ("id", "attributes", "transform")):
            raise RigFileError(f"{where} needs 'id', 'attributes' and 'transform'; {FIX}")
        if sensor.get("blueprint", BLUEPRINT) != BLUEPRINT:
            continue  # not a camera (lidar, radar, ...)
        attributes, transform = sensor["attributes"], sensor["transform"]
        if not isinstance(attributes, dict) or not isinstance(transform, dict):
            raise RigFileError(f"{where}: 'attributes' and 'transform' must be objects; {FIX}")
        size = [whole_number(_value(attributes, key, where), f"{where} attribute {key}")
                for key in ("image_size_x", "image_size_y")]
        fov = _value(attributes, "fov", where)
        location = [_value(transform.get("location"), key, f"{where} location") for key in "xyz"]
        rotation = [_value(transform.get("rotation"), key, f"{where} rotation") for key in ("pitch", "yaw", "roll")]
        position, matrix = carla_to_iso(location, rotation)
        role = attributes.get("role_name", "perception")
        try:
            cameras.append(Camera.pinhole(str(sensor["id"]), position, matrix, fov, tuple(size),
                                          role=role if role in ROLES else "perception"))
        except RigoptError as error:
            raise RigFileError(f"{where}: {error}") from None
    origin = origin or RigOrigin()
    why = "CARLA vehicle actor" if origin.kind == "vehicle_centre" else "--origin"
    rig_name = name or (data.get("rig") if isinstance(data.get("rig"), str) and data.get("rig") else path.stem)
    rig_vehicle = vehicle or (data.get("vehicle") if isinstance(data.get("vehicle"), str) and data.get("vehicle")
                              else "carla")
    rig = make_rig(str(path), rig_name, rig_vehicle, cameras, origin)
    return Imported(rig, (origin_note(origin, why),))


def _value(mapping, key: str, where: str) -> float:
    """A number (or numeric string, as CARLA's attributes are) from ``mapping[key]``."""
    if not isinstance(mapping, dict) or key not in mapping:
        raise RigFileError(f"{where}: missing {key!r}; {FIX}")
    value = mapping[key]
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise RigFileError(f"{where}: {key} must be a number, got {mapping[key]!r}") from None
    return float(numbers([value], (1,), f"{where} {key}")[0])
