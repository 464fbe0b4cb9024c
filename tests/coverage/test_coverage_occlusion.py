"""What blocks a view in coverage: the body, a solid, wherever the lens stands (right on its skin, facing into it),
and the keep-outs in force that occlude, a coupled trailer (lifted by name).

The box car (conftest): x in [-2, 2], y in [-1, 1], z in [0.3, 1.5] m; its left side is the plane y = 1.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rigopt.camera import CameraModel, Lens
from rigopt.coverage.measures import CoverageSettings, camera_coverage, ring_report
from rigopt.coverage.visibility import occluders, visible_by
from rigopt.geometry import rotation_from_yaw_pitch_roll
from rigopt.rig.library import load_rig
from rigopt.rig.model import Camera, Rig
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.placement import rig_on_vehicle

#: A 190-degree surround-view fisheye, equidistant: theta = r / f, 95 deg at the image's side edges.
FISHEYE_190 = Lens(1280, 800, 640 / np.radians(95.0), 640 / np.radians(95.0), 640.0, 400.0, "fisheye",
                   (0.0, 0.0, 0.0, 0.0))
LEFT = rotation_from_yaw_pitch_roll(np.pi / 2, 0.0, 0.0)  # facing +y, out of the left side


@pytest.mark.parametrize("backend", ["auto", "triangle"])
@pytest.mark.parametrize("off", [0.0, 0.03])
def test_a_flush_fisheye_sees_out_and_not_through_the_body(box_vehicle, backend, off):
    """A 190-degree fisheye on the left side (``off`` m out; 0: flush on the skin) sees beside the front corner
    (2.5, 1.05) and the ground out to the left; the point (2.5, 0.95), 91 deg off its axis and in its image, lies
    behind the side's plane: the body hides it."""
    lens = np.array([[0.0, 1.0 + off, 0.9]])
    points = np.array([[2.5, 1.05, 0.9], [0.0, 3.0, 0.0], [2.5, 0.95, 0.9]])
    model = CameraModel.of_lens(FISHEYE_190)
    assert model.in_view((points - lens) @ LEFT).all()
    seen = visible_by(box_vehicle.caster(backend), CameraModel.of_lenses([FISHEYE_190]), lens, LEFT[None], points)
    assert seen[0].tolist() == [True, True, False]


@pytest.mark.parametrize("backend", ["auto", "triangle"])
def test_a_flush_fisheye_is_self_occluded_beyond_its_lens_plane(box_vehicle, rig, small_settings, backend):
    """Flush on the flat side, its image shows the body exactly where its pixel rays point behind the side's
    plane (more than 90 deg off its axis; the box is convex, so no ray in front of it meets the body)."""
    fisheye = Camera("FISH", np.array([0.0, 1.0, 0.9]), LEFT, FISHEYE_190)
    rays = CameraModel.of_lens(FISHEYE_190).grid_rays(small_settings.image_grid)
    assert np.abs(rays[:, 0]).min() > 1e-3  # no ray along the plane
    expected = float(np.mean(rays[:, 0] < 0))
    assert 0.0 < expected < 0.2
    settings = replace(small_settings, backend=backend)
    got = camera_coverage(box_vehicle, rig(fisheye), settings, box_vehicle.footprint)[0].self_occluded_frac
    assert got == expected


def test_cameras_turned_into_the_etron_see_nothing_past_it():
    """R1 with every camera turned 180 deg (CAM_SIDE_RIGHT 0.5 cm off the skin): each image is all body, and no
    camera sees a point of the rings at 5 m and beyond."""
    r1 = load_rig("R1")
    turn = rotation_from_yaw_pitch_roll(np.pi, 0.0, 0.0)
    inward = Rig("R1_inward", r1.vehicle, tuple(replace(c, rotation=c.rotation @ turn) for c in r1.cameras))
    placed, etron, _ = rig_on_vehicle(inward, None)
    settings = CoverageSettings(ring_distances=(5.0, 10.0, 20.0), ring_samples=120, image_grid=(16, 9),
                                overlap_ring=(5.0, 0.8))
    assert all(ring.counts.sum() == 0 for ring in ring_report(placed, etron, settings).rings)
    shares = [c.self_occluded_frac for c in camera_coverage(etron, placed, settings, etron.footprint)]
    assert shares == [1.0] * 8


