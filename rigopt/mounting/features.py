"""Mounting rules an engineer would sign: the features of a body no lens may sit on, each with the reason
``rigopt check`` prints.

Per lens position (the mount points of :mod:`rigopt.mounting.sampling` leave out every place these forbid):

  - *steps* (``[[steps]]``): walkable surfaces (a step, a tailboard, a catwalk): a lens within
    ``MountPractice.feature_margin`` of the step's box is stood on and kicked;
  - *door frames* (``[[door_frames]]``): a lens within ``frame`` of a door opening's edges, in the door's
    plane, sits on the frame, the seals or the shut line; within ``hinge_band`` of the hinged edge, on the
    hinge line, it is pinched when the door opens;
  - *fixtures* (``[[fixtures]]``): rails, ladders, light bars and racks carry no camera;
  - *wheel-arch lips*: a lens outboard of a tyre's inner face within ``lip_band`` of its arch's edge (the
    arch traced on the mesh, :mod:`rigopt.vehicle.arches`) has its housing over the lip, in the tyre's grit;
  - *tyre-spray cones*: behind each tyre's contact patch, a cone of half-angle ``spray_half_angle_deg``
    around the direction backwards and ``spray_elevation_deg`` up, ``spray_length`` m long (the jet a wet road
    throws off the tread; bodywork in between is not counted);
  - *the legal width*: the housing sticks out further than ``width_allowance`` beyond half the vehicle's
    ``legal_width`` from the centreline (or beyond the body's own side where the body is wider still), unless
    its foot lies in one of ``width_exempt_zones`` (mirrors: devices for indirect vision do not count in the
    width);
  - *the tilt-cab arc* (``[tilt_cab]``): a lens not on the cab in the space the cab sweeps as it tilts;
  - *the trailer's swing*: a semi-trailer's front corners turn about its kingpin (``kingpin`` of its
    ``[[keep_out]]``): a lens within that radius of the kingpin, above it, is hit in a turn (the near-view rule
    of :func:`rigopt.mounting.rules.check_rig` and the clear directions of :mod:`rigopt.mounting.candidates`
    also keep the swing out of every camera's first metre: :func:`trailer_swings`, :func:`segments_hit_swings`);
  - *the wiped area* (``[wiped_area]``): a lens in the windscreen's zone must look through the wiped glass;
  - *through the windscreen*: a camera in the windscreen's zone (WINDSCREEN_ZONE) sits behind the glass and looks
    out through it: its view within WINDSCREEN_VIEW_DEG of straight ahead in plan (:func:`off_windscreen_view`);
    one looking sideways would be a housing on the glass's outside;
  - *the wheels' envelope*: the space a wheel may take: each tyre (a cylinder across the vehicle) anywhere from
    rest up to BUMP_TRAVEL_M of suspension travel, a steered (front-axle) one turned about its vertical axis to
    any angle within STEER_LOCK_DEG either way (:func:`wheel_envelope_distances`); no lens inside it, whatever
    the zone says.

Frames and units: ISO 8855 vehicle frame, metres; angles in degrees where named ``_deg``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigopt.mounting.records import MountPractice
from rigopt.mounting.shapes import surface_frame
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import HINGE_EDGES

#: Why each kind of fixture carries no camera.
FIXTURE_REASONS = {
    "rail": "a rail: held and climbed on, no face for a housing",
    "ladder": "a ladder: climbed, loaded and moved",
    "light_bar": "a light bar: its lamps must stay uncovered",
    "rack": "a rack: loaded and unloaded",
    "mud_flap": "a mud flap: it flexes, swings and takes the tyre's spray",
    "lamp": "a lamp: its lens must stay uncovered",
    "number_plate": "a number plate: it must stay legible",
}

_FLIP = np.array([1.0, -1.0, 1.0])
#: Parts of the body this close (m) to an exempt zone's box belong to the exempt device (a mirror's arm).
EXEMPT_REACH_M = 0.2
#: Protrusions beyond the width this small (m) are rounding (rig files give positions to the centimetre).
WIDTH_TOLERANCE_M = 0.005
#: The zone of the front windscreen, whose cameras sit behind the glass and look out through it.
WINDSCREEN_ZONE = "windshield_front"
#: The glass zones (windscreen and rear window), as the built-in vehicles and ``vehicle add`` name them.
GLASS_ZONES = (WINDSCREEN_ZONE, "windshield_rear")
#: Largest angle (deg) in plan between a windscreen camera's optical axis and straight ahead.
WINDSCREEN_VIEW_DEG = 60.0
#: Suspension bump travel (m) above each wheel's rest position.
BUMP_TRAVEL_M = 0.12
#: A steered wheel's lock (deg) either way: cars turn their front wheels 30 to 40 deg (docs/design.md).
STEER_LOCK_DEG = 40.0
#: Steer angles the envelope is sampled at (deg): every 2.5 deg from lock to lock.
STEER_SAMPLES_DEG = np.linspace(-STEER_LOCK_DEG, STEER_LOCK_DEG, 33)


def _mirrored(low, high) -> tuple[np.ndarray, np.ndarray]:
    """The box [low, high] (3,) reflected across y = 0."""
    return np.minimum(low * _FLIP, high * _FLIP), np.maximum(low * _FLIP, high * _FLIP)


def feature_boxes(entries):
    """(entry, low (3,), high (3,)) for each spec entry with ``min``, ``max``, ``mirrored``; copies expanded."""
    for entry in entries:
        yield entry, entry.min, entry.max
        if entry.mirrored:
            yield (entry, *_mirrored(entry.min, entry.max))


def _in_box(points, low, high, margin: float) -> np.ndarray:
    """(n,) bool: ``points`` (n, 3) inside [low - margin, high + margin]."""
    return np.all((points >= low - margin) & (points <= high + margin), axis=1)


def on_steps(vehicle: Vehicle, points, margin: float) -> list[list[str]]:
    """For each lens position (n, 3) m: the walkable surfaces ('on the tailboard step (walkable) at 0.57 m')
    within ``margin`` m of it."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    found: list[list[str]] = [[] for _ in range(len(points))]
    for step, low, high in feature_boxes(vehicle.spec.steps):
        for k in np.flatnonzero(_in_box(points, low, high, margin)):
            message = f"on the {step.name} (walkable) at {points[k, 2]:.2f} m"
            if message not in found[k]:
                found[k].append(message)
    return found


