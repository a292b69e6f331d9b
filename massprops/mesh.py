"""The Mesh value object: vertices, triangles, and how the triangles came from the file's faces."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangulated surface, as read from a file.

    vertices : (n, 3) float64, metres (``--unit`` already applied), the mesh's own frame.
    faces : (m, 3) int64, 0-based vertex indices; counter-clockwise seen from outside, so the
        right-hand normal points out of the solid.
    polygon_sizes : (p,) int64 or None. None when every face of the file was a triangle. Else the
        file's i-th face had ``polygon_sizes[i]`` vertices and was fan-triangulated in order into
        ``polygon_sizes[i] - 2`` consecutive rows of ``faces``: (v0, v1, v2), (v0, v2, v3), ...
        Writers use it to give back the file's polygons unchanged; the fan is also the surface
        the integral uses for a non-planar polygon.
    coordinate_dtype : the precision the file stored coordinates in; float32 (binary STL) makes
        the mass properties carry an input uncertainty from the coordinates alone.
    coordinate_scale : the ``--unit`` factor applied (file unit -> metre); the float32 rounding
        happened before it, so it scales that uncertainty too.
    name : what to call the mesh in messages and reports (usually the path).
    """

    vertices: np.ndarray
    faces: np.ndarray
    polygon_sizes: np.ndarray | None = None
    coordinate_dtype: np.dtype = field(default_factory=lambda: np.dtype(np.float64))
    coordinate_scale: float = 1.0
    name: str = "<mesh>"

    def __post_init__(self) -> None:
        v, f = self.vertices, self.faces
        if v.ndim != 2 or v.shape[1] != 3 or v.dtype != np.float64:
            raise TypeError(f"Mesh.vertices must be (n, 3) float64, got {v.shape} {v.dtype}")
        if f.ndim != 2 or f.shape[1] != 3 or f.dtype != np.int64:
            raise TypeError(f"Mesh.faces must be (m, 3) int64, got {f.shape} {f.dtype}")

    @property
    def n_vertices(self) -> int:
        return int(self.vertices.shape[0])

    @property
    def n_faces(self) -> int:
        """Faces as the file has them (polygons count once)."""
        return int(self.faces.shape[0] if self.polygon_sizes is None else self.polygon_sizes.size)

    def polygons(self) -> list[np.ndarray]:
        """The file's faces as vertex-index arrays (triangles if it had only triangles)."""
        if self.polygon_sizes is None:
            return list(self.faces)
        out, row = [], 0
        for k in self.polygon_sizes.tolist():
            fan = self.faces[row : row + k - 2]
            out.append(np.concatenate([fan[0], fan[1:, 2]]))
            row += k - 2
        return out

    def with_vertices(self, vertices: np.ndarray, name: str | None = None) -> Mesh:
        """The same faces over new vertex positions (same shape)."""
        return Mesh(vertices, self.faces, self.polygon_sizes, self.coordinate_dtype,
                    self.coordinate_scale, self.name if name is None else name)

    def with_faces(self, faces: np.ndarray) -> Mesh:
        """The same vertices with re-wound faces (same count and fan layout)."""
        return Mesh(self.vertices, faces, self.polygon_sizes, self.coordinate_dtype,
                    self.coordinate_scale, self.name)


def fan_triangulate(polygons: list[np.ndarray] | list[list[int]]
                    ) -> tuple[np.ndarray, np.ndarray | None]:
    """Fan-triangulate polygons: (faces (m, 3) int64, polygon_sizes or None if all triangles).

    Polygons need >= 3 vertices; reporting shorter ones is the reader's job.
    """
    sizes = np.fromiter((len(p) for p in polygons), dtype=np.int64, count=len(polygons))
    if sizes.size and (sizes == 3).all():
        return np.asarray(polygons, dtype=np.int64).reshape(-1, 3), None
    tris = []
    for p in polygons:
        p = np.asarray(p, dtype=np.int64)
        k = p.size
        t = np.empty((k - 2, 3), dtype=np.int64)
        t[:, 0] = p[0]
        t[:, 1] = p[1:-1]
        t[:, 2] = p[2:]
        tris.append(t)
    faces = np.concatenate(tris) if tris else np.empty((0, 3), dtype=np.int64)
    return faces, sizes
