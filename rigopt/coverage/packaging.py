"""A camera's packaging sheet: where it sits on the body and what its image holds, for a packaging review.

Every quantity is a pure function of one camera and its vehicle, through the camera's own lens
(:class:`rigopt.camera.CameraModel`: pinhole, radtan or fisheye) and rays cast through the body mesh
(:mod:`rigopt.raycast`). Inputs are in the vehicle's mesh frame: ISO 8855 (x forward, y left, z up), metres,
origin at the vehicle's centre on the ground (z = 0 is the ground); reports shift positions to the datum of
:func:`report_origin` (the ground below the rear axle's centre).

Definitions (one camera; "the lens" is the camera's position, "its ground point" the lens dropped to z = 0):

- body feature: the mounting zone of the lens's mount point (the foot of the lens on the body surface, with the
  surface normal there, by ``Vehicle.zone_names``); outside every zone, the nearest zone's surface (faces of
  ``Vehicle.fine_mesh``, at most ``ZONE_QUERY_EDGE`` m across) and its distance (m) from the mount point;
- surface normal: the outward unit normal of the body face at the mount point; the bracket wedge angle (deg)
  is the angle between it and the optical axis (0 when the camera looks straight out of the surface); the
  protrusion (m) is how far the lens stands in front of the surface along that normal, (lens - mount point) .
  normal (negative: behind the surface, inside the body);
- nearest visible ground: the shortest horizontal distance (m) from the lens's ground point to a ground point
  the camera sees, over the rays through a lattice of GROUND_LATTICE image points (edges and corners
  included) and the straight-down ray when it is in the image; a ray sees the ground where it meets z = 0 with
  no body before it. Also the shortest distance (m) of a seen ground point from the body's footprint (its
  convex outline on the ground; 0 under the body). None when no ground is seen;
- ground resolution (px/m) at GROUND_DISTANCES_M: at the ground point that distance from the lens's ground
  point straight ahead along the optical axis's horizontal direction: ``lateral``, image pixels per metre
  across (horizontal, perpendicular to that direction), and ``longitudinal``, pixels per metre along it
  (central differences of the lens's projection, RESOLUTION_STEP_M apart). None where the point is outside
  the image or hidden by the body, and for an axis pointing straight up or down;
- people: a standing person (a vertical segment from the ground up to PEOPLE's heights: a 1.8 m adult, a
  0.8 m child) at PERSON_DISTANCE_M horizontally from the lens's ground point, at the horizontal direction
  of the ray through the image's left edge (the first pixel column's centre, u = 0.5 px, on the principal
  point's row), of the optical axis, and of the right edge (u = width - 0.5 px). The height in pixels is the
  length of the image of the part of the person that is in the image and not hidden by the body (sampled
  every PERSON_STEP_M): f H / (d cos a) px for an upright pinhole (d the distance, a the angle off the axis);
  0 when none of it is seen, None for a ray pointing straight up or down;
- blocked share: the fraction of the rays through the centres of a BLOCKED_GRID of image cells that meet the
  body (as ``coverage.measures``' self-occluded fraction); per keep-out that blocks views (a coupled trailer,
  unless lifted), the fraction that meet it, before the body and within DEFAULT_MAX_RANGE m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.camera import CameraModel
from rigopt.coverage.visibility import DEFAULT_MAX_RANGE, occluders
from rigopt.mounting.practice import segments_hit_boxes
from rigopt.vehicle.footprint import Footprint
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.placement import to_vehicle_centre

#: Distances (m) from the lens's ground point, straight ahead, where the ground resolution is given.
GROUND_DISTANCES_M = (5.0, 10.0, 20.0)
#: The people whose heights in pixels are given: (name, height m).
PEOPLE = (("adult", 1.8), ("child", 0.8))
#: Horizontal distance (m) from the lens's ground point at which the people stand.
PERSON_DISTANCE_M = 5.0
#: Spacing (m) of the sampled points along a person.
PERSON_STEP_M = 0.01
#: Where the people stand, by the image column whose ray gives their direction (see the module docstring).
PERSON_PLACES = ("left", "centre", "right")
#: Image cells (columns, rows) whose centre rays measure the share of the image the body blocks.
BLOCKED_GRID = (64, 36)
#: Image points (columns, rows), edges included, whose rays find the nearest visible ground.
GROUND_LATTICE = (129, 73)
#: Step (m) of the central differences giving the ground resolution.
RESOLUTION_STEP_M = 0.01
#: A direction whose horizontal part is shorter than this has no azimuth (straight up or down).
VERTICAL_TOLERANCE = 1e-9

#: Where the reports' positions are measured from, in words: the ground below the rear axle's centre, or the
#: vehicle's centre where its axles are unknown.
REAR_AXLE_ORIGIN = "origin on the ground below the rear axle's centre"
CENTRE_ORIGIN = "origin on the ground at the vehicle's centre (the vehicle's axles are unknown)"


@dataclass(frozen=True, eq=False)
class ReportDatum:
    """The origin of a report's positions: ``point`` (3,) m in the vehicle-centre frame and ``origin`` in
    words; the axes are always ISO 8855's (x forward, y left, z up)."""

    point: np.ndarray
    origin: str

    @property
    def frame(self) -> str:
        """The frame's name, e.g. "ISO 8855, origin on the ground below the rear axle's centre"."""
        return f"ISO 8855, {self.origin}"

    @property
    def axis_text(self) -> str:
        """The origin as an axis title names it: "from the rear axle" or "from the vehicle centre"."""
        return "from the rear axle" if self.origin == REAR_AXLE_ORIGIN else "from the vehicle centre"

    def to_dict(self) -> dict:
        """The frame as the reports' JSON names it: ``frame`` and ``origin_from_vehicle_centre_m`` ([x, y, z] m,
        ``point``: subtract it from a vehicle-centre position to get the report's)."""
        return {"frame": self.frame, "origin_from_vehicle_centre_m": self.point.tolist()}


