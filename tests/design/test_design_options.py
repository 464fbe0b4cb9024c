"""Design options: lens catalogues and ranges, camera counts, and the MILP's node limit."""

import numpy as np
import pytest

from rigopt.cli.design_command import parse_camera_count, parse_fovs
from rigopt.design.selection import select_cameras
from rigopt.design.settings import DesignSettings
from rigopt.errors import RigoptError


def test_a_fov_list_is_a_catalogue_without_range():
    assert parse_fovs("60,65,120") == ((60.0, 65.0, 120.0), None)


def test_a_fov_range_seeds_fovs_every_ten_degrees_and_keeps_the_range():
    fovs, fov_range = parse_fovs("60-100")
    assert fovs == (60.0, 70.0, 80.0, 90.0, 100.0)
    assert fov_range == (60.0, 100.0)


@pytest.mark.parametrize("text", ["0,60", "60,180", "120-60", "abc", "60-200"])
def test_bad_fovs_are_refused(text):
    with pytest.raises(RigoptError, match="--fov"):
        parse_fovs(text)


@pytest.mark.parametrize("text, expected", [(None, None), ("8", (8, 8)), ("6-10", (6, 10))])
def test_camera_counts(text, expected):
    assert parse_camera_count(text) == expected


def test_a_node_limit_reached_before_any_selection_is_a_clear_error(monkeypatch):
    """HiGHS stopping at its node limit with no feasible selection yet (made to happen by a solve that only sets
    that status): one error naming --max-nodes, not an empty design."""
    import cvxpy as cp

    def stopped_at_the_limit(problem, *args, **kwargs):
        problem._status = cp.USER_LIMIT

    monkeypatch.setattr(cp.Problem, "solve", stopped_at_the_limit)
    rng = np.random.default_rng(0)
    cost = rng.uniform(0, 5, (40, 6))
    with pytest.raises(RigoptError, match="--max-nodes"):
        select_cameras(cost, np.ones((40, 5), dtype=bool), np.ones(5, dtype=int), np.arange(40), 6, 0.9)


def _node_limited_problem():
    """A small selection MILP (40 candidates, 6 reference cameras, 30 points each seen once) whose root node is
    not integral (found by trying seeds: seed 5 needs branching)."""
    rng = np.random.default_rng(5)
    cost = rng.uniform(0, 5, (40, 6))
    sees = rng.random((40, 30)) < 0.2
    return cost, sees, np.ones(30, dtype=int), np.arange(40)


@pytest.mark.slow
def test_the_milp_stops_at_its_node_limit_the_same_way_every_time():
    """A work limit, not a clock: the same gap and selection on every run, at any machine load."""
    cost, sees, required, mount = _node_limited_problem()
    runs = [select_cameras(cost, sees, required, mount, 6, 0.9, max_nodes=1) for _ in range(2)]
    assert [r.status for r in runs] == ["node_limit", "node_limit"]
    assert runs[0].gap == runs[1].gap > 1e-4
    assert runs[0].chosen.tolist() == runs[1].chosen.tolist()
    solved = select_cameras(cost, sees, required, mount, 6, 0.9)
    assert solved.status == "optimal" and solved.gap <= 1e-4
    assert solved.objective <= runs[0].objective + 1e-12


def test_a_design_not_proven_best_within_the_node_limit_is_an_error_naming_max_nodes(monkeypatch):
    """The designer refuses an answer the MILP has not proven best (unless --accept-gap asks for one)."""
    from rigopt.design import designer

    cost, sees, required, mount = _node_limited_problem()
    points = np.column_stack([np.arange(40.0), np.zeros(40), np.zeros(40)])  # 1 m apart: no clashes
    settings = DesignSettings(max_nodes=1)
    with pytest.raises(RigoptError, match="--max-nodes") as error:
        designer._best_selection([cost], sees, required, mount, points, (6, 6), 0.9, settings, lambda _: None)
    assert "--accept-gap" in str(error.value)
    boxed = designer._best_selection([cost], sees, required, mount, points, (6, 6), 0.9,
                                     DesignSettings(max_nodes=1, accept_gap=True), lambda _: None)
    assert boxed.status == "node_limit" and boxed.gap > 1e-4  # returned, with its gap

