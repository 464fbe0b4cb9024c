"""Design settings: the defaults the command line shows, and the lens rules (catalogue, continuous range)."""

import dataclasses
import inspect

import pytest

from rigopt.design.settings import (DEFAULT_FOVS, DEFAULT_PITCHES_DEG, DEFAULT_YAW_STEP_DEG, RANGE_STEP,
                                    DesignSettings, fov_catalogue, range_fovs)
from rigopt.errors import RigoptError


def test_the_settings_defaults_are_the_named_defaults():
    settings = DesignSettings()
    assert settings.fovs == DEFAULT_FOVS
    # the published design's cameras: the benchmark's 1280 x 720 centred pinholes at those FOVs
    assert all(c.lens.image_size == (1280, 720) and c.lens.is_ideal_pinhole for c in settings.lenses)
    assert settings.pitches_deg == DEFAULT_PITCHES_DEG
    assert settings.yaw_step_deg == DEFAULT_YAW_STEP_DEG


def test_the_design_coverage_rings_and_mount_rules_are_built_per_instance():
    a, b = DesignSettings(), DesignSettings()
    assert a.coverage == b.coverage and a.coverage.ring_distances == (2.0, 5.0, 10.0, 20.0)
    assert a.coverage.sectors == 36
    assert a == b


def test_every_setting_has_its_own_docstring():
    lines = inspect.getsource(DesignSettings).splitlines()
    for field in dataclasses.fields(DesignSettings):
        row = next(k for k, line in enumerate(lines) if line.strip().startswith(f"{field.name}:"))
        assert lines[row + 1].strip().startswith('"""'), f"{field.name} has no docstring"


def test_a_range_seeds_fovs_every_range_step_from_its_low_end():
    assert RANGE_STEP == 10.0
    assert range_fovs(60.0, 100.0) == (60.0, 70.0, 80.0, 90.0, 100.0)
    assert range_fovs(65.0, 100.0) == (65.0, 75.0, 85.0, 95.0)
    assert range_fovs(90.0, 90.0) == (90.0,)


@pytest.mark.parametrize("low, high", [(120.0, 60.0), (0.0, 60.0), (60.0, 180.0)])
def test_bad_ranges_are_refused(low, high):
    with pytest.raises(RigoptError):
        range_fovs(low, high)


def test_a_catalogue_is_checked_and_made_floats():
    assert fov_catalogue([60, 90]) == (60.0, 90.0)
    with pytest.raises(RigoptError, match="180"):
        fov_catalogue([60.0, 180.0])
    with pytest.raises(RigoptError, match="at least one"):
        fov_catalogue([])
