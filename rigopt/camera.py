"""The camera model: a camera's intrinsics, the rays through its pixels, what it sees and where points project.

Everything in rigopt that needs a camera's projection goes through this module: coverage (in-frustum tests,
image rays), mounting (the checked frustum, probe rays), the design refinement (frustum tangents, view
margins), the benchmark renderer (pixel rays, box projection) and the detector baselines (their torch pixel
rays mirror :meth:`CameraModel.pixel_rays`, tested against it).

Conventions
-----------
Camera body frame (as in :mod:`rigopt.geometry`): x along the optical axis, y left, z up; metres.
Optical frame (OpenCV, nuScenes): z along the optical axis, x right, y down; ``R_CAM_OPTICAL`` maps optical
directions into the body frame, so body (x, y, z) is optical (-y, -z, x).

Pixels are (u, v) = (column, row) coordinates in the image plane, u to the right and v down, (0, 0) at the
image's top-left corner; pixel (row i, column j) is centred at (j + 0.5, i + 0.5). These are the
coordinates of the intrinsic matrix ``K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]``: a body-frame point
(x, y, z) in front of the lens (x > 0) has normalised optical coordinates (-y / x, -z / x) and lies at
pixel (cx + fx (-y / x), cy + fy (-z / x)).

Units: FOVs in degrees (the unit users type), image sizes ``(width, height)`` and intrinsics in pixels.

The model
---------
:class:`Lens` is one real camera as calibration files give it: image size, fx, fy, cx, cy and a distortion
model with its coefficients (:data:`DISTORTION_COEFFICIENTS`): "none" (pinhole), "radtan" (OpenCV
radial-tangential k1, k2, p1, p2, k3, on the normalised coordinates (x / z, y / z)) or "fisheye" (OpenCV
fisheye / Kannala-Brandt k1..k4: a ray theta radians off the axis lands at normalised radius
theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8), so lenses wider than 180 degrees work).
Distorted normalised coordinates map to pixels through ``K``. A lens's FOV is the angle between the rays
through the left and right (top and bottom) edge midpoints, through the axis.

:class:`CameraModel` holds a batch of lenses (every field an array of one batch shape, ``()`` for one camera
or ``(c,)`` for c cameras, the distortion model and coefficients included); its methods broadcast over that
batch. It is the one implementation of a lens's geometry: a :class:`Lens` is the validated value of one camera
and maps through its own model of batch shape (), :attr:`Lens.model`. :meth:`CameraModel.of_cameras` builds
the batch from rig cameras' lenses (every camera has one; the benchmark's centred square-pixel pinholes,
:meth:`Lens.pinhole`, by :meth:`CameraModel.from_fov` from their stated FOVs and image sizes). The maths of the
distortion models is in :func:`undistorted_directions` and :func:`distorted_coordinates`. Pinhole cameras take the exact edge-tangent formulas everywhere (bit-identical to
before distortion existed); distorted ones take their projection: a point is in view when it projects
inside the image and lies less than the lens's valid angle (:func:`valid_angle`) off the axis. The checked
view frustum of the mount rules (probe rays, frustum corners) bounds the image's edge rays, its half-angles
capped at ``MAX_FRUSTUM_HALF_ANGLE_DEG`` so that it stays a convex solid.

>>> round(float(focal_from_fov(60.0, 320)), 3)
277.128
>>> model = CameraModel.from_fov(90.0, BENCHMARK_IMAGE_SIZE)
>>> [round(float(t), 4) for t in model.half_tangents()]
[1.0, 0.5625]
>>> model.project(np.array([[10.0, -10.0, 0.0]])).tolist()  # 45 deg right: the image's right edge
[[1280.0, 360.0]]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Protocol, Sequence

import numpy as np

from rigopt.benchmark import BENCHMARK_IMAGE_SIZE, MAX_IMAGE_SIDE
from rigopt.errors import RigoptError

#: Depths (m) below this count as this when margins divide by a point's depth.
MIN_DEPTH = 1e-9

#: How far (deg) a lens's stated horizontal FOV (a rig file's ``fov``) may be from the one its intrinsics give.
FOV_TOLERANCE_DEG = 1e-6


def focal_from_fov(fov_deg, width_px):
    """Focal length in pixels of a horizontal FOV. fov_deg, width_px : (...,) float -> (...,) float."""
    return np.asarray(width_px, dtype=float) / (2.0 * np.tan(np.deg2rad(np.asarray(fov_deg, dtype=float)) / 2.0))


def fov_from_focal(focal_px, width_px):
    """Horizontal FOV in degrees from a focal length. focal_px, width_px : (...,) float -> (...,) float."""
    return np.rad2deg(2.0 * np.arctan(np.asarray(width_px, dtype=float) / (2.0 * np.asarray(focal_px, dtype=float))))


def vertical_fov(fov_deg, width_px, height_px):
    """Vertical FOV in degrees of a square-pixel pinhole. All inputs (...,) float -> (...,) float."""
    return fov_from_focal(focal_from_fov(fov_deg, width_px), height_px)


def intrinsic_matrix(fov_deg, width_px, height_px):
    """3x3 intrinsic matrix ``K`` of a centred pinhole; maps optical-frame rays to pixels. -> (3, 3) float."""
    return CameraModel.from_fov(fov_deg, (width_px, height_px)).intrinsic_matrix()


def pinhole_half_tangents(hfov_deg, width_px, height_px, tan=np.tan):
    """tan of the horizontal and vertical half-angles of a centred square-pixel pinhole.

    hfov_deg : (...,) float deg, or a casadi symbol; width_px, height_px : float, or (...,) float arrays.
    Only arithmetic and ``tan`` are applied to ``hfov_deg``, so with ``tan=casadi.tan`` this is the symbolic
    form the design refinement optimises a lens's FOV with; :meth:`CameraModel.from_fov` builds its focal
    length from the same expression. Returns (tan_h, tan_v), the vertical one scaled by the aspect ratio
    (square pixels).
    """
    tan_h = tan(hfov_deg * (np.pi / 180.0) / 2.0)
    return tan_h, tan_h * (height_px / width_px)


#: Lens distortion models and their coefficients, in the order calibration files give them.
DISTORTION_COEFFICIENTS = {
    "none": (),
    "radtan": ("k1", "k2", "p1", "p2", "k3"),  # OpenCV / Brown-Conrady radial-tangential
    "fisheye": ("k1", "k2", "k3", "k4"),  # OpenCV fisheye / Kannala-Brandt, equidistant base
}

#: Fixed-point and Newton iterations when inverting a distortion (converges to ~1e-12 within real images).
UNDISTORT_ITERATIONS = 40


def radtan_distort(x, y, k) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV radial-tangential distortion of normalised optical coordinates.

    x, y : (...,) float, undistorted (X / Z, Y / Z); k : (..., 5) float (k1, k2, p1, p2, k3), broadcast.
    Returns the distorted (x_d, y_d), each (...,) float.
    """
    k = np.asarray(k, dtype=float)
    k1, k2, p1, p2, k3 = (k[..., i] for i in range(5))
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    return (x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y)


