"""The interactive 3D view: body split by zone, wheels, keep-outs, frustums along the real lens's corner rays,
ground regions, a compared rig, and an HTML fragment that works offline."""

from __future__ import annotations

import re

import numpy as np
import pytest
from box_car import BOX_BODY, BOX_WHEELS, BOX_ZONES, spec_text

from rigopt.camera import Lens, vertical_fov
from rigopt.errors import RigoptError
from rigopt.geometry import R_CAM_OPTICAL, rotation_from_yaw_pitch_roll
from rigopt.mounting.practice import keep_out_boxes
from rigopt.report import frustums, scene_3d
from rigopt.report.scene_3d import BODY, REGION_HEIGHT_M, WHEELS, body_triangles, scene_figure, scene_html
from rigopt.rig.model import Camera, Rig, RigOrigin
from rigopt.vehicle.model import Vehicle
from rigopt.vehicle.spec import read_spec

KEEP_OUTS = """
[[keep_out]]
name = "hatch"
reason = "a service hatch"
min = [-1.0, 0.7, 0.5]
max = [0.0, 1.0, 1.2]
mirrored = true

[[keep_out]]
name = "hitch"
reason = "a towing hitch"
min = [-2.4, -0.3, 0.3]
max = [-1.9, 0.3, 0.8]
optional = true
"""

DESCRIBED_WHEELS = """
[[wheels]]
axles = [1.3, -1.3]
radius = 0.35
width = 0.25
track = 1.6
"""

RANGE = 2.0


def vehicle_from(tmp_path_factory, name: str, solids: str, zones: str) -> Vehicle:
    path = tmp_path_factory.mktemp(name) / "vehicle.toml"
    path.write_text(spec_text(name, solids=solids, zones=zones))
    return Vehicle.from_spec(read_spec(path))


@pytest.fixture(scope="module")
def car(tmp_path_factory) -> Vehicle:
    """The box car on four wheel solids, with a mirrored keep-out and an optional one."""
    return vehicle_from(tmp_path_factory, "wheelbox", BOX_BODY + BOX_WHEELS, BOX_ZONES + KEEP_OUTS)


@pytest.fixture(scope="module")
def fisheye() -> Lens:
    """A fisheye about 190 degrees wide (its corners more than 90 degrees off the axis)."""
    return Lens(1280, 960, 380.0, 380.0, 640.0, 480.0, "fisheye", (0.01, 0.0, 0.0, 0.0))


@pytest.fixture(scope="module")
def rig(fisheye) -> Rig:
    """A pinhole looking forward-down-left, a radtan lens looking left, and the fisheye on the roof."""
    radtan = Lens(1920, 1080, 1000.0, 1010.0, 950.0, 530.0, "radtan", (-0.3, 0.1, 0.001, -0.002, 0.0))
    return Rig("scene", "vehicle.test.wheelbox", (
        Camera.pinhole("front", np.array([2.04, 0.1, 1.2]), rotation_from_yaw_pitch_roll(0.2, -0.1, 0.05), 70.0,
               (1280, 720), zone="front"),
        Camera("left", np.array([0.5, 0.94, 1.0]), rotation_from_yaw_pitch_roll(np.pi / 2, 0.0, 0.0),
                         radtan, zone="side"),
        Camera("up", np.array([0.0, 0.0, 1.54]), rotation_from_yaw_pitch_roll(0.0, np.pi / 2, 0.0),
                         fisheye)))


@pytest.fixture(scope="module")
def figure(car, rig):
    regions = [("notched field", np.array([[4.0, -2.0], [8.0, -2.0], [8.0, 2.0], [6.0, 0.0], [4.0, 2.0], [4.0, -2.0]]))]
    compare = Rig("older", rig.vehicle, (Camera.pinhole("front", np.array([2.04, 0.0, 1.0]), np.eye(3), 90.0),))
    return scene_figure(car, rig, regions=regions, compare=compare, frustum_range=RANGE)


