"""Coverage measures on the box car with hand-derived expectations: rings, overlaps, self-occlusion, blind
zone, cameras inside the body, comparisons."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rigopt.coverage.measures import camera_coverage, compare_coverage, coverage_report, ring_coverage, ring_report

VHALF_DEG = math.degrees(math.atan(0.5625))  # half the vertical FOV of a 90 deg, 1280 x 720 pinhole


def ring(rings, distance, height):
    (found,) = [r for r in rings if (r.distance_m, r.height_m) == (distance, height)]
    return found


# --- two cameras with a known overlap ------------------------------------------------------------------------
#
# Both cameras sit at (0, 0, 3), above the footprint's centre and 1.5 m over the roof, looking level. Seen
# from the centre, a ring point at azimuth a lies in the direction a from the cameras, so camera k (yaw y_k,
# FOV f) sees the azimuths |a - y_k| <= f / 2 (the ring at 0.8 m is 2.2 m below, i.e. 2.5 deg down at 50 m,
# well within the vertical FOV, and the rays pass 1.4 m or more over the roof). The two views overlap on
# [yaw - f / 2, -yaw + f / 2] for yaws +-yaw: f - 2 yaw degrees (or none), and together cover 2 f minus that.

@pytest.mark.parametrize(("fov", "yaw"), [(90.0, 30.0), (90.0, 40.0), (100.0, 20.0), (60.0, 45.0)])
def test_two_cameras_overlap(box_vehicle, box_footprint, small_settings, camera, rig, fov, yaw):
    settings = dataclasses.replace(small_settings, ring_samples=360, overlap_ring=(50.0, 0.8))
    left = camera((0, 0, 3), yaw_deg=yaw, fov=fov, id="LEFT")
    right = camera((0, 0, 3), yaw_deg=-yaw, fov=fov, id="RIGHT")
    pair = rig(left, right)
    sample = 360.0 / settings.ring_samples
    overlap = max(fov - 2 * yaw, 0.0)
    union = 2 * fov - overlap
    per_camera = {c.id: c for c in camera_coverage(box_vehicle, pair, settings, box_footprint)}
    if overlap > 0:
        assert per_camera["LEFT"].overlap_deg["RIGHT"] == pytest.approx(overlap, abs=2 * sample)
        assert per_camera["RIGHT"].overlap_deg["LEFT"] == pytest.approx(overlap, abs=2 * sample)
    else:
        assert per_camera["LEFT"].overlap_deg == {} and per_camera["RIGHT"].overlap_deg == {}
    far = ring(ring_coverage(box_vehicle, pair, settings, box_footprint), 50.0, 0.8)
    assert far.overlap2_frac == pytest.approx(overlap / 360, abs=2 * sample / 360)
    assert far.covered_frac == pytest.approx(union / 360, abs=2 * sample / 360)
    assert far.counts.max() == (2 if overlap > 0 else 1)


# --- one forward camera on the front of the box -------------------------------------------------------------

@pytest.fixture(scope="module")
def forward_report(box_vehicle, small_settings, camera, rig):
    return coverage_report(rig(camera((2.05, 0, 1.0), id="FRONT"), name="front"), box_vehicle, small_settings)


def test_forward_camera_far_ring(forward_report, small_settings):
    far = ring(forward_report.rings, 50.0, 0.8)
    sample = 1 / small_settings.ring_samples
    # Roughly FOV / 360: the camera is 2.05 m ahead of the centre, which narrows the seen azimuths (seen from
    # the centre) by at most 2 asin(2.05 / 50) = 4.7 deg.
    assert far.covered_frac == pytest.approx(90 / 360, abs=4.7 / 360 + sample)
    # Exactly: a ring point (x, y, 0.8) is seen when |atan2(y, x - 2.05)| <= 45 deg (nothing in between,
    # and 0.2 m below the lens is well inside the vertical FOV at x >= 50 m).
    points = forward_report.footprint.ring_points(far.azimuths, 50.0, 0.8)
    expected = np.abs(np.degrees(np.arctan2(points[:, 1], points[:, 0] - 2.05))) <= 45.0
    assert np.sum((far.counts >= 1) != expected) <= 1
    assert far.overlap2_frac == 0.0
    assert forward_report.cameras_inside == ()


def test_forward_camera_bev(forward_report):
    bev = forward_report.bev
    xx, yy = np.meshgrid(bev.x, bev.y)
    inside = (np.abs(xx) < 2) & (np.abs(yy) < 1)
    np.testing.assert_array_equal(bev.counts == -1, inside)
    # Cells well in front (inside the 45-deg wedge, 0.2 m below the lens) are seen; cells behind are not.
    wedge = (xx > 3.0) & (np.abs(yy) < (xx - 2.05) - 0.5)
    assert np.all(bev.counts[wedge] == 1)
    assert np.all(bev.counts[(xx < 2.0) & ~inside] == 0)


# --- cameras inside the body ---------------------------------------------------------------------------------

def test_cameras_inside_are_listed_and_see_nothing(box_vehicle, small_settings, camera, rig):
    inner = camera((0, 0, 0.9), id="INSIDE")
    outer = camera((2.05, 0, 1.0), id="FRONT")
    report = coverage_report(rig(inner, outer), box_vehicle, small_settings)
    assert report.cameras_inside == ("INSIDE",)
    alone = coverage_report(rig(inner), box_vehicle, small_settings)
    assert alone.cameras_inside == ("INSIDE",)
    # Still computed: every ring is there; from inside the closed body every ray meets it.
    assert len(alone.rings) == len(small_settings.ring_distances) * len(small_settings.ring_heights)
    assert all(r.covered_frac == 0.0 for r in alone.rings)
    assert alone.cameras[0].self_occluded_frac == 1.0
    assert np.all(alone.blind.distance_m == np.inf)
    # The inside camera adds nothing to the outside one's rings.
    front = coverage_report(rig(outer), box_vehicle, small_settings)
    for a, b in zip(report.rings, front.rings):
        np.testing.assert_array_equal(a.counts, b.counts)


def test_a_ring_report_is_the_full_reports_rings(box_vehicle, small_settings, camera, rig):
    """What the design report draws from a ring report (rings, footprint, cameras inside) is the full report's."""
    both = rig(camera((0, 0, 0.9), id="INSIDE"), camera((2.05, 0, 1.0), id="FRONT"))
    full, rings = coverage_report(both, box_vehicle, small_settings), ring_report(both, box_vehicle, small_settings)
    assert rings.cameras_inside == full.cameras_inside == ("INSIDE",)
    assert rings.footprint is full.footprint
    assert [(r.distance_m, r.height_m, r.covered_frac) for r in rings.rings] == \
        [(r.distance_m, r.height_m, r.covered_frac) for r in full.rings]
    for a, b in zip(rings.rings, full.rings):
        np.testing.assert_array_equal(a.counts, b.counts)



