"""An interactive 3D view (plotly) of a vehicle, its mounting zones and keep-outs, and a rig's cameras with
their frustums and the frustums' ground footprints, for the HTML reports; the page carries plotly.js inline,
so it opens offline.

Everything is drawn in the ISO 8855 vehicle frame (x forward, y left, z up; metres) from a named origin on
the ground (``datum``): the vehicle's centre, the frame of every rigopt vehicle mesh, or the ground below the
rear axle's centre (the design and coverage reports, whose tables use it too). A rig measured from
another origin (its rear axle) is placed on the vehicle first. What is drawn:

- the body mesh, each face split exactly along the planes of the zone boxes it crosses and each piece
  coloured by the zone it lies in (the first matching zone, as ``Vehicle.zone_names`` decides; grey outside
  every zone). A body of more than MAX_DRAWN_FACES faces is first coarsened by vertex clustering;
- the wheels: the body's faces inside a wheel's cylinder (a cylinder is drawn for a wheel the mesh lacks),
  not mountable;
- the keep-out boxes in force (translucent, their reason on hover);
- each camera: a marker at its lens (hover: id, zone, pose from the datum, lens), its frustum: lines from
  the lens to the image's four corners ``frustum_range`` m (default 5 m) away along the real lens's corner
  rays, and the image's outline through the rays of points along its edges (so a distorted lens draws its
  true, curved outline; see :func:`frustum_lines`), each ray ended at the ground where it meets it sooner
  (:func:`ended_at_ground`), and where that frustum meets the ground, translucent in the camera's colour
  (:func:`frustum_footprint`);
- optionally a second rig in grey (``compare``, frustums only) and ground regions (translucent polygons at
  z = 0).

The view opens framed on the vehicle: the axes span everything drawn at one scale, the camera looks at the
vehicle's bounding box from the front left, above, from a distance that fits the box, and the legend lies
beside the scene, not over it (:func:`framed_scene`).

plotly is imported inside the functions, so importing this module stays cheap.
"""

from __future__ import annotations

import html
from typing import TYPE_CHECKING, Sequence

import numpy as np

from rigopt.errors import RigoptError
from rigopt.geometry import clip_polygon, yaw_pitch_roll_from_rotation
from rigopt.mounting.practice import keep_out_boxes
from rigopt.report.frustums import FRUSTUM_RANGE_M, ended_at_ground, frustum_footprint, frustum_lines
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.placement import to_vehicle_centre

if TYPE_CHECKING:
    from plotly.graph_objects import Figure

#: Bodies with more faces are coarsened (vertex clustering) to about this many before drawing.
MAX_DRAWN_FACES = 20_000
#: A body face counts as a wheel's when its vertices lie within this distance (m) of the wheel's cylinder.
WHEEL_TOLERANCE_M = 0.01
#: Height (m) at which ground regions are drawn, just above the ground plane.
REGION_HEIGHT_M = 0.01
#: Height (m) at which frustums' ground footprints are drawn, just above the regions.
FOOTPRINT_HEIGHT_M = 0.02
#: Direction (ISO axes: ahead, left, above) from which the view first looks at the vehicle, and the eye's
#: distance in radii of the vehicle's bounding sphere (plotly's camera sees 45 degrees vertically: a sphere
#: fills the view's height from 1 / sin(22.5 deg) = 2.61 radii).
VIEW_DIRECTION = (1.5, 1.2, 0.8)
VIEW_DISTANCE_RADII = 2.7
#: The share of the figure's width the 3D scene takes; the legend lies to its right, over none of it.
SCENE_WIDTH_FRACTION = 0.76
#: The origins a view may be drawn from: the vehicle's centre on the ground, or the ground below its rear axle.
DATUMS = ("vehicle_centre", "rear_axle")

WHEELS = "wheels (not mountable)"
BODY = "body (no zone)"
FRAME_TEXT = ("ISO 8855 vehicle frame: x forward, y left, z up, metres, origin at the vehicle's centre on the "
              "ground")
AXIS_TITLES = ("x forward (m), ISO 8855 vehicle frame", "y left (m)", "z up (m)")

