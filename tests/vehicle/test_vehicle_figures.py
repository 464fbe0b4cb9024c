"""Vehicle pictures: top and side views written as PNG files, with and without a rig."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.report.vehicle_figures import _clip_to_box, _zone_patches, write_vehicle_figure
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
    rig = Rig("front", "boxcar", (Camera.pinhole("F", np.array([2.03, 0.0, 1.0]), np.eye(3), 60.0),
                                  Camera.pinhole("L", np.array([0.0, 0.93, 1.0]), np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]),
                                         90.0)))
    assert is_png(write_vehicle_figure(box_car, tmp_path / "rig.png", rig))


def test_figure_creates_missing_folders(box_car, tmp_path):
    assert is_png(write_vehicle_figure(box_car, tmp_path / "a" / "b" / "car.png"))


def _area(polygon) -> float:
    """Area (m^2) of a planar polygon (k, 3)."""
    return 0.5 * float(np.linalg.norm(sum(np.cross(polygon[k], polygon[(k + 1) % len(polygon)])
                                          for k in range(len(polygon)))))


def test_zone_patches_cover_exactly_the_zones_of_the_body_mesh(box_car):
    patches = _zone_patches(box_car)
    assert len(patches) == len(box_car.mesh.faces)
    area = {}
    for face in patches:
        for polygon, name in face:
            area[name] = area.get(name, 0.0) + _area(polygon)
    # front: the whole 1.8 x 1.2 m front face; side: both 4 x 1.2 m sides (mirrored); no roof zone.
    assert area == pytest.approx({"front": 1.8 * 1.2, "side": 2 * 4.0 * 1.2})


def test_clip_to_box_keeps_the_part_inside():
    triangle = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    inside = _clip_to_box(triangle, np.array([0.0, 0.0, -1.0]), np.array([1.0, 1.0, 1.0]))
    assert _area(inside) == pytest.approx(1.0)  # the unit square lies wholly below the hypotenuse x + y = 2
    assert len(_clip_to_box(triangle, np.array([3.0, 3.0, -1.0]), np.array([4.0, 4.0, 1.0]))) < 3


def test_the_zone_palette_is_matplotlibs_tab20():
    """The zones' colours come without matplotlib (the 3D view needs no plotting library): still its tab20."""
    from matplotlib import colormaps

    from rigopt.report.palette import TAB20

    palette = colormaps["tab20"]
    assert [tuple(palette(k)) for k in range(20)] == [(*rgb, 1.0) for rgb in TAB20]


def test_no_plotting_library_for_the_reports_tables_and_3d_view():
    import subprocess
    import sys

    code = ("import sys, rigopt.report.design_report, rigopt.report.scene_3d, rigopt.report.design_html, "
            "rigopt.report.coverage_tables; print('matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
