"""The mesh layer: the `Mesh` value and everything known about a closed surface without reading a
file or repairing it.

    value      the Mesh value object (vertices, triangles, polygon layout, source precision)
    weld       vertices identified by exact coordinates; the round-off near weld
    topology   edge uses, connected components, consistent winding (welded ids)
    geometry   signed volumes, area vectors, exact flatness, winding numbers
    pieces     the surface cut at non-manifold edges (shared by the health check and the repairs)
    nesting    which pieces are solids, cavities, inverted parts or overlaps
    boundary   the boundary loops of an open mesh, for the refusal
    overlap    the volume overlapping pieces share (manifold3d, only when they overlap)
    health     the checks and what has one right answer repaired (`prepare_mesh`)
    facesums   the blocked pass over the faces (fast or double-double determinants)
    integral   `MassProperties`: the exact integral about a local origin and its error bars

Importing the package loads `Mesh` only (numpy); each module is imported where it is used.
"""

from massprops.mesh.value import Mesh

__all__ = ["Mesh"]
