"""A ROS URDF of the rig: one link per camera under the root link and its ``<id>_optical_frame`` child.

Layout written (REP 103 axes, REP 105 ``base_link``)::

    <robot name="R1">
      <link name="base_link"/>
      <link name="CAM_FRONT"/>                         camera body frame: x along the optical axis, y left, z up
      <joint name="CAM_FRONT_joint" type="fixed">
        <parent link="base_link"/> <child link="CAM_FRONT"/> <origin xyz="x y z" rpy="roll pitch yaw"/>
      </joint>
      <link name="CAM_FRONT_optical_frame"/>           z along the optical axis, x right, y down
      <joint name="CAM_FRONT_optical_joint" type="fixed"> ... <origin xyz="0 0 0" rpy="-pi/2 0 -pi/2"/> </joint>
      <gazebo reference="CAM_FRONT">                   SDFormat camera: image size, FOV, intrinsics, distortion
        <sensor type="camera" name="CAM_FRONT"><camera>
          <horizontal_fov>rad</horizontal_fov> <image><width/><height/></image>
          <lens><intrinsics><fx/><fy/><cx/><cy/><s>0</s></intrinsics></lens>
          <distortion><k1/><k2/><k3/><p1/><p2/><center>cx/w cy/h</center></distortion>   (radtan lenses)
        </camera></sensor>
      </gazebo>
    </robot>

``base_link`` is rigopt's vehicle frame (ISO 8855 = REP 103 body axes). URDF rpy are fixed-axis roll, pitch,
yaw: ``R = Rz(yaw) Ry(pitch) Rx(roll)``. Reading walks the joints from the root link (every joint taken at
its origin) to each link a ``<gazebo>`` camera sensor refers to (a camera body link, or an optical frame
link); a camera without ``<lens><intrinsics>`` is the centred pinhole of its ``horizontal_fov`` (in (0, pi) rad);
with both, the intrinsics give the lens and ``horizontal_fov`` must agree with them (``FOV_AGREEMENT_DEG``). The
links and joints must form one tree: every joint between declared links, one parent per link, no loop. SDFormat has
no Kannala-Brandt fisheye, so fisheye lenses are refused on export. The robot name is the rig's name;
the vehicle and zones are not carried. base_link's place on the vehicle is not fixed by REP 105: the rig's
origin is the vehicle centre unless ``--origin`` says otherwise.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np

from rigopt.errors import RigFileError, RigoptError
from rigopt.geometry import body_from_optical, rotation_from_rpy, rpy_from_rotation
from rigopt.rig.formats.common import (Exported, Imported, format_number, make_camera, make_lens, make_rig, numbers,
                                       origin_note, read_text, warn_not_carried, warn_origin, whole_number)
from rigopt.rig.model import Rig, RigOrigin

OPTICAL_SUFFIX = "_optical_frame"
#: rpy of the fixed joint from a camera body link to its optical frame (REP 103).
OPTICAL_RPY = (-math.pi / 2, 0.0, -math.pi / 2)
#: With both <lens><intrinsics> and <horizontal_fov>, the FOV the intrinsics give and the one written must agree
#: within this (degrees): rounding in a hand-written file stays far below it, a different lens does not.
FOV_AGREEMENT_DEG = 0.5
FIX = "write a URDF with <gazebo reference=LINK><sensor type=\"camera\"> blocks (rigopt export --format urdf)"


def _text(values) -> str:
    return " ".join(format_number(v) for v in values)


def export_urdf(rig: Rig) -> Exported:
    """The URDF text of ``rig`` (key "" of the files) and warnings; refuses fisheye lenses."""
    fisheye = [c.id for c in rig.cameras if c.lens.distortion == "fisheye"]
    if fisheye:
        raise RigoptError(f"URDF/SDFormat cameras have no Kannala-Brandt fisheye model, so {', '.join(fisheye)} "
                          "cannot be written; export with --format opencv (Kalibr's equidistant) instead")
    robot = ElementTree.Element("robot", name=rig.name)
    ElementTree.SubElement(robot, "link", name="base_link")
    for camera in rig.cameras:
        optical = camera.id + OPTICAL_SUFFIX
        ElementTree.SubElement(robot, "link", name=camera.id)
        _joint(robot, f"{camera.id}_joint", "base_link", camera.id, camera.position, rpy_from_rotation(camera.rotation))
        ElementTree.SubElement(robot, "link", name=optical)
        _joint(robot, f"{camera.id}_optical_joint", camera.id, optical, (0.0, 0.0, 0.0), OPTICAL_RPY)
        lens = camera.lens
        gazebo = ElementTree.SubElement(robot, "gazebo", reference=camera.id)
        sensor = ElementTree.SubElement(gazebo, "sensor", type="camera", name=camera.id)
        element = ElementTree.SubElement(sensor, "camera")
        ElementTree.SubElement(element, "horizontal_fov").text = format_number(math.radians(camera.fov))
        image = ElementTree.SubElement(element, "image")
        ElementTree.SubElement(image, "width").text = str(lens.width)
        ElementTree.SubElement(image, "height").text = str(lens.height)
        intrinsics = ElementTree.SubElement(ElementTree.SubElement(element, "lens"), "intrinsics")
        for key in ("fx", "fy", "cx", "cy"):
            ElementTree.SubElement(intrinsics, key).text = format_number(getattr(lens, key))
        ElementTree.SubElement(intrinsics, "s").text = "0.0"
        if lens.distortion == "radtan":
            distortion = ElementTree.SubElement(element, "distortion")
            for key, value in zip(("k1", "k2", "p1", "p2", "k3"), lens.coefficients):
                ElementTree.SubElement(distortion, key).text = format_number(value)
            ElementTree.SubElement(distortion, "center").text = _text([lens.cx / lens.width, lens.cy / lens.height])
    ElementTree.indent(robot, space="  ")
    text = '<?xml version="1.0"?>\n' + ElementTree.tostring(robot, encoding="unicode") + "\n"
    warnings = warn_origin(rig, "A URDF's base_link", "vehicle_centre")
    warnings += warn_not_carried(rig, "A URDF", carries_name=True, carries_vehicle=False)
    return Exported({"": text}, warnings)


def _joint(robot, name: str, parent: str, child: str, xyz, rpy) -> None:
    joint = ElementTree.SubElement(robot, "joint", name=name, type="fixed")
    ElementTree.SubElement(joint, "parent", link=parent)
    ElementTree.SubElement(joint, "child", link=child)
    ElementTree.SubElement(joint, "origin", xyz=_text(xyz), rpy=_text(rpy))


# ------------------------------------------------------------------------------------------------ reading


def read_urdf(path, name: str | None = None, vehicle: str = "urdf", origin: RigOrigin | None = None) -> Imported:
    """Read the cameras of a URDF (see the module docstring); name default: the robot's name."""
    path = Path(path)
    text = read_text(path, "URDF", FIX)
    try:
        robot = ElementTree.fromstring(text)
    except ElementTree.ParseError as error:
        raise RigFileError(f"{path}: not valid XML ({error}); {FIX}") from None
    if robot.tag != "robot":
        raise RigFileError(f"{path}: the root element is <{robot.tag}>, a URDF's is <robot>; {FIX}")
    links, parent_of = _tree(robot, path)
    cameras = []
    for gazebo in robot.findall("gazebo"):
        sensor = gazebo.find("sensor")
        if sensor is None or sensor.get("type") not in ("camera", "depth", "wideanglecamera"):
            continue
        link = gazebo.get("reference")
        where = f"{path}: <gazebo reference={link!r}>"
        if link not in links:
            raise RigFileError(f"{where} refers to no <link>; name one of the robot's links")
        pose = _pose_of(link, parent_of)
        camera_id = link
        if link.endswith(OPTICAL_SUFFIX):  # the sensor sits on the optical frame: back to the body frame
            pose[:3, :3] = body_from_optical(pose[:3, :3])
            camera_id = link[: -len(OPTICAL_SUFFIX)]
        lens = _lens(sensor.find("camera"), where)
        cameras.append(make_camera(where, camera_id, pose[:3, 3], pose[:3, :3], lens))
    if not cameras:
        raise RigFileError(f"{path}: no <gazebo reference=...> block holds a <sensor type=\"camera\">; "
                           f"a rig needs at least one camera; {FIX}")
    origin = origin or RigOrigin()
    why = "--origin" if origin.kind != "vehicle_centre" else "assumed for base_link; set it with --origin"
    rig = make_rig(str(path), name or robot.get("name") or path.stem, vehicle, cameras, origin)
    return Imported(rig, (origin_note(origin, why),))


