"""What the designer may choose from and what it must achieve: ``DesignSettings`` and its defaults.

The lens catalogue is a tuple of real cameras (:class:`CatalogueCamera`: a name and a
:class:`rigopt.camera.Lens`, i.e. image size, intrinsics and distortion). The default is the benchmark's
camera, a 1280 x 720 centred pinhole, at the FOVs of ``DEFAULT_FOVS``; a user catalogue file
(:func:`read_catalogue`, TOML or JSON) lists real cameras.

Light to import (numpy only at import time): the command line shows these defaults in its help. The
coverage ring settings and the mount rules, whose modules pull in the geometry libraries, are built on
first use.
"""

from __future__ import annotations

import json
import tomllib
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Sequence

import numpy as np

from rigopt.benchmark import BENCHMARK_IMAGE_SIZE
from rigopt.camera import DISTORTION_COEFFICIENTS, Lens
from rigopt.design.defaults import (DEFAULT_FOVS, DEFAULT_MAX_NODES, DEFAULT_PITCHES_DEG, DEFAULT_YAW_STEP_DEG, POSES,
                                    RANGE_STEP)
from rigopt.errors import DataError, RigoptError, json_loads, not_utf8
from rigopt.output import existing_file
from rigopt.rig.model import Camera

if TYPE_CHECKING:
    from rigopt.mounting.records import MountRules
    from rigopt.coverage.measures import CoverageSettings
    from rigopt.metrics.drop_model import DropModel


def _design_coverage() -> CoverageSettings:
    from rigopt.coverage.measures import CoverageSettings

    return CoverageSettings(ring_distances=(2.0, 5.0, 10.0, 20.0), sectors=36)


def _mount_rules() -> MountRules:
    from rigopt.mounting.records import MountRules

    return MountRules()


def _check_fovs(fovs: Sequence[float]) -> None:
    bad = [f for f in fovs if not 0.0 < f < 180.0]
    if bad:
        raise RigoptError(f"lens FOVs must lie within (0, 180) degrees, got {', '.join(f'{f:g}' for f in bad)}")


def fov_catalogue(fovs: Sequence[float]) -> tuple[float, ...]:
    """The catalogue's horizontal FOVs ``fovs`` (deg) as floats, checked to lie within (0, 180) degrees."""
    out = tuple(float(f) for f in fovs)
    if not out:
        raise RigoptError("a lens catalogue needs at least one FOV")
    _check_fovs(out)
    return out


def range_fovs(low: float, high: float) -> tuple[float, ...]:
    """The FOVs (deg) that seed a continuous FOV range [``low``, ``high``] deg: every RANGE_STEP degrees
    from ``low`` (``high`` itself when the range is a whole number of steps). The MILP picks among their
    pinholes and the refinement then adjusts each camera's FOV within the range (``DesignSettings.fov_range``)."""
    _check_fovs((low, high))
    if low > high:
        raise RigoptError(f"a FOV range needs low <= high, got {low:g}-{high:g}")
    return tuple(float(f) for f in np.arange(low, high + 1e-9, RANGE_STEP))


@dataclass(frozen=True)
class CatalogueCamera:
    """One camera of the lens catalogue: a named :class:`~rigopt.camera.Lens` (image size, intrinsics,
    distortion). Its :attr:`fov` is the lens's horizontal FOV (deg), the one the metrics compare it by."""

    name: str
    lens: Lens

    def __post_init__(self):
        if not isinstance(self.lens, Lens):
            raise RigoptError(f"catalogue camera {self.name!r}: its lens must be a rigopt.camera.Lens, got "
                              f"{type(self.lens).__name__}")

    @classmethod
    def pinhole(cls, fov: float, image_size=BENCHMARK_IMAGE_SIZE) -> "CatalogueCamera":
        """The benchmark's camera: a centred square-pixel pinhole of horizontal FOV ``fov`` (deg) at
        ``image_size`` (width, height) px."""
        _check_fovs((fov,))
        width, height = image_size
        return cls(f"pinhole {fov:g} deg {width}x{height}", Lens.pinhole(float(fov), (width, height)))

    @property
    def fov(self) -> float:
        """Horizontal FOV (deg): the lens's :attr:`~rigopt.camera.Lens.hfov` (a pinhole's, exactly as asked)."""
        return self.lens.hfov

    def camera(self, id: str, position, rotation, zone: str | None = None) -> Camera:
        """A rig camera of this catalogue camera at ``position`` (3,) m with ``rotation`` R_vehicle_cam."""
        return Camera(id, position, rotation, self.lens, zone)


