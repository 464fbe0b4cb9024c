"""Rig calibration formats of datasets and tools, both ways (see docs/formats.md).

Readers return :class:`~rigopt.rig.formats.common.Imported` (the rig and stderr notes: its origin first);
writers return :class:`~rigopt.rig.formats.common.Exported` (files and warnings for what the format cannot
carry) or raise a RigoptError when a camera cannot be written at all.
"""

#: Formats ``rigopt import`` reads and ``rigopt export`` writes.
IMPORT_FORMATS = ("nuscenes", "argoverse1", "argoverse2", "dgp", "waymo", "opencv", "urdf", "carla")
EXPORT_FORMATS = ("nuscenes", "urdf", "opencv", "carla")
#: What ``rigopt export --out`` is for each format: a folder, or a file with one of these extensions.
EXPORT_SUFFIXES = {"nuscenes": None, "urdf": (".urdf", ".xml"), "opencv": (".yaml", ".yml"), "carla": (".json",)}
#: The origin each format's readers assume (``rigopt export`` converts to it when it knows the rig's vehicle).
EXPORT_ORIGINS = {"nuscenes": "rear_axle", "urdf": "vehicle_centre", "opencv": "vehicle_centre",
                  "carla": "vehicle_centre"}


def export_rig(rig, format_name: str):
    """The :class:`Exported` files and warnings of ``rig`` in ``format_name`` (one of EXPORT_FORMATS)."""
    if format_name == "nuscenes":
        from rigopt.rig.formats.nuscenes import export_nuscenes
        return export_nuscenes(rig)
    if format_name == "urdf":
        from rigopt.rig.formats.urdf import export_urdf
        return export_urdf(rig)
    if format_name == "opencv":
        from rigopt.rig.formats.opencv import export_opencv
        return export_opencv(rig)
    if format_name == "carla":
        from rigopt.rig.formats.carla import export_carla
        return export_carla(rig)
    from rigopt.errors import unknown_name
    raise unknown_name("export format", format_name, list(EXPORT_FORMATS))
