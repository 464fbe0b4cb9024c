"""Generating the synthetic benchmark: render every scene under every rig and write the nuScenes layout.

Each (rig, scene) pair is rendered and annotated on its own and leaves ``<root>/.parts/<scene>.json`` (its
table records) beside its images, so an interrupted run resumes by skipping finished pairs; the tables are
assembled from all parts at the end of every run. Scene, sample and instance tokens depend only on the
scene, so the same scene has the same tokens under every rig.

Annotations are the world's objects, the same under every rig: every box within ``ANNOTATION_RANGE`` of
the ego (class >= 0), with the same instance token and box whatever the rig. What depends on the rig is
each box's visible fraction, measured on 26 surface points (corners, edge midpoints and face centres,
pulled 5 % inwards): of the points on faces turned towards some camera, the fraction that some camera sees
unoccluded (the rendered pixel shows this box at the point's depth). It is kept as the nuScenes
``visibility_token`` and, exactly, as the record's ``visible_fraction`` (0: no camera sees the box).

Beside each image the renderer's depth is kept, for depth supervision: ``depth/<CAM>/<token>.png``, 16-bit,
depth along the optical axis in units of 1 / ``DEPTH_SCALE`` m (0: no surface, i.e. sky or behind the lens),
named by the sample_data record's ``depth_filename`` (an addition to the nuScenes fields).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np

from rigopt.validation.synthetic.dataset import pose_record, box_rotation, save_tables, static_tables, visibility_token
from rigopt.validation.synthetic.scene_model import CLASSES, Boxes, Scene
from rigopt.errors import RigoptError
from rigopt.output import atomic_file, atomic_folder
from rigopt.rig.model import Rig
from rigopt.vehicle.placement import in_vehicle_frame
from rigopt.rig.formats.nuscenes import nuscenes_token, write_nuscenes_calibration

if TYPE_CHECKING:
    from rigopt.validation.synthetic.render import EgoBody

ANNOTATION_RANGE = 80.0
#: Relative depth agreement for a surface point to count as the rendered pixel's surface.
DEPTH_TOLERANCE = 0.05
#: Depth map units per metre (1 cm steps; 655 m at most).
DEPTH_SCALE = 100.0
#: zlib level of the written PNGs: 1 writes about twice as fast as PIL's default 6, for somewhat larger files.
PNG_LEVEL = 1


def depth_image(depth: np.ndarray) -> np.ndarray:
    """(h, w) float depth (m; inf or <= 0 where no surface) -> (h, w) uint16 depth map (0: none)."""
    scaled = np.where(np.isfinite(depth) & (depth > 0), np.round(depth * DEPTH_SCALE), 0)
    return np.clip(scaled, 0, np.iinfo(np.uint16).max).astype(np.uint16)


def _surface_points(boxes: Boxes) -> tuple[np.ndarray, np.ndarray]:
    """(n, 26, 3) world points on each box's surface and (n, 26, 3) their outward directions."""
    grid = np.array([[a, b, c] for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1) if (a, b, c) != (0, 0, 0)],
                    dtype=float)
    local = grid[None] * boxes.sizes[:, None] / 2.0 * 0.95
    c, s = np.cos(boxes.yaws)[:, None], np.sin(boxes.yaws)[:, None]

    def turn(v):
        return np.stack([v[..., 0] * c - v[..., 1] * s, v[..., 0] * s + v[..., 1] * c, v[..., 2]], axis=-1)

    outward = grid / np.linalg.norm(grid, axis=1, keepdims=True)
    return turn(local) + boxes.centers[:, None], turn(np.broadcast_to(outward, local.shape))