def traces(figure, meta=None, name_start=None):
    return [t for t in figure.data if (meta is None or t.meta == meta)
            and (name_start is None or (t.name or "").startswith(name_start))]


def corners_of(trace) -> np.ndarray:
    """(4, 3): the corner points of a frustum trace (after the lens, every third point)."""
    points = np.array([trace.x, trace.y, trace.z], dtype=float).T
    return points[[1, 4, 7, 10]]


# --- cameras ---------------------------------------------------------------------------------------------


def test_one_frustum_and_one_lens_marker_per_camera_in_a_legend_group(figure, rig):
    frustums = traces(figure, "frustum")
    assert [t.name for t in frustums] == ["older: front", "front", "left", "up"]  # the compared rig first
    assert len({t.legendgroup for t in frustums}) == 4 and all(t.showlegend for t in frustums)
    for camera in rig.cameras:
        group = [t for t in figure.data if t.legendgroup == f"camera scene {camera.id}"]
        assert sorted(t.meta for t in group) == ["frustum", "lens"]
        lens = next(t for t in group if t.meta == "lens")
        assert np.allclose([lens.x[0], lens.y[0], lens.z[0]], camera.position, atol=1e-12)
        assert f"<b>{camera.id}</b>" in lens.hovertext and "vehicle frame" in lens.hovertext
        assert "CARLA" not in lens.hovertext  # CARLA's frame only in the CARLA export
        assert f"{camera.lens.hfov:.1f} x {camera.lens.vfov:.1f} deg" in lens.hovertext


def test_a_pinhole_frustum_spans_its_fovs(figure, rig):
    camera = rig.cameras[0]
    trace = next(t for t in traces(figure, "frustum") if t.name == "front")
    directions = (corners_of(trace) - camera.position) @ camera.rotation  # camera body frame
    assert np.allclose(np.linalg.norm(directions, axis=1), RANGE, atol=1e-9)
    horizontal = np.arctan2(np.abs(directions[:, 1]), directions[:, 0])
    vertical = np.arctan2(np.abs(directions[:, 2]), directions[:, 0])
    assert np.allclose(horizontal, np.deg2rad(camera.fov / 2), atol=1e-6)
    assert np.allclose(vertical, np.deg2rad(vertical_fov(camera.fov, *camera.image_size) / 2), atol=1e-6)
    assert list(np.sign(directions[:, 1])) == [1, -1, -1, 1]  # top-left, top-right, bottom-right, bottom-left
    assert list(np.sign(directions[:, 2])) == [1, 1, -1, -1]


def test_frustum_lines_follow_the_corner_rays_exactly():
    camera = Camera.pinhole("c", np.array([1.0, 2.0, 3.0]), rotation_from_yaw_pitch_roll(0.3, 0.2, -0.1), 90.0, (1600, 900))
    corners, outline = frustums.frustum_lines(camera, 1.0)
    body = (corners - camera.position) @ camera.rotation
    half_h, half_v = np.deg2rad(45.0), np.deg2rad(vertical_fov(90.0, 1600, 900) / 2)
    assert np.allclose(np.arctan2(np.abs(body[:, 1]), body[:, 0]), half_h, atol=1e-9)
    assert np.allclose(np.arctan2(np.abs(body[:, 2]), body[:, 0]), half_v, atol=1e-9)
    assert len(outline) == 4 * frustums.EDGE_POINTS + 1 and np.allclose(outline[0], outline[-1])


