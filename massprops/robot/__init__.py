"""Robot descriptions: inertials of URDF links, SDF links and MJCF bodies from their geometry,
and the description as a mechanism (its joints and link poses).

Sub-packages, in the order data flows:

- `formats`: `xmltree` (expat, keeps line numbers and byte spans) -> one parser per format
  (`urdf`, `sdf`, `mjcf`; `poses` for each format's orientations, `uris` for package:// and
  model://, `xacro_run`, MuJoCo's `msh`) -> the neutral `model` (links, stated inertials,
  geometries in the link frame);
- `inertials`: `combine` (meshes by massprops' exact integral, `primitives` by closed forms,
  placed and summed) -> `compare` (stated against computed, physical validity), `rules` (MJCF
  compiler bounds); `analyze` is the per-link report, the `model` command's one call;
- `write`: `elements` (each format's ``<inertial>``) and `writeback` (in-place edits);
- `joints`: the joints and link poses at the zero pose per format; `mechanism.read_mechanism`
  picks the reader (the systems engine, dynamics/systems/description.py, makes bodies of them).

Nothing here is imported by ``massprops inspect`` unless it prints an element
(``--format urdf|sdf|mjcf``, which loads `write.elements` alone).
"""

from __future__ import annotations

__all__ = ["analyze_model", "load_model", "ModelReport", "LinkReport", "WRITERS"]


def __getattr__(name: str):
    # lazy: `import massprops.robot.write.elements` must not pull in the parsers and the mesh code
    if name in ("analyze_model", "load_model", "ModelReport", "LinkReport"):
        from massprops.robot import analyze  # lazy, as above

        return getattr(analyze, name)
    if name == "WRITERS":
        from massprops.robot.write.elements import WRITERS  # lazy, as above

        return WRITERS
    raise AttributeError(f"module 'massprops.robot' has no attribute {name!r}")
