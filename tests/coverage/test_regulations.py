"""Regulation presets (rigopt/coverage/regulations.py): where each field lies against the body, the points
checked, the coverage a rig gets, ``--require`` parsing, vehicle categories and ``rigopt coverage --require``.

Geometry on the built-in firetruck (its footprint's bounds give the lines every field is placed against);
coverage on the box car of tests/coverage/conftest.py (x in [-2, 2], y in [-1, 1], z in [0.3, 1.5] m).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import shapely

from rigopt.vehicle.footprint import Footprint
from rigopt.coverage.regulations import (
    CATEGORY_DEFAULTS,
    EYE_SETBACK,
    NEAR_BODY_CLEARANCE,
    PRESETS,
    default_presets,
    parse_require,
    region_coverage,
    required_mask,
)
from rigopt.errors import DataError, RigoptError
from rigopt.rig.model import Rig
from rigopt.rig.pccr_format import write_rig
from rigopt.vehicle.library import find_spec, load_vehicle
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import CATEGORIES, read_spec, spec_from_dict

from box_car import install_user_vehicle
from in_process import run_rigopt

TOL = 1e-6


@pytest.fixture(scope="module")
def firetruck() -> Vehicle:
    return load_vehicle("firetruck")


@pytest.fixture(scope="module")
def lines(firetruck):
    """front, rear, left, right (m) of the firetruck's footprint, and its driver's eye x."""
    (rear, right, _), (front, left, _) = firetruck.mesh.bounds
    return {"front": front, "rear": rear, "left": left, "right": right, "eye": front - EYE_SETBACK["heavy"]}


def _inside(polygon, x, y) -> bool:
    return bool(polygon.contains(shapely.Point(x, y)))


def test_every_preset_checks_the_ground_and_0_8_m_and_r158_its_own_object():
    for preset in PRESETS.values():
        assert {0.0, 0.8} <= set(preset.heights), preset.key
        assert preset.title and preset.source
    assert PRESETS["r158"].heights == (0.0, 0.4, 0.8)  # R158's object is 0.8 m tall: foot, middle, top


def test_r158_lies_behind_the_rear_across_the_vehicle_width(firetruck, lines):
    polygon = PRESETS["r158"].polygon(firetruck)
    x0, y0, x1, y1 = polygon.bounds
    assert x1 == pytest.approx(lines["rear"] - 0.3, abs=TOL) and x0 == pytest.approx(lines["rear"] - 3.5, abs=TOL)
    assert y0 == pytest.approx(lines["right"], abs=TOL) and y1 == pytest.approx(lines["left"], abs=TOL)
    assert _inside(polygon, lines["rear"] - 2.0, 0.0)


def test_r151_lies_along_the_nearside_minus_y_inside_the_mirrors(firetruck, lines):
    polygon = PRESETS["r151"].polygon(firetruck)
    near = PRESETS["r151"].lines(firetruck).nearside
    assert lines["right"] + 0.05 < near < 0.0  # R151's line leaves the mirrors out: it lies inside them
    x0, y0, x1, y1 = polygon.bounds
    assert y1 <= near + TOL and y0 == pytest.approx(near - 4.5, abs=TOL)
    assert x1 == pytest.approx(lines["front"], abs=TOL) and x0 == pytest.approx(lines["front"] - 30.0, abs=TOL)
    assert _inside(polygon, 0.0, near - 1.0) and not _inside(polygon, 0.0, lines["left"] + 1.0)


def test_r159_lies_ahead_of_the_front(firetruck, lines):
    polygon = PRESETS["r159"].polygon(firetruck)
    x0, y0, x1, y1 = polygon.bounds
    assert x0 >= lines["front"] - TOL and x1 == pytest.approx(lines["front"] + 3.7, abs=TOL)
    assert y0 == pytest.approx(lines["right"] - 0.5, abs=TOL) and y1 == pytest.approx(lines["left"] + 0.5, abs=TOL)
    assert _inside(polygon, lines["front"] + 1.0, 0.0)


def test_r46_fields_are_placed_against_the_driver_eye_and_the_nearside(firetruck, lines):
    eye, right = lines["eye"], lines["right"]
    five = PRESETS["r46-v"].polygon(firetruck)
    x0, y0, x1, y1 = five.bounds
    assert x0 == pytest.approx(eye - 1.75, abs=TOL) and x1 == pytest.approx(eye + 1.0, abs=TOL)
    assert y0 == pytest.approx(right - 2.0, abs=TOL) and y1 <= right + TOL
    six = PRESETS["r46-vi"].polygon(firetruck)
    x0, y0, x1, y1 = six.bounds
    assert x0 >= lines["front"] - TOL and x1 == pytest.approx(lines["front"] + 2.0, abs=TOL)
    assert y0 == pytest.approx(right - 2.0, abs=TOL) and y1 == pytest.approx(lines["left"], abs=TOL)
    four = PRESETS["r46-iv"].polygon(firetruck)
    assert _inside(four, eye - 20.0, right - 14.0) and not _inside(four, eye - 20.0, right - 15.2)
    # 5 m behind the eyes the outer edge, running straight from 4.5 m (1.5 m back) to 15 m (10 m back), is
    # 4.5 + 10.5 * 3.5 / 8.5 = 8.82 m out
    assert _inside(four, eye - 5.0, right - 8.7) and not _inside(four, eye - 5.0, right - 8.95)
    assert _inside(four, eye - 5.0, right - 4.0) and four.bounds[2] == pytest.approx(eye - 1.5, abs=TOL)


def test_dvs_wraps_the_cab_front_and_nearside(firetruck, lines):
    polygon = PRESETS["dvs"].polygon(firetruck)
    assert _inside(polygon, lines["front"] + 1.0, 0.0)  # in front of the cab
    assert _inside(polygon, lines["front"] - 0.5, lines["right"] - 4.0)  # beside the cab, 4 m out
    assert _inside(polygon, lines["front"] - 8.0, lines["right"] - 2.0)  # nearside sensors' 9 m x 2.2 m
    assert not _inside(polygon, lines["front"] - 8.0, lines["right"] - 3.0)
    assert not _inside(polygon, lines["front"] - 1.0, lines["left"] + 1.0)  # offside only 0.6 m


def test_no_field_asks_for_ground_under_or_right_next_to_its_reference(firetruck):
    body = Footprint.of_mesh(firetruck.mesh).polygon
    for preset in PRESETS.values():
        polygon = preset.polygon(firetruck)
        parts = 2 if preset.key == "r46-ii" else 1  # class II: a field on each side
        assert len(shapely.get_parts(polygon)) == parts, preset.key
        grown = preset.reference.outline(firetruck).buffer(NEAR_BODY_CLEARANCE - TOL)
        assert polygon.intersection(grown).area < 1e-9, preset.key
        assert polygon.intersection(body).area < 1e-9, preset.key  # never under the body, mirrors included


def test_a_field_box_names_its_lines():
    from rigopt.coverage.regulations import FieldBox, RegionPreset

    with pytest.raises(RigoptError, match="back edge"):
        FieldBox(("middle", 0.0), ("front", 1.0), ("offside", 0.0), ("nearside", 0.0))
    with pytest.raises(RigoptError, match="nearside edge"):
        FieldBox(("rear", -1.0), ("front", 1.0), ("offside", 0.0), ("front", 1.0))
    with pytest.raises(RigoptError, match="heights"):
        RegionPreset("x", "x", "x", (-1.0,), PRESETS["r158"].boxes)


def test_left_hand_traffic_mirrors_the_nearside(box_vehicle):
    for key in ("r151", "r46-ii", "r46-iv", "r46-v", "r46-vi", "dvs"):
        right, left = PRESETS[key], PRESETS[key].with_traffic("left")
        assert left.key == f"{key}:lht" and left.traffic == "left"
        mirrored = shapely.affinity.scale(right.polygon(box_vehicle), 1.0, -1.0, origin=(0, 0))
        assert left.polygon(box_vehicle).symmetric_difference(mirrored).area < 1e-9, key
    assert PRESETS["r151"].with_traffic("left").polygon(box_vehicle).bounds[1] >= 1.0 - TOL  # all at +y


@pytest.mark.parametrize("spacing", [0.5, 0.25])
def test_points_are_a_grid_and_the_outline_at_every_height(firetruck, spacing):
    preset = PRESETS["r158"]
    polygon = preset.polygon(firetruck)
    grid, boundary = preset.ground_samples(firetruck, spacing)
    points = preset.points(firetruck, spacing)
    assert points.shape == ((len(grid) + len(boundary)) * len(preset.heights), 3)
    assert sorted(set(points[:, 2].tolist())) == sorted(preset.heights)
    assert np.allclose(np.round(grid / spacing), grid / spacing)  # on multiples of the spacing
    assert all(polygon.contains(shapely.points(grid)))
    assert np.max(shapely.distance(polygon.boundary, shapely.points(boundary))) < 1e-9
    for corner in shapely.get_coordinates(polygon.exterior):  # every corner is sampled
        assert np.min(np.linalg.norm(boundary - corner, axis=1)) < 1e-9
    steps = np.linalg.norm(np.diff(np.vstack([boundary, boundary[:1]]), axis=0), axis=1)
    assert steps.max() <= spacing + 1e-9
    assert len(grid) == pytest.approx(polygon.area / spacing**2, rel=0.15)


def test_a_front_camera_leaves_r158_unseen_and_a_rear_camera_covers_it(box_vehicle, camera, rig):
    front = rig(camera([2.03, 0.0, 1.0], yaw_deg=0.0, fov=120.0, id="FRONT"))
    rear = rig(camera([-2.03, 0.0, 1.45], yaw_deg=180.0, pitch_deg=-50.0, fov=150.0, id="REAR"))
    preset = PRESETS["r158"].with_min_px(0)  # in view is enough: the geometry alone
    (unseen,) = region_coverage(front, box_vehicle, [preset], spacing=0.1)
    (seen,) = region_coverage(rear, box_vehicle, [preset], spacing=0.1)
    n = len(preset.points(box_vehicle, 0.1))
    assert unseen.n_points == seen.n_points == n  # nothing of the field is under the body
    assert unseen.covered_frac == 0.0 and not unseen.covered and len(unseen.unseen) == n
    assert unseen.unseen_area_m2 == pytest.approx(unseen.area_m2)
    assert seen.covered and seen.covered_frac == 1.0 and len(seen.unseen) == 0 and seen.unseen_area_m2 == 0.0
    assert seen.height_covered_frac == (1.0,) * len(preset.heights)


def test_a_narrow_rear_camera_covers_part_and_names_what_it_misses(box_vehicle, camera, rig):
    narrow = rig(camera([-2.03, 0.0, 1.45], yaw_deg=180.0, pitch_deg=-40.0, fov=100.0, id="REAR"))
    (result,) = region_coverage(narrow, box_vehicle, [PRESETS["r158"]], spacing=0.1)
    assert 0.0 < result.covered_frac < 1.0 and not result.covered
    assert 0.0 < result.unseen_area_m2 < result.area_m2
    assert len(result.unseen) == round(result.n_points * (1.0 - result.covered_frac))
    assert np.max(shapely.distance(result.polygon, shapely.points(result.unseen[:, :2]))) < 1e-9
    per_height = result.n_points // len(result.heights)
    assert np.mean(result.height_covered_frac) == pytest.approx(result.covered_frac, abs=1.0 / per_height)
    edge = result.unseen[np.abs(result.unseen[:, 1]) > 0.95]  # a 100 deg view misses the field's near corners
    assert len(edge) > 0


KEEP_OUT = """
[[keep_out]]
name = "trailer"
reason = "a coupled trailer"
min = [-20.0, -1.5, 0.0]
max = [-2.0, 1.5, 4.0]
optional = true
occludes = true
"""


def test_required_points_skip_keep_outs_in_force_unless_lifted(box_vehicle, tmp_path, camera, rig):
    path = tmp_path / "vehicle.toml"
    path.write_text(Path(box_vehicle.spec.source).read_text() + KEEP_OUT)
    tractor = Vehicle.from_spec(read_spec(path))
    front = rig(camera([2.03, 0.0, 1.0], fov=120.0, id="FRONT"))
    (coupled,) = region_coverage(front, tractor, [PRESETS["r158"]], spacing=0.2)
    (solo,) = region_coverage(front, tractor, [PRESETS["r158"]], spacing=0.2, lifted=("trailer",))
    assert coupled.n_points == 0 and coupled.covered and coupled.covered_frac == 1.0
    assert solo.n_points == len(PRESETS["r158"].points(tractor, 0.2)) and solo.covered_frac == 0.0
    points = np.array([[-3.0, 0.0, 0.8], [-3.0, 1.6, 0.8], [0.0, 0.0, 0.8], [-3.0, 0.0, 4.5]])
    assert required_mask(tractor, points).tolist() == [False, True, False, True]


# ------------------------------------------------------------------------------------------ --require


def test_parse_require_names_defaults_none_and_traffic(box_vehicle, firetruck):
    assert parse_require("none", box_vehicle) == ()
    assert [p.key for p in parse_require("default", box_vehicle)] == ["r158"]  # a car: M1 by its size
    assert [p.key for p in parse_require("default", firetruck)] == ["r151", "r159", "r158"]
    assert [p.key for p in default_presets(firetruck)] == ["r151", "r159", "r158"]
    chosen = parse_require(" R158, r151:LHT ,r158,r46-v:rht", firetruck)
    assert [p.key for p in chosen] == ["r158", "r151:lht", "r46-v"]
    assert [p.traffic for p in chosen] == ["right", "left", "right"]
    assert [p.key for p in parse_require("default:lht", firetruck)] == ["r151:lht", "r159:lht", "r158:lht"]
    assert [p.traffic for p in parse_require("dvs", firetruck, traffic="left")] == ["left"]


@pytest.mark.parametrize("text, fragment", [
    ("r158,r999", "unknown preset 'r999'"),
    ("", "needs preset names"),
    (" , ", "needs preset names"),
    ("r151:uk", ":lht"),
    ("none,r158", "stands alone"),
])
def test_parse_require_errors_say_what_to_use(box_vehicle, text, fragment):
    with pytest.raises(RigoptError) as error:
        parse_require(text, box_vehicle)
    assert fragment in str(error.value)
    if "unknown preset" in fragment:
        assert all(key in str(error.value) for key in [*PRESETS, "default", "none"])


# ------------------------------------------------------------------------------------------ categories


SPEC = {"name": "v", "solids": [{"type": "box", "center": [0, 0, 1], "size": [4, 2, 1.5]}]}


def test_the_spec_category_is_validated_and_normalised():
    assert spec_from_dict({**SPEC, "category": " n2 "}).category == "N2"
    assert spec_from_dict(SPEC).category is None
    for bad in ("truck", "X9", 3, ""):
        with pytest.raises(DataError) as error:
            spec_from_dict({**SPEC, "category": bad}, "v.toml")
        assert "'category'" in str(error.value) and ", ".join(CATEGORIES) in str(error.value)


def box_shape(*boxes) -> Vehicle:
    """A vehicle of boxes (centre, size) m and wheels on axles at its box's front and rear quarter."""
    solids = [{"type": "box", "center": list(c), "size": list(s)} for c, s in boxes]
    return Vehicle.from_spec(spec_from_dict({"name": "v", "solids": solids}))


