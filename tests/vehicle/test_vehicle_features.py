"""The built-in vehicles' body features for mounting practice (vehicles/*/vehicle.toml, docs/vehicles.md
"Body features"): each lies where the spec's own solids put the part, and the traced wheel arches where the
bodies leave them."""

from __future__ import annotations

import numpy as np
import pytest

from rigopt.mounting.features import trailer_swings
from rigopt.vehicle.library import load_vehicle
from rigopt.vehicle.spec import Box, Prism


def solid(vehicle, name):
    return next(s for s in vehicle.spec.solids if s.name == name)


def box_bounds(box: Box) -> tuple[np.ndarray, np.ndarray]:
    return box.center - box.size / 2.0, box.center + box.size / 2.0


def named(entries, name):
    return next(e for e in entries if e.name == name)


@pytest.fixture(scope="module")
def firetruck():
    return load_vehicle("firetruck")


@pytest.fixture(scope="module")
def hgv():
    return load_vehicle("hgv")


def test_the_fire_truck_s_tailboard_step_is_its_tailboard(firetruck):
    step = named(firetruck.spec.steps, "tailboard step")
    low, high = box_bounds(solid(firetruck, "tailboard"))
    np.testing.assert_allclose(step.min, low, atol=1e-9)
    np.testing.assert_allclose(step.max, high, atol=1e-9)


def test_the_fire_truck_s_light_bar_ladder_and_turntable_are_fixtures(firetruck):
    light_bar = named(firetruck.spec.fixtures, "light bar")
    assert light_bar.kind == "light_bar"
    np.testing.assert_allclose(np.stack([light_bar.min, light_bar.max]),
                               np.stack(box_bounds(solid(firetruck, "light_bar"))), atol=1e-9)
    ladder = named(firetruck.spec.fixtures, "aerial ladder")
    for part in ("ladder_rails", "ladder_bed"):
        low, high = box_bounds(solid(firetruck, part))
        assert (ladder.min <= low + 1e-9).all() and (ladder.max >= high - 1e-9).all(), part
    turntable = named(firetruck.spec.fixtures, "ladder turntable")
    np.testing.assert_allclose(np.stack([turntable.min, turntable.max]),
                               np.stack(box_bounds(solid(firetruck, "turntable"))), atol=1e-9)
    assert {f.kind for f in firetruck.spec.fixtures} == {"light_bar", "ladder"}


def test_the_fire_truck_s_locker_door_frames_surround_its_roll_up_doors(firetruck):
    doors = {k.name: k for k in firetruck.spec.keep_outs if k.reason == "roll-up locker doors"}
    frames = [f for f in firetruck.spec.door_frames if "locker" in f.name]
    assert len(doors) == len(frames) == 3
    for frame in frames:
        assert frame.frame == pytest.approx(0.10) and frame.hinge is None and frame.mirrored
        assert any(np.allclose(frame.min, d.min) and np.allclose(frame.max, d.max) for d in doors.values()), frame.name


def test_the_cab_doors_hinge_at_their_front_edge_and_the_steps_lie_below_them(firetruck, hgv):
    for vehicle in (firetruck, hgv):
        door = named(vehicle.spec.door_frames, "cab door")
        step = named(vehicle.spec.steps, "cab entry step")
        assert door.hinge == "front" and door.mirrored and step.mirrored
        assert step.max[2] <= door.min[2] + 0.05  # the step reaches up to the door's sill


def test_the_hgv_s_kingpin_sits_on_its_fifth_wheel_and_the_trailer_swings_3_83_m(hgv):
    (trailer,) = [k for k in hgv.spec.keep_outs if k.kingpin is not None]
    plate = solid(hgv, "fifth_wheel")
    assert isinstance(plate, Prism)
    centre_x = (plate.side[:, 0].min() + plate.side[:, 0].max()) / 2.0
    np.testing.assert_allclose(trailer.kingpin, [centre_x, 0.0, plate.side[:, 1].max()], atol=1e-9)
    (swing,) = trailer_swings(hgv)
    assert swing.radius == pytest.approx(np.hypot(1.30 + 2.30, 1.30), abs=1e-9)  # to the keep-out's front corners
    assert swing.radius == pytest.approx(3.83, abs=0.005)
    assert trailer_swings(hgv, lifted=("trailer",)) == []


