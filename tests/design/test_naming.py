"""Designed cameras are named after where they are mounted and where they look."""

import numpy as np
import pytest

from rigopt.design.naming import look_of, mount_name, unique


@pytest.mark.parametrize("yaw, look", [(0, "FRONT"), (44, "FRONT_LEFT"), (-46, "FRONT_RIGHT"), (90, "LEFT"),
                                       (179, "BACK"), (-179, "BACK"), (-135, "BACK_RIGHT")])
def test_look_is_the_45_degree_sector_of_the_yaw(yaw, look):
    forward = [np.cos(np.radians(yaw)), np.sin(np.radians(yaw)), -0.3]
    assert look_of(forward) == look


def test_names_carry_zone_side_and_look_and_skip_a_side_the_zone_already_says():
    assert mount_name("fender_rear", [-2.0, 1.4, 0.9], [0.0, 1.0, 0.0]) == "CAM_FENDER_REAR_LEFT_TO_LEFT"
    assert mount_name("bumper_front", [3.9, 0.05, 0.7], [1.0, 0.0, 0.0]) == "CAM_BUMPER_FRONT_TO_FRONT"
    assert mount_name("mirror_left", [3.3, 1.5, 2.0], [-1.0, 0.2, 0.0]) == "CAM_MIRROR_LEFT_TO_BACK"
    assert mount_name(None, [0.0, -1.0, 1.0], [0.0, -1.0, 0.0]) == "CAM_BODY_RIGHT_TO_RIGHT"


def test_repeated_names_are_numbered_in_order():
    assert unique(["A", "B", "A", "A"]) == ["A", "B", "A_2", "A_3"]


def test_the_designs_default_image_size_is_the_benchmarks():
    from rigopt.benchmark import BENCHMARK_IMAGE_SIZE
    from rigopt.design.settings import DesignSettings

    assert all(c.lens.image_size == BENCHMARK_IMAGE_SIZE for c in DesignSettings().lenses)
