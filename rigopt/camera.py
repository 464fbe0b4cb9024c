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
:class:`CameraModel` holds the intrinsics of a batch of cameras (every field an array of one batch shape,
``()`` for one camera or ``(c,)`` for c cameras); its methods broadcast over that batch. Today every
rigopt camera is an ideal pinhole with square pixels and its principal point at the image centre, built
from a horizontal FOV and an image size (:meth:`CameraModel.from_fov`, :meth:`CameraModel.of_cameras`).
The methods read only the intrinsics (fx, fy, cx, cy, width, height), so real per-camera intrinsics change
only the constructors. Lens distortion has one place to go: the map between normalised optical
coordinates and pixels, used by :meth:`CameraModel.pixel_rays` (undistort) and :meth:`CameraModel.project`
(distort); the frustum methods (:meth:`CameraModel.in_view`, :meth:`CameraModel.view_margin`, probe and
corner rays) describe the image by the tangents of its edges, exact for a distortion-free pinhole.

>>> round(float(focal_from_fov(60.0, 320)), 3)
277.128
>>> model = CameraModel.from_fov(90.0, (1280, 720))
>>> [round(float(t), 4) for t in model.half_tangents()]
[1.0, 0.5625]
>>> model.project(np.array([[10.0, -10.0, 0.0]])).tolist()  # 45 deg right: the image's right edge
[[1280.0, 360.0]]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

import numpy as np

from rigopt.errors import RigoptError

if TYPE_CHECKING:
    from rigopt.rig.model import Camera

#: Depths (m) below this count as this when margins divide by a point's depth.
MIN_DEPTH = 1e-9


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


