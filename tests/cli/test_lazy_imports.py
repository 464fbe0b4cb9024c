"""The command line stays quick to start: importing it (what ``rigopt --help`` does) loads no heavy library."""

import subprocess
import sys

HEAVY = ("numpy", "scipy", "cvxpy", "casadi", "trimesh", "matplotlib", "torch", "pyarrow", "plotly")


def test_importing_the_command_line_loads_no_heavy_library():
    code = f"import sys, rigopt.cli; print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "", f"import rigopt.cli loaded {loaded}: import it inside the command that needs it"


def test_listing_the_rig_library_loads_neither_scipy_nor_numba():
    """``rigopt rigs`` reads 14 rig files and their RigV: closed-form rotations and plain numpy, no scipy Rotation
    and no compiled pair kernels (they load when rotations are converted through scipy or rig pairs matched)."""
    code = ("import sys; sys.argv = ['rigopt', 'rigs', '--json']; from rigopt.cli import main\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "print('LOADED', ','.join(m for m in ('scipy', 'numba') if m in sys.modules), file=sys.stderr)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.startswith("[")  # the listing ran
    assert done.stderr.strip().splitlines()[-1] == "LOADED"