def radtan_undistort(xd, yd, k) -> tuple[np.ndarray, np.ndarray]:
    """The inverse of :func:`radtan_distort` by fixed-point iteration (OpenCV's scheme), same shapes."""
    k = np.asarray(k, dtype=float)
    k1, k2, p1, p2, k3 = (k[..., i] for i in range(5))
    x, y = np.array(xd, dtype=float), np.array(yd, dtype=float)
    for _ in range(UNDISTORT_ITERATIONS):
        r2 = x * x + y * y
        radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
        x = (xd - 2.0 * p1 * x * y - p2 * (r2 + 2.0 * x * x)) / radial
        y = (yd - p1 * (r2 + 2.0 * y * y) - 2.0 * p2 * x * y) / radial
    return x, y


def fisheye_distort(theta, k) -> np.ndarray:
    """Kannala-Brandt distorted radius: theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8).

    theta : (...,) float, radians from the optical axis (may exceed pi / 2); k : (..., 4) float.
    Returns (...,) float: the radius in normalised image coordinates.
    """
    k = np.asarray(k, dtype=float)
    t2 = np.asarray(theta, dtype=float) ** 2
    return theta * (1.0 + t2 * (k[..., 0] + t2 * (k[..., 1] + t2 * (k[..., 2] + t2 * k[..., 3]))))


def fisheye_undistort(theta_d, k) -> np.ndarray:
    """The inverse of :func:`fisheye_distort` by Newton's method from theta = theta_d, same shapes."""
    k = np.asarray(k, dtype=float)
    theta_d = np.asarray(theta_d, dtype=float)
    theta = theta_d.copy()
    for _ in range(UNDISTORT_ITERATIONS):
        t2 = theta * theta
        value = theta * (1.0 + t2 * (k[..., 0] + t2 * (k[..., 1] + t2 * (k[..., 2] + t2 * k[..., 3])))) - theta_d
        slope = 1.0 + t2 * (3 * k[..., 0] + t2 * (5 * k[..., 1] + t2 * (7 * k[..., 2] + t2 * 9 * k[..., 3])))
        theta = theta - value / np.where(np.abs(slope) > 1e-12, slope, 1e-12)
    return theta


#: Largest number of distortion coefficients of any model (radtan's five); :class:`CameraModel` pads to it.
MAX_COEFFICIENTS = 5


def _first_fold(slope_coefficients) -> float:
    """Smallest positive root t of the polynomial ``1 + c1 t + c2 t^2 + ...`` (``slope_coefficients`` =
    (c1, c2, ...)), i.e. where a distortion curve written in t = r^2 (or theta^2) stops rising; inf if none."""
    coefficients = np.trim_zeros(np.array([1.0, *slope_coefficients])[::-1], "f")
    if len(coefficients) < 2:
        return np.inf
    roots = np.roots(coefficients)
    real = roots[(np.abs(roots.imag) <= 1e-9 * np.maximum(1.0, np.abs(roots.real))) & (roots.real > 0)].real
    return float(real.min()) if len(real) else np.inf


def valid_angle(distortion: str, coefficients) -> float:
    """Radians: the largest angle from the optical axis a lens maps one to one into its image plane.

    none: pi / 2 (a pinhole sees only in front). radtan: the angle where the radial distortion
    r (1 + k1 r^2 + k2 r^4 + k3 r^6) of the undistorted radius r = tan(angle) stops growing (beyond it the
    image folds back; tangential terms are left out of this bound), at most pi / 2. fisheye: where
    theta (1 + k1 theta^2 + ... + k4 theta^8) stops growing, at most pi. A point is seen only at a smaller
    angle (:meth:`CameraModel.in_view`)."""
    k = tuple(float(c) for c in coefficients)
    if distortion == "radtan":
        fold = _first_fold((3 * k[0], 5 * k[1], 7 * k[4]))
        return float(min(np.arctan(np.sqrt(fold)), np.pi / 2))
    if distortion == "fisheye":
        fold = _first_fold((3 * k[0], 5 * k[1], 7 * k[2], 9 * k[3]))
        return float(min(np.sqrt(fold), np.pi))
    return float(np.pi / 2)