def test_the_hgv_s_cab_tilts_about_its_lower_front_edge_clear_of_its_bumper(hgv):
    cab = hgv.spec.tilt_cab
    cab_solid = solid(hgv, "cab")
    front, rear = cab_solid.side[:, 0].max(), cab_solid.side[:, 0].min()
    assert cab.pivot[0] == pytest.approx(front) and cab.pivot[1] == pytest.approx(cab.min[2])
    assert cab.min[0] == pytest.approx(rear) and cab.max[2] >= solid(hgv, "roof_fairing").side[:, 1].max()
    # the bumper (the cab solid's flat face below z 1.40) stays below the tilting cab
    bumper_top = max(z for x, z in cab_solid.side if x == pytest.approx(front) and z < 1.41)
    assert bumper_top == pytest.approx(cab.min[2])
    assert 0 < cab.angle_deg <= 90


@pytest.mark.parametrize("name", ["firetruck", "hgv", "etron", "tt"])
def test_the_wiped_area_lies_on_the_windscreen_zone(name):
    vehicle = load_vehicle(name)
    wiped = vehicle.spec.wiped_area
    assert wiped is not None and wiped.zone == "windshield_front"
    zone = next(z for z in vehicle.zones if z.name == wiped.zone)
    outline = wiped.outline
    assert (outline[:, 0] >= zone.min[1]).all() and (outline[:, 0] <= zone.max[1]).all()
    assert (outline[:, 1] >= zone.min[2]).all() and (outline[:, 1] <= zone.max[2]).all()
    np.testing.assert_allclose(outline * [-1, 1], outline[[1, 0, 5, 4, 3, 2]], atol=1e-9)  # left-right symmetric


@pytest.mark.parametrize("name", ["firetruck", "hgv"])
def test_every_step_fixture_and_door_box_holds_body_surface(name):
    """A feature box is where the body has the part: some of the body's surface lies in it."""
    vehicle = load_vehicle(name)
    centres = vehicle.fine_mesh.triangles_center
    flip = np.array([1.0, -1.0, 1.0])
    for entry in (*vehicle.spec.steps, *vehicle.spec.fixtures, *vehicle.spec.door_frames):
        boxes = [(entry.min, entry.max)]
        if entry.mirrored:
            low, high = entry.min * flip, entry.max * flip
            boxes.append((np.minimum(low, high), np.maximum(low, high)))
        for low, high in boxes:
            assert np.all((centres >= low - 0.01) & (centres <= high + 0.01), axis=1).any(), entry.name


@pytest.mark.parametrize("name, front_top, rear_top", [
    ("firetruck", 1.23, 1.25),  # cab_lower's arch, the lockers over the rear wheel
    ("hgv", 1.15, 1.135),  # the cab's arch, the mudguards over the tandem
    ("etron", 0.80, 0.80),
    ("tt", 0.70, 0.70),
])
def test_the_arches_are_traced_where_the_bodies_leave_them(name, front_top, rear_top):
    """Straight up from each axle, the traced arch edge is the arch's top in the spec's side profile."""
    vehicle = load_vehicle(name)
    for arch in vehicle.wheel_arches:
        up = arch.edge_at(np.array([0.0]))[0]
        top = front_top if arch.centre[0] == vehicle.axles[0] else rear_top
        assert up == pytest.approx(top - arch.radius, abs=0.005), arch.name


def test_the_legal_width_is_the_default_on_every_built_in_vehicle():
    for name in ("firetruck", "hgv", "etron", "tt"):
        assert load_vehicle(name).legal_width == 2.55


def test_a_feature_box_off_the_body_is_an_error_naming_it(tmp_path):
    """A [[steps]] box 5 m beside the box car contradicts its mesh: one DataError with the box and how far; the
    same step against the body's side is accepted."""
    from box_car import spec_text

    from rigopt.errors import DataError
    from rigopt.vehicle.model import Vehicle
    from rigopt.vehicle.spec import read_spec

    def with_step(low, high):
        path = tmp_path / "vehicle.toml"
        path.write_text(spec_text() + f'\n[[steps]]\nname = "side step"\nmin = {low}\nmax = {high}\n')
        return Vehicle.from_spec(read_spec(path))

    with pytest.raises(DataError, match=r"\[\[steps\]\] 'side step' .* lies 4\.\d\d m off the body's surface"):
        with_step([0.0, 6.0, 0.2], [0.4, 6.3, 0.4])
    assert with_step([0.0, 0.9, 0.2], [0.4, 1.2, 0.4]).spec.steps[0].name == "side step"
