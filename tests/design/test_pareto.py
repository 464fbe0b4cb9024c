"""``rigopt design --pareto``: the frontier of hand-made points (hand-derived), and one real sweep on the box
car (a user vehicle under a tmp RIGOPT_HOME) from a two-camera rig: 1-3 cameras x three coverage levels on
a coarse grid (one lens, one pitch, 45 deg yaw steps, 0.5 m spacing), a few seconds.
"""

from __future__ import annotations

import csv
import json
import math

import pytest
from typer.testing import CliRunner

from rigopt.cli.app import app
from rigopt.design.pareto import LEVELS, ParetoPoint, _mark_frontier
from rigopt.rig.pccr_format import write_rig

from box_car import front_and_left_rig, install_user_vehicle

POINT_KEYS = {"n_cameras", "level", "feasible", "predicted_drop", "rigcd", "coverage", "ring_2m_ground",
              "blind_area_m2", "fields", "mounting_cost", "frontier", "reason"}
CRITERIA = ("predicted_drop", "blind_area_m2", "mounting_cost")  # all three: lower is better


def dominates(q: dict, p: dict) -> bool:
    """q is at least as good as p in drop, unseen near-field ground and mounting cost, better in one."""
    return all(q[k] <= p[k] for k in CRITERIA) and any(q[k] < p[k] for k in CRITERIA)


# --- the frontier rule --------------------------------------------------------------------------------


def point(n, level, drop, blind, cost, feasible=True) -> ParetoPoint:
    return ParetoPoint(n, level, feasible, drop, 1.0, 0.9, 0.9, blind, 1.0, cost) if feasible else ParetoPoint(
        n, level, False, reason="infeasible")


def test_the_frontier_of_hand_made_points():
    points = [point(4, "reference", 0.30, 10.0, 4.0),   # A
              point(4, "reference", 0.20, 12.0, 4.0),   # B: less drop, more blind area than A
              point(4, "full", 0.30, 12.0, 4.0),        # C: dominated by A (blind area) and B (drop)
              point(5, "full", 0.20, 10.0, 5.5),        # D: costs more than A for less drop
              point(6, "full", 0.20, 10.0, 6.0),        # E: D at a higher cost: dominated by D
              point(3, "full", 0, 0, 0, feasible=False)]  # never on the frontier
    marked = _mark_frontier(points)
    assert [p.frontier for p in marked] == [True, True, False, True, False, False]
    assert [(p.n_cameras, p.level, p.predicted_drop) for p in marked][:5] == [
        (p.n_cameras, p.level, p.predicted_drop) for p in points][:5]


def test_equal_points_do_not_dominate_each_other():
    twins = [point(4, "reference", 0.3, 10.0, 4.0), point(4, "reference+overlap", 0.3, 10.0, 4.0)]
    assert [p.frontier for p in _mark_frontier(twins)] == [True, True]


# --- one real sweep -----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    """(points as printed by --json, the output folder) of the box car sweep."""
    root = tmp_path_factory.mktemp("pareto")
    install_user_vehicle(root / "home", "paretocar")
    rig_file = write_rig(front_and_left_rig("vehicle.test.paretocar"), root / "boxrig.json")
    out = root / "sweep"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("RIGOPT_HOME", str(root / "home"))
        result = CliRunner().invoke(app, ["design", "--vehicle", "paretocar", "--ref", str(rig_file), "--pareto",
                                          "--cameras", "1-3", "--fov", "100", "--pitch", "0", "--yaw-step", "45",
                                          "--spacing", "0.5", "--json", "--out", str(out)])
    assert result.exit_code == 0, (result.output, result.exception)
    return json.loads(result.stdout), out


@pytest.mark.slow
def test_every_count_and_level_is_one_point_with_the_documented_keys(sweep):
    points, _ = sweep
    assert [(p["n_cameras"], p["level"]) for p in points] == [(n, level) for level in LEVELS for n in (1, 2, 3)]
    for p in points:
        assert set(p) == POINT_KEYS  # the rig itself stays out of the JSON
        assert isinstance(p["feasible"], bool) and isinstance(p["frontier"], bool)


@pytest.mark.slow
def test_feasible_points_have_values_and_infeasible_ones_a_reason(sweep):
    points, _ = sweep
    feasible = [p for p in points if p["feasible"]]
    assert feasible, "the sweep found no feasible design"
    for p in feasible:
        assert p["predicted_drop"] > 0 and p["rigcd"] > 0 and 0 < p["coverage"] <= 1 and p["reason"] == ""
        assert 0 <= p["ring_2m_ground"] <= 1 and p["blind_area_m2"] >= 0 and 0 <= p["fields"] <= 1
        assert p["mounting_cost"] >= p["n_cameras"]  # every camera costs at least an ordinary panel (1)
    for p in points:
        if not p["feasible"]:
            assert p["reason"] and p["predicted_drop"] is None and not p["frontier"]
    # one camera cannot see what the front and left cameras see: infeasible at every level
    assert not any(p["feasible"] for p in points if p["n_cameras"] == 1)


@pytest.mark.slow
def test_the_frontier_is_exactly_the_non_dominated_feasible_points(sweep):
    points, _ = sweep
    feasible = [p for p in points if p["feasible"]]
    frontier = [p for p in feasible if p["frontier"]]
    assert frontier
    for p in feasible:
        assert p["frontier"] == (not any(dominates(q, p) for q in feasible)), p


@pytest.mark.slow
def test_the_table_and_the_picture_are_written(sweep):
    points, out = sweep
    assert sorted(f.name for f in out.iterdir()) == ["pareto.csv", "pareto.png"]
    with (out / "pareto.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == len(points)
    for row, p in zip(rows, points):
        assert (int(row["n_cameras"]), row["level"]) == (p["n_cameras"], p["level"])
        assert row["feasible"] == str(p["feasible"]) and row["frontier"] == str(p["frontier"])
        if p["feasible"]:
            assert math.isclose(float(row["predicted_drop"]), p["predicted_drop"], rel_tol=1e-5)
        else:
            assert row["predicted_drop"] == "nan"
    png = (out / "pareto.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000
