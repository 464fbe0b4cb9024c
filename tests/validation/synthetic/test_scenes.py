"""Procedural benchmark scenes: determinism, splits, sizes, ground contact, no overlaps, consistent motion, roads."""

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rigopt.validation.synthetic.scene_model import CLASSES, SAMPLE_INTERVAL_US, SPLITS, Boxes
from rigopt.validation.synthetic.scenes import (SEED_OFFSET_STEP, SEEDS_PER_SPLIT, SPLIT_OFFSETS, generate_scene, scene_name,
                                  split_scenes, split_seeds)
from rigopt.errors import RigoptError

FIELDS = ("centers", "sizes", "yaws", "classes", "instance")
#: Allowed (length, width, height) ranges per class (m), from the documented size table.
RANGES = {
    "car": ((3.5, 1.5, 1.3), (5.7, 2.3, 2.4)), "truck": ((4.5, 1.9, 2.0), (11.5, 3.0, 4.1)),
    "bus": ((8.0, 2.4, 2.7), (14.0, 3.05, 4.3)), "motorcycle": ((1.5, 0.5, 1.0), (2.7, 1.2, 2.0)),
    "bicycle": ((1.2, 0.35, 0.9), (2.2, 1.0, 1.8)), "adult": ((0.4, 0.4, 1.4), (1.05, 1.05, 2.1)),
    "child": ((0.25, 0.25, 0.85), (0.75, 0.75, 1.55)), "traffic_sign": ((0.03, 0.4, 0.35), (0.2, 1.2, 1.25)),
    "traffic_light": ((0.2, 0.2, 0.6), (0.55, 0.55, 1.4)),
}
MEANS = {"car": (4.6, 1.9, 1.7), "adult": (0.7, 0.7, 1.75)}
VEHICLES = [CLASSES.index(c) for c in ("car", "truck", "bus", "motorcycle", "bicycle")]
RAISED = [CLASSES.index("traffic_sign"), CLASSES.index("traffic_light")]


@pytest.fixture(scope="module")
def scenes():
    return [generate_scene(seed, "train") for seed in split_seeds("train", 20)]


def rectangle(x0, x1, y0, y1, T):
    """The ego-frame rectangle [x0, x1] x [y0, y1] placed in the world by T_world_ego."""
    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    return shapely.Polygon(corners @ T[:2, :2].T + T[:2, 3])


def footprints(boxes: Boxes):
    return shapely.polygons(boxes.corners()[:, [0, 1, 2, 3], :2])


def overlapping_pairs(boxes: Boxes):
    polys = footprints(boxes)
    i, j = shapely.STRtree(polys).query(polys, predicate="intersects")
    return [(a, b) for a, b in zip(i, j) if a < b]


def assert_clear(scene):
    """No two boxes intersect in the bird's-eye view, and none comes near the ego."""
    for k, frame in enumerate(scene.frames):
        boxes = scene.boxes_at(k)
        assert overlapping_pairs(boxes) == [], (scene.name, k)
        polys = footprints(boxes)
        T = frame.T_world_ego
        car = rectangle(-2.5, 2.5, -1.1, 1.1, T)  # a 5 x 2.2 m car around the ego origin
        assert np.all(shapely.distance(polys, car) >= 0.6 - 1e-9), (scene.name, k)
        assert not np.any(shapely.intersects(polys, rectangle(-3.5, 3.5, -1.7, 1.7, T))), (scene.name, k)
        assert not np.any(shapely.intersects(polys, rectangle(-4.45, 4.45, -1.5, 1.5, T)))  # firetruck/hgv


def all_boxes(scene):
    return Boxes.concatenate([scene.static, *(f.agents for f in scene.frames)])


def test_same_seed_gives_identical_arrays_and_different_seeds_differ():
    a, b, c = generate_scene(7), generate_scene(7), generate_scene(8)
    assert a.road.kind == b.road.kind and len(a.frames) == len(b.frames) == 40
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a.static, name), getattr(b.static, name))
    for fa, fb in zip(a.frames, b.frames):
        assert fa.timestamp_us == fb.timestamp_us
        np.testing.assert_array_equal(fa.T_world_ego, fb.T_world_ego)
        for name in FIELDS:
            np.testing.assert_array_equal(getattr(fa.agents, name), getattr(fb.agents, name))
    for sa, sb in zip(a.road.surface, b.road.surface):
        np.testing.assert_array_equal(sa, sb)
    np.testing.assert_array_equal(a.road.markings, b.road.markings)
    np.testing.assert_array_equal(a.road.kerbs, b.road.kerbs)
    assert a.frames[0].timestamp_us != c.frames[0].timestamp_us
    assert len(a.static) != len(c.static) or not np.array_equal(a.static.centers, c.static.centers)


