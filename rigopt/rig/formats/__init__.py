"""Rig calibration formats of datasets and tools, both ways (see docs/formats.md): one module per format.

catalogue.py holds the formats as plain data (names, import options, export targets; light, for the command
line's help) and registry.py binds each to its reader and writer (``FORMATS``, ``find_format``, ``export_rig``).
Nothing is imported here, so that importing one format's module loads only what it needs.
"""