def undistorted_directions(xd, yd, distortion, k) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Optical-frame directions (x, y, z), not normalised, of distorted normalised image points.

    xd, yd : (...,) float, ((u - cx) / fx, (v - cy) / fy); distortion : (...,) str, broadcast (one of
    :data:`DISTORTION_COEFFICIENTS`); k : (..., 5) float coefficients in the model's order, zero-padded.
    Pinhole and radtan points come back at unit depth (z = 1); fisheye ones as unit vectors (z may be <= 0
    beyond 90 degrees). The one implementation of the lens models' inverse.
    """
    xd, yd = np.asarray(xd, dtype=float), np.asarray(yd, dtype=float)
    distortion, k = np.asarray(distortion), np.asarray(k, dtype=float)
    x, y, z = xd, yd, np.ones_like(xd)
    radtan, fisheye = distortion == "radtan", distortion == "fisheye"
    if np.any(radtan):
        xr, yr = radtan_undistort(xd, yd, k)
        x, y = np.where(radtan, xr, x), np.where(radtan, yr, y)
    if np.any(fisheye):
        radius = np.hypot(xd, yd)
        theta = fisheye_undistort(radius, k[..., :4])
        scale = np.where(radius > 0, np.sin(theta) / np.where(radius > 0, radius, 1.0), 1.0)
        x, y, z = (np.where(fisheye, xd * scale, x), np.where(fisheye, yd * scale, y),
                   np.where(fisheye, np.cos(theta), z))
    return x, y, z


def distorted_coordinates(x, y, z, distortion, k) -> tuple[np.ndarray, np.ndarray]:
    """Distorted normalised image coordinates (x_d, y_d) of optical-frame directions (x, y, z) (any length).

    Shapes as :func:`undistorted_directions`. Pinhole and radtan need z > 0 (others give inf or nan, to be
    masked by the caller); fisheye takes any direction but straight behind.
    """
    x, y, z = (np.asarray(a, dtype=float) for a in (x, y, z))
    distortion, k = np.asarray(distortion), np.asarray(k, dtype=float)
    radtan, fisheye = distortion == "radtan", distortion == "fisheye"
    with np.errstate(divide="ignore", invalid="ignore"):
        xd, yd = x / z, y / z
        if np.any(radtan):
            xr, yr = radtan_distort(xd, yd, k)
            xd, yd = np.where(radtan, xr, xd), np.where(radtan, yr, yd)
    if np.any(fisheye):
        radius = np.hypot(x, y)
        theta_d = fisheye_distort(np.arctan2(radius, z), k[..., :4])
        scale = np.where(radius > 0, theta_d / np.where(radius > 0, radius, 1.0), 0.0)
        xd, yd = np.where(fisheye, x * scale, xd), np.where(fisheye, y * scale, yd)
    return xd, yd


@dataclass(frozen=True)
class Lens:
    """One real camera's intrinsics and lens distortion, as calibration files give them.

    width, height : int, image size in px; fx, fy : float, focal lengths in px; cx, cy : float, principal
    point in px (pixel coordinates as in the module docstring); distortion : one of
    :data:`DISTORTION_COEFFICIENTS` ("none", "radtan", "fisheye"); coefficients : tuple of float in that
    model's order (all zero is the same geometry as "none" for radtan; a fisheye with all zero
    coefficients is the equidistant lens).

    Distorted normalised coordinates map to pixels through ``K``: u = fx x_d + cx, v = fy y_d + cy. The
    fisheye model takes the angle theta of a ray from the optical axis and puts it at radius theta_d(theta)
    in the normalised image, so it covers lenses wider than 180 degrees.

    stated_hfov : float or None, deg: the horizontal FOV the lens was stated with (the FOV a benchmark pinhole
    was built from, :meth:`pinhole`; a rig file's ``fov``), within :data:`FOV_TOLERANCE_DEG` of the one its
    intrinsics give; :attr:`hfov` returns it to the bit. None: :attr:`hfov` is derived from the intrinsics.
    Lenses are equal when their geometry is (size, intrinsics, distortion), whatever FOV they were stated with
    (nor is it in their repr, so messages name a lens by its geometry).
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: str = "none"
    coefficients: tuple[float, ...] = ()
    stated_hfov: float | None = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 < value <= MAX_IMAGE_SIDE:
                raise RigoptError(f"lens {name} must be a whole number of pixels from 1 to {MAX_IMAGE_SIDE}, got "
                                  f"{value!r}")
            object.__setattr__(self, name, int(value))
        for name in ("fx", "fy", "cx", "cy"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) or not np.isfinite(value):
                raise RigoptError(f"lens {name} must be a finite number of pixels, got {value!r}")
            if name in ("fx", "fy") and value <= 0:
                raise RigoptError(f"lens {name} must be positive, got {value!r}")
            object.__setattr__(self, name, float(value))
        if not (0.0 <= self.cx <= self.width and 0.0 <= self.cy <= self.height):
            raise RigoptError(f"lens principal point ({self.cx:g}, {self.cy:g}) px lies outside its {self.width} x "
                              f"{self.height} image; check cx, cy (pixels from the top-left corner) and the image size")
        if self.distortion not in DISTORTION_COEFFICIENTS:
            raise RigoptError(f"unknown lens distortion model {self.distortion!r}; use one of "
                              f"{', '.join(DISTORTION_COEFFICIENTS)}")
        names = DISTORTION_COEFFICIENTS[self.distortion]
        coefficients = tuple(self.coefficients) or (0.0,) * len(names)
        if len(coefficients) != len(names) or not all(
                isinstance(c, (int, float, np.number)) and not isinstance(c, bool) and np.isfinite(c)
                for c in coefficients):
            raise RigoptError(f"a {self.distortion} lens needs {len(names)} finite coefficients "
                              f"({', '.join(names) or 'none'}), got {self.coefficients!r}")
        object.__setattr__(self, "coefficients", tuple(float(c) for c in coefficients))
        edges = self.edge_angles()
        if not all(np.isfinite(a) and 0.0 < a for a in edges):
            raise RigoptError(f"lens {self}: its image edges do not map to rays in front of the lens; check the "
                              "focal lengths, principal point and distortion coefficients")
        if self.is_distorted:  # every pixel needs a ray: the corners (farthest out) must invert exactly
            corners = np.array([[0.0, 0.0], [self.width, 0.0], [0.0, self.height], [self.width, self.height]])
            rays = self.pixel_rays(corners)
            angles = np.arctan2(np.hypot(rays[:, 0], rays[:, 1]), rays[:, 2])
            error = np.abs(self.project(rays) - corners).max()
            if not (np.isfinite(error) and error <= 1e-6 * max(self.width, self.height)
                    and np.all(angles <= self.valid_angle)):
                raise RigoptError(f"lens {self}: its image corners lie beyond what the {self.distortion} distortion "
                                  "reaches before it folds back, so some pixels have no ray; check the distortion "
                                  "coefficients and focal lengths")
        if self.stated_hfov is not None:
            stated = self.stated_hfov
            if isinstance(stated, (bool, str)) or not isinstance(stated, (int, float, np.number)) \
                    or not np.isfinite(stated):
                raise RigoptError(f"a lens's stated horizontal FOV must be a finite number of degrees, got {stated!r}")
            derived = float(np.rad2deg(edges[0] + edges[1]))  # derived_hfov, from the edges at hand
            if not abs(float(stated) - derived) <= FOV_TOLERANCE_DEG:
                raise RigoptError(f"a lens's stated horizontal FOV {float(stated):g} deg disagrees with its "
                                  f"intrinsics' {derived:.6f} deg (tolerance {FOV_TOLERANCE_DEG:g} deg)")
            object.__setattr__(self, "stated_hfov", float(stated))

    @classmethod
    def pinhole(cls, hfov_deg: float, image_size=BENCHMARK_IMAGE_SIZE) -> "Lens":
        """The benchmark's camera: a centred square-pixel pinhole of horizontal FOV ``hfov_deg`` (deg) in (0, 180)
        at ``image_size`` (width, height) px. Its :attr:`hfov` is ``hfov_deg`` itself, to the bit."""
        width, height = image_size
        model = CameraModel.from_fov(hfov_deg, (width, height))
        return cls(int(width), int(height), float(model.fx), float(model.fy), float(model.cx), float(model.cy),
                   stated_hfov=float(hfov_deg))

    @property
    def image_size(self) -> tuple[int, int]:
        """(width, height) in px."""
        return self.width, self.height

    @property
    def is_distorted(self) -> bool:
        """True when the lens is not a plain pinhole: a fisheye (whatever its coefficients: even all zero,
        it is the equidistant lens, not a pinhole), or a radtan lens with a non-zero coefficient."""
        return self.distortion == "fisheye" or any(c != 0.0 for c in self.coefficients)

    @property
    def padded_coefficients(self) -> tuple[float, ...]:
        """The coefficients padded with zeros to :data:`MAX_COEFFICIENTS` (the form the shared maths take)."""
        return self.coefficients + (0.0,) * (MAX_COEFFICIENTS - len(self.coefficients))

    @property
    def valid_angle(self) -> float:
        """Radians: the largest angle from the optical axis the lens maps one to one (:func:`valid_angle`)."""
        return valid_angle(self.distortion, self.padded_coefficients)

    @property
    def is_ideal_pinhole(self) -> bool:
        """True for the benchmark's camera: no distortion, square pixels, principal point at the centre."""
        return (not self.is_distorted and abs(self.fx - self.fy) <= 1e-9 * self.fx
                and abs(self.cx - self.width / 2) <= 1e-9 * self.width
                and abs(self.cy - self.height / 2) <= 1e-9 * self.height)

    # ------------------------------------------------------------------------------------------ mapping
    # A lens is the batch model of one camera: every mapping below is :class:`CameraModel`'s, through :attr:`model`.

    @cached_property
    def model(self) -> "CameraModel":
        """This lens as a :class:`CameraModel` of batch shape (), the one implementation of its geometry."""
        return CameraModel.of_lens(self)

    def pixel_rays(self, pixels) -> np.ndarray:
        """(n, 3) float unit optical-frame rays (z along the axis, x right, y down) through pixels (n, 2)."""
        return self.model.pixel_rays(np.atleast_2d(np.asarray(pixels, dtype=float)), frame="optical")

    def project(self, rays) -> np.ndarray:
        """(n, 2) float pixels of optical-frame directions ``rays`` (n, 3) (any length). Pinhole and radtan
        lenses need z > 0; fisheye lenses take any direction but the one straight behind."""
        return self.model.project(np.atleast_2d(np.asarray(rays, dtype=float)), frame="optical")

    def edge_angles(self) -> tuple[float, float, float, float]:
        """(left, right, top, bottom): radians from the optical axis to the rays through the midpoints of the
        image's edges, taken on the principal point's row and column (:meth:`CameraModel.edge_angles`)."""
        return tuple(float(a) for a in self.model.edge_angles())

    @property
    def derived_hfov(self) -> float:
        """Horizontal FOV in degrees from the intrinsics: the angle from the ray through the left edge to the ray
        through the right edge (through the optical axis, so it may exceed 180 for a fisheye)."""
        left, right, _, _ = self.edge_angles()
        return float(np.rad2deg(left + right))

    @property
    def hfov(self) -> float:
        """Horizontal FOV in degrees: :attr:`stated_hfov` when the lens was stated with one (the benchmark's
        pinhole: the FOV it was built from, exactly), else :attr:`derived_hfov`."""
        return self.stated_hfov if self.stated_hfov is not None else self.derived_hfov

    @property
    def vfov(self) -> float:
        """Vertical FOV in degrees, as :attr:`hfov` between the top and bottom edges."""
        _, _, top, bottom = self.edge_angles()
        return float(np.rad2deg(top + bottom))

    def summary(self) -> dict:
        """The lens as plain JSON values, for reports: size and intrinsics (px), distortion model and
        coefficients, and the ``hfov_deg`` and ``vfov_deg`` derived from the intrinsics."""
        return {"width": self.width, "height": self.height, "fx": self.fx, "fy": self.fy, "cx": self.cx,
                "cy": self.cy, "distortion": self.distortion, "coefficients": list(self.coefficients),
                "hfov_deg": self.derived_hfov, "vfov_deg": self.vfov}

    def label(self) -> str:
        """One line for tables, e.g. ``1280x720 fx 640 pinhole 90.0x58.7 deg``."""
        model = "pinhole" if self.distortion == "none" else self.distortion
        return f"{self.width}x{self.height} fx {self.fx:.0f} {model} {self.hfov:.1f}x{self.vfov:.1f} deg"


def pixel_centres(width: int, height: int) -> np.ndarray:
    """(height * width, 2) float: (u, v) of every pixel's centre, row by row from the top-left pixel."""
    u, v = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    return np.stack([u.ravel(), v.ravel()], axis=1)


def camera_frame_points(positions, rotations, points) -> np.ndarray:
    """(c, p, 3) float: ``points`` (p, 3) m, vehicle frame, in the body frames of c cameras at
    ``positions`` (c, 3) m with ``rotations`` (c, 3, 3) R_vehicle_cam: ``R^T (p - t)``.

    Summed term by term in the order (and from the zero) of ``np.einsum("cji,cpj->cpi", R, p - t)``, so the
    values are einsum's to the bit (tested), at a fifth of its time."""
    rotations = np.asarray(rotations, dtype=float)
    points, positions = np.asarray(points, dtype=float), np.asarray(positions, dtype=float)
    offset = [points[None, :, j] - positions[:, j, None] for j in range(3)]  # (c, p) each
    return np.stack([0.0 + rotations[:, 0, i, None] * offset[0] + rotations[:, 1, i, None] * offset[1]
                     + rotations[:, 2, i, None] * offset[2] for i in range(3)], axis=-1)


def _read_only(values) -> np.ndarray:
    array = np.array(values, dtype=float)
    array.flags.writeable = False
    return array


def _is_stated_pinhole(lens: Lens) -> bool:
    """True for the benchmark's pinhole of a stated FOV (:meth:`Lens.pinhole`), whose model :meth:`CameraModel.from_fov`
    builds from that FOV."""
    return lens.stated_hfov is not None and lens.is_ideal_pinhole


#: Half-angles (deg) of the checked view frustum (:meth:`CameraModel.frustum_corners`, probe rays) are capped
#: here so that it stays a convex solid of finite size for lenses near or beyond 180 degrees.
MAX_FRUSTUM_HALF_ANGLE_DEG = 80.0
#: Points per image edge whose rays bound the frustum of a distorted lens (:meth:`CameraModel.side_angles`).
EDGE_SAMPLES = 33


class HasLens(Protocol):
    """Anything with a :class:`Lens` (a rig's :class:`~rigopt.rig.model.Camera`): what the models of rig cameras
    are built from, without this module knowing the rig."""

    lens: Lens


@dataclass(frozen=True, eq=False)
class CameraModel:
    """Intrinsics and lens distortion of a batch of cameras; see the module docstring for frames and units.

    Attributes (each a read-only array of the batch shape, ``()`` or ``(c,)``)
    ----------
    width, height : float, image size, px.
    fx, fy : float, focal lengths, px.
    cx, cy : float, principal point, px (pixel coordinates, (0, 0) the image's top-left corner).
    distortion : str, each camera's model, one of :data:`DISTORTION_COEFFICIENTS` (default "none").
    coefficients : (..., 5) float, each camera's coefficients in its model's order, zero-padded
        (default zeros).
    """

    width: np.ndarray
    height: np.ndarray
    fx: np.ndarray
    fy: np.ndarray
    cx: np.ndarray
    cy: np.ndarray
    distortion: np.ndarray | str = "none"
    coefficients: np.ndarray | None = None

    def __post_init__(self):
        names = ("width", "height", "fx", "fy", "cx", "cy")
        try:
            values = np.broadcast_arrays(*(np.asarray(getattr(self, n), dtype=float) for n in names))
        except ValueError:
            shapes = {n: np.shape(getattr(self, n)) for n in names}
            raise RigoptError(f"camera intrinsics must share one batch shape, got shapes {shapes}") from None
        for name, value in zip(names, values):
            if not np.all(np.isfinite(value)) or (name in ("width", "height", "fx", "fy") and np.any(value <= 0)):
                raise RigoptError(f"camera intrinsics: {name} must be finite"
                                  f"{' and positive' if name in ('width', 'height', 'fx', 'fy') else ''}, "
                                  f"got {value.tolist()}")
            object.__setattr__(self, name, _read_only(value))
        shape = values[0].shape
        try:
            distortion = np.array(np.broadcast_to(np.asarray(self.distortion, dtype=str), shape))
            coefficients = np.zeros((*shape, MAX_COEFFICIENTS)) if self.coefficients is None else \
                np.asarray(self.coefficients, dtype=float)
            if coefficients.ndim == 0 or coefficients.shape[-1] > MAX_COEFFICIENTS:
                raise ValueError
            coefficients = np.concatenate([coefficients, np.zeros((*coefficients.shape[:-1],
                                                                   MAX_COEFFICIENTS - coefficients.shape[-1]))], -1)
            coefficients = np.array(np.broadcast_to(coefficients, (*shape, MAX_COEFFICIENTS)))
        except ValueError:
            raise RigoptError(f"camera distortion must be one model name per camera and up to {MAX_COEFFICIENTS} "
                              f"coefficients per camera, for batch shape {shape}") from None
        unknown = sorted(set(distortion.ravel().tolist()) - set(DISTORTION_COEFFICIENTS))
        if unknown:
            raise RigoptError(f"unknown lens distortion model(s) {', '.join(map(repr, unknown))}; use one of "
                              f"{', '.join(DISTORTION_COEFFICIENTS)}")
        if not np.all(np.isfinite(coefficients)):
            raise RigoptError(f"camera distortion coefficients must be finite, got {coefficients.tolist()}")
        distortion.flags.writeable = False
        object.__setattr__(self, "distortion", distortion)
        object.__setattr__(self, "coefficients", _read_only(coefficients))

    # ------------------------------------------------------------------------------------------ building

    @classmethod
    def from_fov(cls, hfov_deg, image_size) -> "CameraModel":
        """Centred square-pixel pinholes of horizontal FOV ``hfov_deg`` (...,) deg in (0, 180) and
        ``image_size`` (..., 2) px (width, height); the batch shape is the broadcast of both."""
        fovs = np.asarray(hfov_deg, dtype=float)
        bad = ~np.isfinite(fovs) | (fovs <= 0) | (fovs >= 180)
        if np.any(bad):
            bad_fovs = np.atleast_1d(fovs)[np.atleast_1d(bad)]
            raise RigoptError(f"a pinhole's FOV must be in (0, 180) degrees, got {bad_fovs}")
        sizes = np.asarray(image_size, dtype=float)
        if sizes.ndim == 0 or sizes.shape[-1] != 2:
            raise RigoptError(f"image sizes must be (width, height) pairs in pixels, got shape {sizes.shape}")
        width, height = sizes[..., 0], sizes[..., 1]
        tan_h, _ = pinhole_half_tangents(fovs, width, height)
        focal = width / (2.0 * tan_h)
        return cls(width, height, focal, focal, width / 2.0, height / 2.0)

    @classmethod
    def of_lenses(cls, lenses: Sequence[Lens]) -> "CameraModel":
        """The batch (c,) of ``lenses``: their sizes, intrinsics and distortion."""
        columns = [[getattr(lens, n) for lens in lenses] for n in ("width", "height", "fx", "fy", "cx", "cy")]
        return cls(*columns, np.array([lens.distortion for lens in lenses], dtype=str).reshape(len(lenses)),
                   np.array([lens.padded_coefficients for lens in lenses], dtype=float).reshape(len(lenses),
                                                                                              MAX_COEFFICIENTS))

    @classmethod
    def of_lens(cls, lens: Lens) -> "CameraModel":
        """The model of one lens (batch shape ())."""
        return cls(lens.width, lens.height, lens.fx, lens.fy, lens.cx, lens.cy, lens.distortion,
                   lens.padded_coefficients)

    @classmethod
    def of_cameras(cls, cameras: Sequence[HasLens]) -> "CameraModel":
        """The models of rig cameras (batch shape (c,)) from each camera's :attr:`~rigopt.rig.model.Camera.lens`.
        The one place that reads a rig camera's lens, so real lenses reach coverage, mount checks, refinement and
        the renderer. Benchmark pinholes (each lens stated by its FOV, :meth:`Lens.pinhole`) are built from their
        FOVs and image sizes in one :meth:`from_fov`."""
        if all(_is_stated_pinhole(c.lens) for c in cameras):
            return cls.from_fov([c.lens.hfov for c in cameras], [c.lens.image_size for c in cameras])
        return cls.of_lenses([c.lens for c in cameras])

    @classmethod
    def of_camera(cls, camera: HasLens) -> "CameraModel":
        """The model of one rig camera (batch shape ()): its lens's :attr:`Lens.model`."""
        return camera.lens.model

    @classmethod
    def rendered(cls, camera: HasLens, image_size) -> "CameraModel":
        """The model of one rig camera rendered at ``image_size`` (width, height) px, batch shape (): the
        centred pinhole of its FOV at that size for the benchmark's ideal pinhole, else its own lens
        :meth:`resized` to it. What the benchmark's renderer sees through and its tables record."""
        if camera.lens.is_ideal_pinhole:
            return cls.from_fov(camera.lens.hfov, image_size)
        return camera.lens.model.resized(image_size)

    def lens(self, index=()) -> Lens:
        """The :class:`Lens` of the camera at ``index`` of the batch (``()`` for a single camera); image sizes
        are rounded to whole pixels."""
        return Lens(int(round(float(self.width[index]))), int(round(float(self.height[index]))),
                    float(self.fx[index]), float(self.fy[index]), float(self.cx[index]), float(self.cy[index]),
                    str(self.distortion[index]),
                    tuple(self.coefficients[index][:len(DISTORTION_COEFFICIENTS[str(self.distortion[index])])]))

    def resized(self, image_size) -> "CameraModel":
        """The same lenses seeing images resized to ``image_size`` (..., 2) px (width, height): focal lengths and
        principal points scale with the size; distortion, in normalised coordinates, is unchanged."""
        sizes = np.asarray(image_size, dtype=float)
        sx, sy = sizes[..., 0] / self.width, sizes[..., 1] / self.height
        return CameraModel(sizes[..., 0], sizes[..., 1], self.fx * sx, self.fy * sy, self.cx * sx, self.cy * sy,
                           self.distortion, self.coefficients)

    def take(self, index) -> "CameraModel":
        """The cameras ``index`` (a slice or an index array into the batch (c,)) as a model of their own, with
        what this one has derived already (``distorted``, ``valid_angles``)."""
        part = CameraModel(self.width[index], self.height[index], self.fx[index], self.fy[index], self.cx[index],
                           self.cy[index], self.distortion[index], self.coefficients[index])
        for name in ("distorted", "valid_angles"):
            if name in self.__dict__:
                part.__dict__[name] = self.__dict__[name][index]
        return part

    # -------------------------------------------------------------------------------------------- reading

    @property
    def shape(self) -> tuple[int, ...]:
        """The batch shape."""
        return self.fx.shape

    @cached_property
    def distorted(self) -> np.ndarray:
        """(...,) bool: cameras that are not plain pinholes (fisheye, or radtan with a non-zero coefficient);
        the others take the pinhole formulas, exact and unchanged."""
        return (self.distortion == "fisheye") | ((self.distortion == "radtan") & np.any(self.coefficients != 0, -1))

    @cached_property
    def valid_angles(self) -> np.ndarray:
        """(...,) float rad: each lens's largest angle from the optical axis it maps one to one
        (:func:`valid_angle`: pi / 2 for a pinhole)."""
        flat = [valid_angle(d, k)
                for d, k in zip(self.distortion.ravel(), self.coefficients.reshape(-1, MAX_COEFFICIENTS))]
        return _read_only(np.reshape(flat, self.shape))

    def intrinsic_matrix(self) -> np.ndarray:
        """(..., 3, 3) float ``K``: optical-frame rays (x / z, y / z, 1) -> homogeneous pixels (of the distorted
        normalised coordinates for a distorted lens)."""
        zero, one = np.zeros(self.shape), np.ones(self.shape)
        return np.stack([np.stack([self.fx, zero, self.cx], -1), np.stack([zero, self.fy, self.cy], -1),
                         np.stack([zero, zero, one], -1)], -2)

    def edge_tangents(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(left, right, up, down), each (...,) float: tangents of the angles from the optical axis to the
        image's left, right, top and bottom edges of a distortion-free lens (``cx / fx`` ...). A body-frame
        direction (1, a, b) is in a pinhole's view when ``-right <= a <= left`` and ``-down <= b <= up``.
        For a distorted lens use :meth:`edge_angles`."""
        return (self.cx / self.fx, (self.width - self.cx) / self.fx, self.cy / self.fy,
                (self.height - self.cy) / self.fy)

    def half_tangents(self) -> tuple[np.ndarray, np.ndarray]:
        """(tan_h, tan_v), each (...,) float: tangents of the horizontal and vertical half-angles of a
        distortion-free lens (half the image's extent in normalised coordinates)."""
        return (self.width / 2.0) / self.fx, (self.height / 2.0) / self.fy

    def edge_angles(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(left, right, up, down), each (...,) float rad: angles from the optical axis to the rays through
        the midpoints of the image's edges (on the principal point's row and column); up to pi for a fisheye.
        """
        angles = tuple(np.arctan(t) for t in self.edge_tangents())
        if not np.any(self.distorted):
            return angles
        zero = np.zeros(self.shape)
        pixels = np.stack([np.stack([zero, self.cy], -1), np.stack([self.width, self.cy], -1),
                           np.stack([self.cx, zero], -1), np.stack([self.cx, self.height], -1)], -2)
        rays = self.pixel_rays(pixels)
        real = np.arctan2(np.hypot(rays[..., 1], rays[..., 2]), rays[..., 0])
        return tuple(np.where(self.distorted, real[..., i], angles[i]) for i in range(4))

    @property
    def hfov(self) -> np.ndarray:
        """(...,) float: horizontal FOV, degrees: from the left-edge ray to the right-edge ray through the axis
        (as :attr:`Lens.hfov`; more than 180 for a wide fisheye)."""
        left, right, _, _ = self.edge_angles()
        return np.rad2deg(left + right)

    @property
    def vfov(self) -> np.ndarray:
        """(...,) float: vertical FOV, degrees, between the top-edge and bottom-edge rays."""
        _, _, up, down = self.edge_angles()
        return np.rad2deg(up + down)

    # --------------------------------------------------------------------------------------------- rays

    def pixel_rays(self, pixels, unit: bool = True, frame: str = "body") -> np.ndarray:
        """Rays from the lens through image points, through the lens's distortion.

        pixels : (..., n, 2) float (u, v) px, broadcast against the batch (a leading axis per batch axis).
        unit : True for unit rays; False for rays scaled to unit depth (optical-axis component 1), so that
            the point at depth d is ``d * ray`` (a fisheye pixel 90 degrees or more off the axis has no such
            ray: RigoptError).
        frame : "body" (x forward, y left, z up) or "optical" (z forward, x right, y down).
        Returns (..., n, 3) float.
        """
        if frame not in ("body", "optical"):
            raise RigoptError(f"unknown camera frame {frame!r}; use 'body' or 'optical'")
        pixels = np.asarray(pixels, dtype=float)
        x = (pixels[..., 0] - self.cx[..., None]) / self.fx[..., None]  # normalised optical coordinates
        y = (pixels[..., 1] - self.cy[..., None]) / self.fy[..., None]
        one = np.ones_like(x)
        if np.any(self.distorted):
            x, y, one = undistorted_directions(x, y, self.distortion[..., None], self.coefficients[..., None, :])
            if not unit:
                if np.any(one <= MIN_DEPTH):
                    raise RigoptError("a fisheye pixel 90 degrees or more off the optical axis has no ray at unit "
                                      "depth; ask for unit rays")
                x, y, one = x / one, y / one, one / one
        rays = np.stack([one, -x, -y], axis=-1) if frame == "body" else np.stack([x, y, one], axis=-1)
        return rays / np.linalg.norm(rays, axis=-1, keepdims=True) if unit else rays

    def grid_rays(self, grid=(64, 36)) -> np.ndarray:
        """(..., gw * gh, 3) float: unit body-frame rays through the centres of a ``grid`` (gw, gh) of equal
        image cells, row by row from the top-left cell."""
        gw, gh = (int(g) for g in grid)
        if gw <= 0 or gh <= 0:
            raise RigoptError(f"an image grid needs positive (columns, rows), got {tuple(grid)}")
        cols, rows = np.meshgrid((np.arange(gw) + 0.5) / gw, (np.arange(gh) + 0.5) / gh)
        pixels = np.stack([cols.ravel() * self.width[..., None], rows.ravel() * self.height[..., None]], axis=-1)
        return self.pixel_rays(pixels)

    def side_angles(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(left, right, up, down), each (...,) float rad: the half-angles of the smallest frustum (a box in
        the tangents y / x and z / x) that holds the whole image, capped at MAX_FRUSTUM_HALF_ANGLE_DEG.

        A pinhole's are its edge angles. A distorted lens's come from rays through EDGE_SAMPLES points along
        each image edge: the largest horizontal angle atan2(y, x) to each side and vertical angle
        atan2(z, x) up and down (barrel distortion puts the corners' rays outside the edge midpoints'). The
        cap keeps the frustum a convex solid of finite size for lenses near or beyond 180 degrees: such a
        frustum is narrower than the lens sees.
        """
        cap = np.deg2rad(MAX_FRUSTUM_HALF_ANGLE_DEG)
        angles = [np.arctan(t) for t in self.edge_tangents()]
        if np.any(self.distorted):
            s = np.linspace(0.0, 1.0, EDGE_SAMPLES)
            w, h = self.width[..., None], self.height[..., None]
            zero, one = np.zeros_like(w * s), np.ones_like(w * s)
            u = np.concatenate([w * s, w * s, zero, w * one], -1)
            v = np.concatenate([zero, h * one, h * s, h * s], -1)
            rays = self.pixel_rays(np.stack([u, v], -1))
            horizontal = np.arctan2(rays[..., 1], rays[..., 0])
            vertical = np.arctan2(rays[..., 2], rays[..., 0])
            real = (horizontal.max(-1), -horizontal.min(-1), vertical.max(-1), -vertical.min(-1))
            angles = [np.where(self.distorted, r, a) for r, a in zip(real, angles)]
        return tuple(np.minimum(a, cap) for a in angles)

    def _shrunk_tangents(self, angle_scale: float):
        """Tangents of :meth:`side_angles`, each multiplied by ``angle_scale``."""
        return tuple(np.tan(a * angle_scale) for a in self.side_angles())

    def probe_rays(self, angle_scale: float = 1.0) -> np.ndarray:
        """(..., 9, 3) float: unit body-frame rays along the optical axis and towards the edge midpoints and
        corners of the checked frustum (:meth:`side_angles`, each angle scaled by ``angle_scale`` in (0, 1]);
        ordered by (horizontal, vertical) side in (right, centre, left) x (down, centre, up)."""
        left, right, up, down = self._shrunk_tangents(angle_scale)
        zero = np.zeros(self.shape)
        sides_y, sides_z = (-right, zero, left), (-down, zero, up)
        rays = np.stack([np.stack([np.ones(self.shape), a, b], -1) for a in sides_y for b in sides_z], -2)
        return rays / np.linalg.norm(rays, axis=-1, keepdims=True)

    def frustum_corners(self, near: float, far: float, angle_scale: float = 1.0) -> np.ndarray:
        """(..., 8, 3) float, m, body frame: the corners of the checked view frustum (:meth:`side_angles`, each
        angle scaled by ``angle_scale``) between depths ``near`` and ``far``, near plane first, each plane
        ordered (left, up), (left, down), (right, up), (right, down). Always a convex hexahedron."""
        left, right, up, down = self._shrunk_tangents(angle_scale)
        one = np.ones(self.shape)
        corners = np.stack([np.stack([one, a, b], -1) for a in (left, -right) for b in (up, -down)], -2)
        return np.concatenate([corners * near, corners * far], axis=-2)

    # ------------------------------------------------------------------------------------ what it sees

    def project(self, points, frame: str = "body") -> np.ndarray:
        """(..., p, 2) float pixels (u, v) of ``points`` (..., p, 3) m (body frame, or optical with
        ``frame="optical"``), through the lens's distortion. Pinhole and radtan projections are meaningful
        only in front of the lens (x > 0: mask or clamp the depth first); a fisheye's for any point but one
        straight behind (mask with :meth:`in_view`)."""
        if frame not in ("body", "optical"):
            raise RigoptError(f"unknown camera frame {frame!r}; use 'body' or 'optical'")
        points = np.asarray(points, dtype=float)
        if frame == "optical":
            points = np.stack([points[..., 2], -points[..., 0], -points[..., 1]], axis=-1)
        depth = points[..., 0]
        if np.any(self.distorted):
            xd, yd = distorted_coordinates(-points[..., 1], -points[..., 2], depth, self.distortion[..., None],
                                           self.coefficients[..., None, :])
            return np.stack([self.cx[..., None] + self.fx[..., None] * xd,
                             self.cy[..., None] + self.fy[..., None] * yd], axis=-1)
        u = self.cx[..., None] + self.fx[..., None] * -points[..., 1] / depth
        v = self.cy[..., None] + self.fy[..., None] * -points[..., 2] / depth
        return np.stack([u, v], axis=-1)

    def _distorted_view(self, local) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(angle from the axis (..., p) rad, u (..., p), v (..., p) px) of body-frame points, the projection
        taken with depths clamped to MIN_DEPTH (pinhole and radtan) so it stays finite."""
        x, y, z = local[..., 0], local[..., 1], local[..., 2]
        angle = np.arctan2(np.hypot(y, z), x)
        depth = np.where(self.distortion[..., None] == "fisheye", x, np.maximum(x, MIN_DEPTH))
        xd, yd = distorted_coordinates(-y, -z, depth, self.distortion[..., None], self.coefficients[..., None, :])
        return angle, self.cx[..., None] + self.fx[..., None] * xd, self.cy[..., None] + self.fy[..., None] * yd

    def _fisheye_view(self, local) -> np.ndarray:
        """(..., p) bool: the image test of :meth:`in_view` for a batch of fisheyes only, each value computed as
        the general path (:meth:`_distorted_view`, :func:`distorted_coordinates`) computes it, without its
        second angle and the pinhole division it discards."""
        x, y, z = local[..., 0], local[..., 1], local[..., 2]
        radius = np.hypot(y, z)  # = hypot(-y, -z), the distorted_coordinates' radius
        angle = np.arctan2(radius, x)  # the angle from the axis, and the fisheye's theta (its depth is x)
        theta_d = fisheye_distort(angle, self.coefficients[..., None, :4])
        scale = np.where(radius > 0, theta_d / np.where(radius > 0, radius, 1.0), 0.0)
        u = self.cx[..., None] + self.fx[..., None] * (-y * scale)
        v = self.cy[..., None] + self.fy[..., None] * (-z * scale)
        return ((angle < self.valid_angles[..., None]) & (0 <= u) & (u <= self.width[..., None])
                & (0 <= v) & (v <= self.height[..., None]))

    def in_view(self, points, max_range: float = np.inf) -> np.ndarray:
        """(..., p) bool: body-frame ``points`` (..., p, 3) m inside the image (edges included), at most
        ``max_range`` m (Euclidean) from the lens, and, for a distorted lens, less than its
        :attr:`valid_angles` off the optical axis (so a radtan image folding back, or a fisheye ray beyond
        its range, does not count). A pinhole's test is the exact edge-tangent one: in front, between the
        edges."""
        local = np.asarray(points, dtype=float)
        if self.distortion.size and np.all(self.distortion == "fisheye"):
            real = self._fisheye_view(local)
            return real & (np.einsum("...i,...i->...", local, local) <= max_range**2)
        inside = None
        if not np.all(self.distorted):
            left, right, up, down = (t[..., None] for t in self.edge_tangents())
            x, y, z = local[..., 0], local[..., 1], local[..., 2]
            inside = (x > 0) & (-(x * right) <= y) & (y <= x * left) & (-(x * down) <= z) & (z <= x * up)
        if np.any(self.distorted):
            angle, u, v = self._distorted_view(local)
            real = ((angle < self.valid_angles[..., None]) & (0 <= u) & (u <= self.width[..., None])
                    & (0 <= v) & (v <= self.height[..., None]))
            inside = real if inside is None else np.where(self.distorted[..., None], real, inside)
        return inside & (np.einsum("...i,...i->...", local, local) <= max_range**2)

    def view_margin(self, points) -> np.ndarray:
        """(..., p) float: how deep body-frame ``points`` (..., p, 3) lie inside the image: the smaller of the
        horizontal and vertical ``1 - |u - cx| / e`` (e the principal point's distance to the image edge on
        the point's side, in px), 1 on the optical axis, 0 on an edge, negative outside. For a pinhole this is
        the tangent form ``1 - |a| / edge``; a distorted lens takes its projection, and a point beyond its
        valid angle gets ``min(margin, 0) - (angle - valid angle)``."""
        local = np.asarray(points, dtype=float)
        left, right, up, down = (t[..., None] for t in self.edge_tangents())
        x = np.maximum(local[..., 0], MIN_DEPTH)
        y, z = local[..., 1], local[..., 2]
        edge_y, edge_z = np.where(y >= 0, left, right), np.where(z >= 0, up, down)
        margin = np.minimum(1 - np.abs(y) / (x * edge_y), 1 - np.abs(z) / (x * edge_z))
        if np.any(self.distorted):
            angle, u, v = self._distorted_view(local)
            cx, cy = self.cx[..., None], self.cy[..., None]
            with np.errstate(divide="ignore", invalid="ignore"):
                side_u = np.where(u <= cx, cx, self.width[..., None] - cx)
                side_v = np.where(v <= cy, cy, self.height[..., None] - cy)
                real = np.minimum(1 - np.abs(u - cx) / side_u, 1 - np.abs(v - cy) / side_v)
            beyond = angle - self.valid_angles[..., None]
            real = np.where(beyond >= 0, np.minimum(np.nan_to_num(real, nan=-1.0), 0.0) - beyond, real)
            margin = np.where(self.distorted[..., None], real, margin)
        return margin


#: Working-array size (entries, cameras x points) of one block of :func:`in_frustum`: its temporaries stay in
#: the cache.
FRUSTUM_BLOCK_ENTRIES = 200_000


def in_frustum(model: CameraModel, positions, rotations, points, max_range: float = np.inf) -> np.ndarray:
    """(c, p) bool: point p inside camera c's view frustum (no occlusion).

    model : CameraModel of batch shape (c,); positions : (c, 3) m; rotations : (c, 3, 3) R_vehicle_cam;
    points : (p, 3) m, vehicle frame; max_range : m, Euclidean from the lens. Computed in blocks of cameras
    (each camera's row is the same whatever its block).
    """
    positions, rotations = np.asarray(positions, dtype=float), np.asarray(rotations, dtype=float)
    points = np.asarray(points, dtype=float)
    if model.shape != (len(positions),):
        return model.in_view(camera_frame_points(positions, rotations, points), max_range)
    step = max(1, FRUSTUM_BLOCK_ENTRIES // max(len(points), 1))
    if step >= len(positions):
        return model.in_view(camera_frame_points(positions, rotations, points), max_range)
    seen = np.zeros((len(positions), len(points)), dtype=bool)
    for start in range(0, len(positions), step):
        block = slice(start, start + step)
        seen[block] = model.take(block).in_view(camera_frame_points(positions[block], rotations[block], points),
                                                max_range)
    return seen
