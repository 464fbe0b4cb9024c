"""Design options: lens catalogues and ranges, camera counts, and the MILP's time limit."""

import numpy as np
import pytest

from rigopt.cli.design_command import parse_camera_count, parse_lenses
from rigopt.design.selection import select_cameras
from rigopt.errors import RigoptError


def test_a_lens_list_is_a_catalogue_without_range():
    assert parse_lenses("60,65,120") == ((60.0, 65.0, 120.0), None)


def test_a_lens_range_seeds_lenses_every_ten_degrees_and_keeps_the_range():
    lenses, fov_range = parse_lenses("60-100")
    assert lenses == (60.0, 70.0, 80.0, 90.0, 100.0)
    assert fov_range == (60.0, 100.0)


@pytest.mark.parametrize("text", ["0,60", "60,180", "120-60", "abc", "60-200"])
def test_bad_lenses_are_refused(text):
    with pytest.raises(RigoptError, match="--fov"):
        parse_lenses(text)


@pytest.mark.parametrize("text, expected", [(None, None), ("8", (8, 8)), ("6-10", (6, 10))])
def test_camera_counts(text, expected):
    assert parse_camera_count(text) == expected


def test_a_time_limit_too_short_for_any_selection_is_a_clear_error():
    rng = np.random.default_rng(0)
    n, refs = 400, 8
    cost = rng.uniform(0, 5, (n, refs))
    sees = rng.random((n, 200)) < 0.05
    with pytest.raises(RigoptError, match="time limit"):
        select_cameras(cost, sees, np.ones(200, dtype=int), np.arange(n), 8, 0.9, time_limit=0.0)