_BODY_GREY = "rgb(199, 199, 204)"
_WHEEL_GREY = "rgb(60, 60, 64)"
_KEEP_OUT = "rgb(232, 89, 12)"
_COMPARE_GREY = "rgb(140, 140, 140)"
#: Strong colours for cameras (the zones take matplotlib's tab20, as in the PNG pictures).
_CAMERA_COLOURS = ("#d62728", "#1f3fbf", "#2ca02c", "#9467bd", "#e377c2", "#8c564b", "#17becf", "#bcbd22",
                   "#ff7f0e", "#111111")
_REGION_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf")
_LIGHTING = dict(ambient=0.55, diffuse=0.6, specular=0.05, roughness=0.9, fresnel=0.0)


# ------------------------------------------------------------------------------------------------ body


def _coarse_triangles(vertices: np.ndarray, faces: np.ndarray, max_faces: int) -> np.ndarray:
    """(n, 3, 3) float m: the mesh's triangles, coarsened by vertex clustering on a cubic grid (each cell's
    vertices merged into their mean, collapsed and repeated faces dropped) when it has more than
    ``max_faces`` faces; the cell grows until at most ``max_faces`` remain."""
    triangles = vertices[faces]
    if len(faces) <= max_faces:
        return triangles
    area = 0.5 * np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]),
                                axis=1).sum()
    cell = np.sqrt(2.0 * area / max_faces)
    while True:
        _, cluster = np.unique(np.floor(vertices / cell).astype(np.int64), axis=0, return_inverse=True)
        cluster = cluster.ravel()
        merged = np.stack([np.bincount(cluster, vertices[:, k]) for k in range(3)], axis=1)
        merged /= np.bincount(cluster)[:, None]
        kept = cluster[faces]
        kept = kept[(kept[:, 0] != kept[:, 1]) & (kept[:, 1] != kept[:, 2]) & (kept[:, 0] != kept[:, 2])]
        _, first = np.unique(np.sort(kept, axis=1), axis=0, return_index=True)
        kept = kept[np.sort(first)]
        if len(kept) <= max_faces:
            return merged[kept]
        cell *= 1.3


def _split_along_boxes(triangle: np.ndarray, boxes: list[tuple[np.ndarray, np.ndarray]]) -> list[np.ndarray]:
    """Convex pieces (each (j, 3) m) of ``triangle`` (3, 3) cut along every plane of ``boxes`` [(low, high)]
    that crosses it: each piece lies wholly inside or wholly outside each box."""
    pieces = [triangle]
    for low, high in boxes:
        for axis in range(3):
            for bound in (low[axis], high[axis]):
                cut = []
                for piece in pieces:
                    offset = piece[:, axis] - bound
                    if offset.min() < -1e-9 and offset.max() > 1e-9:
                        cut += [p for p in (clip_polygon(piece, axis, bound, 1.0), clip_polygon(piece, axis, bound, -1.0))
                                if len(p) >= 3]
                    else:
                        cut.append(piece)
                pieces = cut
    return pieces


def _wheel_faces(triangles: np.ndarray, wheels) -> tuple[np.ndarray, list[int]]:
    """(n,) bool: triangles (n, 3, 3) m with every vertex within a wheel's cylinder (WHEEL_TOLERANCE_M), and
    the indices of the ``wheels`` [(centre (3,), radius, width)] none of the triangles belongs to."""
    on_wheel = np.zeros(len(triangles), dtype=bool)
    missing = []
    for k, (centre, radius, width) in enumerate(wheels):
        offset = triangles - centre
        inside = ((np.hypot(offset[..., 0], offset[..., 2]) <= radius + WHEEL_TOLERANCE_M)
                  & (np.abs(offset[..., 1]) <= width / 2.0 + WHEEL_TOLERANCE_M)).all(axis=1)
        on_wheel |= inside
        if not inside.any():
            missing.append(k)
    return on_wheel, missing