@pytest.mark.parametrize("index", [1, 2])
def test_a_distorted_lens_draws_its_true_corners_and_outline(figure, rig, index):
    camera = rig.cameras[index]
    lens = camera.lens
    corners, outline = frustums.frustum_lines(camera, RANGE)
    optical = ((np.concatenate([corners, outline]) - camera.position) @ camera.rotation) @ R_CAM_OPTICAL
    pixels = lens.project(optical)  # back through the lens's own projection
    width, height = lens.image_size
    assert np.allclose(pixels[:4], [[0, 0], [width, 0], [width, height], [0, height]], atol=1e-6 * width)
    on_border = np.minimum.reduce([np.abs(pixels[4:, 0]), np.abs(pixels[4:, 0] - width), np.abs(pixels[4:, 1]),
                                   np.abs(pixels[4:, 1] - height)])
    assert on_border.max() < 1e-6 * width
    trace = next(t for t in traces(figure, "frustum") if t.name == camera.id)
    assert np.allclose(corners_of(trace), corners, atol=1e-9)


def test_the_fisheye_frustum_reaches_behind_its_lens_on_a_sphere(rig):
    camera = rig.cameras[2]  # wider than 180 degrees: its corner rays point behind the image plane
    corners, outline = frustums.frustum_lines(camera, RANGE)
    assert np.all(((corners - camera.position) @ camera.rotation)[:, 0] < 0)
    assert np.allclose(np.linalg.norm(outline - camera.position, axis=1), RANGE, atol=1e-9)


def test_a_pinhole_frustum_ends_in_a_rectangle_across_its_axis(rig):
    camera = rig.cameras[0]
    corners, outline = frustums.frustum_lines(camera, RANGE)
    body = (outline - camera.position) @ camera.rotation
    assert np.allclose(body[:, 0], body[0, 0], atol=1e-9)  # one plane across the optical axis
    left, right, top, bottom = body[:, 1].max(), body[:, 1].min(), body[:, 2].max(), body[:, 2].min()
    on_an_edge = np.minimum.reduce([abs(body[:, 1] - left), abs(body[:, 1] - right), abs(body[:, 2] - top),
                                    abs(body[:, 2] - bottom)])
    assert on_an_edge.max() < 1e-9  # straight edges


def test_an_off_centre_lens_has_its_farthest_corner_at_the_range(rig):
    camera = rig.cameras[1]  # radtan, principal point off the image centre
    corners, _ = frustums.frustum_lines(camera, RANGE)
    distances = np.linalg.norm(corners - camera.position, axis=1)
    assert distances.max() == pytest.approx(RANGE, abs=1e-9) and distances.min() < RANGE - 1e-4


def test_the_compared_rig_is_grey_and_dashed(figure):
    (other,) = [t for t in traces(figure, "frustum") if t.name.startswith("older: ")]
    assert other.line.dash == "dash" and other.line.color == scene_3d._COMPARE_GREY


def test_a_rig_from_the_rear_axle_is_drawn_from_the_vehicle_centre(car):
    camera = Camera.pinhole("c", np.array([3.3, 0.0, 1.2]), np.eye(3), 60.0)  # 3.3 m ahead of the rear axle (x -1.3)
    rig = Rig("axle", "vehicle.test.wheelbox", (camera,), origin=RigOrigin("rear_axle"))
    (lens,) = traces(scene_figure(car, rig), "lens")
    assert lens.x[0] == pytest.approx(2.0) and lens.z[0] == pytest.approx(1.2)


def test_a_non_positive_frustum_range_is_refused(car, rig):
    with pytest.raises(RigoptError, match="frustum range"):
        scene_figure(car, rig, frustum_range=0.0)


# --- body, zones, wheels, keep-outs ------------------------------------------------------------------------


def _areas(triangles) -> np.ndarray:
    return 0.5 * np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1)


def test_zones_are_named_traces_that_name_their_zone(figure, car):
    names = {t.name for t in figure.data if t.type == "mesh3d"}
    assert {"zone front", "zone side", BODY, WHEELS} <= names
    side = next(t for t in figure.data if t.name == "zone side")
    assert side.hovertext == "zone side" and side.legendgroup == "side"