def on_fixtures(vehicle: Vehicle, points, margin: float) -> list[list[str]]:
    """For each lens position (n, 3) m: the fixtures (rails, ladders, light bars, racks) within ``margin`` m."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    found: list[list[str]] = [[] for _ in range(len(points))]
    for fixture, low, high in feature_boxes(vehicle.spec.fixtures):
        for k in np.flatnonzero(_in_box(points, low, high, margin)):
            message = f"on the {fixture.name} ({FIXTURE_REASONS[fixture.kind]})"
            if message not in found[k]:
                found[k].append(message)
    return found


def in_door_frames(vehicle: Vehicle, points, margin: float, hinge_band: float) -> list[list[str]]:
    """For each lens position (n, 3) m: the door frames and hinge lines it is on.

    A door's box is its opening; its thinnest side is across the door (the *normal* axis), where a lens counts
    within ``margin`` of the box. In the door's plane a lens within the door's ``frame`` of the opening's
    edge (inside or outside) is in the frame; within ``hinge_band`` of the hinged edge, along the hinge's
    length, on the hinge line (said instead of the frame).
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    found: list[list[str]] = [[] for _ in range(len(points))]
    for door, low, high in feature_boxes(vehicle.spec.door_frames):
        normal = int(np.argmin(high - low))
        plane = [a for a in range(3) if a != normal]
        across = (points[:, normal] >= low[normal] - margin) & (points[:, normal] <= high[normal] + margin)
        lo, hi = low[plane], high[plane]
        p = points[:, plane]
        outside = np.linalg.norm(np.maximum(np.maximum(lo - p, p - hi), 0.0), axis=1)
        inside = np.min(np.minimum(p - lo, hi - p), axis=1)
        edge = np.where(outside > 0, outside, np.maximum(inside, 0.0))  # in-plane distance to the opening's edge
        hinge_gap = np.full(len(points), np.inf)
        if door.hinge is not None:
            axis, side = HINGE_EDGES[door.hinge]
            along = next(a for a in plane if a != axis)
            line = high[axis] if side > 0 else low[axis]
            beside = (points[:, along] >= low[along] - hinge_band) & (points[:, along] <= high[along] + hinge_band)
            hinge_gap = np.where(beside, np.abs(points[:, axis] - line), np.inf)
        for k in np.flatnonzero(across & ((edge <= door.frame) | (hinge_gap <= hinge_band))):
            if hinge_gap[k] <= hinge_band:
                message = f"on the hinge line of the {door.name} ({hinge_gap[k]:.2f} m from it): pinched as it opens"
            else:
                message = f"in the frame of the {door.name} ({edge[k]:.2f} m from its edge)"
            if message not in found[k]:
                found[k].append(message)
    return found


