"""The format registry: each format of :data:`~rigopt.rig.formats.catalogue.SPECS` with its reader and writer.

Readers return :class:`~rigopt.rig.formats.common.Imported` (the rig and stderr notes: its origin first);
writers return :class:`~rigopt.rig.formats.common.Exported` (files and warnings for what the format cannot
carry) or raise a RigoptError when a camera cannot be written at all.

``rigopt import FORMAT PATH`` and ``rigopt export --format FORMAT`` serve every format through :data:`FORMATS`.
Adding a format is its module (a reader and, if it writes, a writer), its spec in catalogue.py and one
:class:`Format` entry below.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from rigopt.errors import RigoptError, unknown_name
from rigopt.rig.formats.argoverse1 import read_argoverse1
from rigopt.rig.formats.carla import export_carla, read_carla
from rigopt.rig.formats.catalogue import LIST, SPECS, FormatSpec
from rigopt.rig.formats.datasets import dgp_calibrations, read_argoverse2, read_dgp, read_waymo, waymo_calibrations
from rigopt.rig.formats.nuscenes import describe_calibrations, export_nuscenes, nuscenes_calibrations, read_nuscenes
from rigopt.rig.formats.opencv import export_opencv, read_camchain
from rigopt.rig.formats.urdf import export_urdf, read_urdf


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
    """A format's ``spec`` (name, options, export target) and its functions: ``read`` (ImportRequest -> Imported),
    ``listing`` (ImportRequest -> rows of the distinct calibrations, ``--list``; exactly when the spec takes
    :data:`~rigopt.rig.formats.catalogue.LIST`) and ``write`` (Rig -> Exported; exactly when the spec writes)."""

    spec: FormatSpec
    read: Callable
    listing: Callable | None = None
    write: Callable | None = None

    def __post_init__(self):
        if (self.listing is not None) != (LIST in self.spec.options):
            raise ValueError(f"format {self.spec.name}: a listing goes with the --list option, and only with it")
        if (self.write is not None) != self.spec.writes:
            raise ValueError(f"format {self.spec.name}: a writer goes with writes=True, and only with it")

    @property
    def name(self) -> str:
        return self.spec.name


# --- Readers: each format's reader called with an ImportRequest ------------------------------------------------

def _nuscenes(r: ImportRequest):
    return read_nuscenes(r.path, r.image_sizes, r.calibration, r.log, r.scene, r.name, r.vehicle or "nuscenes",
                         r.origin)


def _nuscenes_listing(r: ImportRequest) -> list[dict]:
    return describe_calibrations(nuscenes_calibrations(r.path, r.image_sizes))


def _argoverse1(r: ImportRequest):
    return read_argoverse1(r.path, r.name, r.vehicle or "argoverse1", r.origin, r.axle_height, r.cameras, r.raw_lens)


def _argoverse2(r: ImportRequest):
    return read_argoverse2(r.path, r.name, r.vehicle or "argoverse2", r.origin)


def _dgp(r: ImportRequest):
    return read_dgp(r.path, r.image_sizes[None], r.calibration, r.name, r.vehicle or "dgp", r.origin)


def _dgp_listing(r: ImportRequest) -> list[dict]:
    return dgp_calibrations(r.path, r.image_sizes[None])


def _waymo(r: ImportRequest):
    return read_waymo(r.path, r.calibration, r.segment, r.name, r.vehicle or "waymo", r.origin)


def _waymo_listing(r: ImportRequest) -> list[dict]:
    return [{"calibration": k, "cameras": [c.id for c in g["cameras"]], "segments": g["segments"]}
            for k, g in enumerate(waymo_calibrations(r.path))]


def _opencv(r: ImportRequest):
    return read_camchain(r.path, r.name, r.vehicle or "opencv", r.origin)


def _urdf(r: ImportRequest):
    return read_urdf(r.path, r.name, r.vehicle or "urdf", r.origin)


def _carla(r: ImportRequest):
    return read_carla(r.path, r.name, r.vehicle, r.origin)


#: Every format, by name, in the order of :data:`~rigopt.rig.formats.catalogue.SPECS`.
FORMATS: dict[str, Format] = {f.name: f for f in (
    Format(SPECS["nuscenes"], _nuscenes, _nuscenes_listing, export_nuscenes),
    Format(SPECS["argoverse1"], _argoverse1),
    Format(SPECS["argoverse2"], _argoverse2),
    Format(SPECS["dgp"], _dgp, _dgp_listing),
    Format(SPECS["waymo"], _waymo, _waymo_listing),
    Format(SPECS["urdf"], _urdf, write=export_urdf),
    Format(SPECS["opencv"], _opencv, write=export_opencv),
    Format(SPECS["carla"], _carla, write=export_carla),
)}


def find_format(name: str, writing: bool = False) -> Format:
    """The format ``name``; an error naming the formats rigopt reads (or, ``writing``, writes) otherwise."""
    names = [n for n, f in FORMATS.items() if f.spec.writes or not writing]
    if name in names:
        return FORMATS[name]
    if not writing:
        raise unknown_name("format", name, names)
    reads = " (one rigopt reads but does not write)" if name in FORMATS else ""
    raise RigoptError(f"--format {name!r} is not one rigopt writes{reads}; use one of {', '.join(names)}")


def export_rig(rig, format_name: str):
    """The :class:`Exported` files and warnings of ``rig`` in ``format_name`` (a format that writes)."""
    return find_format(format_name, writing=True).write(rig)
