"""Camera and Rig: frozen values in the ISO 8855 vehicle frame (see :mod:`rigopt.geometry`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np

from rigopt.benchmark import BENCHMARK_IMAGE_SIZE
from rigopt.camera import Lens
from rigopt.errors import RigFileError, RigoptError
from rigopt.geometry import is_rotation, matrix_to_quaternion, sum_of_squares

#: Rows of :func:`camera_columns`: position (m), unit quaternion, FOV (deg).
POSITION, QUATERNION, FOV = slice(0, 3), slice(3, 7), 7


def camera_columns(positions, rotations, fovs) -> np.ndarray:
    """Cameras as component-first columns, the form batched metrics work on.

    positions : (..., N, 3) float m; rotations : (..., N, 3, 3) float; fovs : (..., N) float deg
    -> (8, ..., N) float: x, y, z; qw, qx, qy, qz (unit quaternion of the rotation, w >= 0); fov.
    """
    p = np.asarray(positions, dtype=float)
    q = matrix_to_quaternion(rotations)
    q = q / np.sqrt(sum_of_squares(np.moveaxis(q, -1, 0)))[..., None]
    f = np.asarray(fovs, dtype=float)
    lead = np.broadcast_shapes(p.shape[:-1], q.shape[:-1], f.shape)
    out = np.empty((8, *lead))
    out[POSITION] = np.moveaxis(p, -1, 0)
    out[QUATERNION] = np.moveaxis(q, -1, 0)
    out[FOV] = f
    return out


def _frozen_array(values, shape, what: str) -> np.ndarray:
    try:
        array = np.array(values, dtype=float)
    except (TypeError, ValueError):
        raise RigFileError(f"{what} must be numbers of shape {shape}, got {values!r}") from None
    if array.shape != shape:
        raise RigFileError(f"{what} must have shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise RigFileError(f"{what} contains NaN or inf: {array.tolist()}")
    array.flags.writeable = False
    return array


@dataclass(frozen=True, eq=False)
class Camera:
    """One camera of a rig: a pose and a :class:`~rigopt.camera.Lens`.

    Attributes
    ----------
    id : str
        Unique name inside its rig, e.g. ``CAM_BUMPER_FRONT``.
    position : (3,) float
        Lens centre in metres, ISO 8855 vehicle frame (x forward, y left, z up).
    rotation : (3, 3) float
        ``R_vehicle_cam``: camera body (x along the optical axis, y left, z up) -> vehicle frame.
    lens : Lens
        The camera's intrinsics and distortion. The benchmark's ideal centred pinhole is
        ``Lens.pinhole(fov, image_size)`` (:meth:`Camera.pinhole` builds such a camera); an ideal pinhole given
        otherwise is stored as that pinhole of its horizontal FOV, so a camera has one form.
    zone : str or None
        Name of the mounting zone the camera sits in, when known.
    module : str or None
        Name of the camera module (one housing) it shares with other cameras of the rig: a roof cluster, a
        stereo pair. Cameras of one module are one part to the mount rules (their housings do not clash with
        each other); None for a camera in a housing of its own.
    role : str
        ``"perception"`` (fed to the transferred detector: matched to the reference and counted in the rig
        distances) or ``"near_field"`` (for the regulation fields and the blind near field, not fed to the
        detector: counted for coverage, cost and packaging). One of ROLES; default perception.

    :attr:`fov` and :attr:`image_size` are read from the lens. Names (``id``, ``zone``, ``module``) are
    printable text: no control characters or terminal escapes, so that they print and serialise (XML, JSON,
    tables) as they are. Positions lie within ``MAX_POSITION_M`` of the origin in every coordinate.
    """

    id: str
    position: np.ndarray
    rotation: np.ndarray
    lens: Lens
    zone: str | None = None
    module: str | None = None
    role: str = "perception"

    def __post_init__(self):
        _check_name(self.id, "camera id")
        what = f"camera {self.id!r}"
        if self.role not in ROLES:
            raise RigFileError(f"{what} role must be one of {', '.join(ROLES)}, got {self.role!r}")
        for key in ("zone", "module"):
            if getattr(self, key) is not None:
                _check_name(getattr(self, key), f"{what} {key}")
        object.__setattr__(self, "position", _frozen_array(self.position, (3,), f"{what} position"))
        if np.max(np.abs(self.position)) > MAX_POSITION_M:
            raise RigFileError(f"{what} position {self.position.tolist()} is more than {MAX_POSITION_M:g} m from the "
                               "rig's origin; positions are metres in the vehicle frame (check the file's units)")
        rotation = _frozen_array(self.rotation, (3, 3), f"{what} rotation")
        if not is_rotation(rotation):
            raise RigFileError(f"{what} rotation is not a proper rotation matrix (orthonormal, det +1)")
        object.__setattr__(self, "rotation", rotation)
        if not isinstance(self.lens, Lens):
            raise RigFileError(f"{what} lens must be a rigopt.camera.Lens (Camera.pinhole builds the benchmark's "
                               f"pinhole from a FOV), got {type(self.lens).__name__}")
        if self.lens.is_ideal_pinhole:
            pinhole = _pinhole(self.lens.hfov, self.lens.image_size)
            if self.lens != pinhole or self.lens.stated_hfov != pinhole.stated_hfov:
                object.__setattr__(self, "lens", pinhole)

    @classmethod
    def pinhole(cls, id: str, position, rotation, fov: float, image_size=BENCHMARK_IMAGE_SIZE,
                zone: str | None = None, module: str | None = None, role: str = "perception") -> "Camera":
        """A camera with the benchmark's ideal centred square-pixel pinhole: horizontal FOV ``fov`` deg in
        (0, 180), ``image_size`` (width, height) px; its :attr:`fov` is ``fov`` to the bit."""
        what = f"camera {id!r}"
        if isinstance(fov, (bool, str)) or not isinstance(fov, (int, float, np.number)):
            raise RigFileError(f"{what} fov must be a number of degrees, got {fov!r}")
        if not (np.isfinite(fov) and 0.0 < fov < 180.0):
            raise RigFileError(f"{what} fov must be in (0, 180) degrees, got {fov!r}")
        size = tuple(image_size) if isinstance(image_size, (tuple, list)) else ()
        if len(size) != 2 or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v > 0
                                     for v in size):
            raise RigFileError(f"{what} image_size must be two positive integers (width, height), got {image_size!r}")
        try:
            lens = _pinhole(float(fov), (int(size[0]), int(size[1])))
        except RigFileError as error:  # a FOV so narrow that the focal length overflows
            raise RigFileError(f"{what} fov {fov!r} deg has no pinhole: {error}") from None
        return cls(id, position, rotation, lens, zone, module, role)

    @property
    def fov(self) -> float:
        """Horizontal field of view in degrees, the lens's :attr:`~rigopt.camera.Lens.hfov`: in (0, 180) for a
        pinhole (exactly the FOV it was built from), up to 360 for a fisheye; the value RigV and RigCD use."""
        return self.lens.hfov

    @property
    def image_size(self) -> tuple[int, int]:
        """``(width, height)`` in pixels, the lens's."""
        return self.lens.image_size

    @property
    def forward(self) -> np.ndarray:
        """(3,) float: the optical axis as a unit vector in the vehicle frame."""
        return self.rotation[:, 0]

    def same_as(self, other: "Camera", atol: float = 1e-9) -> bool:
        """True when every field agrees (arrays and the lens's numbers within ``atol``)."""
        return (
            self.id == other.id
            and np.allclose(self.position, other.position, atol=atol, rtol=0)
            and np.allclose(self.rotation, other.rotation, atol=atol, rtol=0)
            and abs(self.fov - other.fov) <= atol
            and self.zone == other.zone
            and self.module == other.module
            and self.role == other.role
            and _same_lens(self.lens, other.lens, atol)
        )