def _on_a_wheel(points, vehicle, tolerance) -> np.ndarray:
    """(n,) bool: points (n, 3) within ``tolerance`` m of one of the vehicle's wheel cylinders."""
    found = np.zeros(len(points), dtype=bool)
    for centre, radius, width in vehicle.wheels:
        offset = points - centre
        found |= ((np.hypot(offset[:, 0], offset[:, 2]) <= radius + tolerance)
                  & (np.abs(offset[:, 1]) <= width / 2 + tolerance))
    return found


def test_the_zone_pieces_cover_what_the_fine_mesh_says(car):
    triangles, labels, missing = body_triangles(car)
    areas = _areas(triangles)
    assert missing == []
    assert areas.sum() == pytest.approx(car.mesh.area, rel=1e-9)  # a partition of the body's faces
    fine_mesh = car.fine_mesh
    off_wheels = ~_on_a_wheel(fine_mesh.triangles_center, car, 0.011)  # tyre sidewalls are wheels, not zones
    for zone in ("front", "side"):
        drawn = areas[labels == zone].sum()
        fine = fine_mesh.area_faces[(car.fine_face_zones == zone) & off_wheels].sum()
        assert drawn == pytest.approx(fine, rel=0.03) and drawn > 0.5


def test_the_wheel_solids_are_drawn_as_wheels(car):
    triangles, labels, _ = body_triangles(car)
    wheel_points = triangles[labels == WHEELS].reshape(-1, 3)
    assert len(wheel_points) > 0 and _on_a_wheel(wheel_points, car, 0.011).all()
    body_points = triangles[labels != WHEELS].mean(axis=1)
    assert not _on_a_wheel(body_points, car, -0.02).any()  # no face well inside a wheel is left to the body


def test_wheels_the_mesh_lacks_are_drawn_as_cylinders(tmp_path_factory):
    described = vehicle_from(tmp_path_factory, "describedwheels", BOX_BODY, BOX_ZONES + DESCRIBED_WHEELS)
    assert body_triangles(described)[2] == [0, 1, 2, 3]
    wheels = [t for t in scene_figure(described).data if t.name == WHEELS]
    assert len(wheels) == 4 and sum(t.showlegend for t in wheels) == 1


def test_keep_outs_in_force_are_translucent_boxes_with_their_reason(figure, car):
    boxes = [t for t in traces(figure, name_start="keep-out: ") if t.type == "mesh3d"]
    assert [t.name for t in boxes] == ["keep-out: hatch (a service hatch)"] * 2 + ["keep-out: hitch (a towing hitch)"]
    assert all(t.opacity < 0.5 and "no camera here" in t.hovertext for t in boxes)
    lifted = scene_figure(car, lifted=("hitch",))
    assert not traces(lifted, name_start="keep-out: hitch")


def test_the_firetruck_shows_its_locker_doors():
    from rigopt.vehicle.library import load_vehicle

    firetruck = load_vehicle("firetruck")
    figure = scene_figure(firetruck)
    boxes = [t for t in traces(figure, name_start="keep-out: ") if t.type == "mesh3d"]
    assert len(boxes) == len(keep_out_boxes(firetruck)) >= 6
    assert all("roll-up locker doors" in t.name for t in boxes)
    drawn = sum(len(t.i) for t in figure.data if t.type == "mesh3d" and not t.name.startswith("keep-out"))
    assert len(firetruck.mesh.faces) <= drawn < 3 * len(firetruck.mesh.faces)


def test_a_large_mesh_is_coarsened_to_the_face_budget(car):
    vertices, faces = np.asarray(car.mesh.vertices), np.asarray(car.mesh.faces)
    coarse = scene_3d._coarse_triangles(vertices, faces, 300)
    assert 50 < len(coarse) <= 300 < len(faces)
    low, high = coarse.reshape(-1, 3).min(axis=0), coarse.reshape(-1, 3).max(axis=0)
    assert np.allclose(low, vertices.min(axis=0), atol=0.3) and np.allclose(high, vertices.max(axis=0), atol=0.3)
    assert scene_3d._coarse_triangles(vertices, faces, len(faces)).shape == (len(faces), 3, 3)  # under budget: as is