def on_arch_lips(vehicle: Vehicle, points, lip_band: float, wheel_clearance: float) -> list[list[str]]:
    """For each lens position (n, 3) m: the wheel-arch lips it is on: outboard of the tyre's inner face, further
    than ``wheel_radius + wheel_clearance`` from the axle (closer is on the wheel itself) and within
    ``lip_band`` m of the arch's edge (or inside the arch)."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    found: list[list[str]] = [[] for _ in range(len(points))]
    for arch in vehicle.wheel_arches:
        outboard = arch.side * points[:, 1] >= arch.inner_y - 0.02
        distance, angle = arch.side_view(points)
        edge = arch.edge_at(angle)
        gap = distance - edge
        near = outboard & np.isfinite(edge) & (gap <= lip_band) & (distance > arch.radius + wheel_clearance)
        for k in np.flatnonzero(near):
            where = (f"{gap[k]:.2f} m from the arch's edge, at least {lip_band:.2f} m" if gap[k] >= 0
                     else f"{-gap[k]:.2f} m inside the arch")
            found[k].append(f"on the wheel-arch lip of the {arch.name} ({where})")
    return found


def wheel_envelope_distances(vehicle: Vehicle, points) -> np.ndarray | None:
    """(n,) float m, 0 inside: each point's (n, 3) m distance to the nearest wheel's envelope (the module
    docstring): a tyre, a cylinder of its radius and width across y, its centre anywhere from rest up to
    BUMP_TRAVEL_M higher; a front-axle tyre also turned about its vertical axis to each of STEER_SAMPLES_DEG
    (the distance to the nearest of those, a hair above the swept solid's between samples). None for a vehicle
    whose wheels are unknown."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    if not vehicle.wheels:
        return None
    front = max(vehicle.axles) if vehicle.axles else None
    gaps = []
    for centre, radius, width in vehicle.wheels:
        d = points - centre
        up = np.where(d[:, 2] > 0, np.maximum(d[:, 2] - BUMP_TRAVEL_M, 0.0), d[:, 2])  # the centre up to its bump
        steered = front is not None and abs(centre[0] - front) < 1e-6
        angles = np.deg2rad(STEER_SAMPLES_DEG if steered else [0.0])[:, None]  # (a, 1)
        along = d[:, 0] * np.cos(angles) + d[:, 1] * np.sin(angles)  # (a, n): in the turned tyre's frame
        across = -d[:, 0] * np.sin(angles) + d[:, 1] * np.cos(angles)
        in_plane = np.maximum(np.hypot(along, up) - radius, 0.0)
        gaps.append(np.hypot(in_plane, np.maximum(np.abs(across) - width / 2.0, 0.0)).min(axis=0))
    return np.min(gaps, axis=0)


def off_windscreen_view(zones, forwards) -> np.ndarray:
    """(n,) bool: cameras in the windscreen's zone (``zones`` (n,) names) whose optical axes ``forwards`` (n, 3)
    do not look out through it: in plan more than WINDSCREEN_VIEW_DEG from straight ahead (or straight up or
    down)."""
    forwards = np.atleast_2d(np.asarray(forwards, dtype=float))
    on_glass = np.asarray([zone == WINDSCREEN_ZONE for zone in zones], dtype=bool)
    heading = np.degrees(np.arctan2(np.abs(forwards[:, 1]), forwards[:, 0]))
    level = np.hypot(forwards[:, 0], forwards[:, 1]) > 1e-9
    return on_glass & (~level | (heading > WINDSCREEN_VIEW_DEG))


def in_wheel_envelopes(vehicle: Vehicle, points) -> list[list[str]]:
    """For each lens position (n, 3) m: the wheels' envelope when it lies inside it (the tyres with their steer
    and bump travel, :func:`wheel_envelope_distances`)."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    distance = wheel_envelope_distances(vehicle, points)
    if distance is None:
        return [[] for _ in range(len(points))]
    reason = f"inside the wheels' envelope (a tyre at up to {STEER_LOCK_DEG:g} deg of steer and {BUMP_TRAVEL_M:g} m of bump)"
    return [[reason] if gap <= 0.0 else [] for gap in distance]


def in_spray_cones(vehicle: Vehicle, points, practice: MountPractice) -> list[list[str]]:
    """For each lens position (n, 3) m: the wheels whose tyre-spray cone holds it (see the module doc)."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    found: list[list[str]] = [[] for _ in range(len(points))]
    elevation = np.deg2rad(practice.spray_elevation_deg)
    axis = np.array([-np.cos(elevation), 0.0, np.sin(elevation)])
    cos_half = np.cos(np.deg2rad(practice.spray_half_angle_deg))
    for arch in vehicle.wheel_arches:
        apex = np.array([arch.centre[0], arch.centre[1], 0.0])  # the contact patch
        offset = points - apex
        distance = np.linalg.norm(offset, axis=1)
        cosine = offset @ axis / np.maximum(distance, 1e-12)
        for k in np.flatnonzero((distance <= practice.spray_length) & (cosine >= cos_half)):
            found[k].append(f"in the tyre-spray cone of the {arch.name} ({distance[k]:.2f} m behind its contact "
                            f"patch, {np.rad2deg(np.arccos(min(cosine[k], 1.0))):.0f} deg off the jet)")
    return found


def width_limits(vehicle: Vehicle, exempt=("mirror",)) -> tuple[float, float]:
    """(left, right) m: how far from the centreline a housing may reach on each side: half the legal width, or
    the body's own outermost side where the body is wider (parts within EXEMPT_REACH_M of an ``exempt`` zone's
    box, the mirror heads and their arms, left out): a camera may not make the vehicle wider than the law
    allows, nor than the body already is."""
    vertices = np.asarray(vehicle.mesh.vertices)
    kept = np.ones(len(vertices), dtype=bool)
    for zone in vehicle.zones:
        if zone.name in exempt:
            kept &= ~_in_box(vertices, zone.min, zone.max, EXEMPT_REACH_M)
    half = vehicle.legal_width / 2.0
    return max(half, float(vertices[kept, 1].max())), max(half, float(-vertices[kept, 1].min()))


def width_protrusion(vehicle: Vehicle, points, normals, zones, housing, exempt=("mirror",)
                     ) -> tuple[np.ndarray, np.ndarray]:
    """How far each housing (``housing`` (w, h, d) m centred on the lens at ``points`` (n, 3), its back on a
    surface of outward ``normals`` (n, 3)) sticks out beyond its side's limit (:func:`width_limits`): (n,) m,
    0 where it does not (by more than WIDTH_TOLERANCE_M) or where its foot's zone (``zones`` (n,)) is one of
    ``exempt``; and that limit (n,) m. Whether a protrusion is allowed is the practice's ``width_allowance``."""
    points, normals = np.atleast_2d(points), np.atleast_2d(normals)
    half = np.asarray(housing, dtype=float) / 2.0
    reach = np.array([np.abs(surface_frame(n, np.array([1.0, 0.0, 0.0]))[1]) @ half for n in normals])
    left, right = width_limits(vehicle, exempt)
    limit = np.where(points[:, 1] >= 0, left, right)
    beyond = np.abs(points[:, 1]) + reach - limit
    exempted = np.isin(np.asarray(zones, dtype=object), list(exempt))
    return np.where(exempted | (beyond <= WIDTH_TOLERANCE_M), 0.0, beyond), limit


def in_tilt_arc(vehicle: Vehicle, points, margin: float, step_deg: float = 1.0) -> np.ndarray:
    """(n,) bool: lens positions (n, 3) m the tilting cab sweeps (``[tilt_cab]``) without being on the cab (within
    ``margin`` of its box): some tilt in [0, angle_deg] brings the cab over the point."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    cab = vehicle.spec.tilt_cab
    if cab is None:
        return np.zeros(len(points), dtype=bool)
    on_cab = _in_box(points, cab.min, cab.max, margin)
    dx, dz = points[:, 0] - cab.pivot[0], points[:, 2] - cab.pivot[1]
    swept = np.zeros(len(points), dtype=bool)
    for tilt in np.deg2rad(np.arange(0.0, cab.angle_deg + 1e-9, step_deg)):
        # where the point lies in the cab's own frame when the cab is tilted (nose down) by ``tilt``
        x = cab.pivot[0] + dx * np.cos(tilt) - dz * np.sin(tilt)
        z = cab.pivot[1] + dx * np.sin(tilt) + dz * np.cos(tilt)
        swept |= ((x >= cab.min[0]) & (x <= cab.max[0]) & (z >= cab.min[2]) & (z <= cab.max[2])
                  & (points[:, 1] >= cab.min[1]) & (points[:, 1] <= cab.max[1]))
    return swept & ~on_cab


@dataclass(frozen=True)
class TrailerSwing:
    """The space a semi-trailer's front sweeps as it turns about its kingpin: ``name`` (its keep-out's),
    ``kingpin`` (3,) m, ``radius`` m (the kingpin to the front corners, in plan), ``top`` m; the cylinder about
    the kingpin's vertical from its height (the trailer's underside on the fifth wheel) to ``top``."""

    name: str
    kingpin: np.ndarray
    radius: float
    top: float

    def holds(self, points) -> tuple[np.ndarray, np.ndarray]:
        """(n,) bool: ``points`` (n, 3) m in the swing; (n,) m how far inside its radius each lies."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        depth = self.radius - np.hypot(points[:, 0] - self.kingpin[0], points[:, 1] - self.kingpin[1])
        return (depth >= 0) & (points[:, 2] >= self.kingpin[2]) & (points[:, 2] <= self.top), depth

    def describe(self) -> str:
        return (f"the {self.name}'s swing (its front corners turn {self.radius:.2f} m about the kingpin at "
                f"x {self.kingpin[0]:.2f} m)")


