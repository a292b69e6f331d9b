"""Mesh files: ``read_mesh`` and ``write_mesh`` over a registry of formats, and the length units.

One module per format family (``obj``, ``stl``, ``vf``, ``off``, ``ply_off`` writers,
``fallback`` for everything meshio or trimesh reads); ``registry.FORMATS`` lists them, one line
each, and the CLI's choices derive from it. meshio and trimesh are imported only when a fallback
format is read.
"""

from __future__ import annotations

from massprops.io.dispatch import read_mesh, unit_scale, write_mesh
from massprops.io.registry import (
    FORMATS,
    UNITS,
    Format,
    input_formats,
    output_formats,
)

__all__ = [
    "FORMATS",
    "UNITS",
    "Format",
    "input_formats",
    "output_formats",
    "read_mesh",
    "unit_scale",
    "write_mesh",
]