@pytest.mark.parametrize("boxes, axles, category, words", [
    ([((0, 0, 0.9), (4.6, 1.9, 1.4))], (1.4, -1.4), "M1", "a car"),  # a saloon's box
    ([((0, 0, 1.45), (5.9, 2.0, 2.5))], (1.9, -1.7), "N1", "a van"),  # a high-roof van
    ([((0, 0, 1.7), (12.0, 2.55, 2.8))], (3.3, -3.3), "M3", "a bus"),  # the door ahead of the front axle
    ([((2.5, 0, 1.6), (2.2, 2.5, 2.8)), ((-2.0, 0, 2.1), (6.8, 2.5, 3.8))], (3.2, -2.0), "N3", "a truck"),
])
def test_the_category_is_guessed_from_the_shape_when_not_given(boxes, axles, category, words):
    vehicle = box_shape(*boxes)
    vehicle = Vehicle(dataclasses.replace(vehicle.spec, axles=axles), vehicle.mesh)
    assert vehicle.spec.category is None and vehicle.category == category
    assert words in vehicle.category_guess.reason


def test_a_bus_and_a_truck_require_the_blind_spot_field_and_a_car_and_a_van_do_not():
    assert all("r151" in CATEGORY_DEFAULTS[c] for c in ("M2", "M3", "N2", "N3"))
    assert all("r151" not in CATEGORY_DEFAULTS[c] for c in ("M1", "N1"))


