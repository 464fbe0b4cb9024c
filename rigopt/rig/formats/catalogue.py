"""The calibration formats as plain data: each one's name, the import options it takes, what export writes.

No numpy here: ``rigopt --help`` builds the import and export commands' help from :data:`SPECS` (which formats
take an option, which write). :mod:`rigopt.rig.formats.registry` gives each entry its reader and writer.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ImportOption:
    """An option of ``rigopt import`` that only some formats take: its ``flag`` and ``help`` (what it does, without
    the formats taking it: the command's help puts those before it)."""

    flag: str
    help: str


CALIBRATION = ImportOption("--calibration", "take the K-th distinct calibration (0-based; --list)")
LIST = ImportOption("--list", "list the distinct calibrations with their logs, files or segments")
IMAGE_SIZE = ImportOption("--image-size", "image size WIDTHxHEIGHT where the files give none")
LOG = ImportOption("--log", "take the calibration this log used (logfile or token)")
SCENE = ImportOption("--scene", "take the calibration this scene used (name or token)")
SEGMENT = ImportOption("--segment", "take this segment's calibration (key.segment_context_name)")
CAMERAS = ImportOption("--cameras", "ring (the seven ring cameras, default) or all (and the two stereo cameras)")
RAW_LENS = ImportOption("--raw-lens", "keep the lenses' radial distortion (radtan k1, k2, 0, 0, k3) instead of the "
                                      "undistorted pinholes")
AXLE_HEIGHT = ImportOption("--axle-height", "the rear axle's height above the ground in metres, by which positions "
                                            "are raised (default 0.328, the Ford Fusion Hybrid's tyre radius)")


@dataclass(frozen=True)
class FormatSpec:
    """A calibration format as data.

    ``summary``: a few words for the commands' help; ``options``: the :class:`ImportOption` objects ``rigopt
    import`` takes for it (beyond --out, --vehicle, --name, --origin; the command refuses the others; :data:`LIST`
    when it lists its distinct calibrations); ``image_size``: the default ``--image-size``; ``channel_size``: an
    example ``CHANNEL=WxH`` where the format takes a size per camera channel (None: one size for every camera);
    ``suffixes``: what ``export --out`` is, a file with one of these extensions or, None, a folder; ``writes``:
    whether rigopt writes it; ``origin``: where the format measures positions from (export converts to it)."""

    name: str
    summary: str
    options: tuple[ImportOption, ...] = ()
    image_size: str | None = None
    channel_size: str | None = None
    writes: bool = False
    suffixes: tuple[str, ...] | None = None
    origin: str = "vehicle_centre"


#: Every format, by name, in the order the commands list them.
SPECS: dict[str, FormatSpec] = {s.name: s for s in (
    FormatSpec("nuscenes", "calibration tables, a folder", (CALIBRATION, LIST, IMAGE_SIZE, LOG, SCENE),
               image_size="1600x900", channel_size="CAM_BACK=1440x900", writes=True, origin="rear_axle"),
    FormatSpec("argoverse1", "vehicle_calibration_info.json", (CAMERAS, RAW_LENS, AXLE_HEIGHT)),
    FormatSpec("argoverse2", "a log's calibration/ folder"),
    FormatSpec("dgp", "DDAD calibration JSON", (CALIBRATION, LIST, IMAGE_SIZE), image_size="1936x1216"),
    FormatSpec("waymo", "v2 Parquet, v1 TFRecord", (CALIBRATION, LIST, SEGMENT)),
    FormatSpec("urdf", "ROS URDF with gazebo camera sensors", writes=True, suffixes=(".urdf", ".xml")),
    FormatSpec("opencv", "Kalibr camchain YAML", writes=True, suffixes=(".yaml", ".yml")),
    FormatSpec("carla", "spawn list JSON", writes=True, suffixes=(".json",)),
)}


def taking(option: ImportOption) -> list[FormatSpec]:
    """The formats that take ``option``, in :data:`SPECS` order."""
    return [s for s in SPECS.values() if option in s.options]


def writing() -> list[FormatSpec]:
    """The formats rigopt writes, in :data:`SPECS` order."""
    return [s for s in SPECS.values() if s.writes]
