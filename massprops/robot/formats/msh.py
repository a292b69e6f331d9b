"""MuJoCo's binary mesh format ``.msh`` (an MJCF asset; not GMSH's ``.msh``)."""

from __future__ import annotations

import numpy as np

from massprops.errors import MeshFileError
from massprops.files import read_input

__all__ = ["read_msh"]


def read_msh(entry: dict) -> None:
    """MuJoCo's own binary ``.msh`` (not GMSH): the counts nvertex, nnormal, ntexcoord, nface
    (int32), then float32 positions (3 each), normals (3), texture coordinates (2) and int32
    faces (3 each); the size must be exactly 16 + 12 (nvertex + nnormal + nface) + 8 ntexcoord
    bytes (MuJoCo XML reference, mesh/file). Sets the entry's inline vertices and faces, or its
    problem."""
    path = entry["path"]
    try:
        raw = read_input(path, what="a MuJoCo .msh mesh")
    except MeshFileError as exc:
        entry["problem"] = exc.template
        return
    if len(raw) < 16:
        entry["problem"] = f"{path}: too short for MuJoCo's .msh format"
        return
    nv, nn, nt, nf = (int(x) for x in np.frombuffer(raw[:16], dtype="<i4"))
    if min(nv, nn, nt, nf) < 0 or len(raw) != 16 + 12 * (nv + nn + nf) + 8 * nt:
        entry["problem"] = (f"{path}: not a MuJoCo .msh file (its size does not match its "
                            "counts); re-export it as STL or OBJ")
        return
    if nf == 0:
        entry["problem"] = (f"{path}: a .msh without faces is MuJoCo's convex hull of its "
                            "points: not supported")
        return
    at = 16
    vertices = np.frombuffer(raw, dtype="<f4", count=3 * nv, offset=at).astype(np.float64)
    at += 12 * (nv + nn) + 8 * nt
    faces = np.frombuffer(raw, dtype="<i4", count=3 * nf, offset=at).astype(np.int64)
    if faces.min() < 0 or faces.max() >= nv:
        entry["problem"] = f"{path}: a face indexes beyond the {nv} vertices"
        return
    entry["vertices"], entry["faces"] = vertices.reshape(-1, 3), faces.reshape(-1, 3)
    entry["uri"] = str(path)
