"""``rigopt bench show``: the picture of a sample is written at the size its camera count gives, with the
sample's boxes drawn (in the camera tiles and the bird's-eye panel); and the projection it draws with.

Data: one mini scene of one frame under R5 (4 cameras, one row of tiles) and R1 (8 cameras, two rows),
64 x 36 pixels, rendered without the ego body. "Boxes drawn" is measured against the same sample drawn
with its boxes removed: the pixels in the class colours of the boxes come from the boxes.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from matplotlib import colormaps
from PIL import Image
from typer.testing import CliRunner

from rigopt.validation.synthetic.dataset import read_dataset
from rigopt.cli.app import app
from rigopt.report.bench_figures import project, write_sample_figure

DPI = 110  # write_sample_figure's


@pytest.fixture(scope="module")
def bench_data(tmp_path_factory):
    from rigopt.validation.synthetic.generate import generate_split
    from rigopt.validation.synthetic.render import render_rig
    from rigopt.validation.synthetic.scenes import split_scenes
    from rigopt.rig.library import load_rig

    out = tmp_path_factory.mktemp("bench_show")
    generate_split([load_rig("R5"), load_rig("R1")], split_scenes("mini", 1, 1), out, (64, 36), render_rig,
                   lambda rig: None)
    return out


def show(data, rig: str, out) -> np.ndarray:
    result = CliRunner().invoke(app, ["bench", "show", str(data), "--rig", rig, "--sample", "0", "--out", str(out)])
    assert result.exit_code == 0, (result.output, result.exception)
    return np.asarray(Image.open(out).convert("RGB")).astype(int)


def class_colour_pixels(image: np.ndarray, classes, tolerance: float = 25.0) -> np.ndarray:
    """(h, w) bool: pixels within ``tolerance`` (RGB 0-255) of the drawing colour of any of ``classes``."""
    palette = colormaps["tab10"]
    near = np.zeros(image.shape[:2], dtype=bool)
    for cls in set(int(c) for c in classes):
        colour = np.array(palette(cls % 10)[:3]) * 255
        near |= np.linalg.norm(image - colour, axis=2) <= tolerance
    return near


@pytest.mark.slow
@pytest.mark.parametrize("rig, cameras, size_inches", [("R5", 4, (4 * 4 + 5, 2.6 * 1 + 1)),
                                                      ("R1", 8, (4 * 4 + 5, 2.6 * 2 + 1))])
def test_the_picture_has_the_size_of_its_tiles(bench_data, tmp_path, rig, cameras, size_inches):
    sample = read_dataset(bench_data / rig / "mini")[0]
    assert len(sample.images) == cameras
    image = show(bench_data, rig, tmp_path / f"{rig}.png")
    assert image.shape[:2] == (round(size_inches[1] * DPI), round(size_inches[0] * DPI))


def test_the_boxes_are_drawn_in_the_tiles_and_from_above(bench_data, tmp_path):
    sample = read_dataset(bench_data / "R5" / "mini")[0]
    assert len(sample.classes) >= 3  # the scene has boxes around the ego
    drawn = show(bench_data, "R5", tmp_path / "with.png")
    empty = dataclasses.replace(sample, centers=np.zeros((0, 3)), sizes=np.zeros((0, 3)), yaws=np.zeros(0),
                                classes=np.zeros(0, dtype=int), visible_fractions=np.zeros(0))
    bare = np.asarray(Image.open(write_sample_figure(empty, tmp_path / "without.png")).convert("RGB")).astype(int)
    assert bare.shape == drawn.shape
    width = drawn.shape[1]
    tiles, overhead = slice(0, width * 4 // 6), slice(width * 4 // 6, width)  # 4 tile columns, then 2 for the view
    coloured = [c for c in sample.classes if c != 7]  # tab10's 7 (traffic signs) is the axes' and grid's grey
    with_boxes, without = class_colour_pixels(drawn, coloured), class_colour_pixels(bare, coloured)
    assert with_boxes[:, overhead].sum() > 100 and without[:, overhead].sum() < 20
    assert with_boxes[:, tiles].sum() > without[:, tiles].sum() + 100


def test_a_point_on_the_optical_axis_lands_on_the_principal_point():
    intrinsics = np.array([[200.0, 0.0, 320.0], [0.0, 200.0, 180.0], [0.0, 0.0, 1.0]])
    T_ego_cam = np.eye(4)
    T_ego_cam[:3, :3] = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])  # optical z -> ego x
    T_ego_cam[:3, 3] = [1.5, 0.0, 1.2]
    points = np.array([[11.5, 0.0, 1.2], [11.5, 1.0, 1.2], [-5.0, 0.0, 1.2]])  # ahead, ahead and left, behind
    pixels, front = project(points, T_ego_cam, intrinsics)
    assert pixels[0] == pytest.approx([320.0, 180.0])
    assert pixels[1] == pytest.approx([320.0 - 200.0 * 1.0 / 10.0, 180.0])  # left of the axis: smaller u
    assert front.tolist() == [True, True, False]