def test_names_and_frame_count():
    scene = generate_scene(3, "val", 5, name="scene-val-0002")
    assert (scene.name, scene.seed, scene.split, len(scene.frames)) == ("scene-val-0002", 3, "val", 5)
    assert generate_scene(3, "mini", 1).name == "scene-mini-s3"


def test_split_seeds_are_disjoint_deterministic_and_validated():
    seeds = {split: split_seeds(split, 500) for split in SPLITS}
    assert seeds["train"][:3] == [0, 1, 2] and split_seeds("val", 500) == seeds["val"]
    for a in SPLITS:
        assert len(set(seeds[a])) == 500
        for b in SPLITS:
            assert a == b or not set(seeds[a]) & set(seeds[b])
    for bad in (("dev", 3), ("train", 0), ("test", -1), ("val", 10**9)):
        with pytest.raises(RigoptError):
            split_seeds(*bad)
    with pytest.raises(RigoptError):
        generate_scene(0, "dev")
    with pytest.raises(RigoptError):
        generate_scene(0, "train", 0)


def test_split_scenes_are_named_by_index_and_seed_and_offsets_never_share_a_scene():
    plain, shifted = split_scenes("val", 2, 1), split_scenes("val", 2, 1, seed_offset=3)
    first = split_seeds("val", 2)
    assert [s.seed for s in plain] == first
    assert [s.name for s in plain] == [scene_name("val", 0, first[0]), scene_name("val", 1, first[1])]
    assert plain[1].name == f"scene-val-0001-s{first[1]}"
    assert [s.seed for s in shifted] == [seed + 3 * SEED_OFFSET_STEP for seed in first]
    assert SEED_OFFSET_STEP >= max(SPLIT_OFFSETS.values()) + SEEDS_PER_SPLIT  # past every split's range
    assert all(len(s.frames) == 1 and s.split == "val" for s in plain + shifted)


@pytest.mark.parametrize("offset", [-5, 1.5, True])
def test_a_bad_seed_offset_is_refused_with_what_it_got(offset):
    with pytest.raises(RigoptError, match=f"seed offset must be a whole number >= 0, got {offset!r}"):
        split_scenes("mini", 1, 1, seed_offset=offset)


def test_every_class_appears_and_indices_are_valid(scenes):
    classes = np.concatenate([all_boxes(s).classes for s in scenes])
    assert set(np.unique(classes)) == set(range(-1, len(CLASSES)))


def test_sizes_follow_the_table(scenes):
    boxes = Boxes.concatenate([all_boxes(s) for s in scenes])
    for name, (low, high) in RANGES.items():
        sizes = boxes.sizes[boxes.classes == CLASSES.index(name)]
        assert len(sizes) and np.all(sizes >= low) and np.all(sizes <= high), name
        if name in MEANS:  # per-instance means, not weighted by frames
            ids = boxes.instance[boxes.classes == CLASSES.index(name)]
            _, first = np.unique(ids, return_index=True)
            np.testing.assert_allclose(sizes[first].mean(axis=0), MEANS[name], atol=0.15)
    assert np.all(boxes.sizes[boxes.classes == -1] > 0.1)


def test_boxes_sit_on_the_ground_and_signs_are_raised(scenes):
    for scene in scenes:
        boxes = all_boxes(scene)
        bottom = boxes.centers[:, 2] - boxes.sizes[:, 2] / 2
        raised = np.isin(boxes.classes, RAISED)
        np.testing.assert_allclose(bottom[~raised], 0.0, atol=1e-9)
        assert np.all(bottom[raised] >= 1.5)


def test_no_boxes_overlap_each_other_or_the_ego(scenes):
    for scene in scenes:
        assert_clear(scene)


def test_timestamps_are_spaced_by_the_sample_interval(scenes):
    for scene in scenes:
        stamps = np.array([f.timestamp_us for f in scene.frames])
        assert all(isinstance(f.timestamp_us, int) for f in scene.frames) and stamps[0] > 0
        assert np.all(np.diff(stamps) == SAMPLE_INTERVAL_US)
    assert len({s.frames[0].timestamp_us for s in scenes}) == len(scenes)