def visible_fractions(boxes: Boxes, rig: Rig, T_world_ego: np.ndarray, rendered: dict) -> np.ndarray:
    """(n,) float: the visible fraction of each box (see the module docstring); 0 when unseen."""
    points, outward = _surface_points(boxes)
    seeable = np.zeros(points.shape[:2], dtype=bool)
    seen = np.zeros(points.shape[:2], dtype=bool)
    for camera in rig.cameras:
        image = rendered[camera.id]
        T_world_cam = T_world_ego[:3, :3] @ camera.rotation, T_world_ego[:3, :3] @ camera.position + T_world_ego[:3, 3]
        rotation, origin = T_world_cam
        local = np.einsum("ji,npj->npi", rotation, points - origin)  # camera body frame
        facing = np.einsum("npk,npk->np", outward, origin - points) > 0
        depth = local[..., 0]
        k = image.intrinsics
        h, w = image.object_id.shape
        model = getattr(image, "model", None)  # render_rig is injectable: older renders carry no model
        if model is not None and bool(model.distorted):  # a real lens (a fisheye sees behind its lens plane)
            angle = np.arctan2(np.hypot(local[..., 1], local[..., 2]), depth)
            seeable |= facing & (angle < model.valid_angles)
            in_view = model.in_view(local)
            u, v = np.moveaxis(model.project(np.where(in_view[..., None], local, [1.0, 0.0, 0.0])), -1, 0)
            inside = facing & in_view & (u < w) & (v < h)
        else:
            seeable |= facing & (local[..., 0] > 0)
            u = k[0, 0] * (-local[..., 1]) / np.maximum(depth, 1e-9) + k[0, 2]
            v = k[1, 1] * (-local[..., 2]) / np.maximum(depth, 1e-9) + k[1, 2]
            inside = facing & (depth > 0) & (u >= 0) & (u < w) & (v >= 0) & (v < h)
        col, row = np.clip(u.astype(int), 0, w - 1), np.clip(v.astype(int), 0, h - 1)
        shows_box = image.object_id[row, col] == boxes.instance[:, None]
        near = np.abs(image.depth[row, col] - depth) <= DEPTH_TOLERANCE * np.abs(depth) + 0.1
        seen |= inside & shows_box & near
    return np.where(seeable.sum(axis=1) > 0, seen.sum(axis=1) / np.maximum(seeable.sum(axis=1), 1), 0.0)


def scene_records(scene: Scene, rig: Rig, root: Path, size: tuple[int, int], ego_body,
                  render_rig: Callable) -> dict[str, list[dict]]:
    """Render ``scene`` under ``rig``: write the images under ``root/samples`` and return the scene's records."""
    from PIL import Image

    tables: dict[str, list[dict]] = {name: [] for name in ("log", "scene", "sample", "sample_data", "ego_pose",
                                                           "sample_annotation", "instance")}
    scene_token = nuscenes_token("scene", scene.name)
    log_token = nuscenes_token("log", scene.name)
    tables["log"].append({"token": log_token, "logfile": scene.name, "vehicle": rig.vehicle, "location": "rigopt"})
    sample_tokens = [nuscenes_token("sample", f"{scene.name}/{k}") for k in range(len(scene.frames))]
    instances: dict[int, dict] = {}
    for k, frame in enumerate(scene.frames):
        rendered = render_rig(scene, k, rig, ego_body, size)
        ego_token = nuscenes_token("ego_pose", f"{scene.name}/{k}")
        tables["ego_pose"].append(pose_record(ego_token, frame.T_world_ego, timestamp=frame.timestamp_us))
        tables["sample"].append({"token": sample_tokens[k], "timestamp": frame.timestamp_us, "scene_token": scene_token,
                                 "prev": sample_tokens[k - 1] if k else "",
                                 "next": sample_tokens[k + 1] if k + 1 < len(scene.frames) else ""})
        for camera in rig.cameras:
            data_token = nuscenes_token("sample_data", f"{scene.name}/{k}/{camera.id}")
            filename = f"samples/{camera.id}/{data_token}.png"
            depth_filename = f"depth/{camera.id}/{data_token}.png"
            with atomic_file(root / filename) as work:  # an image on disk is always complete
                Image.fromarray(rendered[camera.id].rgb).save(work, format="PNG", compress_level=PNG_LEVEL)
            with atomic_file(root / depth_filename) as work:
                Image.fromarray(depth_image(rendered[camera.id].depth)).save(work, format="PNG", compress_level=PNG_LEVEL)
            tables["sample_data"].append({
                "token": data_token, "sample_token": sample_tokens[k], "ego_pose_token": ego_token,
                "calibrated_sensor_token": nuscenes_token("calibrated_sensor", camera.id), "filename": filename,
                "depth_filename": depth_filename, "fileformat": "png", "width": size[0], "height": size[1], "timestamp": frame.timestamp_us,
                "is_key_frame": True, "prev": "", "next": ""})
        boxes = scene.boxes_at(k)
        ego = frame.T_world_ego[:2, 3]
        keep = (boxes.classes >= 0) & (np.linalg.norm(boxes.centers[:, :2] - ego, axis=1) <= ANNOTATION_RANGE)
        boxes = Boxes(*(getattr(boxes, f)[keep] for f in ("centers", "sizes", "yaws", "classes", "instance")))
        fractions = visible_fractions(boxes, rig, frame.T_world_ego, rendered)
        for j in range(len(boxes)):
            instance = int(boxes.instance[j])
            instance_token = nuscenes_token("instance", f"{scene.name}/{instance}")
            instances.setdefault(instance, {"token": instance_token, "category_token":
                                            nuscenes_token("category", CLASSES[boxes.classes[j]]), "nbr_annotations": 0})
            instances[instance]["nbr_annotations"] += 1
            length, width, height = boxes.sizes[j]
            tables["sample_annotation"].append({
                "token": nuscenes_token("sample_annotation", f"{scene.name}/{k}/{instance}"),
                "sample_token": sample_tokens[k], "instance_token": instance_token,
                "visibility_token": visibility_token(float(fractions[j])),
                "visible_fraction": round(float(fractions[j]), 4), "attribute_tokens": [],
                "translation": boxes.centers[j].tolist(), "size": [float(width), float(length), float(height)],
                "rotation": box_rotation(float(boxes.yaws[j])), "num_lidar_pts": 0, "num_radar_pts": 0})
    tables["instance"] = list(instances.values())
    tables["scene"].append({"token": scene_token, "name": scene.name, "log_token": log_token,
                            "nbr_samples": len(scene.frames), "first_sample_token": sample_tokens[0],
                            "last_sample_token": sample_tokens[-1], "description": scene.road.kind})
    return tables