def pinhole_catalogue(fovs: Sequence[float], image_size=BENCHMARK_IMAGE_SIZE) -> tuple[CatalogueCamera, ...]:
    """Benchmark pinholes of horizontal FOVs ``fovs`` (deg, within (0, 180)) at ``image_size`` (w, h) px."""
    return tuple(CatalogueCamera.pinhole(f, image_size) for f in fov_catalogue(fovs))


def catalogue_of(entries) -> tuple[CatalogueCamera, ...]:
    """A catalogue from CatalogueCameras, Lenses (named by their size and model) or FOVs (deg: benchmark
    pinholes at the benchmark's image size), in the given order."""
    out = []
    for entry in entries:
        if isinstance(entry, CatalogueCamera):
            out.append(entry)
        elif isinstance(entry, Lens):
            out.append(CatalogueCamera(f"{entry.distortion} {entry.width}x{entry.height} fx {entry.fx:g}", entry))
        else:
            out.append(CatalogueCamera.pinhole(entry))
    if not out:
        raise RigoptError("a lens catalogue needs at least one camera")
    return tuple(out)


#: The keys of one camera in a catalogue file; ``distortion`` and ``coefficients`` may be left out (pinhole).
CATALOGUE_KEYS = ("name", "width", "height", "fx", "fy", "cx", "cy", "distortion", "coefficients")


def parse_catalogue(data, where: str) -> tuple[CatalogueCamera, ...]:
    """The cameras of a parsed catalogue file (``{"cameras": [{name, width, height, fx, fy, cx, cy,
    distortion, coefficients}, ...]}``); ``where`` names the file in errors (DataError)."""
    entries = data.get("cameras") if isinstance(data, dict) else None
    if not isinstance(entries, list) or not entries:
        raise DataError(f"{where}: a camera catalogue needs a non-empty list 'cameras' of cameras "
                        f"({', '.join(CATALOGUE_KEYS)}), e.g. [[cameras]] tables in TOML")
    cameras, names = [], set()
    for i, entry in enumerate(entries):
        what = f"{where}: camera {i + 1}"
        if not isinstance(entry, dict):
            raise DataError(f"{what} must be a table of {', '.join(CATALOGUE_KEYS)}, got {entry!r}")
        unknown = sorted(set(entry) - set(CATALOGUE_KEYS))
        missing = [k for k in CATALOGUE_KEYS[:7] if k not in entry]
        if unknown or missing:
            raise DataError(f"{what} has {'unknown keys ' + ', '.join(unknown) if unknown else ''}"
                            f"{' and ' if unknown and missing else ''}"
                            f"{'no ' + ', '.join(missing) if missing else ''}; a camera has "
                            f"{', '.join(CATALOGUE_KEYS)} (the last two optional)")
        name = entry["name"]
        if not isinstance(name, str) or not name.strip():
            raise DataError(f"{what}: 'name' must be a non-empty string, got {name!r}")
        if name in names:
            raise DataError(f"{what}: the name {name!r} is used twice; give each camera its own name")
        names.add(name)
        distortion = entry.get("distortion", "none")
        coefficients = entry.get("coefficients", [])
        if distortion not in DISTORTION_COEFFICIENTS or not isinstance(coefficients, list):
            raise DataError(f"{what} ({name}): 'distortion' must be one of {', '.join(DISTORTION_COEFFICIENTS)} "
                            f"and 'coefficients' a list of numbers, got {distortion!r}, {coefficients!r}")
        try:
            lens = Lens(entry["width"], entry["height"], entry["fx"], entry["fy"], entry["cx"], entry["cy"],
                        distortion, tuple(coefficients))
        except RigoptError as error:
            raise DataError(f"{what} ({name}): {error}") from None
        cameras.append(CatalogueCamera(name, lens))
    return tuple(cameras)


def read_catalogue(path) -> tuple[CatalogueCamera, ...]:
    """The cameras of a catalogue file: TOML (``.toml``) or JSON (any other name); see
    :func:`parse_catalogue` and docs/design.md. Raises DataError for an unreadable or malformed file."""
    path = existing_file(path, "camera catalogue (TOML or JSON)", "docs/design.md shows one",
                         option="--cameras-file", kind=DataError)
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as error:
        raise DataError(f"{path}: cannot read the camera catalogue ({error.strerror}); check the path") from None
    except UnicodeDecodeError as error:
        raise not_utf8(path, "camera catalogue", error) from None
    try:
        data = tomllib.loads(text) if path.suffix.lower() == ".toml" else json_loads(text)
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as error:
        kind = "TOML" if path.suffix.lower() == ".toml" else "JSON"
        raise DataError(f"{path}: the camera catalogue is not valid {kind} ({error}); fix the file") from None
    return parse_catalogue(data, str(path))