# --- self-occlusion ------------------------------------------------------------------------------------------

@pytest.mark.parametrize(("position", "yaw", "expected"), [
    # Looking away from the body: nothing of the image shows it (the ground is not part of the body).
    ((2.5, 0, 0.9), 0.0, 0.0),
    # 10 cm from the front face, looking at it: the image's corner rays meet x = 2 at |y| <= 0.1,
    # |z - 0.9| <= 0.056, well inside the face, so the whole image shows the body.
    ((2.1, 0, 0.9), 180.0, 1.0),
    # 0.5 m in front of the face at roof height, looking level at it: rays below the horizon meet the face
    # (|y| <= 0.5, z >= 1.5 - 0.5 * 0.5625), rays above pass over the roof: half the rows of the grid.
    ((2.5, 0, 1.5), 180.0, 0.5),
])
def test_self_occluded_fraction(box_vehicle, box_footprint, small_settings, camera, rig, position, yaw, expected):
    assert small_settings.image_grid[1] % 2 == 0  # no row exactly on the horizon
    (only,) = camera_coverage(box_vehicle, rig(camera(position, yaw_deg=yaw)), small_settings, box_footprint)
    assert only.self_occluded_frac == pytest.approx(expected, abs=1e-12)


def test_self_occlusion_beyond_max_range_does_not_count(box_vehicle, box_footprint, small_settings, camera, rig):
    settings = dataclasses.replace(small_settings, max_range=0.05)
    (only,) = camera_coverage(box_vehicle, rig(camera((2.1, 0, 0.9), yaw_deg=180.0)), settings, box_footprint)
    assert only.self_occluded_frac == 0.0  # the face is 0.1 m away


# --- blind zone ----------------------------------------------------------------------------------------------
#
# A camera at (2.2, 0, 1.0), 0.2 m in front of the bumper, pitched 45 deg down: it sees the ground straight
# ahead at depression angles down to 45 + VHALF = 74.36 deg, i.e. from 1.0 / tan(74.36 deg) = 0.28 m ahead of
# the lens: 0.48 m from the footprint. blind_azimuths = 45 (odd) puts a sample at azimuth 0, whose ring
# points are (2 + d, 0, 0).