@dataclass(frozen=True)
class Lens:
    """One real camera's intrinsics and lens distortion, as calibration files give them.

    width, height : int, image size in px; fx, fy : float, focal lengths in px; cx, cy : float, principal
    point in px (pixel coordinates as in the module docstring); distortion : one of
    :data:`DISTORTION_COEFFICIENTS` ("none", "radtan", "fisheye"); coefficients : tuple of float in that
    model's order (all zero is the same geometry as "none").

    Distorted normalised coordinates map to pixels through ``K``: u = fx x_d + cx, v = fy y_d + cy. The
    fisheye model takes the angle theta of a ray from the optical axis and puts it at radius theta_d(theta)
    in the normalised image, so it covers lenses wider than 180 degrees.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: str = "none"
    coefficients: tuple[float, ...] = ()

    def __post_init__(self):
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value <= 0:
                raise RigoptError(f"lens {name} must be a positive whole number of pixels, got {value!r}")
            object.__setattr__(self, name, int(value))
        for name in ("fx", "fy", "cx", "cy"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) or not np.isfinite(value):
                raise RigoptError(f"lens {name} must be a finite number of pixels, got {value!r}")
            if name in ("fx", "fy") and value <= 0:
                raise RigoptError(f"lens {name} must be positive, got {value!r}")
            object.__setattr__(self, name, float(value))
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

    @classmethod
    def pinhole(cls, hfov_deg: float, image_size=(1280, 720)) -> "Lens":
        """The benchmark's camera: a centred square-pixel pinhole of horizontal FOV ``hfov_deg`` in (0, 180)."""
        width, height = image_size
        model = CameraModel.from_fov(hfov_deg, (width, height))
        return cls(int(width), int(height), float(model.fx), float(model.fy), float(model.cx), float(model.cy))

    @property
    def image_size(self) -> tuple[int, int]:
        """(width, height) in px."""
        return self.width, self.height

    @property
    def is_distorted(self) -> bool:
        """True when the lens has non-zero distortion coefficients."""
        return any(c != 0.0 for c in self.coefficients)

    @property
    def is_ideal_pinhole(self) -> bool:
        """True for the benchmark's camera: no distortion, square pixels, principal point at the centre."""
        return (not self.is_distorted and abs(self.fx - self.fy) <= 1e-9 * self.fx
                and abs(self.cx - self.width / 2) <= 1e-9 * self.width
                and abs(self.cy - self.height / 2) <= 1e-9 * self.height)

    # ------------------------------------------------------------------------------------------ mapping

    def pixel_rays(self, pixels) -> np.ndarray:
        """(n, 3) float unit optical-frame rays (z along the axis, x right, y down) through pixels (n, 2)."""
        pixels = np.atleast_2d(np.asarray(pixels, dtype=float))
        xd = (pixels[:, 0] - self.cx) / self.fx
        yd = (pixels[:, 1] - self.cy) / self.fy
        k = np.array(self.coefficients)
        if self.distortion == "fisheye":
            radius = np.hypot(xd, yd)
            theta = fisheye_undistort(radius, k)
            scale = np.where(radius > 0, np.sin(theta) / np.where(radius > 0, radius, 1.0), 1.0)
            rays = np.stack([xd * scale, yd * scale, np.cos(theta)], axis=1)
        else:
            x, y = radtan_undistort(xd, yd, k) if self.distortion == "radtan" else (xd, yd)
            rays = np.stack([x, y, np.ones_like(x)], axis=1)
        return rays / np.linalg.norm(rays, axis=1, keepdims=True)

    def project(self, rays) -> np.ndarray:
        """(n, 2) float pixels of optical-frame directions ``rays`` (n, 3) (any length). Pinhole and radtan
        lenses need z > 0; fisheye lenses take any direction but the one straight behind."""
        rays = np.atleast_2d(np.asarray(rays, dtype=float))
        x, y, z = rays[:, 0], rays[:, 1], rays[:, 2]
        k = np.array(self.coefficients)
        if self.distortion == "fisheye":
            radius = np.hypot(x, y)
            theta_d = fisheye_distort(np.arctan2(radius, z), k)
            scale = np.where(radius > 0, theta_d / np.where(radius > 0, radius, 1.0), 0.0)
            xd, yd = x * scale, y * scale
        else:
            xd, yd = x / z, y / z
            if self.distortion == "radtan":
                xd, yd = radtan_distort(xd, yd, k)
        return np.stack([self.fx * xd + self.cx, self.fy * yd + self.cy], axis=1)

    def edge_angles(self) -> tuple[float, float, float, float]:
        """(left, right, top, bottom): radians from the optical axis to the rays through the midpoints of the
        image's edges, taken on the principal point's row and column."""
        pixels = np.array([[0.0, self.cy], [self.width, self.cy], [self.cx, 0.0], [self.cx, self.height]])
        rays = self.pixel_rays(pixels)
        return tuple(float(a) for a in np.arctan2(np.hypot(rays[:, 0], rays[:, 1]), rays[:, 2]))

    @property
    def hfov(self) -> float:
        """Horizontal FOV in degrees: the angle from the ray through the left edge to the ray through the
        right edge (through the optical axis, so it may exceed 180 for a fisheye). For the benchmark's pinhole
        it is the FOV the lens was built from."""
        left, right, _, _ = self.edge_angles()
        return float(np.rad2deg(left + right))

    @property
    def vfov(self) -> float:
        """Vertical FOV in degrees, as :attr:`hfov` between the top and bottom edges."""
        _, _, top, bottom = self.edge_angles()
        return float(np.rad2deg(top + bottom))


def pixel_centres(width: int, height: int) -> np.ndarray:
    """(height * width, 2) float: (u, v) of every pixel's centre, row by row from the top-left pixel."""
    u, v = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    return np.stack([u.ravel(), v.ravel()], axis=1)


def camera_frame_points(positions, rotations, points) -> np.ndarray:
    """(c, p, 3) float: ``points`` (p, 3) m, vehicle frame, in the body frames of c cameras at
    ``positions`` (c, 3) m with ``rotations`` (c, 3, 3) R_vehicle_cam: ``R^T (p - t)``."""
    return np.einsum("cji,cpj->cpi", np.asarray(rotations, dtype=float),
                     np.asarray(points, dtype=float)[None] - np.asarray(positions, dtype=float)[:, None])


def _read_only(values) -> np.ndarray:
    array = np.array(values, dtype=float)
    array.flags.writeable = False
    return array