@dataclass(frozen=True)
class DesignSettings:
    """What the designer may choose from and what it must achieve."""

    cameras: tuple[int, int] | None = None
    """(min, max) camera count, inclusive; None for the (first) reference's count."""
    lenses: tuple[CatalogueCamera, ...] = DEFAULT_FOVS
    """The lens catalogue: real cameras (CatalogueCamera). Lenses or FOVs (deg; benchmark pinholes at
    1280 x 720) are turned into catalogue cameras, so the default is the benchmark's pinholes at
    ``DEFAULT_FOVS``."""
    zones: tuple[str, ...] | None = None
    """The zone names cameras may be mounted on; None for every zone of the vehicle."""
    pitches_deg: tuple[float, ...] = DEFAULT_PITCHES_DEG
    """Pitch angles (deg, > 0 up) of the orientation grid; their range also bounds the refinement."""
    yaw_step_deg: float = DEFAULT_YAW_STEP_DEG
    """Step (deg) of the yaw grid, from -180 deg."""
    spacing: float | None = None
    """Mount point spacing (m); None to size it from the vehicle (about ``target_mounts`` points)."""
    target_mounts: int = 400
    """How many mount points a sized spacing aims at on the allowed zones."""
    min_coverage: int = 0
    """Cameras every sector point needs (0: only where the reference sees it, 1)."""
    min_overlap: int = 0
    """Cameras needed where the reference sees a sector point with >= 2 (0: no overlap requirement)."""
    keep_per_reference: int = 150
    """Pruning: each reference camera's cheapest candidates offered to the MILP."""
    keep_per_sector: int = 6
    """Pruning: for every required sector point, the cheapest candidates that see it offered to the MILP."""
    keep_coverers: int = 300
    """Pruning: the candidates that see the most required field points, offered to the MILP."""
    coverage_mounts: int = 80
    """About how many mount points offer every orientation for coverage (the coverage pool)."""
    max_nodes: int = DEFAULT_MAX_NODES
    """MILP work limit: branch-and-bound nodes (one thread, fixed seed). A design the MILP has not proven best
    within it (relative gap above ``mip_gap``) is an error, unless ``accept_gap``. No clock limits the MILP: the
    same input gives the same selection on any machine at any load."""
    accept_gap: bool = False
    """Return the best selection found within ``max_nodes`` with its gap (status ``node_limit``) instead of
    refusing a selection not proven best."""
    mip_gap: float = 1e-4
    """MILP relative optimality gap at which HiGHS stops."""
    refine: bool = True
    """Run the continuous stage (casadi + IPOPT) after the MILP (single-reference designs only)."""
    fov_range: tuple[float, float] | None = None
    """(min, max) deg when the lens is continuous (the refinement then adjusts FOVs; see ``range_fovs``)."""
    coverage: CoverageSettings = field(default_factory=_design_coverage)
    """The rings and sectors of the coverage requirements (rings at 2, 5, 10, 20 m, 36 sectors)."""
    rules: MountRules = field(default_factory=_mount_rules)
    """The mount checks every camera of a design passes."""
    max_body_fraction: float | None = 0.10
    """Largest share of a designed camera's image that may show the ego body (None: no limit)."""
    require: str | None = None
    """The regulation fields the design must see (:func:`rigopt.coverage.regulations.parse_require`):
    comma-separated preset keys, ``default`` (the vehicle category's: trucks r151, r159, r158; cars r158) or
    ``none``; None (the default) requires the category's fields unless no design sees them all, when they
    are dropped with a note and reported."""
    field_pixels: float | None = None
    """The pixels a field's test object must be tall in a camera's image for a field point to count as seen (None:
    each preset's own, :data:`rigopt.coverage.regulations.MIN_OBJECT_PX`; 0: in view is enough)."""
    cost_weight: float = 0.0
    """Weight of the chosen cameras' mean relative mounting cost (zone cost, tyre spray) added to the
    calibrated RigCD in the MILP's objective (0: the cost is reported only)."""
    symmetric: bool | None = None
    """Cameras in mirrored pairs across y = 0 or on the centreline: None on a mirror-symmetric vehicle
    (:mod:`rigopt.vehicle.symmetry`), True always, False never (``--asymmetric``)."""
    perception_symmetric: bool = True
    """False: the perception cameras are placed freely while the near-field cameras keep their mirrored pairs
    (``--free-perception``): the reference's own layout, which a mirrored body may not offer at the nearest pose
    (a low rear camera beside a fire truck's tailboard)."""
    match_height_m: float | None = None
    """Pose tolerance of the perception cameras (``--match-height``): each may be matched only to a reference
    camera whose height above the ground is within this many metres of its own (None: any). A lifting
    detector's depth prior is its training rig's (docs/design.md, "Pose tolerance")."""
    match_pitch_deg: float | None = None
    """Pose tolerance (``--match-pitch``): each perception camera's pitch within this many degrees of its
    matched reference camera's (None: any)."""
    match_yaw_deg: float | None = None
    """Pose tolerance (``--match-yaw``): each perception camera's yaw within this many degrees of its matched
    reference camera's (None: any). On the yaw grid, half its step keeps the nearest grid yaw."""
    match_fov_deg: float | None = None
    """Lens tolerance (``--match-fov``): each perception camera's horizontal FOV within this many degrees of its
    matched reference camera's (None: any; 0: the reference's lens)."""
    height_search_m: float = 0.0
    """With a height tolerance and freely placed perception cameras: after the MILP, each perception camera moves
    to the valid mount within this many metres whose height is nearest its matched reference camera's, on a grid
    finer than the MILP's (``--height-search``; :mod:`rigopt.design.heights`; 0: off)."""
    perception_range_m: float = 0.0
    """With near-field cameras: the perception cameras keep the reference's coverage only on the rings at least
    this far (m) from the body (``--perception-range``; 0: every ring); the nearer rings are the near-field
    cameras' ground."""
    drop_model: DropModel | None = None
    """The model of the measured drop whose pair cost the MILP minimises instead of the calibrated RigCD's
    (:meth:`rigopt.metrics.drop_model.DropModel.pair_costs`, its count weight setting the MILP's alpha); the
    continuous stage, whose objective has RigCD's terms only, is then off. None: RigCD."""
    near_field: bool = True
    """Two roles (the default): the perception cameras are designed for the reference alone (no fields asked
    of them), then near_field fisheyes (:mod:`rigopt.design.near_field`) see the required fields and the near
    ring around the body. False (``--single-set``): one camera set serves both."""

    @classmethod
    def preset(cls, pose: str = "nearest", **fields) -> DesignSettings:
        """The settings ``rigopt design`` designs with: the perception cameras' pose preset ``pose`` (POSES:
        "nearest", the default design, or "free"), any other field from ``fields`` (a pose field given there wins
        over the preset's). The nearest pose is a two-role design's: with ``near_field=False`` (one camera set)
        the pose is "free"'s. ``design_rig`` without settings designs with ``preset()``."""
        key = str(pose).lower()
        if key not in POSES:
            raise RigoptError(f"the pose preset must be one of {', '.join(POSES)}, got {pose!r}")
        return cls(**{**POSES[key if fields.get("near_field", True) else "free"], **fields})

    @property
    def tolerances(self) -> bool:
        """Whether any pose or lens tolerance constrains the perception cameras."""
        return any(v is not None for v in (self.match_height_m, self.match_pitch_deg, self.match_yaw_deg,
                                           self.match_fov_deg))

    def is_symmetric_on(self, vehicle) -> bool:
        """Whether a design on ``vehicle`` places its cameras in mirrored pairs."""
        return vehicle.symmetry.symmetric if self.symmetric is None else bool(self.symmetric)

    def perception_mirrored_on(self, vehicle) -> bool:
        """Whether a design on ``vehicle`` places its perception cameras in mirrored pairs."""
        return self.is_symmetric_on(vehicle) and (self.perception_symmetric or not self.near_field)

    def __post_init__(self):
        object.__setattr__(self, "lenses", catalogue_of(self.lenses))
        if not self.cost_weight >= 0.0:
            raise RigoptError(f"the mounting cost weight must be >= 0, got {self.cost_weight}")
        for name, value in (("height", self.match_height_m), ("pitch", self.match_pitch_deg),
                            ("yaw", self.match_yaw_deg), ("FOV", self.match_fov_deg)):
            if value is not None and not (np.isfinite(value) and value >= 0.0):
                raise RigoptError(f"the {name} tolerance must be a finite number >= 0, got {value}")
        if not (np.isfinite(self.height_search_m) and self.height_search_m >= 0.0):
            raise RigoptError(f"the height search radius must be a finite number of metres >= 0, got "
                              f"{self.height_search_m}")
        if not (np.isfinite(self.perception_range_m) and self.perception_range_m >= 0.0):
            raise RigoptError(f"the perception range must be a finite number of metres >= 0, got "
                              f"{self.perception_range_m}")
        if self.max_body_fraction is not None and not 0.0 <= self.max_body_fraction <= 1.0:
            raise RigoptError(f"the largest ego-body share of an image must be in [0, 1], got {self.max_body_fraction}")

    @property
    def fovs(self) -> tuple[float, ...]:
        """The catalogue cameras' horizontal FOVs (deg), in catalogue order."""
        return tuple(c.fov for c in self.lenses)