#: The vehicle-centre frame's datum: the mesh's and the rig file's origin, the figures' default.
CENTRE_DATUM = ReportDatum(np.zeros(3), "origin on the ground at the vehicle's centre")


def report_origin(vehicle: Vehicle) -> ReportDatum:
    """The reports' datum: the ground below the rear axle's centre (:attr:`Vehicle.rear_axle`), or the
    vehicle's centre when its axles are unknown."""
    rear_axle = vehicle.rear_axle
    if rear_axle is None:
        return ReportDatum(np.zeros(3), CENTRE_ORIGIN)
    return ReportDatum(np.asarray(rear_axle, dtype=float), REAR_AXLE_ORIGIN)


@dataclass(frozen=True)
class GroundResolution:
    """Image pixels per metre of ground ``distance_m`` ahead (see the module docstring); None where unseen."""

    distance_m: float
    lateral_px_per_m: float | None
    longitudinal_px_per_m: float | None


@dataclass(frozen=True)
class PersonHeight:
    """A person of ``height_m`` at ``distance_m``: height in pixels at the image's ``left``, ``centre`` and
    ``right`` edge directions (0 when unseen, None for a vertical ray)."""

    person: str
    height_m: float
    distance_m: float
    left: float | None
    centre: float | None
    right: float | None