def test_ego_drives_forward_at_a_constant_speed_in_range(scenes):
    speeds = []
    for scene in scenes:
        T = np.stack([f.T_world_ego for f in scene.frames])
        np.testing.assert_allclose(T[:, 3], np.tile([0, 0, 0, 1.0], (len(T), 1)))
        np.testing.assert_allclose(T[:, :3, :3] @ T[:, :3, :3].transpose(0, 2, 1), np.tile(np.eye(3), (len(T), 1, 1)),
                                   atol=1e-12)
        np.testing.assert_allclose(T[:, :3, :3], np.broadcast_to(T[0, :3, :3], T[:, :3, :3].shape), atol=1e-12)
        np.testing.assert_allclose(T[:, :3, 2], np.tile([0, 0, 1.0], (len(T), 1)), atol=1e-12)  # level, on the ground
        np.testing.assert_allclose(T[:, 2, 3], 0.0)
        step = np.diff(T[:, :3, 3], axis=0)
        speed = np.linalg.norm(step, axis=1) / (SAMPLE_INTERVAL_US * 1e-6)
        np.testing.assert_allclose(speed, speed[0], atol=1e-9)
        assert 0.0 <= speed[0] <= 48 / 3.6 + 1e-9
        np.testing.assert_allclose(step, speed[0] * 0.5 * np.tile(T[0, :3, 0], (len(step), 1)), atol=1e-9)
        speeds.append(speed[0])
    assert max(speeds) > 5 and min(speeds) < max(speeds)


def test_agents_move_at_constant_velocity_along_their_heading(scenes):
    for scene in scenes:
        tracks = {}
        for k, frame in enumerate(scene.frames):
            a = frame.agents
            assert len(set(a.instance)) == len(a) and not set(a.instance) & set(scene.static.instance)
            np.testing.assert_allclose(a.centers[:, 2], a.sizes[:, 2] / 2)
            for j, i in enumerate(a.instance):
                tracks.setdefault(i, []).append((k, a.centers[j], a.sizes[j], a.yaws[j], a.classes[j]))
        for track in tracks.values():
            ks = np.array([t[0] for t in track])
            assert np.all(np.diff(ks) == 1)  # present in one run of consecutive frames
            assert all(np.array_equal(t[2], track[0][2]) and t[3] == track[0][3] and t[4] == track[0][4] for t in track)
            if len(track) < 2:
                continue
            step = np.diff([t[1] for t in track], axis=0)
            np.testing.assert_allclose(step, np.broadcast_to(step[0], step.shape), atol=1e-9)
            speed = np.linalg.norm(step[0]) / 0.5
            assert speed <= (20.0 if track[0][4] in VEHICLES else 2.5)
            heading = np.array([np.cos(track[0][3]), np.sin(track[0][3]), 0.0])
            if track[0][4] in VEHICLES or speed > 0:
                np.testing.assert_allclose(step[0], speed * 0.5 * heading, atol=1e-9)


def test_boxes_at_concatenates_static_and_agents(scenes):
    scene = scenes[0]
    boxes = scene.boxes_at(3)
    n = len(scene.static)
    assert len(boxes) == n + len(scene.frames[3].agents)
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(boxes, name)[:n], getattr(scene.static, name))
        np.testing.assert_array_equal(getattr(boxes, name)[n:], getattr(scene.frames[3].agents, name))


def test_markings_lie_on_the_asphalt_and_kerbs_on_its_edge(scenes):
    for scene in scenes:
        road = scene.road
        asphalt = shapely.union_all(shapely.polygons(list(road.surface))).buffer(1e-6)
        lines = shapely.linestrings(road.markings)
        assert np.all(shapely.length(lines) > 0.5)
        assert np.all(shapely.contains(asphalt, shapely.buffer(lines, road.marking_width / 2, cap_style="flat")))
        assert np.all(shapely.distance(shapely.linestrings(road.kerbs), asphalt.boundary) < 1e-5)
        assert np.all(shapely.within(shapely.points(road.kerbs.mean(axis=1)), asphalt))


def test_both_layouts_occur_and_traffic_surrounds_the_ego(scenes):
    assert {s.road.kind for s in scenes} == {"straight", "junction"}
    leaving = 0
    for scene in scenes:
        near = {}
        for k, frame in enumerate(scene.frames):
            boxes = scene.boxes_at(k)
            d = np.linalg.norm(boxes.centers[:, :2] - frame.T_world_ego[:2, 3], axis=1)
            assert np.sum((d < 80) & (boxes.classes >= 0)) >= 5, (scene.name, k)
            assert np.any(d[len(scene.static):] > 80)  # agents beyond the annotated range are kept
            for i, inside in zip(boxes.instance[len(scene.static):], d[len(scene.static):] < 80):
                near.setdefault(i, set()).add(bool(inside))
        leaving += sum(len(v) == 2 for v in near.values())
    assert leaving > 0


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 10**7), n_frames=st.integers(1, 8))
def test_random_seeds_give_clear_deterministic_scenes(seed, n_frames):
    scene = generate_scene(seed, "test", n_frames)
    assert len(scene.frames) == n_frames
    assert_clear(scene)
    again = generate_scene(seed, "test", n_frames)
    np.testing.assert_array_equal(scene.static.centers, again.static.centers)
    np.testing.assert_array_equal(scene.frames[-1].agents.centers, again.frames[-1].agents.centers)
