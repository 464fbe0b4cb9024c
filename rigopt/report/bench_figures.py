"""Pictures of a benchmark sample: every camera's image with the projected boxes, and a bird's-eye view."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from rigopt.validation.synthetic.dataset import TrainingSample
from rigopt.validation.synthetic.scene_model import CLASSES, Boxes

#: Edges of a box over the corner order of ``ego_corners`` (bottom four, then top four).
_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)]


def ego_corners(sample: TrainingSample) -> np.ndarray:
    """(n, 8, 3) float: the sample's box corners in the ego frame (bottom four, then top four), metres."""
    n = len(sample.classes)
    return Boxes(sample.centers, sample.sizes, sample.yaws, sample.classes, np.arange(n)).corners()


def project(points_ego: np.ndarray, T_ego_cam: np.ndarray, intrinsics: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixels (..., 2) of ego-frame points (..., 3) in a camera (optical frame -> ego ``T_ego_cam``, K), and
    (...,) bool: in front of the camera."""
    T_cam_ego = np.linalg.inv(T_ego_cam)
    optical = points_ego @ T_cam_ego[:3, :3].T + T_cam_ego[:3, 3]
    z = optical[..., 2]
    pixels = optical @ intrinsics.T
    return pixels[..., :2] / np.where(np.abs(z) > 1e-9, z, 1e-9)[..., None], z > 0.1


def write_sample_figure(sample: TrainingSample, path, title: str = "") -> Path:
    """Tile the sample's camera images with the boxes the rig sees drawn in, beside a bird's-eye view of
    every annotated box (dotted: no camera of the rig sees it)."""
    from matplotlib import colormaps
    from PIL import Image

    channels = sorted(sample.images)
    columns = min(4, len(channels))
    rows = int(np.ceil(len(channels) / columns))
    figure = Figure(figsize=(4 * columns + 5, 2.6 * rows + 1), dpi=110, layout="constrained")
    grid = figure.add_gridspec(rows, columns + 2)
    colours = colormaps["tab10"]
    corners = ego_corners(sample)
    seen = sample.visible
    for k, channel in enumerate(channels):
        ax = figure.add_subplot(grid[k // columns, k % columns])
        image = np.asarray(Image.open(sample.images[channel]))
        ax.imshow(image)
        pixels, front = project(corners, sample.T_ego_cam[channel], sample.intrinsics[channel])
        for box in np.flatnonzero(seen):
            cls = sample.classes[box]
            for a, b in _EDGES:
                if front[box, a] and front[box, b]:
                    ax.plot(pixels[box, [a, b], 0], pixels[box, [a, b], 1], color=colours(cls % 10), linewidth=0.8)
        ax.set_xlim(0, image.shape[1])
        ax.set_ylim(image.shape[0], 0)
        ax.set_title(channel, fontsize=8)
        ax.axis("off")
    bev = figure.add_subplot(grid[:, columns:])
    for box, cls in enumerate(sample.classes):
        outline = corners[box, [0, 1, 2, 3, 0]]
        bev.plot(-outline[:, 1], outline[:, 0], color=colours(cls % 10), linewidth=1,
                 linestyle="-" if seen[box] else ":")
    bev.plot([0], [0], marker="^", color="black", markersize=8)
    for cls in sorted(set(sample.classes.tolist())):
        bev.plot([], [], color=colours(cls % 10), label=CLASSES[cls])
    bev.set_aspect("equal")
    bev.set_xlabel("-y (m, right)")
    bev.set_ylabel("x (m, forward)")
    bev.grid(alpha=0.3)
    if len(sample.classes):
        bev.legend(fontsize=7, loc="upper right")
    bev.set_title("boxes, ego frame (ego at the triangle; dotted: unseen)", fontsize=9)
    figure.suptitle(title or f"{sample.scene} sample {sample.token[:8]}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path)
    return path