@dataclass(frozen=True, eq=False)
class CameraPackaging:
    """One camera's packaging sheet (definitions in the module docstring); positions (3,) m in the
    vehicle-centre frame, ``surface_normal`` (3,) unit, ISO 8855 axes."""

    camera: str
    zone: str | None
    nearest_zone: str | None
    nearest_zone_m: float | None
    position: np.ndarray
    mount_point: np.ndarray
    surface_normal: np.ndarray
    wedge_deg: float
    protrusion_m: float
    nearest_ground_m: float | None
    nearest_ground_from_body_m: float | None
    ground_resolution: tuple[GroundResolution, ...]
    people: tuple[PersonHeight, ...]
    blocked_frac: float
    keep_out_blocked: tuple[tuple[str, float], ...] = ()

    def __post_init__(self):
        for name in ("position", "mount_point", "surface_normal"):
            array = np.array(getattr(self, name), dtype=float)
            array.flags.writeable = False
            object.__setattr__(self, name, array)

    def to_dict(self, origin=None) -> dict:
        """Plain JSON values, positions measured from ``origin`` (3,) m (a point in the vehicle-centre frame,
        e.g. :func:`report_origin`'s ``point``; default the vehicle's centre)."""
        origin = np.zeros(3) if origin is None else np.asarray(origin, dtype=float)
        return {
            "camera": self.camera, "zone": self.zone, "nearest_zone": self.nearest_zone,
            "nearest_zone_m": self.nearest_zone_m,
            "position_m": (self.position - origin).tolist(), "mount_point_m": (self.mount_point - origin).tolist(),
            "surface_normal": self.surface_normal.tolist(), "wedge_angle_deg": self.wedge_deg,
            "protrusion_m": self.protrusion_m, "nearest_ground_m": self.nearest_ground_m,
            "nearest_ground_from_body_m": self.nearest_ground_from_body_m,
            "ground_resolution_px_per_m": [{"distance_m": g.distance_m, "lateral": g.lateral_px_per_m,
                                            "longitudinal": g.longitudinal_px_per_m} for g in self.ground_resolution],
            "person_height_px": [{"person": p.person, "height_m": p.height_m, "distance_m": p.distance_m,
                                  "left": p.left, "centre": p.centre, "right": p.right} for p in self.people],
            "blocked_frac": self.blocked_frac,
            "blocked_by_keep_outs": dict(self.keep_out_blocked),
        }


# ------------------------------------------------------------------------------------------------ body


def body_feature(vehicle: Vehicle, mount_point, normal) -> tuple[str | None, str | None, float | None]:
    """(zone, nearest zone, its distance m) of a mount point (3,) m on the body surface with outward
    ``normal`` (3,): the zone it lies in (nearest zone the same, distance 0), else None and the zone whose
    surface (faces of the fine mesh, by their centres) is nearest; (None, None, None) without zones."""
    zone = vehicle.zone_names(np.asarray(mount_point)[None], np.asarray(normal)[None])[0]
    if zone is not None:
        return zone, zone, 0.0
    labels = vehicle.fine_face_zones
    labelled = np.flatnonzero([label is not None for label in labels])
    if len(labelled) == 0:
        return None, None, None
    distance = np.linalg.norm(vehicle.fine_mesh.triangles_center[labelled] - mount_point, axis=1)
    nearest = int(np.argmin(distance))
    return None, str(labels[labelled[nearest]]), float(distance[nearest])


# ------------------------------------------------------------------------------------------------ image


def _azimuth(direction) -> np.ndarray | None:
    """(3,) unit horizontal direction of ``direction`` (3,), None when it points straight up or down."""
    horizontal = np.array([direction[0], direction[1], 0.0])
    length = np.linalg.norm(horizontal)
    return None if length < VERTICAL_TOLERANCE else horizontal / length


def _seen(camera: Camera, model: CameraModel, vehicle: Vehicle, points, backend: str) -> np.ndarray:
    """(n,) bool: ``points`` (n, 3) m in the camera's image with no body between them and the lens."""
    points = np.atleast_2d(points)
    local = (points - camera.position) @ camera.rotation
    inside = model.in_view(local)
    clear = np.zeros(len(points), dtype=bool)
    if inside.any():
        clear[inside] = vehicle.caster(backend).segments_clear(
            np.repeat(camera.position[None], int(inside.sum()), axis=0), points[inside])
    return inside & clear


def _pixels(camera: Camera, model: CameraModel, points) -> np.ndarray:
    """(n, 2) float: pixels of vehicle-frame ``points`` (n, 3) m through the camera's lens."""
    return model.project((np.atleast_2d(points) - camera.position) @ camera.rotation)


