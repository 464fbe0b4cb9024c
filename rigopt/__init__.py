"""rigopt: design automotive camera rigs that a camera-only 3D detector transfers to.

The Python API in one place; see docs/index.md.
"""

from rigopt.errors import DataError, RigFileError, RigoptError, UnknownNameError
from rigopt.metrics.calibration import Calibration, load_weights
from rigopt.metrics.ranking import predict_transfer, rank_candidates
from rigopt.metrics.rigcd import RigBatch, RigCDBreakdown, RigCDMatrix, rigcd, rigcd_matrix, rigcd_pairs
from rigopt.metrics.rigv import RigVBreakdown, rigv
from rigopt.rig.library import load_rig, rig_names
from rigopt.rig.model import Camera, Rig
from rigopt.rig.pccr_format import read_rig, write_rig

__version__ = "0.1.0"

__all__ = [
    "Calibration", "Camera", "DataError", "Rig", "RigBatch", "RigCDBreakdown", "RigCDMatrix", "RigFileError",
    "RigVBreakdown", "RigoptError", "UnknownNameError", "load_rig", "load_weights", "predict_transfer",
    "rank_candidates", "read_rig", "rig_names", "rigcd", "rigcd_matrix", "rigcd_pairs", "rigv", "write_rig",
]