def _tree(robot, path: Path) -> tuple[list[str], dict]:
    """The declared link names, and child link -> (parent link, (4, 4) joint transform) of every joint, checked to
    be one tree: links named once, every joint between declared links, one parent per link, no loop, one root."""
    links = []
    for link in robot.findall("link"):
        name = link.get("name")
        if not name:
            raise RigFileError(f"{path}: a <link> has no name; give every link name=\"...\"")
        if name in links:
            raise RigFileError(f"{path}: link {name!r} is declared twice; a URDF names each link once")
        links.append(name)
    parent_of, joint_of = {}, {}
    for joint in robot.findall("joint"):
        name = joint.get("name", "?")
        where = f"{path}: joint {name!r}"
        parent, child = joint.find("parent"), joint.find("child")
        if parent is None or child is None or not parent.get("link") or not child.get("link"):
            raise RigFileError(f"{where} needs <parent link=...> and <child link=...>")
        for role, link in (("parent", parent.get("link")), ("child", child.get("link"))):
            if link not in links:
                raise RigFileError(f"{where}: its {role} link {link!r} is not a declared <link>; add <link "
                                   f"name=\"{link}\"/> or name one of the robot's links")
        child_link = child.get("link")
        if child_link in parent_of:
            raise RigFileError(f"{where}: link {child_link!r} has two parents (joint {joint_of[child_link]!r} gives it "
                               f"{parent_of[child_link][0]!r}, this one {parent.get('link')!r}); a URDF is a tree, "
                               "each link the child of one joint")
        parent_of[child_link] = (parent.get("link"), _origin(joint.find("origin"), where))
        joint_of[child_link] = name
    for link in links:
        seen = [link]
        while seen[-1] in parent_of:
            up = parent_of[seen[-1]][0]
            if up in seen:
                loop = seen[seen.index(up):] + [up]
                raise RigFileError(f"{path}: the joints form a loop: {' -> '.join(reversed(loop))} (parent to "
                                   "child); a URDF is a tree, remove one of those joints")
            seen.append(up)
    roots = [link for link in links if link not in parent_of]
    if len(roots) != 1:
        raise RigFileError(f"{path}: a URDF has one root link, found {len(roots)} ({', '.join(roots[:5])}); "
                           "join every camera link to base_link")
    return links, parent_of