# --- ground regions --------------------------------------------------------------------------------------


def test_a_concave_region_is_filled_exactly_on_the_ground(figure):
    fill = next(t for t in figure.data if t.name == "notched field" and t.type == "mesh3d")
    points = np.array([fill.x, fill.y, fill.z], dtype=float).T
    triangles = points[np.array([fill.i, fill.j, fill.k]).T]
    assert np.allclose(points[:, 2], REGION_HEIGHT_M)
    assert _areas(triangles).sum() == pytest.approx(16.0 - 4.0, rel=1e-6)  # the 4 x 4 square less its notch
    assert len(triangles) == 3  # five corners: three triangles, none over the notch


@pytest.mark.parametrize("outline", [np.zeros((2, 2)), np.zeros((4, 3)), np.array([[0, 0], [1, 0], [np.nan, 1]])])
def test_a_bad_region_is_refused(car, outline):
    with pytest.raises(RigoptError, match="ground region 'r'"):
        scene_figure(car, regions=[("r", outline)])


# --- layout and HTML -------------------------------------------------------------------------------------


def test_axes_are_equal_and_name_the_frame(figure):
    scene = figure.layout.scene
    ranges = np.array([scene.xaxis.range, scene.yaxis.range, scene.zaxis.range])
    lengths = ranges[:, 1] - ranges[:, 0]
    ratio = np.array([scene.aspectratio.x, scene.aspectratio.y, scene.aspectratio.z])
    assert scene.aspectmode == "manual" and np.allclose(ratio, lengths / lengths.max())  # one scale on every axis
    assert "vehicle frame from the vehicle centre" in scene.xaxis.title.text
    assert scene.yaxis.title.text.startswith("y left")


def _drawn_points(figure) -> np.ndarray:
    """(n, 3): every drawn point of the figure (gaps left out)."""
    points = []
    for trace in figure.data:
        xyz = [np.array([np.nan if v is None else v for v in getattr(trace, a)], dtype=float) for a in "xyz"]
        points.append(np.stack(xyz, axis=1))
    points = np.concatenate(points)
    return points[np.all(np.isfinite(points), axis=1)]


def test_the_axes_hold_everything_drawn(figure):
    scene = figure.layout.scene
    ranges = np.array([scene.xaxis.range, scene.yaxis.range, scene.zaxis.range])
    points = _drawn_points(figure)
    assert np.all(points >= ranges[:, 0]) and np.all(points <= ranges[:, 1])  # nothing clipped by the axes


def test_the_view_opens_framed_on_the_vehicle_beside_its_legend(figure, car):
    scene = figure.layout.scene
    ranges = np.array([scene.xaxis.range, scene.yaxis.range, scene.zaxis.range])
    middle, scale = ranges.mean(axis=1), (ranges[:, 1] - ranges[:, 0]).max()

    def to_scene(points):  # plotly's scene coordinates of equal axes
        return (np.asarray(points) - middle) / scale

    centre = np.array([scene.camera.center.x, scene.camera.center.y, scene.camera.center.z])
    eye = np.array([scene.camera.eye.x, scene.camera.eye.y, scene.camera.eye.z])
    low, high = car.mesh.bounds
    assert np.allclose(centre, to_scene((low + high) / 2))  # looks at the vehicle's centre
    corners = to_scene(np.array([[(high if (k >> a) & 1 else low)[a] for a in range(3)] for k in range(8)]))
    view = (centre - eye) / np.linalg.norm(centre - eye)
    angles = np.degrees(np.arccos(((corners - eye) @ view) / np.linalg.norm(corners - eye, axis=1)))
    assert angles.max() < 22.5  # plotly's camera sees 45 degrees: the whole box is in view ...
    assert angles.max() > 12.0  # ... and fills it, not a speck in a scene of frustums and fields
    assert eye[0] > centre[0] and eye[1] > centre[1] and eye[2] > centre[2]  # from the front left, above
    assert figure.layout.legend.x >= scene.domain.x[1] and figure.layout.legend.xanchor == "left"


