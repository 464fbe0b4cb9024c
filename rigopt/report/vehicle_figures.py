"""Pictures of a vehicle: top and side views with its zones coloured and, optionally, a rig's cameras."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from rigopt.camera import vertical_fov
from rigopt.rig.model import Rig
from rigopt.vehicle.model import Vehicle

#: Length (m) of the frustum wedges drawn for cameras.
FRUSTUM_DRAW_LENGTH = 1.2
_BODY_GREY = (0.78, 0.78, 0.80)


def _face_colours(vehicle: Vehicle) -> tuple[np.ndarray, dict[str, tuple]]:
    """(F, 4) RGBA per face: its zone's colour, grey outside every zone; and the legend of zone colours."""
    from matplotlib import colormaps

    mesh = vehicle.fine_mesh
    names = sorted({z.name for z in vehicle.zones})
    palette = colormaps["tab20"]
    legend = {name: palette(k % 20) for k, name in enumerate(names)}
    colours = np.tile((*_BODY_GREY, 1.0), (len(mesh.faces), 1))
    for k, name in enumerate(vehicle.fine_face_zones):
        if name is not None:
            colours[k] = legend[name]
    return colours, legend


def _shaded(colours: np.ndarray, normals: np.ndarray, light: np.ndarray) -> np.ndarray:
    shade = 0.55 + 0.45 * np.clip(normals @ light, 0.0, 1.0)
    out = colours.copy()
    out[:, :3] *= shade[:, None]
    return out


def _draw_view(ax, vehicle: Vehicle, colours, axes: tuple[int, int], depth_axis: int, towards: float):
    """Painter's algorithm: faces facing the viewer, drawn far to near, projected on ``axes``."""
    mesh = vehicle.fine_mesh
    facing = mesh.face_normals[:, depth_axis] * towards > 1e-6
    order = np.argsort(mesh.triangles_center[facing, depth_axis] * towards)
    triangles = mesh.triangles[facing][order][:, :, list(axes)]
    light = np.zeros(3)
    light[depth_axis] = towards
    light += np.array([0.3, 0.2, 0.5])
    colour = _shaded(colours[facing][order], mesh.face_normals[facing][order], light / np.linalg.norm(light))
    ax.add_collection(PolyCollection(triangles, facecolors=colour, edgecolors=colour, linewidths=0.2))
    low, high = mesh.bounds[0, list(axes)], mesh.bounds[1, list(axes)]
    pad = 1.0
    ax.set_xlim(low[0] - pad, high[0] + pad)
    ax.set_ylim(low[1] - pad, high[1] + pad)
    ax.set_aspect("equal")


def _draw_cameras(ax, rig: Rig, axes: tuple[int, int], vertical: bool):
    """Cameras as dots with their frustum wedge (horizontal FOV in the top view, vertical in the side view)."""
    for camera in rig.cameras:
        half = np.deg2rad((vertical_fov(camera.fov, *camera.image_size) if vertical else camera.fov) / 2.0)
        spread = np.array([0.0, 0.0, 1.0]) if vertical else np.array([0.0, 1.0, 0.0])
        rays = [camera.rotation @ (np.array([np.cos(a), 0.0, 0.0]) + spread * np.sin(a)) for a in (-half, half)]
        origin = camera.position[list(axes)]
        tips = [origin + FRUSTUM_DRAW_LENGTH * r[list(axes)] for r in rays]
        ax.fill([origin[0], tips[0][0], tips[1][0]], [origin[1], tips[0][1], tips[1][1]], color="tab:red", alpha=0.18,
                linewidth=0)
        ax.plot(*origin, "o", color="tab:red", markersize=3)


def write_vehicle_figure(vehicle: Vehicle, path, rig: Rig | None = None) -> Path:
    """Top view (x-y, from above) and side view (x-z, from the left) of ``vehicle``; PNG at ``path``."""
    colours, legend = _face_colours(vehicle)
    figure = Figure(figsize=(12, 8.5), dpi=120, layout="constrained")
    top, side = figure.subplots(2, 1, height_ratios=[vehicle.size[1] + 2, vehicle.size[2] + 2])
    _draw_view(top, vehicle, colours, (0, 1), 2, 1.0)
    _draw_view(side, vehicle, colours, (0, 2), 1, 1.0)
    if rig is not None:
        _draw_cameras(top, rig, (0, 1), vertical=False)
        _draw_cameras(side, rig, (0, 2), vertical=True)
    title = f"{vehicle.name} ({vehicle.blueprint})" + (f" with rig {rig.name}" if rig is not None else "")
    top.set_title(f"{title}: top view (x forward, y left)")
    side.set_title("side view from the left (x forward, z up)")
    for ax in (top, side):
        ax.set_xlabel("x (m)")
        ax.grid(alpha=0.3)
    top.set_ylabel("y (m)")
    side.set_ylabel("z (m)")
    handles = [top.scatter([], [], color=c, marker="s", label=n) for n, c in legend.items()]
    if handles:
        figure.legend(handles=handles, loc="outside right center", title="zones", fontsize=8)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path)
    return path
