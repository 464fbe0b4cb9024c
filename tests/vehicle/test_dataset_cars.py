"""The datasets' own cars as built-in vehicles: the nuScenes Renault Zoe, the Argoverse Ford Fusion Hybrid and the
Waymo Chrysler Pacifica Hybrid. Each builds, matches its published dimensions, is found by the vehicle name
rigopt's importers write, and carries its dataset's cameras (imported without --vehicle) validly on its rack."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from in_process import run_rigopt
from rigopt.errors import DataError
from rigopt.resources import data_dir
from rigopt.rig.library import load_rig
from rigopt.vehicle.library import find_spec, load_vehicle
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec, spec_from_dict

REAL = Path(__file__).resolve().parents[2] / "measurements" / "rigs" / "real"
INCH = 0.0254


def tyre_radius(width_mm: float, aspect: float, rim_in: float) -> float:
    """Unloaded radius (m) of an ISO metric tyre ``width_mm/aspect R rim_in``: half the rim plus the sidewall."""
    return rim_in * INCH / 2 + width_mm * aspect / 100 / 1000


#: The published figures (see each vehicle.toml for where each comes from): length, width without mirrors and
#: height (m), wheelbase, front and rear track (m), rear overhang (m), tyre (width mm, aspect %, rim in).
PUBLISHED = {
    "renault_zoe": dict(length=4.084, width=1.730, height=1.562, wheelbase=2.588, track=(1.511, 1.510),
                        rear_overhang=0.657, tyre=(195, 55, 16)),
    "ford_fusion_hybrid": dict(length=191.8 * INCH, width=72.9 * INCH, height=58.0 * INCH, wheelbase=112.2 * INCH,
                               track=(1.589, 1.585), rear_overhang=1.047, tyre=(225, 50, 17)),
    "chrysler_pacifica_hybrid": dict(length=203.6 * INCH, width=79.6 * INCH, height=69.9 * INCH,
                                     wheelbase=121.6 * INCH, track=(68.3 * INCH, 68.3 * INCH), rear_overhang=1.087,
                                     tyre=(235, 65, 17)),
}
#: The mounting zone of each car's sensor platform, rack or dome.
RACK_ZONE = {"renault_zoe": "sensor_platform", "ford_fusion_hybrid": "roof_rack",
             "chrysler_pacifica_hybrid": "roof_dome"}
#: Dataset rigs (source folder under measurements/rigs/real, import format) and the car each lands on.
DATASETS = {"nuscenes": ("nuscenes", "renault_zoe"), "argoverse2": ("argoverse2", "ford_fusion_hybrid"),
            "waymo": ("waymo", "chrysler_pacifica_hybrid")}


def body_only(vehicle: Vehicle) -> Vehicle:
    """The vehicle without its sensor solids and mirror heads: the body the published dimensions describe."""
    kept = tuple(s for s in vehicle.spec.solids if not s.name.startswith(("sensor", "mirror")))
    assert len(kept) < len(vehicle.spec.solids) - 1  # a rack and mirrors were there to leave out
    return Vehicle.from_spec(replace(vehicle.spec, solids=kept))


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_each_car_builds_closed_as_an_m1_with_every_zone_on_its_surface(name):
    vehicle = load_vehicle(name)
    assert vehicle.mesh.is_watertight and vehicle.category == "M1"
    fine = vehicle.fine_mesh
    for zone in vehicle.zones:
        assert zone.contains(fine.triangles_center, fine.face_normals).any(), zone.name


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_the_body_has_the_published_length_width_and_height(name):
    published = PUBLISHED[name]
    expected = [published["length"], published["width"], published["height"]]
    np.testing.assert_allclose(body_only(load_vehicle(name)).size, expected, rtol=0.03)
    whole = load_vehicle(name).size  # the rack stays within the body's length and the mirrors' width
    assert whole[0] == pytest.approx(published["length"], rel=0.03)
    assert published["width"] < whole[1] < published["width"] + 0.3
    assert whole[2] > published["height"] + 0.2  # the rack stands on the roof


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_wheels_axles_and_tracks_are_the_published_ones(name):
    published, vehicle = PUBLISHED[name], load_vehicle(name)
    front, rear = vehicle.axles
    assert front - rear == pytest.approx(published["wheelbase"], abs=0.005)
    assert len(vehicle.wheels) == 4
    for centre, radius, width in vehicle.wheels:
        track = published["track"][0] if centre[0] == front else published["track"][1]
        assert 2 * abs(centre[1]) == pytest.approx(track, abs=0.002)
        assert radius == pytest.approx(tyre_radius(*published["tyre"]), abs=0.002)
        assert width == pytest.approx(published["tyre"][0] / 1000, abs=0.002)


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_the_rear_axle_sits_its_overhang_ahead_of_the_tail(name):
    vehicle = load_vehicle(name)
    tail = vehicle.mesh.bounds[0, 0]
    np.testing.assert_allclose(vehicle.rear_axle, [tail + PUBLISHED[name]["rear_overhang"], 0.0, 0.0], atol=0.002)
    assert abs(vehicle.mesh.bounds[:, 0].sum()) < 0.002  # the origin is the middle of the length


@pytest.mark.parametrize("alias, name", [("nuscenes", "renault_zoe"), ("NuScenes", "renault_zoe"),
                                         ("argoverse1", "ford_fusion_hybrid"), ("argoverse2", "ford_fusion_hybrid"),
                                         ("waymo", "chrysler_pacifica_hybrid"), ("zoe", "renault_zoe"),
                                         ("pacifica", "chrysler_pacifica_hybrid"), ("fusion", "ford_fusion_hybrid")])
def test_aliases_resolve(alias, name):
    assert find_spec(alias).name == name


def test_no_two_built_in_vehicles_share_a_name_alias_or_blueprint():
    seen: dict[str, str] = {}
    for path in sorted(data_dir("vehicles").glob("*/vehicle.toml")):
        spec = read_spec(path)
        for key in {k.lower() for k in (spec.name, spec.blueprint, *spec.aliases)}:
            assert key not in seen, f"{key!r} names both {seen[key]} and {spec.name}"
            seen[key] = spec.name
    assert {"nuscenes", "argoverse1", "argoverse2", "waymo", "etron", "suv"} <= set(seen)


def test_a_title_is_optional_text():
    body = {"name": "car", "solids": [{"type": "box", "center": [0, 0, 0.5], "size": [4, 1.8, 1]}]}
    assert spec_from_dict(body).title is None
    assert spec_from_dict({**body, "title": "Lab car"}).title == "Lab car"
    with pytest.raises(DataError, match="'title' must be a non-empty string"):
        spec_from_dict({**body, "title": 3}, "car.toml")
    assert find_spec("nuscenes").title == "nuScenes' Renault Zoe"


@pytest.fixture(scope="module")
def imported(tmp_path_factory) -> dict[str, Path]:
    """Each dataset's rig imported from its source folder as measurements/rigs/real/README.md does, but without
    --vehicle (so on the vehicle name the importer writes)."""
    out = tmp_path_factory.mktemp("imported")
    paths = {}
    for dataset, (folder, _) in DATASETS.items():
        paths[dataset] = out / f"{dataset}.json"
        done = run_rigopt("import", dataset, REAL / folder, "--name", dataset, "--out", paths[dataset])
        assert done.returncode == 0, done.stderr
    return paths


@pytest.mark.parametrize("dataset", sorted(DATASETS))
def test_an_import_without_vehicle_is_on_the_dataset_car(imported, dataset):
    rig = load_rig(imported[dataset])
    assert rig.vehicle == dataset and rig.origin.kind == "rear_axle"
    assert find_spec(rig.vehicle).name == DATASETS[dataset][1]


@pytest.mark.parametrize("dataset", sorted(DATASETS))
def test_the_dataset_cameras_pass_every_mount_rule_on_the_rack(imported, dataset):
    car = DATASETS[dataset][1]
    done = run_rigopt("check", imported[dataset], "--json")
    assert done.returncode == 0, done.stdout + done.stderr
    result = json.loads(done.stdout)
    assert result["vehicle"] == car and len(result["cameras"]) == len(load_rig(imported[dataset]))
    for camera in result["cameras"]:
        assert camera["valid"] and camera["problems"] == [], camera
        assert 0.0 < camera["distance_to_surface"] <= 0.05 and camera["zone"] == RACK_ZONE[car], camera
    title = find_spec(car).title
    assert f"rigopt: note: {dataset}: on {car} ({title}), positions from the rear axle, converted" in done.stderr


def test_rigcd_of_r1_and_an_imported_nuscenes_rig_needs_no_vehicle_and_names_the_zoe(imported):
    done = run_rigopt("rigcd", "R1", imported["nuscenes"], "--json")
    assert done.returncode == 0, done.stderr
    offset = float(load_vehicle("nuscenes").rear_axle[0])  # rear-axle positions move by the axle's x
    assert ("rigopt: note: nuscenes: on renault_zoe (nuScenes' Renault Zoe), positions from the rear axle, converted "
            f"to the vehicle centre (x {offset:+.3f} m)") in done.stderr
    data = json.loads(done.stdout)
    assert data["origin_changes"] == [{"rig": "nuscenes", "vehicle": "renault_zoe", "from": "rear_axle",
                                       "to": "vehicle_centre", "offset_m": [pytest.approx(offset), 0.0, 0.0]}]
    assert data["rigcd"] > 0


@pytest.mark.slow
def test_coverage_says_which_car_it_used(imported):
    done = run_rigopt("coverage", imported["waymo"], "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["vehicle"] == "chrysler_pacifica_hybrid"
    offset = float(load_vehicle("waymo").rear_axle[0])
    assert ("rigopt: note: waymo: on chrysler_pacifica_hybrid (Waymo's Chrysler Pacifica Hybrid), positions from "
            f"the rear axle, converted to the vehicle centre (x {offset:+.3f} m)") in done.stderr


def test_a_benchmark_rig_is_noted_on_its_own_vehicle_unconverted():
    done = run_rigopt("check", "R1")
    assert done.returncode == 0
    assert "rigopt: note: R1: on etron, positions from the vehicle centre\n" in done.stderr


def test_vehicles_lists_the_dataset_cars():
    done = run_rigopt("vehicles", "--json")
    assert done.returncode == 0, done.stderr
    rows = {row["vehicle"]: row for row in json.loads(done.stdout)}
    for name in PUBLISHED:
        assert name in rows
    assert "nuscenes" in rows["renault_zoe"]["aliases"] and "waymo" in rows["chrysler_pacifica_hybrid"]["aliases"]