def body_triangles(vehicle: Vehicle, max_faces: int = MAX_DRAWN_FACES) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """The body as drawn: triangles (n, 3, 3) m (vehicle frame), each one's label (n,) object (its zone's
    name, WHEELS, or BODY), and the indices of ``vehicle.wheels`` the mesh does not hold.

    The (coarsened, see MAX_DRAWN_FACES) mesh's faces on a wheel are labelled WHEELS; every other face is
    split along the planes of the zone boxes it overlaps whose normal cone holds its normal, and each piece,
    fan-triangulated, takes the zone of its centroid by ``Vehicle.zone_names``."""
    mesh = vehicle.mesh
    triangles = _coarse_triangles(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces), max_faces)
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    length = np.linalg.norm(normals, axis=1)
    triangles, normals = triangles[length > 1e-12], normals[length > 1e-12] / length[length > 1e-12, None]
    on_wheel, missing = _wheel_faces(triangles, vehicle.wheels)
    low, high = triangles.min(axis=1), triangles.max(axis=1)
    crossing = np.zeros((len(triangles), len(vehicle.zones)), dtype=bool)
    for z, zone in enumerate(vehicle.zones):
        facing = normals @ zone.normal >= np.cos(np.deg2rad(zone.cone_deg)) - 1e-12
        crossing[:, z] = facing & np.all((high >= zone.min) & (low <= zone.max), axis=1) & ~on_wheel
    pieces, piece_normals, labels = [], [], []
    for face in range(len(triangles)):
        if not crossing[face].any():
            pieces.append(triangles[face])
            piece_normals.append(normals[face])
            labels.append(WHEELS if on_wheel[face] else "")  # "" : decided below
            continue
        boxes = [(vehicle.zones[z].min, vehicle.zones[z].max) for z in np.flatnonzero(crossing[face])]
        for piece in _split_along_boxes(triangles[face], boxes):
            pieces.append(piece)
            piece_normals.append(normals[face])
            labels.append("")
    undecided = [k for k, label in enumerate(labels) if label == ""]
    if undecided:
        centroids = np.array([pieces[k].mean(axis=0) for k in undecided])
        names = vehicle.zone_names(centroids, np.array([piece_normals[k] for k in undecided]))
        for k, name in zip(undecided, names):
            labels[k] = name or BODY
    out_triangles, out_labels = [], []
    for piece, label in zip(pieces, labels):
        for k in range(1, len(piece) - 1):  # fan: a convex piece
            out_triangles.append((piece[0], piece[k], piece[k + 1]))
            out_labels.append(label)
    return np.array(out_triangles, dtype=float).reshape(-1, 3, 3), np.array(out_labels, dtype=object), missing


def _mesh_trace(go, triangles: np.ndarray, name: str, colour: str, hover: str, **extra):
    """A Mesh3d of ``triangles`` (n, 3, 3) m, flat shaded, one legend entry ``name``."""
    points = triangles.reshape(-1, 3).astype(np.float32)
    index = np.arange(len(points), dtype=np.int32).reshape(-1, 3)
    return go.Mesh3d(x=points[:, 0], y=points[:, 1], z=points[:, 2], i=index[:, 0], j=index[:, 1], k=index[:, 2],
                     name=name, color=colour, flatshading=True, lighting=_LIGHTING, hovertext=hover,
                     hoverinfo="text", **{"showlegend": True, **extra})


def _cylinder_triangles(centre: np.ndarray, radius: float, width: float, segments: int = 24) -> np.ndarray:
    """(4 * segments, 3, 3) m: a wheel's cylinder (axis along y) as triangles, caps included."""
    angle = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    ring = np.stack([radius * np.cos(angle), np.zeros_like(angle), radius * np.sin(angle)], axis=1)
    sides = [centre + ring + [0.0, s * width / 2.0, 0.0] for s in (-1.0, 1.0)]
    caps = [centre + [0.0, s * width / 2.0, 0.0] for s in (-1.0, 1.0)]
    out = []
    for k in range(segments):
        a, b, c, d = sides[0][k], sides[0][k + 1], sides[1][k + 1], sides[1][k]
        out += [(a, b, c), (a, c, d), (caps[0], b, a), (caps[1], d, c)]
    return np.array(out)


