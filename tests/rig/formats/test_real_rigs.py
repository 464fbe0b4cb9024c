"""The dataset rigs of baselines/rigs/real: each committed rig file is what ``rigopt import`` makes of its source
folder (the commands of baselines/rigs/real/README.md), so neither can drift from the other; and the rigs
hold the datasets' documented camera sets and image sizes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from in_process import run_rigopt

from rigopt.rig.pccr_format import read_rig

REAL = Path(__file__).resolve().parents[3] / "baselines" / "rigs" / "real"

#: dataset: (the import command's arguments after ``rigopt import``, {camera: (width, height)} as documented)
IMPORTS = {
    "nuscenes": (["nuscenes", "nuscenes", "--name", "nuscenes", "--vehicle", "tt"],
                 {c: (1600, 900) for c in ("CAM_FRONT", "CAM_FRONT_LEFT", "CAM_FRONT_RIGHT", "CAM_BACK",
                                           "CAM_BACK_LEFT", "CAM_BACK_RIGHT")}),
    "argoverse2": (["argoverse2", "argoverse2", "--name", "argoverse2", "--vehicle", "etron"],
                   {"ring_front_center": (1550, 2048),
                    **{f"ring_{c}": (2048, 1550) for c in ("front_left", "front_right", "rear_left", "rear_right",
                                                           "side_left", "side_right")}}),
    "waymo": (["waymo", "waymo", "--name", "waymo", "--vehicle", "etron"],
              {"FRONT": (1920, 1280), "FRONT_LEFT": (1920, 1280), "FRONT_RIGHT": (1920, 1280),
               "SIDE_LEFT": (1920, 886), "SIDE_RIGHT": (1920, 886)}),
    "ddad": (["dgp", "ddad", "--name", "ddad", "--vehicle", "etron"],
             {f"CAMERA_0{k}": (1936, 1216) for k in (1, 5, 6, 7, 8, 9)}),
}


@pytest.mark.parametrize("dataset", list(IMPORTS))
def test_committed_rig_is_the_import_of_its_source(dataset, tmp_path):
    args, sizes = IMPORTS[dataset]
    out = tmp_path / f"{dataset}.json"
    result = run_rigopt("import", *args, "--out", out, cwd=REAL)
    assert result.returncode == 0, result.stderr
    fresh, committed = read_rig(out), read_rig(REAL / f"{dataset}.json")
    assert [c.id for c in committed.cameras] == [c.id for c in fresh.cameras] == list(sizes)
    assert (committed.name, committed.vehicle, committed.origin.kind) == (fresh.name, fresh.vehicle, "rear_axle")
    for old, new in zip(committed.cameras, fresh.cameras):
        np.testing.assert_allclose(old.position, new.position, atol=1e-3, err_msg=old.id)
        np.testing.assert_allclose(old.rotation, new.rotation, atol=1e-6, err_msg=old.id)
        assert old.fov == pytest.approx(new.fov, abs=1e-6), old.id
        assert old.image_size == new.image_size == sizes[old.id]


def test_real_rigs_sit_on_the_roof_and_look_level():
    """Every camera of the four rigs is a roof camera (1.45-2.2 m up) looking within 5 deg of level."""
    for dataset in IMPORTS:
        for camera in read_rig(REAL / f"{dataset}.json").cameras:
            assert 1.45 < camera.position[2] < 2.2, (dataset, camera.id)
            assert abs(camera.forward[2]) < np.sin(np.radians(5.0)), (dataset, camera.id)