def test_the_builtin_vehicles_name_their_category():
    assert {name: find_spec(name).category for name in ("etron", "tt", "firetruck", "hgv")} == \
        {"etron": "M1", "tt": "M1", "firetruck": "N3", "hgv": "N3"}


# ------------------------------------------------------------------------------------------ command line


@pytest.fixture(scope="module")
def cli_rig(tmp_path_factory):
    """(RIGOPT_HOME with the box car as user vehicle 'regcar', a rig file with one rear camera on it)."""
    from rigopt.geometry import rotation_from_yaw_pitch_roll
    from rigopt.rig.model import Camera

    root = tmp_path_factory.mktemp("regulations_cli")
    install_user_vehicle(root / "home", "regcar")
    rear = Camera.pinhole("CAM_BACK", np.array([-2.03, 0.0, 1.45]),
                  rotation_from_yaw_pitch_roll(np.pi, np.deg2rad(-50.0), 0.0), 150.0)
    return root / "home", write_rig(Rig("rearonly", "vehicle.test.regcar", (rear,)), root / "rear.json")


@pytest.mark.slow
def test_coverage_require_adds_the_fields_to_json_tables_and_folder(cli_rig, tmp_path):
    home, rig_file = cli_rig
    env = {"RIGOPT_HOME": str(home)}
    result = run_rigopt("coverage", rig_file, "--require", "r158,r159", "--json", "--out", tmp_path / "out", env=env)
    assert result.returncode == 0, result.stderr
    regions = {r["key"]: r for r in json.loads(result.stdout)["regions"]}
    assert list(regions) == ["r158", "r159"]
    assert regions["r158"]["covered"] is True and regions["r158"]["covered_frac"] == 1.0
    assert regions["r159"]["covered"] is False and regions["r159"]["unseen_area_m2"] > 0
    assert [h["height_m"] for h in regions["r158"]["height_covered_frac"]] == list(PRESETS["r158"].heights)
    assert regions["r158"]["weighted_covered_frac"] == 1.0 and regions["r158"]["overlap_frac"] == 0.0
    assert regions["r158"]["cameras"] == [{"camera": "CAM_BACK", "seen_frac": 1.0, "only_frac": 1.0}]
    assert regions["r159"]["cameras"][0]["seen_frac"] < 1.0 and 0.0 <= regions["r159"]["weighted_covered_frac"] < 1.0
    written = json.loads((tmp_path / "out" / "coverage.json").read_text())
    assert written["regions"] == json.loads(result.stdout)["regions"]
    assert (tmp_path / "out" / "regions.png").read_bytes().startswith(b"\x89PNG")
    page = (tmp_path / "out" / "report.html").read_text(encoding="utf-8")
    assert "Regulation fields" in page and "r159" in page

    text = run_rigopt("coverage", rig_file, "--require", "r158", env=env)
    assert text.returncode == 0 and "regulation fields" in text.stdout and "r158" in text.stdout
    assert "unseen area" in text.stdout and "weighted seen" in text.stdout
    assert "by camera" in text.stdout and "CAM_BACK" in text.stdout and "100.0 % (100.0 % alone)" in text.stdout


def test_coverage_require_refuses_a_bad_name_in_one_line(cli_rig):
    home, rig_file = cli_rig
    result = run_rigopt("coverage", rig_file, "--require", "r158,r160", env={"RIGOPT_HOME": str(home)})
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and result.stdout == ""
    assert len(lines) == 1 and lines[0].startswith("rigopt: error: --require") and "r160" in lines[0]


def test_the_require_help_names_every_preset():
    from rigopt.cli.coverage_command import REQUIRE_HELP

    assert all(key in REQUIRE_HELP for key in PRESETS)
