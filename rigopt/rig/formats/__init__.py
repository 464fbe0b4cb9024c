"""Rig calibration formats of datasets and tools, both ways (see docs/formats.md), in one registry.

Readers return :class:`~rigopt.rig.formats.common.Imported` (the rig and stderr notes: its origin first);
writers return :class:`~rigopt.rig.formats.common.Exported` (files and warnings for what the format cannot
carry) or raise a RigoptError when a camera cannot be written at all.

``rigopt import FORMAT PATH`` and ``rigopt export --format FORMAT`` serve every format through :data:`FORMATS`.
Adding a format is its module (a reader and, if it writes, a writer) and one :class:`Format` entry below.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from rigopt.errors import RigoptError, unknown_name


@dataclass(frozen=True)
class ImportRequest:
    """What ``rigopt import`` asks of a reader: the ``path`` (file or folder) and the options a format takes.

    ``name``, ``vehicle`` (None: the format's default), ``origin`` (a RigOrigin, None: the format's own);
    ``calibration``: the K-th distinct calibration; ``image_sizes``: {None: default, channel: (w, h) px} where the
    files give none; ``log``, ``scene``, ``segment``: the calibration a log, scene or segment used; ``cameras``:
    which cameras ("ring" or "all"); ``raw_lens``: keep the lenses' distortion; ``axle_height`` (m)."""

    path: Path
    name: str | None = None
    vehicle: str | None = None
    origin: object | None = None
    calibration: int | None = None
    image_sizes: dict | None = None
    log: str | None = None
    scene: str | None = None
    segment: str | None = None
    cameras: str = "ring"
    raw_lens: bool = False
    axle_height: float | None = None


@dataclass(frozen=True)
class Format:
    """A calibration format: ``read`` (ImportRequest -> Imported), optionally ``listing`` (ImportRequest -> rows
    of the distinct calibrations, ``--list``) and ``write`` (Rig -> Exported).

    ``options``: the ImportRequest fields the reader takes beyond path, name, vehicle and origin (the command
    refuses the others); ``suffixes``: what ``export --out`` is, a file with one of these extensions or, None, a
    folder; ``origin``: where the format measures positions from (export converts to it); ``image_size``: the
    default ``--image-size``; ``summary``: one line for the command's help."""

    name: str
    summary: str
    read: Callable
    options: tuple[str, ...] = ()
    listing: Callable | None = None
    write: Callable | None = None
    suffixes: tuple[str, ...] | None = field(default=None)
    origin: str = "vehicle_centre"
    image_size: str | None = None

    @property
    def writes(self) -> bool:
        return self.write is not None


def _lazy(target: str) -> Callable:
    """The function ``module:name`` of this package, imported on first call (a format's dependencies, such as
    pyarrow, load only when it is used)."""
    module, _, name = target.partition(":")

    def call(*args, **kwargs):
        return getattr(importlib.import_module(f"{__name__}.{module}"), name)(*args, **kwargs)

    return call


# --- Readers: each format's reader called with an ImportRequest ------------------------------------------------

def _nuscenes(r: ImportRequest):
    return _lazy("nuscenes:read_nuscenes")(r.path, r.image_sizes, r.calibration, r.log, r.scene, r.name,
                                           r.vehicle or "nuscenes", r.origin)


def _nuscenes_listing(r: ImportRequest) -> list[dict]:
    return _lazy("nuscenes:describe_calibrations")(_lazy("nuscenes:nuscenes_calibrations")(r.path, r.image_sizes))


def _argoverse1(r: ImportRequest):
    return _lazy("argoverse1:read_argoverse1")(r.path, r.name, r.vehicle or "argoverse1", r.origin, r.axle_height,
                                               r.cameras, r.raw_lens)


def _argoverse2(r: ImportRequest):
    return _lazy("datasets:read_argoverse2")(r.path, r.name, r.vehicle or "argoverse2", r.origin)


def _dgp(r: ImportRequest):
    return _lazy("datasets:read_dgp")(r.path, r.image_sizes[None], r.calibration, r.name, r.vehicle or "dgp",
                                      r.origin)


def _dgp_listing(r: ImportRequest) -> list[dict]:
    return _lazy("datasets:dgp_calibrations")(r.path, r.image_sizes[None])


def _waymo(r: ImportRequest):
    return _lazy("datasets:read_waymo")(r.path, r.calibration, r.segment, r.name, r.vehicle or "waymo", r.origin)


def _waymo_listing(r: ImportRequest) -> list[dict]:
    return [{"calibration": k, "cameras": [c.id for c in g["cameras"]], "segments": g["segments"]}
            for k, g in enumerate(_lazy("datasets:waymo_calibrations")(r.path))]


def _opencv(r: ImportRequest):
    return _lazy("opencv:read_camchain")(r.path, r.name, r.vehicle or "opencv", r.origin)


def _urdf(r: ImportRequest):
    return _lazy("urdf:read_urdf")(r.path, r.name, r.vehicle or "urdf", r.origin)


def _carla(r: ImportRequest):
    return _lazy("carla:read_carla")(r.path, r.name, r.vehicle, r.origin)


#: Every format, by name, in the order the commands list them.
FORMATS: dict[str, Format] = {f.name: f for f in (
    Format("nuscenes", "nuScenes calibration tables (a folder: sensor.json, calibrated_sensor.json, ...)", _nuscenes,
           ("calibration", "image_sizes", "log", "scene"), _nuscenes_listing, _lazy("nuscenes:export_nuscenes"),
           None, "rear_axle", "1600x900"),
    Format("argoverse1", "Argoverse 1 vehicle_calibration_info.json (or its log folder)", _argoverse1,
           ("cameras", "raw_lens", "axle_height")),
    Format("argoverse2", "Argoverse 2 calibration (a log folder or its calibration/ folder)", _argoverse2),
    Format("dgp", "DGP (DDAD) calibration JSON (or a scene folder)", _dgp, ("calibration", "image_sizes"),
           _dgp_listing, image_size="1936x1216"),
    Format("waymo", "Waymo Open Dataset v2 camera_calibration Parquet or v1 Frame TFRecords (or a folder)", _waymo,
           ("calibration", "segment"), _waymo_listing),
    Format("urdf", "ROS URDF with <gazebo> camera sensors", _urdf, (), None, _lazy("urdf:export_urdf"),
           (".urdf", ".xml")),
    Format("opencv", "Kalibr / OpenCV camchain YAML", _opencv, (), None, _lazy("opencv:export_opencv"),
           (".yaml", ".yml")),
    Format("carla", "CARLA camera spawn list JSON", _carla, (), None, _lazy("carla:export_carla"), (".json",)),
)}


def find_format(name: str, writing: bool = False) -> Format:
    """The format ``name``; an error naming the formats rigopt reads (or, ``writing``, writes) otherwise."""
    names = [n for n, f in FORMATS.items() if f.writes or not writing]
    if name in names:
        return FORMATS[name]
    if not writing:
        raise unknown_name("format", name, names)
    reads = " (one rigopt reads but does not write)" if name in FORMATS else ""
    raise RigoptError(f"--format {name!r} is not one rigopt writes{reads}; use one of {', '.join(names)}")


def export_rig(rig, format_name: str):
    """The :class:`Exported` files and warnings of ``rig`` in ``format_name`` (a format that writes)."""
    return find_format(format_name, writing=True).write(rig)