@dataclass(frozen=True, eq=False)
class CameraModel:
    """Intrinsics of a batch of cameras; see the module docstring for frames and units.

    Attributes (each a read-only float array of the batch shape, ``()`` or ``(c,)``)
    ----------
    width, height : image size, px.
    fx, fy : focal lengths, px.
    cx, cy : principal point, px (pixel coordinates, (0, 0) the image's top-left corner).
    """

    width: np.ndarray
    height: np.ndarray
    fx: np.ndarray
    fy: np.ndarray
    cx: np.ndarray
    cy: np.ndarray

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
    def of_cameras(cls, cameras: Sequence["Camera"]) -> "CameraModel":
        """The models of rig cameras (batch shape (c,)), from each camera's FOV and image size.

        The one place that reads a :class:`rigopt.rig.model.Camera`'s lens: when cameras carry their own
        intrinsics and distortion, only this changes."""
        return cls.from_fov([c.fov for c in cameras], [c.image_size for c in cameras])

    @classmethod
    def of_camera(cls, camera: "Camera") -> "CameraModel":
        """The model of one rig camera (batch shape ())."""
        return cls.from_fov(camera.fov, camera.image_size)

    # -------------------------------------------------------------------------------------------- reading

    @property
    def shape(self) -> tuple[int, ...]:
        """The batch shape."""
        return self.fx.shape

    def intrinsic_matrix(self) -> np.ndarray:
        """(..., 3, 3) float ``K``: optical-frame rays (x / z, y / z, 1) -> homogeneous pixels."""
        zero, one = np.zeros(self.shape), np.ones(self.shape)
        return np.stack([np.stack([self.fx, zero, self.cx], -1), np.stack([zero, self.fy, self.cy], -1),
                         np.stack([zero, zero, one], -1)], -2)

    def edge_tangents(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(left, right, up, down), each (...,) float: tangents of the angles from the optical axis to the
        image's left, right, top and bottom edges. A body-frame direction (1, a, b) is in view when
        ``-right <= a <= left`` and ``-down <= b <= up``."""
        return (self.cx / self.fx, (self.width - self.cx) / self.fx, self.cy / self.fy,
                (self.height - self.cy) / self.fy)

    def half_tangents(self) -> tuple[np.ndarray, np.ndarray]:
        """(tan_h, tan_v), each (...,) float: tangents of the horizontal and vertical half-angles (half the
        image's extent in normalised coordinates; left and right agree for a centred principal point)."""
        return (self.width / 2.0) / self.fx, (self.height / 2.0) / self.fy

    @property
    def hfov(self) -> np.ndarray:
        """(...,) float: horizontal FOV, degrees."""
        left, right, _, _ = self.edge_tangents()
        return np.rad2deg(np.arctan(left) + np.arctan(right))

    @property
    def vfov(self) -> np.ndarray:
        """(...,) float: vertical FOV, degrees."""
        _, _, up, down = self.edge_tangents()
        return np.rad2deg(np.arctan(up) + np.arctan(down))

    # --------------------------------------------------------------------------------------------- rays

    def pixel_rays(self, pixels, unit: bool = True, frame: str = "body") -> np.ndarray:
        """Rays from the lens through image points.

        pixels : (..., n, 2) float (u, v) px, broadcast against the batch (a leading axis per batch axis).
        unit : True for unit rays; False for rays scaled to unit depth (optical-axis component 1), so that
            the point at depth d is ``d * ray``.
        frame : "body" (x forward, y left, z up) or "optical" (z forward, x right, y down).
        Returns (..., n, 3) float.
        """
        if frame not in ("body", "optical"):
            raise RigoptError(f"unknown camera frame {frame!r}; use 'body' or 'optical'")
        pixels = np.asarray(pixels, dtype=float)
        x = (pixels[..., 0] - self.cx[..., None]) / self.fx[..., None]  # normalised optical coordinates
        y = (pixels[..., 1] - self.cy[..., None]) / self.fy[..., None]
        one = np.ones_like(x)
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

    def _shrunk_tangents(self, angle_scale: float):
        """edge_tangents with each edge's angle from the optical axis multiplied by ``angle_scale``."""
        return tuple(np.tan(np.arctan(t) * angle_scale) for t in self.edge_tangents())

    def probe_rays(self, angle_scale: float = 1.0) -> np.ndarray:
        """(..., 9, 3) float: unit body-frame rays along the optical axis and towards the image's edge
        midpoints and corners, each edge's angle from the axis scaled by ``angle_scale`` (in (0, 1]); ordered
        by (horizontal, vertical) side in (right, centre, left) x (down, centre, up)."""
        left, right, up, down = self._shrunk_tangents(angle_scale)
        zero = np.zeros(self.shape)
        sides_y, sides_z = (-right, zero, left), (-down, zero, up)
        rays = np.stack([np.stack([np.ones(self.shape), a, b], -1) for a in sides_y for b in sides_z], -2)
        return rays / np.linalg.norm(rays, axis=-1, keepdims=True)

    def frustum_corners(self, near: float, far: float, angle_scale: float = 1.0) -> np.ndarray:
        """(..., 8, 3) float, m, body frame: the corners of the view frustum between depths ``near`` and ``far``
        (each edge's angle scaled by ``angle_scale``), near plane first, each plane ordered
        (left, up), (left, down), (right, up), (right, down)."""
        left, right, up, down = self._shrunk_tangents(angle_scale)
        one = np.ones(self.shape)
        corners = np.stack([np.stack([one, a, b], -1) for a in (left, -right) for b in (up, -down)], -2)
        return np.concatenate([corners * near, corners * far], axis=-2)

    # ------------------------------------------------------------------------------------ what it sees

    def project(self, points) -> np.ndarray:
        """(..., p, 2) float pixels (u, v) of body-frame ``points`` (..., p, 3) m; meaningful only in front of
        the lens (x > 0): mask or clamp the depth first."""
        points = np.asarray(points, dtype=float)
        depth = points[..., 0]
        u = self.cx[..., None] + self.fx[..., None] * -points[..., 1] / depth
        v = self.cy[..., None] + self.fy[..., None] * -points[..., 2] / depth
        return np.stack([u, v], axis=-1)

    def in_view(self, points, max_range: float = np.inf) -> np.ndarray:
        """(..., p) bool: body-frame ``points`` (..., p, 3) m in front of the lens, inside the image (edges
        included) and at most ``max_range`` m (Euclidean) from the lens."""
        local = np.asarray(points, dtype=float)
        left, right, up, down = (t[..., None] for t in self.edge_tangents())
        x, y, z = local[..., 0], local[..., 1], local[..., 2]
        inside = (x > 0) & (-(x * right) <= y) & (y <= x * left) & (-(x * down) <= z) & (z <= x * up)
        return inside & (np.einsum("...i,...i->...", local, local) <= max_range**2)

    def view_margin(self, points) -> np.ndarray:
        """(..., p) float: how deep body-frame ``points`` (..., p, 3) lie inside the image, as the smaller of
        the horizontal and vertical ``1 - |a| / edge`` (a the point's tangent, edge that of the image edge on
        its side): 1 on the optical axis, 0 on an edge, negative outside."""
        local = np.asarray(points, dtype=float)
        left, right, up, down = (t[..., None] for t in self.edge_tangents())
        x = np.maximum(local[..., 0], MIN_DEPTH)
        y, z = local[..., 1], local[..., 2]
        edge_y, edge_z = np.where(y >= 0, left, right), np.where(z >= 0, up, down)
        return np.minimum(1 - np.abs(y) / (x * edge_y), 1 - np.abs(z) / (x * edge_z))


def in_frustum(model: CameraModel, positions, rotations, points, max_range: float = np.inf) -> np.ndarray:
    """(c, p) bool: point p inside camera c's view frustum (no occlusion).

    model : CameraModel of batch shape (c,); positions : (c, 3) m; rotations : (c, 3, 3) R_vehicle_cam;
    points : (p, 3) m, vehicle frame; max_range : m, Euclidean from the lens.
    """
    return model.in_view(camera_frame_points(positions, rotations, points), max_range)
