"""A CAD shape as a triangle mesh (for ``align ... out.stl`` and the tests' cross-check)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["tessellate"]


def tessellate(shape: Any, deflection: float, *, angle: float = 0.1
               ) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (n, 3) float64 in the shape's unit and frame, faces (m, 3) int64 wound
    outward). ``deflection``: the largest chord distance from the exact surface (shape unit);
    ``angle``: the largest angle between neighbouring normals, radians. Shared edges give
    coinciding vertices (not merged here: the mesh reader's weld identifies them)."""
    # optional extra: OCP is imported only once a CAD file is read
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    BRepMesh_IncrementalMesh(shape, deflection, False, angle, True)
    points, triangles, offset = [], [], 0
    explorer = TopExp_Explorer(shape, TopAbs_FACE)
    while explorer.More():
        face = TopoDS.Face(explorer.Current())
        location = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(face, location)
        explorer.Next()
        if tri is None:
            continue
        trsf = location.Transformation()
        n = tri.NbNodes()
        pts = np.empty((n, 3))
        for i in range(n):
            p = tri.Node(i + 1).Transformed(trsf)
            pts[i] = (p.X(), p.Y(), p.Z())
        idx = np.empty((tri.NbTriangles(), 3), dtype=np.int64)
        for i in range(tri.NbTriangles()):
            idx[i] = tri.Triangle(i + 1).Get()
        idx -= 1
        if face.Orientation() == TopAbs_REVERSED:
            idx = idx[:, ::-1]
        points.append(pts)
        triangles.append(idx + offset)
        offset += n
    if not points:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    return np.concatenate(points), np.concatenate(triangles)