@lru_cache(maxsize=4096)
def _pinhole(fov: float, image_size: tuple[int, int]) -> Lens:
    """``Lens.pinhole(fov, image_size)``, built once per FOV and size (lenses are frozen values)."""
    try:
        return Lens.pinhole(fov, image_size)
    except RigoptError as error:
        raise RigFileError(str(error)) from None


#: What a camera is for (see :class:`Camera`): fed to the detector, or for the near field and the regulations.
ROLES = ("perception", "near_field")

#: Largest distance (m) of a camera from its rig's origin, per coordinate: cameras are on their vehicle.
MAX_POSITION_M = 1000.0


def _check_name(value, what: str) -> None:
    """A name must be non-empty printable text (no control characters, no terminal escape sequences)."""
    if not isinstance(value, str) or not value:
        raise RigFileError(f"{what} must be a non-empty string, got {value!r}")
    if not value.isprintable():
        raise RigFileError(f"{what} {value!r} holds control characters; use printable characters only "
                           "(letters, digits, punctuation, spaces)")


def _same_lens(a: Lens, b: Lens, atol: float) -> bool:
    """Lenses alike within ``atol`` (px): two benchmark pinholes by their image sizes (their FOVs, compared by
    :meth:`Camera.same_as`, give the rest); other lenses by every intrinsic and coefficient."""
    if a.is_ideal_pinhole and b.is_ideal_pinhole:
        return a.image_size == b.image_size
    return (a.image_size == b.image_size and a.distortion == b.distortion
            and np.allclose([a.fx, a.fy, a.cx, a.cy, *a.coefficients], [b.fx, b.fy, b.cx, b.cy, *b.coefficients],
                            atol=atol, rtol=0))


#: The reference points a rig's positions may be measured from (see :class:`RigOrigin`).
ORIGIN_KINDS = ("vehicle_centre", "rear_axle", "custom")


