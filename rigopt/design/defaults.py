"""The designer's default grid and catalogue as plain numbers: importable without numpy, so that the command
line can show them in ``--help`` at once (:mod:`rigopt.design.settings` builds the settings from them)."""

#: Horizontal FOVs (deg) of the default catalogue's pinholes: the published design's.
DEFAULT_LENSES = (60.0, 65.0, 70.0, 75.0, 80.0, 90.0, 100.0, 110.0, 120.0)
#: Pitch angles (deg, > 0 up) of the orientation grid.
DEFAULT_PITCHES_DEG = (-20.0, -10.0, 0.0, 10.0)
#: Step (deg) of the yaw grid, from -180 deg.
DEFAULT_YAW_STEP_DEG = 10.0
#: Step (deg) of the discrete lenses that seed a continuous FOV range.
RANGE_STEP = 10.0
#: The benchmark's image size (width, height) px, as ``rigopt.rig.model.DEFAULT_IMAGE_SIZE`` (tested equal).
BENCHMARK_IMAGE_SIZE = (1280, 720)
#: Branch-and-bound nodes the selection MILP may explore (``--max-nodes``): a work limit, never a clock, so that
#: the same input gives the same design on any machine at any load.
DEFAULT_MAX_NODES = 20000
