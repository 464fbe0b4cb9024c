"""Rigs on vehicles: converting a rig's reference point (its origin) and placing a rig on a vehicle.

The benchmark measures camera positions from the vehicle's centre (CARLA's origin: the bounding box's centre
in x and y, on the ground); imported nuScenes, Argoverse 2, Waymo and DDAD rigs measure them from the rear
axle on the ground (see :class:`rigopt.rig.model.RigOrigin`). Comparing rigs measured from different points mixes a
vehicle's rear overhang into every position term, so RigCD, ranking and design compare rigs in one frame:
rigs that share an origin are compared as they are; otherwise each is converted to its vehicle's centre,
which needs the vehicle (where its rear axle is). A rig whose vehicle rigopt does not know (an imported
rig, vehicle ``nuscenes``) cannot be converted: it is placed on a rigopt vehicle first (``--vehicle``).

Frames: ISO 8855 (x forward, y left, z up), metres.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Sequence

import numpy as np

from rigopt.errors import RigoptError, UnknownNameError
from rigopt.rig.model import VEHICLE_CENTRE, Camera, Rig, RigOrigin
from rigopt.vehicle.model import Vehicle

#: How deep (m) a lens may sit inside the body surface before the camera counts as inside it: the surface
#: models of the built-in vehicles pass about 3 cm behind the benchmark's lenses.
INSIDE_TOLERANCE_M = 0.0


@dataclass(frozen=True)
class OriginChange:
    """A rig's positions moved to another origin: ``offset`` (3,) m was added to every camera position.

    rig : the rig's name; vehicle : the vehicle whose reference points were used; source, target : the
    origins before and after.
    """

    rig: str
    vehicle: str
    source: RigOrigin
    target: RigOrigin
    offset: np.ndarray

    def describe(self) -> str:
        """One line for messages, e.g. 'nusc: positions converted from the rear axle to the vehicle centre of
        etron (x -1.430 m)'."""
        moved = ", ".join(f"{axis} {value:+.3f} m" for axis, value in zip("xyz", self.offset) if abs(value) > 5e-4)
        return (f"{self.rig}: positions converted from the {self.source.describe()} to the {self.target.describe()} "
                f"of {self.vehicle} ({moved or 'no shift'})")

    def as_dict(self) -> dict:
        """JSON form: rig, vehicle, from, to, offset_m [x, y, z]."""
        return {"rig": self.rig, "vehicle": self.vehicle, "from": self.source.kind, "to": self.target.kind,
                "offset_m": [float(v) for v in self.offset]}


def origin_point(origin: RigOrigin, vehicle: Vehicle) -> np.ndarray:
    """(3,) float m: where ``origin`` lies in ``vehicle``'s centre frame."""
    if origin.kind == "vehicle_centre":
        return np.zeros(3)
    if origin.kind == "custom":
        return np.array(origin.point, dtype=float)
    rear_axle = vehicle.rear_axle
    if rear_axle is None:
        raise RigoptError(f"vehicle {vehicle.name!r} has no axles, so a rear-axle origin cannot be placed on it; "
                          "add axles = [x, ...] to its vehicle.toml (or re-add it with --axles)")
    return rear_axle


def convert_origin(rig: Rig, vehicle: Vehicle, target: RigOrigin) -> tuple[Rig, OriginChange | None]:
    """``rig`` with its positions measured from ``target`` on ``vehicle``, and the change made (None if none)."""
    if rig.origin == target:
        return rig, None
    offset = origin_point(rig.origin, vehicle) - origin_point(target, vehicle)
    cameras = tuple(replace(camera, position=camera.position + offset) for camera in rig.cameras)
    change = OriginChange(rig.name, vehicle.name, rig.origin, target, offset)
    return Rig(rig.name, rig.vehicle, cameras, target), change


def to_vehicle_centre(rig: Rig, vehicle: Vehicle) -> tuple[Rig, OriginChange | None]:
    """``rig`` with its positions measured from ``vehicle``'s centre, and the change made (None if none)."""
    return convert_origin(rig, vehicle, VEHICLE_CENTRE)


def known_vehicle(rig: Rig) -> Vehicle | None:
    """The built-in or user vehicle ``rig.vehicle`` names, or None when rigopt does not know it (an imported
    rig's dataset name)."""
    from rigopt.vehicle.library import load_vehicle

    try:
        return load_vehicle(rig.vehicle)
    except UnknownNameError:
        return None