def test_blind_zone_of_a_camera_looking_down(box_vehicle, small_settings, camera, rig):
    settings = small_settings
    assert settings.blind_azimuths % 2 == 1
    report = coverage_report(rig(camera((2.2, 0, 1.0), pitch_deg=-45.0, id="DOWN")), box_vehicle, settings)
    blind = report.blind
    degrees = np.degrees(blind.azimuths)
    ahead = int(np.argmin(np.abs(degrees)))
    assert degrees[ahead] == pytest.approx(0.0, abs=1e-9)
    first = 0.2 + 1.0 / math.tan(math.radians(45.0 + VHALF_DEG))
    assert first == pytest.approx(0.48, abs=0.01)
    step = settings.blind_cell / 2
    assert first <= blind.distance_m[ahead] < first + step
    assert np.all(np.isfinite(blind.distance_m[np.abs(degrees) <= 20]))
    assert np.all(np.isinf(blind.distance_m[np.abs(degrees) >= 90]))
    # Unseen area: positive, and below the whole band within blind_radius of the rectangle
    # (2 r (4 + 2) + pi r^2).
    band = 2 * settings.blind_radius * 6.0 + math.pi * settings.blind_radius**2
    assert 0 < blind.area_m2 < band


def test_blind_zone_is_infinite_when_no_camera_sees_the_ground(box_vehicle, small_settings, camera, rig):
    # Looking 50 deg up: the lowest ray climbs at 50 - 29.36 = 20.6 deg.
    report = coverage_report(rig(camera((2.2, 0, 1.0), pitch_deg=50.0, id="UP")), box_vehicle, small_settings)
    assert np.all(np.isinf(report.blind.distance_m))
    # Then the unseen area is the whole band (up to the cell discretisation).
    r = small_settings.blind_radius
    assert report.blind.area_m2 == pytest.approx(2 * r * 6.0 + math.pi * r**2, rel=0.03)


# --- comparisons ---------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def two_reports(box_vehicle, small_settings, camera, rig):
    front = camera((2.05, 0, 1.0), id="FRONT")
    rear = camera((-2.05, 0, 1.0), yaw_deg=180.0, pitch_deg=-20.0, id="REAR")
    a = coverage_report(rig(front, name="a"), box_vehicle, small_settings)
    b = coverage_report(rig(front, rear, name="b"), box_vehicle, small_settings)
    return a, b


def test_compare_with_itself_is_zero(two_reports):
    a, _ = two_reports
    comparison = compare_coverage(a, a)
    assert len(comparison.rings) == len(a.rings)
    for r in comparison.rings:
        assert r.covered_diff == 0.0 and r.overlap2_diff == 0.0
        np.testing.assert_array_equal(r.sector_diff, 0.0)
    assert comparison.blind_area_diff_m2 == 0.0


def test_adding_a_camera_never_loses_coverage(two_reports, small_settings):
    a, b = two_reports
    comparison = compare_coverage(a, b)
    assert (comparison.a, comparison.b) == ("a", "b")
    for r in comparison.rings:
        assert r.covered_diff >= 0.0 and r.overlap2_diff >= 0.0
        assert r.sector_diff.shape == (small_settings.sectors,)
        assert np.all(r.sector_diff >= 0.0)
    # The rear camera sees the far ring behind: a strict gain there, and the blind area shrinks.
    far = [r for r in comparison.rings if (r.distance_m, r.height_m) == (50.0, 0.8)][0]
    assert far.covered_diff > 0.2
    assert comparison.blind_area_diff_m2 < 0.0


def test_compare_differences_are_b_minus_a(two_reports):
    a, b = two_reports
    for diff, ra, rb in zip(compare_coverage(a, b).rings, a.rings, b.rings):
        assert diff.covered_diff == pytest.approx(rb.covered_frac - ra.covered_frac)
        np.testing.assert_allclose(diff.sector_diff, rb.sector_covered(36) - ra.sector_covered(36))
    reverse = compare_coverage(b, a)
    assert all(r.covered_diff <= 0 for r in reverse.rings)


def test_sector_covered_by_hand():
    from rigopt.coverage.measures import RingCoverage
    azimuths = -np.pi + (np.arange(8) + 0.5) * (2 * np.pi / 8)
    counts = np.array([0, 1, 2, 0, 0, 0, 1, 1])
    ring_ = RingCoverage(1.0, 0.0, 0.5, 0.125, azimuths, counts)
    np.testing.assert_allclose(ring_.sector_covered(4), [0.5, 0.5, 0.0, 1.0])
    np.testing.assert_allclose(ring_.sector_covered(2), [0.5, 0.5])
