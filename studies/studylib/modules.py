"""Another study's module, loaded from its file under a name of its own (several studies have an ``analysis.py``)."""

import importlib.util
from pathlib import Path


def study_module(name: str, path: Path):
    """The module at ``path``, loaded as ``name``."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
