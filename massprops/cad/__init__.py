"""CAD parts (STEP, IGES, BREP): exact mass properties of boundary-representation solids.

Reading goes through OpenCASCADE (the optional extra ``massprops[cad]``, the
``cadquery-ocp-novtk`` wheel, or ``cadquery-ocp``: import name ``OCP`` for both), which is
imported only when a CAD file is read: importing this package costs nothing and mesh commands
never load the ~0.8 s kernel.

Modules: ``occ`` (the kernel import and its missing-extra error), ``read`` (files to solids with
names, assembly paths, placements and units), ``sew`` (loose faces, as IGES face mode writes
them, sewn into closed solids), ``labels`` (names, colours, materials), ``faces`` (the face
census and an area bound), ``integrate`` (one solid about a local origin, with its error
bars), ``freeform``, ``nurbs``, ``planar`` and ``trimmed`` (free-form faces by our rules: per
knot span on untrimmed faces, Green's theorem along a plane's edges and in a trimmed face's
parameters),
``shell`` (``--shell T``: faces as a wall's mid-surface), ``inspect`` (per-solid results,
densities by name, the total), ``write`` (align: exact geometry moved into the principal
frame, or tessellated), ``tessellate`` (a shape as triangles).
"""

from __future__ import annotations

CAD_EXTENSIONS = (".step", ".stp", ".iges", ".igs", ".brep")
"""File extensions read as CAD parts (case-insensitive)."""


def is_cad_path(path: object) -> bool:
    """True when ``path`` (a str or PathLike) names a CAD file by its extension."""
    import os  # a stdlib module, kept local so the package's namespace stays this small

    return isinstance(path, (str, os.PathLike)) and os.fspath(path).lower().endswith(
        CAD_EXTENSIONS)


__all__ = ["CAD_EXTENSIONS", "is_cad_path"]