def test_frustums_reach_5_m_by_default_or_the_ground_before(car, rig):
    assert frustums.FRUSTUM_RANGE_M == 5.0
    trace = next(t for t in traces(scene_figure(car, rig), "frustum") if t.name == "front")
    camera = rig.cameras[0]
    drawn, corners = corners_of(trace), frustums.frustum_lines(camera)[0]
    assert np.allclose(np.linalg.norm(drawn[:2] - camera.position, axis=1), 5.0, atol=1e-9)  # the top corners
    assert np.all(corners[2:, 2] < 0) and np.allclose(drawn[2:, 2], 0.0)  # the bottom ones end on the ground ...
    along = (drawn[2:] - camera.position) / (corners[2:] - camera.position)
    assert np.allclose(along, along[:, :1]) and np.all((0 < along) & (along < 1))  # ... on their own rays


def test_no_frustum_line_runs_below_the_ground_and_the_footprints_stay(car, fisheye):
    """Cameras low and tilted down (a pinhole, the fisheye looking down and sideways): every drawn frustum point
    is at or above z = 0, from either datum; the ground footprints are the frustums' sections, as before."""
    cameras = (Camera.pinhole("low", np.array([2.04, 0.0, 0.6]), rotation_from_yaw_pitch_roll(0.1, -0.5, 0.0), 90.0),
               Camera("down", np.array([0.0, 0.94, 1.5]), rotation_from_yaw_pitch_roll(np.pi / 2, -1.2, 0.0), fisheye))
    rig = Rig("low", "vehicle.test.wheelbox", cameras)
    compare = Rig("grey", rig.vehicle, cameras[:1])
    for datum in scene_3d.DATUMS:
        figure = scene_figure(car, rig, compare=compare, datum=datum)
        for trace in traces(figure, "frustum"):
            z = np.array([v for v in trace.z if v is not None], dtype=float)
            assert z.min() >= -1e-6, (datum, trace.name)
        assert min(v for t in traces(figure, "frustum") for v in t.z if v is not None) < 1e-6  # some reach it
    for camera in cameras:
        fills = [t for t in traces(scene_figure(car, rig), "footprint") if t.type == "mesh3d" and t.name == camera.id]
        points = np.concatenate([np.array([t.x, t.y, t.z], dtype=float).T[np.array([t.i, t.j, t.k]).T]
                                 for t in fills])
        assert _areas(points).sum() == pytest.approx(frustums.frustum_footprint(camera).area, rel=1e-6)


def test_ended_at_ground_moves_only_points_below_it_along_their_rays():
    lens = np.array([1.0, 2.0, 1.0])
    points = np.array([[3.0, 2.0, -1.0], [1.0, 5.0, 0.5], [1.0, 2.0, -3.0]])
    assert np.allclose(frustums.ended_at_ground(lens, points), [[2.0, 2.0, 0.0], [1.0, 5.0, 0.5], [1.0, 2.0, 0.0]])
    buried = np.array([0.0, 0.0, -0.1])  # a lens not above the ground: nothing to end
    assert np.array_equal(frustums.ended_at_ground(buried, points), points)


# --- ground footprints -----------------------------------------------------------------------------------


def _half_plane(normal_xy, offset, size=500.0):
    """The ground half-plane normal_xy . g >= offset as a (large) shapely polygon."""
    import shapely

    length = np.linalg.norm(normal_xy)
    n, offset = np.asarray(normal_xy) / length, offset / length
    side, point = np.array([-n[1], n[0]]), n * offset
    return shapely.Polygon([point + side * size, point - side * size, point - side * size + n * size,
                            point + side * size + n * size])


