"""``rigopt vehicle show`` names the body features the mount rules read (``Vehicle.body_features``)."""

from __future__ import annotations

from in_process import run_rigopt

from rigopt.vehicle.library import load_vehicle


def test_vehicle_show_names_the_body_features_the_mount_rules_read_in_the_reports_frame(tmp_path):
    """The hgv's mirror zone, steps, hinged cab door, wiped windscreen, tilt cab and trailer keep-out, each box
    measured from the ground below the rear axle (the mirror zone's spec box starts at x 3.1 m from the centre)."""
    hgv = load_vehicle("hgv")
    result = run_rigopt("vehicle", "show", "hgv", "--out", tmp_path / "hgv.png")
    assert result.returncode == 0, result.stderr
    kinds = [row["kind"] for row in hgv.body_features()]
    assert kinds == ["mirror zone", "step", "step", "mud_flap", "door", "wiped area", "tilt cab", "keep-out"]
    flat = " ".join(result.stdout.split())  # the table's title wraps
    for text in ("cab entry step", "catwalk", "mud flap", "hinged front", "on zone windshield_front", "tilts up to 65 deg",
                 "a coupled semi-trailer", "below the rear axle"):
        assert text in flat, text
    mirror = next(r for r in hgv.body_features() if r["kind"] == "mirror zone")
    x = mirror["min"][0] - hgv.rear_axle[0]
    assert f"{x:.2f}, {mirror['min'][1]:.2f}, {mirror['min'][2]:.2f}" in result.stdout
    assert abs(x - 3.1) > 1.0  # not the vehicle-centre frame's