@dataclass(frozen=True)
class RigOrigin:
    """The point a rig's camera positions are measured from (axes always ISO 8855: x forward, y left, z up).

    kind : "vehicle_centre"
        The benchmark's (CARLA's) vehicle origin: the centre of the vehicle's bounding box in x and y, on
        the ground (z = 0). Every benchmark rig and every rigopt vehicle mesh uses it.
    kind : "rear_axle"
        The point on the ground below the centre of the rear axle, the origin of nuScenes, Waymo and DDAD
        ego frames (Argoverse 2's lies at the axle's height above it; its importer lowers it to the ground).
    kind : "custom"
        ``point`` (3,) float m: the origin's position in the vehicle-centre frame.

    Converting between origins needs the vehicle (where its rear axle is); see
    :func:`rigopt.vehicle.placement.to_vehicle_centre`.
    """

    kind: str = "vehicle_centre"
    point: tuple[float, float, float] | None = None

    def __post_init__(self):
        if self.kind not in ORIGIN_KINDS:
            raise RigFileError(f"unknown rig origin {self.kind!r}; use one of {', '.join(ORIGIN_KINDS)}")
        if self.kind == "custom":
            point = _frozen_array(self.point, (3,), "a custom rig origin's point") if self.point is not None else None
            if point is None:
                raise RigFileError("a custom rig origin needs its point [x, y, z] in metres in the vehicle-centre frame")
            object.__setattr__(self, "point", tuple(float(v) for v in point))
        elif self.point is not None:
            raise RigFileError(f"a {self.kind} rig origin takes no point; use kind 'custom' for a point of your own")

    @property
    def is_benchmark(self) -> bool:
        """True for the benchmark's vehicle-centre origin."""
        return self.kind == "vehicle_centre"

    def describe(self) -> str:
        """Words for messages: 'vehicle centre', 'rear axle', 'custom point (x, y, z) m'."""
        if self.kind == "custom":
            return "custom point ({:.3f}, {:.3f}, {:.3f}) m".format(*self.point)
        return self.kind.replace("_", " ")


VEHICLE_CENTRE = RigOrigin()


@dataclass(frozen=True, eq=False)
class Rig:
    """An ordered set of N >= 1 cameras on one vehicle.

    Attributes
    ----------
    name : str
        The rig's name (a library name such as ``R1``, or the file stem).
    vehicle : str
        The vehicle the rig is mounted on, as the benchmark names it (a CARLA blueprint such as
        ``vehicle.audi.etron``) or a rigopt vehicle name.
    cameras : tuple of Camera
        At least one camera, ids unique.
    origin : RigOrigin
        The point the camera positions are measured from: the benchmark's vehicle centre by default.
    """

    name: str
    vehicle: str
    cameras: tuple[Camera, ...] = field(default_factory=tuple)
    origin: RigOrigin = VEHICLE_CENTRE

    def __post_init__(self):
        cameras = tuple(self.cameras)
        if not cameras:
            raise RigFileError(f"rig {self.name!r} has no cameras; a rig needs at least one")
        ids = [c.id for c in cameras]
        duplicated = sorted({i for i in ids if ids.count(i) > 1})
        if duplicated:
            raise RigFileError(f"rig {self.name!r} repeats camera ids {duplicated}; ids must be unique")
        object.__setattr__(self, "cameras", cameras)
        if not isinstance(self.origin, RigOrigin):
            raise RigFileError(f"rig {self.name!r} origin must be a RigOrigin, got {self.origin!r}")

    def __len__(self) -> int:
        return len(self.cameras)

    @cached_property
    def positions(self) -> np.ndarray:
        """(N, 3) float: lens centres in metres, vehicle frame."""
        return _read_only(np.stack([c.position for c in self.cameras]))

    @cached_property
    def rotations(self) -> np.ndarray:
        """(N, 3, 3) float: ``R_vehicle_cam`` of each camera."""
        return _read_only(np.stack([c.rotation for c in self.cameras]))

    @cached_property
    def fovs(self) -> np.ndarray:
        """(N,) float: horizontal FOVs in degrees."""
        return _read_only(np.array([c.fov for c in self.cameras]))

    @cached_property
    def column_bytes(self) -> bytes:
        """The cameras as :func:`camera_columns` (position, unit quaternion, FOV), camera after camera: the bytes
        of an (N, 8) float64 array, built once. Batches of many rigs join these in one copy
        (:class:`rigopt.metrics.rigcd.RigBatch`)."""
        return camera_columns(self.positions, self.rotations, self.fovs).T.tobytes()  # C order: camera-major

    @property
    def near_field_count(self) -> int:
        """How many cameras have the near_field role."""
        return sum(c.role == "near_field" for c in self.cameras)

    def perception(self) -> "Rig":
        """The rig of its perception cameras (itself when all are): what the transferred detector is fed and the
        rig distances compare. A rig with none is an error."""
        if self.near_field_count == 0:
            return self
        kept = tuple(c for c in self.cameras if c.role == "perception")
        if not kept:
            raise RigFileError(f"rig {self.name!r} has no perception cameras (all {len(self)} are near_field); the "
                               "rig distances compare the cameras fed to the detector: mark some 'perception'")
        return Rig(self.name, self.vehicle, kept, self.origin)

    def same_as(self, other: "Rig", atol: float = 1e-9) -> bool:
        """True when names, vehicles and every camera agree (arrays within ``atol``)."""
        return (
            self.name == other.name
            and self.vehicle == other.vehicle
            and self.origin == other.origin
            and len(self) == len(other)
            and all(a.same_as(b, atol) for a, b in zip(self.cameras, other.cameras))
        )


def _read_only(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array