def generate_split(rigs: Sequence[Rig], scenes: Sequence[Scene], out, size: tuple[int, int], render_rig: Callable,
                   ego_body_of: Callable, progress: Callable[[str], None] = lambda message: None,
                   note: Callable[[str], None] = lambda message: None, ray_address: str | None = None,
                   workers: int = 1) -> list[Path]:
    """Render every (rig, scene) pair not done yet and (re)assemble each rig's tables; returns the roots
    ``<out>/<rig>/<split>``. Rigs are rendered from their vehicle's centre (:func:`in_vehicle_frame`; ``note``
    gets each move). The pairs run in ``workers`` processes here, or as Ray tasks with ``ray_address``
    (``bench.cluster``; ``out`` must then be on storage every node sees); the files are the same either way."""
    from rigopt.validation.synthetic.cluster import run_tasks

    if not (len(size) == 2 and all(isinstance(v, int) and v > 0 for v in size)):
        raise RigoptError(f"image size must be two positive integers (width, height), got {size}")
    placed = []
    for rig in rigs:
        rig, moved = in_vehicle_frame(rig)
        if moved:
            note(moved)
        placed.append(rig)
    todo = {}
    for rig in placed:
        for scene in scenes:
            root = Path(out) / rig.name / scene.split
            if (root / ".parts" / f"{scene.name}.json").is_file():
                progress(f"{rig.name} / {scene.name}: done before, skipped")
            else:
                todo[(rig.name, scene.name)] = (scene, rig, root, size, render_rig, ego_body_of(rig))
    if ray_address or workers > 1:
        where = "as Ray tasks" if ray_address else f"in {workers} processes"
        progress(f"{len(todo)} (rig, scene) pairs to render {where}")
        for (rig_name, scene_name), _ in run_tasks(render_scene, todo, ray_address, workers, what="rendering of"):
            progress(f"{rig_name} / {scene_name}: rendered")
    else:
        for (rig_name, scene_name), arguments in todo.items():
            scene, rig = arguments[:2]
            progress(f"{rig_name} / {scene_name}: rendering {len(scene.frames)} samples x {len(rig)} cameras")
            render_scene(*arguments)
    roots = []
    for rig in placed:
        for split in sorted({scene.split for scene in scenes}):
            roots.append(assemble(Path(out) / rig.name / split, rig, split, size))
    return roots