def common_frame(rigs: Sequence[Rig], vehicle_of: Callable[[Rig], Vehicle | None] = known_vehicle
                 ) -> tuple[list[Rig], list[OriginChange]]:
    """``rigs`` measured from one origin, and the changes made.

    Rigs that all share an origin come back as they are. Otherwise every rig is converted to its vehicle's
    centre (the benchmark's frame), its vehicle given by ``vehicle_of``; a rig that needs converting and has
    no known vehicle is an error that says how to place it.
    """
    rigs = list(rigs)
    if len({rig.origin for rig in rigs}) <= 1:
        return rigs, []
    out, changes = [], []
    for rig in rigs:
        if rig.origin.is_benchmark:
            out.append(rig)
            continue
        vehicle = vehicle_of(rig)
        if vehicle is None:
            others = sorted({r.origin.describe() for r in rigs if r.origin != rig.origin})
            raise RigoptError(f"rig {rig.name!r} measures its positions from the {rig.origin.describe()} of "
                              f"{rig.vehicle!r}, which rigopt does not know, and the other rigs from the "
                              f"{' / '.join(others)}; comparing them would mix reference points: add --vehicle NAME "
                              f"to place it on a rigopt vehicle (see rigopt vehicles), or import it with --vehicle")
        converted, change = to_vehicle_centre(rig, vehicle)
        out.append(converted)
        changes.append(change)
    return out, changes


def cameras_inside(rig: Rig, vehicle: Vehicle) -> list[tuple[Camera, float]]:
    """Cameras of ``rig`` (in ``vehicle``'s centre frame) whose lens lies inside the body, each with its depth
    below the surface (m, > 0)."""
    distance = vehicle.surface(rig.positions).distance
    return [(camera, float(-d)) for camera, d in zip(rig.cameras, distance) if d < -INSIDE_TOLERANCE_M]


def place_rig(rig: Rig, vehicle: Vehicle, refuse_inside: bool = True) -> tuple[Rig, OriginChange | None]:
    """``rig`` on ``vehicle``: positions converted to the vehicle's centre and the rig's vehicle set to it.

    A camera that lands inside the body would see nothing through it, so where the body matters (coverage,
    design) it is an error naming each such camera and how deep it lies, never a silent loss of coverage;
    ``refuse_inside=False`` is for the metrics, which use the vehicle only for its reference points.
    """
    placed, change = to_vehicle_centre(rig, vehicle)
    if known_vehicle(placed) is not vehicle:
        placed = Rig(placed.name, vehicle.blueprint, placed.cameras, placed.origin)
    inside = cameras_inside(placed, vehicle) if refuse_inside else []
    if inside:
        listed = ", ".join(f"{camera.id} ({depth:.2f} m deep)" for camera, depth in inside)
        moved = f" after {change.describe()}" if change is not None else ""
        raise RigoptError(f"rig {rig.name!r} on {vehicle.name}{moved}: {len(inside)} camera(s) inside the body: "
                          f"{listed}; place the rig on a vehicle its cameras fit (--vehicle), give the rig's "
                          "origin right, or move those cameras onto the surface")
    return placed, change


def rig_on_vehicle(rig: Rig, vehicle_name: str | None) -> tuple[Rig, Vehicle, OriginChange | None]:
    """The CLI's rule for one rig: on ``vehicle_name`` when given (converted and checked by
    :func:`place_rig`), else on its own vehicle (converted to its centre, cameras inside refused)."""
    from rigopt.vehicle.library import load_vehicle

    if vehicle_name is not None:
        vehicle = load_vehicle(vehicle_name)
        placed, change = place_rig(rig, vehicle)
        return placed, vehicle, change
    vehicle = known_vehicle(rig)
    if vehicle is None:
        raise RigoptError(f"rig {rig.name!r} is on {rig.vehicle!r}, which is not a rigopt vehicle; add --vehicle "
                          "NAME to place it on one (see rigopt vehicles), or import it with --vehicle")
    placed, change = place_rig(rig, vehicle)
    return placed, vehicle, change