def _pinhole_footprint_oracle(camera, reach):
    """The frustum's section by z = 0, by clipping the ground with the pyramid's five planes: its four sides
    (through the lens and two neighbouring corner rays) and its end (the plane across the axis at the
    corners' depth)."""
    import shapely

    width, height = camera.image_size
    corners = np.array([[0, 0], [width, 0], [width, height], [0, height]], dtype=float)
    from rigopt.camera import CameraModel

    rays = CameraModel.of_camera(camera).pixel_rays(corners) @ camera.rotation.T
    region = shapely.box(-100, -100, 100, 100)
    for a, b in zip(rays, np.roll(rays, -1, axis=0)):
        normal = np.cross(a, b)
        normal = normal if normal @ camera.forward > 0 else -normal  # pointing into the pyramid
        region = region.intersection(_half_plane(normal[:2], normal @ camera.position))
    axis, depth = camera.forward, reach * rays[0] @ camera.forward
    return region.intersection(_half_plane(-axis[:2], -(depth + axis @ camera.position)))


@pytest.mark.parametrize("yaw, pitch, roll", [(0.3, -0.35, 0.0), (-2.0, -0.6, 0.2), (1.0, -1.2, -0.1)])
def test_a_pinhole_footprint_is_the_pyramids_section_by_the_ground(yaw, pitch, roll):
    camera = Camera.pinhole("c", np.array([1.0, 0.5, 1.2]), rotation_from_yaw_pitch_roll(yaw, pitch, roll), 90.0, (1280, 720))
    footprint = frustums.frustum_footprint(camera, 5.0)
    oracle = _pinhole_footprint_oracle(camera, 5.0)
    assert oracle.area > 1.0
    assert footprint.area == pytest.approx(oracle.area, rel=1e-6)
    assert footprint.symmetric_difference(oracle).area < 1e-6 * oracle.area


def test_a_camera_looking_up_has_no_footprint_and_draws_none(car):
    up = Camera.pinhole("sky", np.array([0.0, 0.0, 1.6]), rotation_from_yaw_pitch_roll(0.0, 1.0, 0.0), 60.0)
    assert frustums.frustum_footprint(up).is_empty
    figure = scene_figure(car, Rig("upwards", "vehicle.test.wheelbox", (up,)))
    assert not traces(figure, "footprint")


def test_a_fisheye_looking_down_covers_the_disc_its_sphere_cuts(fisheye):
    down = Camera("down", np.array([0.0, 0.0, 1.5]), rotation_from_yaw_pitch_roll(0.0, -np.pi / 2, 0.0),
                            fisheye)
    footprint = frustums.frustum_footprint(down, 5.0)  # wider than 150 degrees: it ends on the 5 m sphere
    radius = np.sqrt(5.0**2 - 1.5**2)
    assert footprint.area <= np.pi * radius**2 and footprint.area > 0.9 * np.pi * radius**2
    assert np.max(np.abs(footprint.bounds)) <= radius + 1e-9
    assert footprint.contains(__import__("shapely").Point(0.0, 0.0))  # it sees straight down


def test_the_footprint_is_drawn_on_the_ground_in_the_cameras_group(car):
    camera = Camera.pinhole("down", np.array([2.04, 0.0, 1.2]), rotation_from_yaw_pitch_roll(0.0, -0.6, 0.0), 90.0)
    figure = scene_figure(car, Rig("r", "vehicle.test.wheelbox", (camera,)))
    fill = next(t for t in traces(figure, "footprint") if t.type == "mesh3d")
    points = np.array([fill.x, fill.y, fill.z], dtype=float).T
    assert np.allclose(points[:, 2], scene_3d.FOOTPRINT_HEIGHT_M)
    assert fill.legendgroup == "camera r down" and not fill.showlegend
    area = _areas(points[np.array([fill.i, fill.j, fill.k]).T]).sum()
    assert area == pytest.approx(_pinhole_footprint_oracle(camera, frustums.FRUSTUM_RANGE_M).area, rel=1e-6)


