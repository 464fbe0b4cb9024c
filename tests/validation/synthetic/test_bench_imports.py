"""The benchmark package stands below the torch baselines: importing any of its modules loads neither
``rigopt.validation.detectors`` nor torch (checked in a fresh interpreter, so nothing imported by other tests counts)."""

from __future__ import annotations

import pkgutil
import subprocess
import sys

import pytest

import rigopt.validation.synthetic


@pytest.mark.slow
def test_no_bench_module_imports_the_baselines_or_torch():
    modules = sorted(f"rigopt.validation.synthetic.{m.name}" for m in pkgutil.iter_modules(rigopt.validation.synthetic.__path__))
    assert "rigopt.validation.synthetic.evaluation" in modules
    script = ("import importlib, sys\n"
              f"for name in {modules!r}:\n"
              "    importlib.import_module(name)\n"
              "print(sorted(m for m in sys.modules if m == 'torch' or m.startswith(('torch.', 'rigopt.validation.detectors'))))")
    shown = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True).stdout
    assert shown.strip() == "[]"