# --- a coupled trailer ------------------------------------------------------------------------------------------

MAST = np.array([[3.0, 0.0, 5.0]])  # above the hgv's cab, looking back 10 deg down
BACK_DOWN = rotation_from_yaw_pitch_roll(np.pi, np.deg2rad(-10.0), 0.0)[None]
BEHIND_TRAILER = np.array([[-20.0, 0.0, 1.0]])  # the segment dips into the trailer box behind the cab


@pytest.fixture(scope="module")
def hgv():
    return load_vehicle("hgv")


def test_a_ray_through_the_hgv_s_trailer_is_blocked(hgv):
    model = CameraModel.from_fov([90.0], [[1280, 720]])
    assert hgv.ray_caster.segments_clear(MAST, BEHIND_TRAILER).all()  # the body alone does not block it
    assert [label for *_, label in occluders(hgv)] == ["trailer (a coupled semi-trailer)"]
    assert not visible_by(hgv.ray_caster, model, MAST, BACK_DOWN, BEHIND_TRAILER, boxes=occluders(hgv)).any()
    assert visible_by(hgv.ray_caster, model, MAST, BACK_DOWN, BEHIND_TRAILER,
                      boxes=occluders(hgv, ("trailer",))).all()


def test_coverage_counts_the_coupled_trailer_unless_lifted(hgv):
    """By default the trailer hides what lies in and behind it: no ring point inside its box is seen."""
    rig = Rig("mast", hgv.spec.blueprint, (Camera.pinhole("CAM_MAST", MAST[0], BACK_DOWN[0], 90.0),))
    settings = CoverageSettings(ring_distances=(5.0,), ring_heights=(0.8,), ring_samples=180)
    (coupled,) = ring_report(rig, hgv, settings).rings
    (solo,) = ring_report(rig, hgv, replace(settings, lifted=("trailer",))).rings
    points = hgv.footprint.ring_points(coupled.azimuths, 5.0, 0.8)
    (low, high, _), = occluders(hgv)
    in_trailer = np.all((points >= low) & (points <= high), axis=1)
    assert in_trailer.any() and coupled.counts[in_trailer].sum() == 0 and solo.counts[in_trailer].sum() > 0
    assert 0.0 < coupled.covered_frac < solo.covered_frac


def test_the_packaging_sheet_gives_the_share_of_the_image_the_trailer_blocks(hgv):
    """The mast camera looks back over the coupled trailer: part of its image is the trailer's box (the body's
    share unchanged), none once the trailer is lifted; a camera looking forward sees no trailer."""
    from rigopt.coverage.packaging import camera_packaging

    mast = Camera.pinhole("CAM_MAST", MAST[0], BACK_DOWN[0], 90.0)
    ahead = Camera.pinhole("CAM_AHEAD", MAST[0], rotation_from_yaw_pitch_roll(0.0, np.deg2rad(-10.0), 0.0), 90.0)
    coupled, solo = camera_packaging(mast, hgv), camera_packaging(mast, hgv, lifted=("trailer",))
    (label, share), = coupled.keep_out_blocked
    assert label == "trailer (a coupled semi-trailer)" and 0.3 < share < 1.0
    assert solo.keep_out_blocked == () and solo.blocked_frac == coupled.blocked_frac
    assert dict(camera_packaging(ahead, hgv).keep_out_blocked) == {label: 0.0}
    assert coupled.to_dict()["blocked_by_keep_outs"] == {label: share}