def comparable_rigs(rigs: Sequence[Rig], vehicle: Vehicle | None = None) -> tuple[list[Rig], list[OriginChange]]:
    """``rigs`` ready to compare (RigCD, ranking), and every origin change made.

    With ``vehicle``, rigs whose own vehicle rigopt does not know (imported rigs) are first placed on it
    (:func:`place_rig`; only its reference points matter here, so cameras inside its body are allowed);
    then all are brought to one origin (:func:`common_frame`).
    """
    placed, changes = [], []
    for rig in rigs:
        if vehicle is not None and known_vehicle(rig) is None:
            rig, change = place_rig(rig, vehicle, refuse_inside=False)
            changes += [change] if change is not None else []
        placed.append(rig)
    same, more = common_frame(placed)
    return same, changes + more


def in_vehicle_frame(rig: Rig) -> tuple[Rig, str | None]:
    """``rig`` with its positions measured from its vehicle's centre, the ego origin the benchmark renders and
    measures from (its ego meshes and the scenes' clearance are centred there), and a one-line note when it was
    moved or could not be. A rig measured from another origin (an imported dataset rig: the rear axle) is
    moved with its vehicle's axle position; one on a vehicle rigopt does not know keeps its own origin."""
    if rig.origin.is_benchmark:
        return rig, None
    vehicle = known_vehicle(rig)
    if vehicle is None:
        return rig, (f"{rig.name}: positions are measured from the {rig.origin.describe()} of {rig.vehicle!r}, which "
                     "rigopt does not know; kept with that point as the ego origin")
    moved, change = to_vehicle_centre(rig, vehicle)
    return moved, change.describe()


def benchmark_rig_lookup(folders=None, note: Callable[[str], None] = lambda message: None) -> Callable[[str], Rig]:
    """``lookup(name)``: the rig of measured transfer results named ``name``, as the benchmark measured it: the
    file ``<name>.json`` in one of ``folders`` (a folder or a sequence of them; the first folder holding one wins,
    within a folder the shallowest file) or a folder below it, else the library rig; moved to its vehicle's
    centre (:func:`in_vehicle_frame`, ``note`` told of each move), the frame ``rigopt bench generate`` renders
    in. Each rig is loaded once.

    A folder that is missing or a file is refused at once (``calibrate --rigs``); a name found nowhere raises
    UnknownNameError saying that the results name a rig rigopt does not know and that ``--rigs`` gives it.
    """
    from pathlib import Path

    from rigopt.output import existing_folder
    from rigopt.rig.library import load_rig, rig_names

    if folders is None:
        folders = ()
    elif isinstance(folders, (str, Path)):
        folders = (folders,)
    folders = tuple(existing_folder(folder, "the rig files (<rig>.json) the results were measured with",
                                    option="--rigs") for folder in folders)
    files: dict[str, Path] = {}  # rig name -> its file: the first folder's, the shallowest of equal names
    for folder in folders:
        for path in sorted(folder.rglob("*.json"), key=lambda path: len(path.parts)):
            files.setdefault(path.stem, path)
    loaded: dict[str, Rig] = {}

    def lookup(name: str) -> Rig:
        if name not in loaded:
            try:
                rig = load_rig(files[name]) if name in files else load_rig(name)
            except UnknownNameError:
                raise _unknown_result_rig(name, folders, rig_names()) from None
            loaded[name], moved = in_vehicle_frame(rig)
            if moved:
                note(moved)
        return loaded[name]
    return lookup


def _unknown_result_rig(name: str, folders: tuple, library: list[str]) -> UnknownNameError:
    """The error for a rig of measured transfer found neither in the ``folders`` (``--rigs``) nor the library."""
    library = ", ".join(library)
    if not folders:
        return UnknownNameError(
            f"the results name rig {name!r}, which rigopt does not know: it is no library rig ({library}); give "
            f"--rigs FOLDER, the folder of the rig files the results were measured with ({name}.json in it or below "
            "it; e.g. --rigs measurements/rigs, whose real/ holds the real datasets' rigs)")
    shown = " ".join(f"--rigs {folder}" for folder in folders)
    return UnknownNameError(
        f"the results name rig {name!r}, which rigopt does not know: there is no {name}.json in or below {shown}, "
        f"and it is no library rig ({library}); add --rigs with the folder holding {name}.json (--rigs may be "
        "given several times)")
