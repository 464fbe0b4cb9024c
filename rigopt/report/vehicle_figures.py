"""Pictures of a vehicle: top and side views with its zones coloured and, optionally, a rig's cameras, drawn in
ISO 8855 axes (x forward, y left, z up; metres) from a datum (:class:`rigopt.coverage.packaging.ReportDatum`):
the vehicle's centre on the ground, or the report's (the ground below the rear axle's centre) so that a
picture and its report's tables give a camera the same x."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from rigopt.camera import vertical_fov
from rigopt.coverage.packaging import CENTRE_DATUM, ReportDatum
from rigopt.geometry import clip_polygon
from rigopt.report.palette import zone_colours
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.placement import to_vehicle_centre

#: Length (m) of the frustum wedges drawn for cameras.
FRUSTUM_DRAW_LENGTH = 1.2
_BODY_GREY = (0.78, 0.78, 0.80)


def _clip_to_box(polygon: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """The part of a convex planar ``polygon`` (k, 3) m inside the box [``low``, ``high``] (3,) m, as (j, 3);
    j < 3 when nothing of it is inside (Sutherland-Hodgman against the six faces of the box)."""
    for axis in range(3):
        for bound, side in ((low[axis], 1.0), (high[axis], -1.0)):
            if len(polygon) < 3:
                return polygon
            polygon = clip_polygon(polygon, axis, bound, side)
    return polygon


def _zone_patches(vehicle: Vehicle) -> list[list[tuple[np.ndarray, str]]]:
    """Per face of the body mesh, its zone patches: (polygon (j, 3) m, zone name), each the part of the face
    inside a zone's box when the face's normal is within the zone's cone. Listed last zone first, so that
    drawn in order the first matching zone lies on top (the zone a point belongs to)."""
    mesh = vehicle.mesh
    triangles, normals = mesh.triangles, mesh.face_normals
    low, high = triangles.min(axis=1), triangles.max(axis=1)
    patches: list[list[tuple[np.ndarray, str]]] = [[] for _ in range(len(triangles))]
    for zone in reversed(vehicle.zones):
        facing = normals @ zone.normal >= np.cos(np.deg2rad(zone.cone_deg)) - 1e-12
        overlapping = np.all((high >= zone.min) & (low <= zone.max), axis=1)
        for face in np.flatnonzero(facing & overlapping):
            polygon = _clip_to_box(triangles[face], zone.min, zone.max)
            if len(polygon) >= 3:
                patches[face].append((polygon, zone.name))
    return patches


def _shaded(colours: np.ndarray, normals: np.ndarray, light: np.ndarray) -> np.ndarray:
    shade = 0.55 + 0.45 * np.clip(normals @ light, 0.0, 1.0)
    out = colours.copy()
    out[:, :3] *= shade[:, None]
    return out


def _draw_view(ax, vehicle: Vehicle, patches, legend: dict[str, tuple], axes: tuple[int, int], depth_axis: int,
               towards: float, origin: np.ndarray):
    """Painter's algorithm on the body mesh: faces facing the viewer, drawn far to near, each followed by its
    zone patches, projected on ``axes`` and measured from ``origin`` (3,) m (a point in the vehicle-centre
    frame)."""
    mesh = vehicle.mesh
    facing = np.flatnonzero(mesh.face_normals[:, depth_axis] * towards > 1e-6)
    order = facing[np.argsort(mesh.triangles_center[facing, depth_axis] * towards)]
    polygons, colours, normals = [], [], []
    shift = origin[list(axes)]
    for face in order:
        polygons.append(mesh.triangles[face][:, list(axes)] - shift)
        colours.append((*_BODY_GREY, 1.0))
        normals.append(mesh.face_normals[face])
        for polygon, name in patches[face]:
            polygons.append(polygon[:, list(axes)] - shift)
            colours.append(legend[name])
            normals.append(mesh.face_normals[face])
    light = np.zeros(3)
    light[depth_axis] = towards
    light += np.array([0.3, 0.2, 0.5])
    colour = _shaded(np.array(colours, dtype=float).reshape(-1, 4), np.array(normals).reshape(-1, 3),
                     light / np.linalg.norm(light))
    ax.add_collection(PolyCollection(polygons, facecolors=colour, edgecolors=colour, linewidths=0.2))
    low, high = mesh.bounds[0, list(axes)] - shift, mesh.bounds[1, list(axes)] - shift
    pad = 1.0
    ax.set_xlim(low[0] - pad, high[0] + pad)
    ax.set_ylim(low[1] - pad, high[1] + pad)
    ax.set_aspect("equal")


def _draw_cameras(ax, rig: Rig, axes: tuple[int, int], vertical: bool, origin: np.ndarray):
    """Cameras of ``rig`` (vehicle-centre frame) as dots with their frustum wedge (horizontal FOV in the top
    view, vertical in the side view), measured from ``origin`` (3,) m."""
    for camera in rig.cameras:
        vfov = vertical_fov(camera.fov, *camera.image_size) if camera.lens.is_ideal_pinhole else camera.lens.vfov
        half = np.deg2rad((vfov if vertical else camera.fov) / 2.0)
        spread = np.array([0.0, 0.0, 1.0]) if vertical else np.array([0.0, 1.0, 0.0])
        rays = [camera.rotation @ (np.array([np.cos(a), 0.0, 0.0]) + spread * np.sin(a)) for a in (-half, half)]
        lens = (camera.position - origin)[list(axes)]
        tips = [lens + FRUSTUM_DRAW_LENGTH * r[list(axes)] for r in rays]
        ax.fill([lens[0], tips[0][0], tips[1][0]], [lens[1], tips[0][1], tips[1][1]], color="tab:red", alpha=0.18,
                linewidth=0)
        ax.plot(*lens, "o", color="tab:red", markersize=3)


def vehicle_figure(vehicle: Vehicle, rig: Rig | None = None, datum: ReportDatum = CENTRE_DATUM) -> Figure:
    """Top view (x-y, from above) and side view (x-z, from the left) of ``vehicle``'s body mesh, zones
    coloured (legend beside), with ``rig``'s cameras (placed on the vehicle first when measured from another origin), every
    position measured from ``datum`` (its ``point`` in the vehicle-centre frame; the axes' titles name it)."""
    legend, patches = zone_colours(vehicle), _zone_patches(vehicle)
    figure = Figure(figsize=(12, 8.5), dpi=120, layout="constrained")
    top, side = figure.subplots(2, 1, height_ratios=[vehicle.size[1] + 2, vehicle.size[2] + 2])
    origin = np.asarray(datum.point, dtype=float)
    _draw_view(top, vehicle, patches, legend, (0, 1), 2, 1.0, origin)
    _draw_view(side, vehicle, patches, legend, (0, 2), 1, 1.0, origin)
    if rig is not None:
        placed, _ = to_vehicle_centre(rig, vehicle)
        _draw_cameras(top, placed, (0, 1), False, origin)
        _draw_cameras(side, placed, (0, 2), True, origin)
    title = f"{vehicle.name} ({vehicle.blueprint})" + (f" with rig {rig.name}" if rig is not None else "")
    top.set_title(f"{title}: top view (x forward, y left)\n{datum.frame}")
    side.set_title("side view from the left (x forward, z up)")
    for ax in (top, side):
        ax.set_xlabel(f"x forward (m), {datum.axis_text}")
        ax.grid(alpha=0.3)
    top.set_ylabel("y left (m)")
    side.set_ylabel("z up (m), from the ground")
    handles = [top.scatter([], [], color=c, marker="s", label=n) for n, c in legend.items()]
    if handles:
        figure.legend(handles=handles, loc="outside right center", title="zones", fontsize=8)
    return figure


def write_vehicle_figure(vehicle: Vehicle, path, rig: Rig | None = None, datum: ReportDatum = CENTRE_DATUM) -> Path:
    """:func:`vehicle_figure` as a picture at ``path`` (PNG, or the format its suffix names)."""
    figure = vehicle_figure(vehicle, rig, datum)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path)
    return path
