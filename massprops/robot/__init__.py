"""Robot descriptions: inertials of URDF links, SDF links and MJCF bodies from their geometry.

Pipeline: `xmltree` (expat, keeps line numbers and byte spans) -> one parser per format
(`urdf`, `sdf`, `mjcf`; `poses` for each format's orientations, `uris` for package:// and
model://) -> the neutral `model` (links, stated inertials, geometries in the link frame) ->
`combine` (meshes by massprops' exact integral, `primitives` by closed forms, placed and summed)
-> `compare` (stated against computed, physical validity) -> `analyze` (the per-link report, the
CLI's one call) -> `elements` (each format's ``<inertial>``) and `writeback` (in-place edits).

Nothing here is imported by ``massprops inspect`` unless it prints an element
(``--format urdf|sdf|mjcf``, which loads `elements` alone).
"""

from __future__ import annotations

__all__ = ["analyze_model", "load_model", "ModelReport", "LinkReport", "WRITERS"]


def __getattr__(name: str):
    # lazy: `import massprops.robot.elements` must not pull in the parsers and the mesh code
    if name in ("analyze_model", "load_model", "ModelReport", "LinkReport"):
        from massprops.robot import analyze  # lazy, as above

        return getattr(analyze, name)
    if name == "WRITERS":
        from massprops.robot.elements import WRITERS  # lazy, as above

        return WRITERS
    raise AttributeError(f"module 'massprops.robot' has no attribute {name!r}")
