"""Coverage through real lenses: a camera's lens (not only its FOV) decides what it sees."""

from __future__ import annotations

import numpy as np

from rigopt.camera import CameraModel, Lens
from rigopt.coverage.matrix import coverage_matrix, rig_coverage_matrix
from rigopt.coverage.measures import coverage_report
from rigopt.rig.model import Camera

FISHEYE = Lens(1280, 960, 380.0, 380.0, 640.0, 480.0, "fisheye", (-0.02, 0.003, 0.0, 0.0))
SAME_FOCAL = Lens(1280, 960, 380.0, 380.0, 640.0, 480.0)  # the pinhole of the same intrinsics


def test_a_fisheye_covers_more_than_the_pinhole_of_its_focal_length(box_vehicle, rig, small_settings, camera):
    pose = camera([2.1, 0.0, 1.0])  # on the nose, looking forward
    fisheye = Camera("FISH", pose.position, pose.rotation, FISHEYE)
    pinhole = Camera("PIN", pose.position, pose.rotation, SAME_FOCAL)
    sees = rig_coverage_matrix(rig(pinhole, fisheye), box_vehicle, small_settings).sees
    assert sees[1].sum() > sees[0].sum()
    assert np.all(sees[1] | ~sees[0])  # and everything the pinhole sees
    # the wide fisheye sees sector points behind its lens plane, round the corners of the box
    points = rig_coverage_matrix(rig(fisheye), box_vehicle, small_settings).points
    assert np.any(sees[1] & (points[:, 0] < 2.1))


def test_a_rig_matrix_is_the_candidate_matrix_of_its_lenses(box_vehicle, rig, small_settings, camera):
    pose = camera([0.0, 1.1, 1.0], yaw_deg=90.0)
    cameras = [Camera("FISH", pose.position, pose.rotation, FISHEYE), camera([2.1, 0.0, 1.0], id="P")]
    the_rig = rig(*cameras)
    model = CameraModel.of_cameras(cameras)
    direct = coverage_matrix(box_vehicle, the_rig.positions, the_rig.rotations, settings=small_settings, model=model)
    np.testing.assert_array_equal(rig_coverage_matrix(the_rig, box_vehicle, small_settings).sees, direct.sees)


def test_a_coverage_report_lists_each_cameras_lens(box_vehicle, rig, small_settings, camera):
    pose = camera([2.1, 0.0, 1.0])
    report = coverage_report(rig(Camera("FISH", pose.position, pose.rotation, FISHEYE), pose),
                             box_vehicle, small_settings)
    assert report.cameras[0].lens == FISHEYE
    assert report.cameras[1].lens == Lens.pinhole(90.0, (1280, 720))
    # the fisheye's image grid shows more of the body than the forward pinhole's
    assert report.cameras[0].self_occluded_frac >= report.cameras[1].self_occluded_frac