def trailer_swings(vehicle: Vehicle, lifted=()) -> list[TrailerSwing]:
    """The swing of each coupled semi-trailer (a ``[[keep_out]]`` with a ``kingpin``; lifted ones left out):
    its radius from the kingpin to the keep-out's front corners (x = its max, y = its min and max)."""
    swings = []
    for box in vehicle.spec.keep_outs:
        if box.kingpin is None or (box.optional and box.name in lifted):
            continue
        corners = np.array([[box.max[0], box.min[1]], [box.max[0], box.max[1]]])
        radius = float(np.max(np.hypot(corners[:, 0] - box.kingpin[0], corners[:, 1] - box.kingpin[1])))
        swings.append(TrailerSwing(box.name, box.kingpin, radius, float(box.max[2])))
    return swings


def outside_wiped_area(vehicle: Vehicle, feet, zones) -> np.ndarray:
    """(n,) float m: for lenses whose foot (``feet`` (n, 3) m) lies in the wiped area's zone (``zones`` (n,)),
    how far the foot, seen from the front (y, z), lies outside the wiped outline; 0 inside it or elsewhere."""
    import shapely

    feet = np.atleast_2d(np.asarray(feet, dtype=float))
    wiped = vehicle.spec.wiped_area
    if wiped is None:
        return np.zeros(len(feet))
    in_zone = np.array([z == wiped.zone for z in zones], dtype=bool)
    distance = shapely.distance(shapely.Polygon(wiped.outline), shapely.points(feet[:, 1:3]))
    return np.where(in_zone, distance, 0.0)