def render_scene(scene: Scene, rig: Rig, root: Path, size: tuple[int, int], render_rig: Callable,
                 ego_body) -> None:
    """Render and annotate one (rig, scene) pair under ``root`` (``ego_body``: the vehicle's EgoBody, None for none) and
    leave its part, the mark of a finished pair (written last, whole). Takes plain values only, so that it
    can run as a Ray task."""
    records = scene_records(scene, rig, root, size, ego_body, render_rig)
    part = root / ".parts" / f"{scene.name}.json"
    part.parent.mkdir(parents=True, exist_ok=True)
    temporary = part.with_suffix(".tmp")
    temporary.write_text(json.dumps(records))
    temporary.replace(part)


def assemble(root: Path, rig: Rig, split: str, size: tuple[int, int]) -> Path:
    """Write the tables of ``root`` from all its scene parts, the rig's calibration and the fixed tables.

    The table folder ``v1.0-<split>`` is replaced whole (written beside it, then renamed), so that it always
    describes complete scenes only: an interrupted run leaves the previous tables (or none) and the parts of
    the scenes it finished, which a rerun skips.
    """
    version = f"v1.0-{split}"
    tables = static_tables()
    for part in sorted((root / ".parts").glob("*.json")):
        for name, records in json.loads(part.read_text()).items():
            tables.setdefault(name, []).extend(records)
    with atomic_folder(root / version, force=True) as work:
        save_tables(work.parent, work.name, tables)
        write_nuscenes_calibration(rig, work, image_size=size)
    return root


def ego_body_lookup(warn: Callable[[str], None] = lambda message: None) -> Callable[[Rig], EgoBody | None]:
    """``ego_body_of(rig)``: the body of the rig's vehicle (an EgoBody of its mesh), made once per vehicle; None
    (after ``warn``) for a vehicle rigopt has no mesh of, which is then rendered without its body."""
    from rigopt.validation.synthetic.render import EgoBody
    from rigopt.vehicle.library import load_vehicle

    bodies: dict[str, EgoBody | None] = {}

    def ego_body_of(rig: Rig) -> EgoBody | None:
        if rig.vehicle not in bodies:
            try:
                bodies[rig.vehicle] = EgoBody(load_vehicle(rig.vehicle).mesh)
            except RigoptError:
                warn(f"no mesh for vehicle {rig.vehicle!r}: rendering {rig.name} without the ego body "
                     "(no self-occlusion)")
                bodies[rig.vehicle] = None
        return bodies[rig.vehicle]

    return ego_body_of


def split_layout(root) -> tuple[list[Scene], tuple[int, int]]:
    """The scenes of a generated split ``root`` (regenerated from the seeds in their names, with their
    sample counts) and its image size (width, height): what renders the same split under another rig."""
    import re

    from rigopt.validation.synthetic.scenes import generate_scene

    root = Path(root)
    tables = sorted(root.glob("v1.0-*/scene.json"))
    if not tables:
        raise RigoptError(f"{root}: no v1.0-*/scene.json; is it a split made by rigopt bench generate?")
    split = tables[0].parent.name.removeprefix("v1.0-")
    scenes = []
    for record in json.loads(tables[0].read_text()):
        seed = re.search(r"-s(\d+)$", record["name"])
        if seed is None:
            raise RigoptError(f"{root}: scene {record['name']!r} was not made by rigopt bench generate (no seed)")
        scenes.append(generate_scene(int(seed.group(1)), split, int(record["nbr_samples"]), name=record["name"]))
    sample_data = json.loads((tables[0].parent / "sample_data.json").read_text())
    if not scenes or not sample_data:
        raise RigoptError(f"{root}: the split has no scenes or images")
    return scenes, (int(sample_data[0]["width"]), int(sample_data[0]["height"]))