def _box_triangles(low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(12, 3, 3) m: the box [low, high] as triangles."""
    corner = np.array([[(high if (k >> a) & 1 else low)[a] for a in range(3)] for k in range(8)])
    quads = ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3))
    return np.array([corner[list(t)] for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])


def _box_edges(low: np.ndarray, high: np.ndarray) -> list[list]:
    """x, y, z lists (None between segments) of the box's 12 edges."""
    corner = np.array([[(high if (k >> a) & 1 else low)[a] for a in range(3)] for k in range(8)])
    pairs = [(k, k | (1 << a)) for k in range(8) for a in range(3) if not (k >> a) & 1]
    return _polylines([corner[[a, b]] for a, b in pairs])


def _polylines(lines: Sequence[np.ndarray]) -> list[list]:
    """x, y, z lists of the polylines (each (k, 3) m), None between them (a gap in plotly)."""
    coords: list[list] = [[], [], []]
    for n, line in enumerate(lines):
        for axis in range(3):
            coords[axis] += ([None] if n else []) + [float(v) for v in line[:, axis]]
    return coords


# ------------------------------------------------------------------------------------------------ cameras


def camera_hover(camera: Camera, rig_name: str, origin=None, origin_text: str = "from the vehicle centre") -> str:
    """The hover text (plotly's HTML subset, text escaped) of a camera: id, rig, zone, position (measured from
    ``origin`` (3,) m, a point in the camera's frame, default its origin; ``origin_text`` names it) and
    yaw/pitch/roll in the ISO 8855 vehicle frame, and its lens."""
    yaw, pitch, roll = (float(np.rad2deg(a)) for a in yaw_pitch_roll_from_rotation(camera.rotation))
    lens = camera.lens
    model = "pinhole" if lens.distortion == "none" else f"{lens.distortion} " + ", ".join(
        f"{c:.3g}" for c in lens.coefficients)
    x, y, z = camera.position - (np.zeros(3) if origin is None else np.asarray(origin, dtype=float))
    lines = [f"<b>{html.escape(camera.id)}</b> ({html.escape(rig_name)})",
             f"zone: {html.escape(camera.zone or '-')}",
             f"x, y, z: {x:.2f}, {y:.2f}, {z:.2f} m (ISO 8855 vehicle frame {html.escape(origin_text)}: y left)",
             f"yaw, pitch, roll: {yaw:.1f}, {pitch:.1f}, {roll:.1f} deg (yaw > 0 left, pitch > 0 up)",
             f"lens: {lens.hfov:.1f} x {lens.vfov:.1f} deg, {html.escape(model)}, {lens.width}x{lens.height} px, "
             f"fx {lens.fx:.0f} px"]
    return "<br>".join(lines)


def _footprint_traces(go, footprint, colour: str, name: str, group: str) -> list:
    """A frustum's ground footprint (shapely, vehicle frame) as translucent fills (polygons without holes,
    ear-clipped) and outlines at FOOTPRINT_HEIGHT_M, in the camera's legend group."""
    import shapely

    traces = []
    for part in shapely.get_parts(footprint):
        if part.is_empty or part.area <= 1e-9:
            continue
        rings = [np.asarray(part.exterior.coords)[:, :2], *(np.asarray(r.coords)[:, :2] for r in part.interiors)]
        if not part.interiors:
            outline = rings[0][:-1]
            flat = np.column_stack([outline, np.full(len(outline), FOOTPRINT_HEIGHT_M)])
            traces.append(_mesh_trace(go, flat[_ear_clipping(outline)], name, colour,
                                      f"{html.escape(name)}: ground footprint", opacity=0.18, legendgroup=group,
                                      showlegend=False, meta="footprint"))
        x, y, z = _polylines([np.column_stack([r, np.full(len(r), FOOTPRINT_HEIGHT_M)]) for r in rings])
        traces.append(go.Scatter3d(x=x, y=y, z=z, mode="lines", name=name, legendgroup=group, showlegend=False,
                                   line=dict(color=colour, width=2), hoverinfo="name", meta="footprint"))
    return traces


def _camera_traces(go, rig: Rig, frustum_range: float, dimmed: bool, origin=None,
                   origin_text: str = "from the vehicle centre") -> list:
    """Per camera: its frustum (Scatter3d lines, the legend entry), its lens marker (hover details, positions
    from ``origin``, see :func:`camera_hover`) and, for the designed (not ``dimmed``) rig, the frustum's ground
    footprint (:func:`frustum_footprint`), in one legend group so that one click shows or hides them.

    The frustum trace's x, y, z: for each corner (top-left, top-right, bottom-right, bottom-left) the lens
    and that corner, then a gap (None); then the image outline (:func:`frustum_lines`); every point below the
    ground is taken back along its ray to the ground (:func:`ended_at_ground`), so no line runs under it."""
    traces = []
    for n, camera in enumerate(rig.cameras):
        colour = _COMPARE_GREY if dimmed else _CAMERA_COLOURS[n % len(_CAMERA_COLOURS)]
        name = f"{rig.name}: {camera.id}" if dimmed else camera.id
        group = f"camera {rig.name} {camera.id}"
        corners, outline = (ended_at_ground(camera.position, p) for p in frustum_lines(camera, frustum_range))
        x, y, z = _polylines([np.stack([camera.position, c]) for c in corners] + [outline])
        traces.append(go.Scatter3d(x=x, y=y, z=z, mode="lines", name=name, legendgroup=group, showlegend=True,
                                   line=dict(color=colour, width=2 if dimmed else 3, dash="dash" if dimmed else "solid"),
                                   opacity=0.6 if dimmed else 1.0, hoverinfo="name", meta="frustum"))
        x, y, z = _polylines([camera.position[None]])
        traces.append(go.Scatter3d(x=x, y=y, z=z,
                                   mode="markers", name=name, legendgroup=group, showlegend=False,
                                   marker=dict(size=4 if dimmed else 6, color=colour, symbol="diamond"),
                                   opacity=0.6 if dimmed else 1.0,
                                   hovertext=camera_hover(camera, rig.name, origin, origin_text),
                                   hoverinfo="text", meta="lens"))
        if not dimmed:
            traces += _footprint_traces(go, frustum_footprint(camera, frustum_range), colour, name, group)
    return traces


# ------------------------------------------------------------------------------------------------ ground


def _ear_clipping(outline: np.ndarray) -> np.ndarray:
    """(k - 2, 3) int: triangles (vertex indices) covering a simple polygon ``outline`` (k, 2), convex or not.
    A polygon that has no ear left (self-intersecting) has its remaining vertices fanned."""
    signed = 0.5 * np.sum(outline[:, 0] * np.roll(outline[:, 1], -1) - np.roll(outline[:, 0], -1) * outline[:, 1])
    left = list(range(len(outline))) if signed >= 0 else list(range(len(outline)))[::-1]
    triangles = []

    def cross(o, a, b):
        return (a[..., 0] - o[0]) * (b[..., 1] - o[1]) - (a[..., 1] - o[1]) * (b[..., 0] - o[0])

    while len(left) > 3:
        for n in range(len(left)):
            a, b, c = left[n - 1], left[n], left[(n + 1) % len(left)]
            pa, pb, pc = outline[a], outline[b], outline[c]
            if cross(pa, pb, pc) <= 1e-12:
                continue  # reflex or flat corner
            others = outline[[k for k in left if k not in (a, b, c)]]
            if np.any((cross(pa, pb, others) >= 0) & (cross(pb, pc, others) >= 0) & (cross(pc, pa, others) >= 0)):
                continue  # another vertex inside: not an ear
            triangles.append((a, b, c))
            left.pop(n)
            break
        else:
            triangles += [(left[0], left[k], left[k + 1]) for k in range(1, len(left) - 1)]
            return np.array(triangles, dtype=int)
    triangles.append(tuple(left))
    return np.array(triangles, dtype=int)


def _region_outline(name: str, outline) -> np.ndarray:
    """(k, 2) float m: a region's outline, the closing repeat of its first point dropped; RigoptError if it is
    not at least three finite points (x, y)."""
    points = np.asarray(outline, dtype=float)
    if points.ndim != 2 or points.shape[1] != 2 or not np.all(np.isfinite(points)):
        raise RigoptError(f"ground region {name!r} must be an outline of (x, y) points in metres, got shape "
                          f"{points.shape}")
    if len(points) > 1 and np.allclose(points[0], points[-1]):
        points = points[:-1]
    if len(points) < 3:
        raise RigoptError(f"ground region {name!r} needs at least three points, got {len(points)}")
    return points


def _region_traces(go, regions: Sequence[tuple[str, np.ndarray]]) -> list:
    traces = []
    for n, (name, outline) in enumerate(regions):
        points = _region_outline(name, outline)
        flat = np.column_stack([points, np.full(len(points), REGION_HEIGHT_M)])
        colour = _REGION_COLOURS[n % len(_REGION_COLOURS)]
        group = f"region {n} {name}"
        traces.append(_mesh_trace(go, flat[_ear_clipping(points)], str(name), colour, html.escape(str(name)),
                                  opacity=0.3, legendgroup=group))
        x, y, z = _polylines([np.concatenate([flat, flat[:1]])])
        traces.append(go.Scatter3d(x=x, y=y, z=z, mode="lines", line=dict(color=colour, width=3), name=str(name),
                                   legendgroup=group, showlegend=False, hoverinfo="name"))
    return traces


# ------------------------------------------------------------------------------------------------ figure


def view_datum(vehicle: Vehicle, datum: str = "vehicle_centre"):
    """The origin a view is drawn from, a :class:`rigopt.coverage.packaging.ReportDatum` (its point (3,) m in the
    vehicle-centre frame and its words). ``datum``: "vehicle_centre" (the mesh's own origin) or "rear_axle" (the
    reports' datum, :func:`rigopt.coverage.packaging.report_origin`: the vehicle's centre where its axles are
    unknown)."""
    from rigopt.coverage.packaging import ReportDatum, report_origin

    if datum not in DATUMS:
        raise RigoptError(f"unknown view datum {datum!r}; use one of {', '.join(DATUMS)}")
    if datum == "vehicle_centre":
        return ReportDatum(np.zeros(3), "origin at the vehicle's centre on the ground")
    return report_origin(vehicle)


def frame_text(vehicle: Vehicle, datum: str = "vehicle_centre") -> str:
    """The words naming the frame a view is drawn in (:data:`FRAME_TEXT` for the vehicle centre)."""
    return f"ISO 8855 vehicle frame: x forward, y left, z up, metres, {view_datum(vehicle, datum).origin}"


def _translate(traces: list, offset: np.ndarray) -> None:
    """Move every trace's points by -``offset`` (3,) m, in place (gaps, None, stay gaps)."""
    for trace in traces:
        for axis, shift in zip("xyz", offset):
            values = getattr(trace, axis)
            if values is None or shift == 0:
                continue
            if trace.type == "mesh3d":
                setattr(trace, axis, np.asarray(values, dtype=np.float32) - np.float32(shift))
            else:
                setattr(trace, axis, [None if v is None else float(v) - shift for v in values])


def _bounds(traces: list) -> np.ndarray:
    """(2, 3) float m: the lowest and highest x, y, z of every trace's points."""
    low, high = np.full(3, np.inf), np.full(3, -np.inf)
    for trace in traces:
        for k, axis in enumerate("xyz"):
            values = getattr(trace, axis)
            if values is None or len(values) == 0:
                continue
            array = np.array([np.nan if v is None else v for v in values], dtype=float)
            if np.isfinite(array).any():
                low[k], high[k] = min(low[k], np.nanmin(array)), max(high[k], np.nanmax(array))
    return np.stack([low, high])


def framed_scene(bounds: np.ndarray, vehicle_box: np.ndarray, origin_text: str = "from the vehicle centre") -> dict:
    """The plotly ``scene`` layout (axis ranges, aspect ratio, camera) that shows everything within ``bounds``
    (2, 3) m at one scale and opens framed on ``vehicle_box`` (2, 3) m; the x axis's title names the frame's
    origin (``origin_text``, e.g. "from the rear axle").

    The axes span ``bounds`` padded by 3 % of their largest extent L, drawn at equal scale (aspect ratio:
    each extent over L), so plotly's scene coordinates are (point - the ranges' middle) / L. The camera
    looks at the box's centre from VIEW_DIRECTION, VIEW_DISTANCE_RADII box half-diagonals away."""
    pad = 0.03 * float(np.max(bounds[1] - bounds[0]))
    low, high = bounds[0] - pad, bounds[1] + pad
    lengths = high - low
    scale = float(lengths.max())
    middle = (low + high) / 2
    centre = (vehicle_box.mean(axis=0) - middle) / scale
    radius = 0.5 * float(np.linalg.norm(vehicle_box[1] - vehicle_box[0])) / scale
    direction = np.asarray(VIEW_DIRECTION, dtype=float) / np.linalg.norm(VIEW_DIRECTION)
    eye = centre + VIEW_DISTANCE_RADII * radius * direction
    titles = (f"{AXIS_TITLES[0]} {origin_text}", *AXIS_TITLES[1:])
    axes = {f"{axis}axis": dict(title=dict(text=text), range=[float(low[k]), float(high[k])], autorange=False)
            for k, (axis, text) in enumerate(zip("xyz", titles))}
    return dict(aspectmode="manual", aspectratio=dict(zip("xyz", (float(v) for v in lengths / scale))),
                camera=dict(center=dict(zip("xyz", (float(v) for v in centre))),
                            eye=dict(zip("xyz", (float(v) for v in eye))), up=dict(x=0.0, y=0.0, z=1.0)),
                domain=dict(x=[0.0, SCENE_WIDTH_FRACTION], y=[0.0, 1.0]), **axes)


def scene_figure(vehicle: Vehicle, rig: Rig | None = None, *, regions: Sequence[tuple[str, np.ndarray]] = (),
                 compare: Rig | None = None, frustum_range: float = FRUSTUM_RANGE_M, lifted: Sequence[str] = (),
                 max_faces: int = MAX_DRAWN_FACES, datum: str = "vehicle_centre") -> "Figure":
    """The 3D view of ``vehicle`` with ``rig`` (and ``compare`` in grey, dashed) on it, as a plotly Figure.

    Traces, in order: the body by zone (one Mesh3d per zone name, then BODY, then WHEELS; hover names the
    zone), wheel cylinders the mesh lacks, the keep-out boxes in force (``lifted``: names of optional
    keep-outs switched off, as ``MountPractice.lifted``; a translucent Mesh3d named ``keep-out: name
    (reason)`` and its edges), each camera's frustum, lens marker and (``rig``'s cameras) ground footprint
    (:func:`_camera_traces`; the frustum trace is named by the camera id, ``"<rig>: <id>"`` for the compared
    rig), and the ground ``regions`` [(name, outline (k, 2) m in the vehicle-centre frame)] as translucent
    polygons at z = 0. Rigs measured from another origin are moved to the vehicle's centre (RigoptError when
    the vehicle's axles, needed for that, are unknown). ``frustum_range`` m > 0: where frustums end.
    ``datum``: the origin everything is drawn from (:func:`view_datum`; axes ISO 8855, :func:`frame_text`).
    The view opens framed on the vehicle (:func:`framed_scene`), the legend beside the scene."""
    import plotly.graph_objects as go

    from rigopt.report.palette import zone_colours

    if not frustum_range > 0:
        raise RigoptError(f"the frustum range must be positive (m), got {frustum_range}")
    drawn_from = view_datum(vehicle, datum)
    origin, origin_text = drawn_from.point, drawn_from.axis_text
    triangles, labels, missing = body_triangles(vehicle, max_faces)
    colours = {name: "rgb({:.0f}, {:.0f}, {:.0f})".format(*(255 * np.array(c[:3])))
               for name, c in zone_colours(vehicle).items()}
    traces = []
    for name in [*colours, BODY, WHEELS]:
        mine = labels == name
        if not mine.any():
            continue
        colour = colours.get(name, _WHEEL_GREY if name == WHEELS else _BODY_GREY)
        hover = {BODY: "body: outside every mounting zone", WHEELS: "wheel and tyre: not mountable"}.get(
            name, f"zone {html.escape(name)}")
        traces.append(_mesh_trace(go, triangles[mine], f"zone {name}" if name in colours else name, colour, hover,
                                  legendgroup=name))
    for k in missing:  # wheels the mesh does not hold
        centre, radius, width = vehicle.wheels[k]
        traces.append(_mesh_trace(go, _cylinder_triangles(centre, radius, width), WHEELS, _WHEEL_GREY,
                                  "wheel and tyre: not mountable", legendgroup=WHEELS,
                                  showlegend=not any(t.name == WHEELS for t in traces)))
    seen = set()
    for low, high, label in keep_out_boxes(vehicle, tuple(lifted)):
        name = f"keep-out: {label}"
        hover = f"keep-out {html.escape(label)}: no camera here"
        traces.append(_mesh_trace(go, _box_triangles(low, high), name, _KEEP_OUT, hover, opacity=0.22,
                                  legendgroup=name, showlegend=name not in seen))
        x, y, z = _box_edges(low, high)
        traces.append(go.Scatter3d(x=x, y=y, z=z, mode="lines", line=dict(color=_KEEP_OUT, width=2), name=name,
                                   legendgroup=name, showlegend=False, hoverinfo="name"))
        seen.add(name)
    for other, dimmed in ((compare, True), (rig, False)):
        if other is not None:
            placed, _ = to_vehicle_centre(other, vehicle)
            traces += _camera_traces(go, placed, frustum_range, dimmed, origin, origin_text)
    traces += _region_traces(go, regions)
    _translate(traces, origin)
    title = f"{vehicle.name} ({vehicle.blueprint})" + (f" with rig {rig.name}" if rig is not None else "") + (
        f", {compare.name} in grey" if compare is not None else "")
    vehicle_box = np.asarray(vehicle.mesh.bounds, dtype=float) - origin
    figure = go.Figure(traces)
    figure.update_layout(
        title=dict(text=html.escape(title)), template="plotly_white", height=720,
        margin=dict(l=0, r=0, t=40, b=0), scene=framed_scene(_bounds(traces), vehicle_box, origin_text),
        legend=dict(title=dict(text="click to show or hide"), itemsizing="constant", groupclick="togglegroup",
                    x=SCENE_WIDTH_FRACTION + 0.01, xanchor="left", y=1.0, yanchor="top"))
    return figure


def plotly_library_html() -> str:
    """A ``<script>`` element holding plotly.js itself (about 4.8 MB), for a page that shows several views:
    put it once before them and render each with ``include_plotlyjs=False``."""
    from plotly.offline import get_plotlyjs

    return f"<script>{get_plotlyjs()}</script>"


def figure_html(figure: "Figure", *, include_plotlyjs: bool = True, div_id: str = "scene-3d") -> str:
    """A ``<div>`` fragment that draws ``figure``; with ``include_plotlyjs`` it carries plotly.js inline (no
    network needed: the page opens offline). ``div_id`` must be unique on the page."""
    import plotly.io as pio

    return pio.to_html(figure, include_plotlyjs=include_plotlyjs, full_html=False, div_id=div_id,
                       config={"displaylogo": False, "responsive": True})


def scene_html(vehicle: Vehicle, rig: Rig | None = None, *, regions: Sequence[tuple[str, np.ndarray]] = (),
               compare: Rig | None = None, frustum_range: float = FRUSTUM_RANGE_M, lifted: Sequence[str] = (),
               datum: str = "vehicle_centre", include_plotlyjs: bool = True, div_id: str = "scene-3d") -> str:
    """:func:`scene_figure` as an HTML fragment (:func:`figure_html`)."""
    figure = scene_figure(vehicle, rig, regions=regions, compare=compare, frustum_range=frustum_range,
                          lifted=lifted, datum=datum)
    return figure_html(figure, include_plotlyjs=include_plotlyjs, div_id=div_id)
