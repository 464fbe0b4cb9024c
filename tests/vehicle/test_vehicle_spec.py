"""Vehicle spec validation: every malformed spec raises DataError, and the message names the file."""

from __future__ import annotations

import pytest

from rigopt.errors import DataError
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import Box, Prism, Wheels, read_spec

BODY = """
[[solids]]
name = "body"
type = "prism"
side = [[-2, 0.3], [2, 0.3], [2, 1.5], [-2, 1.5]]
plan = [[2, 0], [2, 0.9], [-2, 0.9], [-2, 0]]
"""


def zone(**overrides) -> str:
    values = {"name": '"front"', "min": "[1.9, -1.0, 0.2]", "max": "[2.2, 1.0, 1.6]", "normal": "[1, 0, 0]",
              "cone_deg": "45"}
    values.update(overrides)
    return "\n[[zones]]\n" + "\n".join(f"{k} = {v}" for k, v in values.items()) + "\n"


def assert_data_error(write_spec, text: str, *words: str):
    path = write_spec(text)
    with pytest.raises(DataError) as caught:
        read_spec(path)
    message = str(caught.value)
    assert str(path) in message
    for word in words:
        assert word in message


def test_a_valid_spec_reads(write_spec):
    spec = read_spec(write_spec('name = "car"\nblueprint = "vehicle.test.car"\naliases = ["c"]\n'
                                'box = [4, 1.8, 1.5]\n' + BODY + zone()))
    assert spec.name == "car" and spec.blueprint == "vehicle.test.car" and spec.aliases == ("c",)
    assert isinstance(spec.solids[0], Prism) and spec.zones[0].name == "front"


def test_blueprint_defaults_to_the_name(write_spec):
    assert read_spec(write_spec('name = "car"\n' + BODY)).blueprint == "car"


def test_missing_name(write_spec):
    assert_data_error(write_spec, BODY, "'name'")


def test_no_solids(write_spec):
    assert_data_error(write_spec, 'name = "car"\n' + zone(), "solids")


def test_unknown_solid_type(write_spec):
    assert_data_error(write_spec, 'name = "car"\n[[solids]]\ntype = "sphere"\nradius = 1\n', "sphere")


def test_plan_with_negative_y(write_spec):
    assert_data_error(write_spec, 'name = "car"\n' + BODY.replace("[-2, 0.9], [-2, 0]]", "[-2, 0.9], [-2, -0.5]]"),
                      "plan")


def test_polygon_with_two_points(write_spec):
    assert_data_error(write_spec, 'name = "car"\n' + BODY.replace(
        "side = [[-2, 0.3], [2, 0.3], [2, 1.5], [-2, 1.5]]", "side = [[-2, 0.3], [2, 1.5]]"), "side")


def test_zone_min_not_below_max(write_spec):
    assert_data_error(write_spec, 'name = "car"\n' + BODY + zone(min="[1.9, -1.0, 1.6]"), "min", "max")


def test_zone_zero_normal(write_spec):
    assert_data_error(write_spec, 'name = "car"\n' + BODY + zone(normal="[0, 0, 0]"), "normal")


def test_zone_cone_above_180(write_spec):
    assert_data_error(write_spec, 'name = "car"\n' + BODY + zone(cone_deg="200"), "cone_deg")


def test_zone_cone_of_180_is_allowed(write_spec):
    assert read_spec(write_spec('name = "car"\n' + BODY + zone(cone_deg="180"))).zones[0].cone_deg == 180.0


def test_non_number_box(write_spec):
    assert_data_error(write_spec, 'name = "car"\nbox = ["long", 1.8, 1.5]\n' + BODY, "box")


def test_invalid_toml(write_spec):
    assert_data_error(write_spec, 'name = "car\n' + BODY, "TOML")


def test_unreadable_file(tmp_path):
    missing = tmp_path / "nothing.toml"
    with pytest.raises(DataError, match="nothing.toml"):
        read_spec(missing)


def test_wheels_and_mirrored_box_are_read(write_spec):
    spec = read_spec(write_spec('name = "car"\n' + BODY + """
[[solids]]
type = "wheels"
axles = [1.3, -1.3]
radius = 0.35
width = 0.2
track = 1.6

[[solids]]
type = "box"
center = [0, 1.0, 1.0]
size = [0.2, 0.2, 0.2]
mirrored = true
"""))
    wheels, box = spec.solids[1], spec.solids[2]
    assert isinstance(wheels, Wheels) and wheels.axles == (1.3, -1.3) and wheels.track == 1.6
    assert isinstance(box, Box) and box.mirrored


def test_mirrored_zone_normal_is_made_unit(write_spec):
    spec = read_spec(write_spec('name = "car"\n' + BODY + zone(normal="[2, 0, 2]")))
    assert spec.zones[0].normal == pytest.approx([2**-0.5, 0.0, 2**-0.5])


# --- malformed inputs that must not escape the validation as plain Python errors ---------------------------


def test_zones_not_an_array_of_tables(write_spec):
    assert_data_error(write_spec, 'name = "car"\nzones = 5\n' + BODY, "zones")


def test_polygon_with_a_non_number(write_spec):
    assert_data_error(write_spec, 'name = "car"\n' + BODY.replace("[[-2, 0.3], [2, 0.3]", '[["a", 0.3], [2, 0.3]'),
                      "side")


def test_ragged_polygon(write_spec):
    assert_data_error(write_spec, 'name = "car"\n' + BODY.replace("[[-2, 0.3], [2, 0.3]", "[[-2], [2, 0.3]"), "side")


def test_mirrored_must_be_a_boolean(write_spec):
    assert_data_error(write_spec, 'name = "car"\n' + BODY + zone(mirrored='"false"'), "mirrored")


def test_mesh_solid_with_a_missing_file(write_spec):
    path = write_spec('name = "car"\n[[solids]]\ntype = "mesh"\nfile = "nowhere.ply"\n')
    with pytest.raises(DataError, match="nowhere.ply"):
        Vehicle.from_spec(read_spec(path))