def segments_hit_swings(starts, directions, length: float, swings) -> np.ndarray:
    """(n,) bool: segments ``starts + s directions``, s in [0, length] (starts, directions (n, 3), unit), that
    enter any of ``swings`` (:class:`TrailerSwing` cylinders), solved exactly."""
    starts, directions = np.atleast_2d(starts), np.atleast_2d(directions)
    hit = np.zeros(len(starts), dtype=bool)
    for swing in swings:
        offset = starts[:, :2] - swing.kingpin[:2]
        a = (directions[:, :2] ** 2).sum(axis=1)
        b = 2.0 * (offset * directions[:, :2]).sum(axis=1)
        c = (offset**2).sum(axis=1) - swing.radius**2
        with np.errstate(divide="ignore", invalid="ignore"):
            root = np.sqrt(np.maximum(b * b - 4.0 * a * c, 0.0))
            plan_low = np.where(a > 1e-12, (-b - root) / (2.0 * a), np.where(c <= 0, -np.inf, np.inf))
            plan_high = np.where(a > 1e-12, (-b + root) / (2.0 * a), np.where(c <= 0, np.inf, -np.inf))
            plan_low = np.where((a > 1e-12) & (b * b - 4.0 * a * c < 0), np.inf, plan_low)
            z_low = (swing.kingpin[2] - starts[:, 2]) / directions[:, 2]
            z_high = (swing.top - starts[:, 2]) / directions[:, 2]
        flat = np.abs(directions[:, 2]) < 1e-12
        z_in = (starts[:, 2] >= swing.kingpin[2]) & (starts[:, 2] <= swing.top)
        z_from = np.where(flat, np.where(z_in, -np.inf, np.inf), np.minimum(z_low, z_high))
        z_to = np.where(flat, np.where(z_in, np.inf, -np.inf), np.maximum(z_low, z_high))
        enter = np.maximum.reduce([plan_low, z_from, np.zeros(len(starts))])
        leave = np.minimum.reduce([plan_high, z_to, np.full(len(starts), length)])
        hit |= enter <= leave
    return hit
