"""Vehicle pictures: top and side views written as PNG files, with and without a rig."""

from __future__ import annotations

import numpy as np

from rigopt.report.vehicle_figures import write_vehicle_figure
from rigopt.rig.model import Camera, Rig

PNG = b"\x89PNG"


def is_png(path) -> bool:
    data = path.read_bytes()
    return data[:4] == PNG and len(data) > 10_000


def test_figure_without_rig(box_car, tmp_path):
    path = write_vehicle_figure(box_car, tmp_path / "car.png")
    assert path == tmp_path / "car.png"
    assert is_png(path)


def test_figure_with_rig(box_car, tmp_path):
    rig = Rig("front", "boxcar", (Camera("F", np.array([2.03, 0.0, 1.0]), np.eye(3), 60.0),
                                  Camera("L", np.array([0.0, 0.93, 1.0]), np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]),
                                         90.0)))
    assert is_png(write_vehicle_figure(box_car, tmp_path / "rig.png", rig))


def test_figure_creates_missing_folders(box_car, tmp_path):
    assert is_png(write_vehicle_figure(box_car, tmp_path / "a" / "b" / "car.png"))