# --- the datum -------------------------------------------------------------------------------------------


def test_a_view_from_the_rear_axle_moves_everything_by_the_axle(car, rig):
    from_centre = scene_figure(car, rig, frustum_range=RANGE)
    from_axle = scene_figure(car, rig, frustum_range=RANGE, datum="rear_axle")
    axle = car.rear_axle
    assert np.allclose(axle, [-1.3, 0.0, 0.0])
    assert np.allclose(_drawn_points(from_axle), _drawn_points(from_centre) - axle, atol=1e-5)
    lens = traces(from_axle, "lens")[0]
    assert "from the rear axle" in lens.hovertext and "from the rear axle" in from_axle.layout.scene.xaxis.title.text
    x = rig.cameras[0].position[0] - axle[0]
    assert f"x, y, z: {x:.2f}, " in lens.hovertext and "CARLA" not in lens.hovertext
    assert scene_3d.frame_text(car, "rear_axle").endswith("origin on the ground below the rear axle's centre")


def test_an_unknown_datum_is_refused(car):
    with pytest.raises(RigoptError, match="unknown view datum 'roof'"):
        scene_figure(car, datum="roof")


def test_the_fragment_carries_plotly_inline_and_needs_no_network(car, rig):
    fragment = scene_html(car, rig, div_id="view-a")
    assert fragment.startswith("<div") and "<html" not in fragment
    assert fragment.count("plotly.js v") == 1 and 'id="view-a"' in fragment
    assert 'src="http' not in fragment
    assert not re.search(r"<script[^>]*\bsrc=", fragment)  # inline scripts only, nothing fetched
    second = scene_html(car, rig, include_plotlyjs=False, div_id="view-b")
    assert "plotly.js v" not in second and 'id="view-b"' in second and len(second) < len(fragment) / 5
    assert scene_3d.plotly_library_html().count("plotly.js v") == 1


def test_the_design_page_section_names_the_compared_rig():
    from rigopt.report.design_html import scene_section

    heading, note, scene = scene_section("<div>view</div>", "R1")
    assert heading == "<h2>3D view</h2>" and "R1 is drawn in grey" in note and "ISO 8855" in note
    assert "grey, dashed" not in scene_section("<div>view</div>", None)[1]
    named = scene_section("<div>view</div>", None, "ISO 8855, origin on the ground below the rear axle's centre")[1]
    assert "below the rear axle" in named and "to 5 m" in named and "CARLA" not in named


def test_the_coverage_page_holds_the_view_when_given_the_vehicle(car, tmp_path):
    from rigopt.coverage.measures import CoverageSettings, coverage_report
    from rigopt.report.coverage_html import write_html_report

    rig = Rig("two", "vehicle.test.wheelbox", (Camera.pinhole("F", np.array([2.04, 0.0, 1.0]), np.eye(3), 100.0),
                                                Camera.pinhole("B", np.array([-2.04, 0.0, 1.0]), rotation_from_yaw_pitch_roll(
                                                    np.pi, 0.0, 0.0), 100.0)))
    quick = CoverageSettings(ring_distances=(2.0,), ring_heights=(0.0,), ring_samples=72, sectors=72, bev_extent=10.0,
                             blind_azimuths=36, blind_search=5.0, blind_cell=0.2, image_grid=(16, 9),
                             overlap_ring=(2.0, 0.0))
    report = coverage_report(rig, car, quick)
    with_view = write_html_report(report, tmp_path / "a", rig, figures={}, vehicle=car).read_text(encoding="utf-8")
    without = write_html_report(report, tmp_path / "b", rig, figures={}).read_text(encoding="utf-8")
    assert "<h2>3D view</h2>" in with_view and with_view.count("plotly.js v") == 1
    assert '"name":"F"' in with_view and "<h2>3D view</h2>" not in without and "plotly" not in without
