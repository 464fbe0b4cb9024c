"""The command line stays quick to start: importing it (what ``rigopt --help`` does) loads no heavy library."""

import subprocess
import sys

HEAVY = ("numpy", "scipy", "cvxpy", "casadi", "trimesh", "matplotlib", "torch", "pyarrow", "plotly")


def test_importing_the_command_line_loads_no_heavy_library():
    code = f"import sys, rigopt.cli; print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "", f"import rigopt.cli loaded {loaded}: import it inside the command that needs it"