def ground_resolution(camera: Camera, vehicle: Vehicle, distance: float, backend: str = "auto") -> GroundResolution:
    """Pixels per metre of ground ``distance`` m straight ahead of the lens's ground point (module docstring)."""
    model = CameraModel.of_camera(camera)
    ahead = _azimuth(camera.forward)
    if ahead is None:
        return GroundResolution(float(distance), None, None)
    ground = np.array([camera.position[0], camera.position[1], 0.0]) + distance * ahead
    if not _seen(camera, model, vehicle, ground, backend)[0]:
        return GroundResolution(float(distance), None, None)
    across = np.array([-ahead[1], ahead[0], 0.0])
    step = RESOLUTION_STEP_M
    pixels = _pixels(camera, model, [ground - step * across, ground + step * across,
                                     ground - step * ahead, ground + step * ahead])
    lateral = float(np.linalg.norm(pixels[1] - pixels[0]) / (2 * step))
    longitudinal = float(np.linalg.norm(pixels[3] - pixels[2]) / (2 * step))
    return GroundResolution(float(distance), lateral, longitudinal)


def person_directions(camera: Camera) -> dict[str, np.ndarray]:
    """Vehicle-frame unit rays (3,) by place (PERSON_PLACES): through the first and last pixel columns'
    centres on the principal point's row, and the optical axis."""
    lens = camera.lens
    pixels = np.array([[0.5, lens.cy], [lens.cx, lens.cy], [lens.width - 0.5, lens.cy]])
    rays = CameraModel.of_camera(camera).pixel_rays(pixels) @ camera.rotation.T
    return dict(zip(PERSON_PLACES, rays))


def person_height_px(camera: Camera, vehicle: Vehicle, height: float, direction, distance: float = PERSON_DISTANCE_M,
                     backend: str = "auto") -> float | None:
    """The height in pixels of the seen part of a person ``height`` m tall standing ``distance`` m from the
    lens's ground point along the horizontal part of ``direction`` (3,); 0 when unseen, None when
    ``direction`` is vertical."""
    model = CameraModel.of_camera(camera)
    azimuth = _azimuth(direction)
    if azimuth is None:
        return None
    foot = np.array([camera.position[0], camera.position[1], 0.0]) + distance * azimuth
    heights = np.linspace(0.0, height, int(np.ceil(height / PERSON_STEP_M)) + 1)
    points = foot + heights[:, None] * np.array([0.0, 0.0, 1.0])
    seen = _seen(camera, model, vehicle, points, backend)
    if seen.sum() < 2:
        return 0.0
    pixels = _pixels(camera, model, points)
    both = seen[1:] & seen[:-1]
    return float(np.linalg.norm(np.diff(pixels, axis=0), axis=1)[both].sum())


def _lattice_rays(camera: Camera, model: CameraModel, lattice) -> np.ndarray:
    """(c * r, 3) float: vehicle-frame unit rays through a lattice (columns, rows) of image points spanning the
    whole image, its edges and corners included."""
    columns, rows = (int(n) for n in lattice)
    u, v = np.meshgrid(np.linspace(0.0, float(model.width), columns), np.linspace(0.0, float(model.height), rows))
    return model.pixel_rays(np.stack([u.ravel(), v.ravel()], axis=1)) @ camera.rotation.T


def nearest_visible_ground(camera: Camera, vehicle: Vehicle, footprint: Footprint | None = None,
                           backend: str = "auto") -> tuple[float | None, float | None]:
    """(from the lens's ground point m, from the body's footprint m): the nearest ground the camera sees
    (module docstring); (None, None) when it sees none or its lens is not above the ground."""
    height = float(camera.position[2])
    if height <= 0:
        return None, None
    model = CameraModel.of_camera(camera)
    rays = _lattice_rays(camera, model, GROUND_LATTICE)
    down = np.array([0.0, 0.0, -1.0])
    if model.in_view(down @ camera.rotation):  # the ground point below the lens
        rays = np.concatenate([rays, down[None]])
    rays = rays[rays[:, 2] < -VERTICAL_TOLERANCE]
    if len(rays) == 0:
        return None, None
    along = height / -rays[:, 2]  # m along each ray to the ground
    body = vehicle.caster(backend).blocked_distance(np.repeat(camera.position[None], len(rays), axis=0), rays)
    seen = body >= along
    if not seen.any():
        return None, None
    ground = camera.position[:2] + along[seen, None] * rays[seen, :2]
    from_lens = np.linalg.norm(ground - camera.position[:2], axis=1)
    footprint = footprint or vehicle.footprint
    return float(from_lens.min()), float(footprint.distance_to(ground).min())