def _origin(element, where: str) -> np.ndarray:
    """(4, 4) transform of a joint's <origin xyz rpy> (identity when absent)."""
    t = np.eye(4)
    if element is None:
        return t
    values = []
    for key in ("xyz", "rpy"):
        words = (element.get(key) or "0 0 0").split()
        try:
            parsed = [float(w) for w in words]
        except ValueError:
            parsed = words
        values.append(numbers(parsed, (3,), f"{where} <origin {key}>"))
    t[:3, :3] = rotation_from_rpy(*values[1])
    t[:3, 3] = values[0]
    return t


def _pose_of(link: str, parent_of: dict) -> np.ndarray:
    """(4, 4) pose of ``link`` in the root link's frame: the joint transforms from the root down (a tree, checked
    by :func:`_tree`)."""
    pose = np.eye(4)
    while link in parent_of:
        link, t = parent_of[link]
        pose = t @ pose
    return pose


def _number(element, key: str, where: str, default=None) -> float:
    child = element.find(key) if element is not None else None
    if child is None or child.text is None:
        if default is None:
            raise RigFileError(f"{where}: missing <{key}>; {FIX}")
        return default
    try:
        value = float(child.text)
    except ValueError:
        raise RigFileError(f"{where}: <{key}> must be a number, got {child.text.strip()!r}") from None
    return numbers([value], (1,), f"{where} <{key}>")[0]


def _lens(camera, where: str):
    if camera is None:
        raise RigFileError(f"{where}: the sensor has no <camera> element; {FIX}")
    image = camera.find("image")
    width = whole_number(_number(image, "width", f"{where} <image>"), f"{where} <image><width>")
    height = whole_number(_number(image, "height", f"{where} <image>"), f"{where} <image><height>")
    intrinsics = camera.find("lens/intrinsics")
    hfov = None
    if intrinsics is None or camera.find("horizontal_fov") is not None:
        hfov = _number(camera, "horizontal_fov", where)
        if not 0.0 < hfov < math.pi:
            raise RigFileError(f"{where}: <horizontal_fov> must be in (0, pi) radians for a pinhole camera "
                               f"(0 to 180 degrees, not reached), got {hfov:g}")
    if intrinsics is not None:
        fx, fy, cx, cy = (_number(intrinsics, k, f"{where} <lens><intrinsics>") for k in ("fx", "fy", "cx", "cy"))
        if _number(intrinsics, "s", where, default=0.0) != 0.0:
            raise RigFileError(f"{where}: <lens><intrinsics><s> (skew) must be 0; rigopt's lenses have no skew")
    else:
        fx = fy = width / (2.0 * math.tan(hfov / 2.0))
        cx, cy = width / 2.0, height / 2.0
    distortion = camera.find("distortion")
    if distortion is None:
        lens = make_lens(where, width, height, fx, fy, cx, cy)
    else:
        coefficients = [_number(distortion, k, f"{where} <distortion>", default=0.0)
                        for k in ("k1", "k2", "p1", "p2", "k3")]
        lens = make_lens(where, width, height, fx, fy, cx, cy, "radtan", coefficients)
    if intrinsics is not None and hfov is not None:
        _check_fov_agrees(lens, hfov, where)
    return lens


def _check_fov_agrees(lens, hfov: float, where: str) -> None:
    """With both <lens><intrinsics> and <horizontal_fov>, the intrinsics give the lens; the FOV must agree with it
    within FOV_AGREEMENT_DEG: with the lens's own (distortion included, what rigopt export writes) or with the
    undistorted pinhole's of fx and cx (what a simulator derives from the intrinsics)."""
    pinhole = math.degrees(math.atan(lens.cx / lens.fx) + math.atan((lens.width - lens.cx) / lens.fx))
    given = math.degrees(hfov)
    if min(abs(given - lens.hfov), abs(given - pinhole)) > FOV_AGREEMENT_DEG:
        raise RigFileError(f"{where}: <horizontal_fov> {hfov:g} rad ({given:.2f} deg) disagrees with "
                           f"<lens><intrinsics>, whose fx {lens.fx:g} and cx {lens.cx:g} on {lens.width} px give "
                           f"{pinhole:.2f} deg; rigopt takes the intrinsics: fix <horizontal_fov> to match them, or "
                           "drop <lens><intrinsics> to use the FOV's centred pinhole")