def blocked_fraction(camera: Camera, vehicle: Vehicle, grid=BLOCKED_GRID, backend: str = "auto") -> float:
    """The share of the image the body blocks: rays through the centres of ``grid`` (columns, rows) image cells
    that the body, a solid, blocks (:meth:`rigopt.raycast.RayCaster.blocked_distance`), in [0, 1]."""
    return blocked_shares(camera, vehicle, grid, backend)[0]


def blocked_shares(camera: Camera, vehicle: Vehicle, grid=BLOCKED_GRID, backend: str = "auto",
                   lifted=None) -> tuple[float, tuple[tuple[str, float], ...]]:
    """(the body's share of the image, ((label, share), ...) per keep-out that blocks views): rays through the
    centres of ``grid`` (columns, rows) image cells that meet the body, and those that meet each keep-out in
    force (:func:`rigopt.coverage.visibility.occluders`; ``lifted`` names those lifted, None: no keep-out is
    looked at) before the body and within DEFAULT_MAX_RANGE m; shares in [0, 1]."""
    rays = CameraModel.of_camera(camera).grid_rays(grid) @ camera.rotation.T
    starts = np.repeat(camera.position[None], len(rays), axis=0)
    hits = vehicle.caster(backend).blocked_distance(starts, rays)
    reach = np.minimum(np.where(np.isfinite(hits), hits, DEFAULT_MAX_RANGE), DEFAULT_MAX_RANGE)
    keep_outs = () if lifted is None else occluders(vehicle, lifted)
    return float(np.mean(np.isfinite(hits))), tuple(
        (label, float(np.mean(segments_hit_boxes(starts, rays, reach, [(low, high, label)]))))
        for low, high, label in keep_outs)


# ------------------------------------------------------------------------------------------------ sheet


def camera_packaging(camera: Camera, vehicle: Vehicle, footprint: Footprint | None = None,
                     backend: str = "auto", lifted=()) -> CameraPackaging:
    """The packaging sheet of ``camera`` (position in ``vehicle``'s centre frame) on ``vehicle``, ``lifted``
    naming the keep-outs lifted (a trailer not coupled)."""
    surface = vehicle.surface(camera.position[None])
    mount_point, normal = surface.foot[0], surface.normal[0] / np.linalg.norm(surface.normal[0])
    zone, nearest, nearest_m = body_feature(vehicle, mount_point, normal)
    wedge = float(np.rad2deg(np.arccos(np.clip(normal @ camera.forward, -1.0, 1.0))))
    footprint = footprint or vehicle.footprint
    ground_m, body_m = nearest_visible_ground(camera, vehicle, footprint, backend)
    directions = person_directions(camera)
    people = tuple(PersonHeight(name, height, PERSON_DISTANCE_M,
                                *(person_height_px(camera, vehicle, height, directions[place], PERSON_DISTANCE_M,
                                                   backend) for place in PERSON_PLACES))
                   for name, height in PEOPLE)
    return CameraPackaging(
        camera.id, zone, nearest, nearest_m, camera.position, mount_point, normal, wedge,
        float((camera.position - mount_point) @ normal), ground_m, body_m,
        tuple(ground_resolution(camera, vehicle, d, backend) for d in GROUND_DISTANCES_M), people,
        *blocked_shares(camera, vehicle, BLOCKED_GRID, backend, lifted))


def rig_packaging(rig: Rig, vehicle: Vehicle, backend: str = "auto", lifted=()) -> tuple[CameraPackaging, ...]:
    """Every camera's packaging sheet, the rig first moved to ``vehicle``'s centre frame (RigoptError when its
    origin needs axles the vehicle lacks); ``lifted`` names the keep-outs lifted (a trailer not coupled)."""
    placed, _ = to_vehicle_centre(rig, vehicle)
    footprint = vehicle.footprint
    return tuple(camera_packaging(camera, vehicle, footprint, backend, lifted) for camera in placed.cameras)
