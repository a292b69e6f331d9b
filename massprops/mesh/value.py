"""The Mesh value object: vertices, triangles, and how the triangles came from the file's faces."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

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
    vertex_displacement : m, how far (per axis) any vertex may lie from where the file put it:
        0.0 as read; set when the health checks weld the two sides of a round-off crack. The
        ``input`` error bar of the mass properties covers it.
    notes : what the reader skipped or changed on the way (one line each, e.g. OBJ polyline
        elements); reported as warnings.
    """

    vertices: np.ndarray
    faces: np.ndarray
    polygon_sizes: np.ndarray | None = None
    coordinate_dtype: np.dtype = field(default_factory=lambda: np.dtype(np.float64))
    coordinate_scale: float = 1.0
    name: str = "<mesh>"
    vertex_displacement: float = 0.0
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        v, f, sizes = self.vertices, self.faces, self.polygon_sizes
        if v.ndim != 2 or v.shape[1] != 3 or v.dtype != np.float64:
            raise TypeError(f"Mesh.vertices must be (n, 3) float64, got {v.shape} {v.dtype}")
        if f.ndim != 2 or f.shape[1] != 3 or f.dtype != np.int64:
            raise TypeError(f"Mesh.faces must be (m, 3) int64, got {f.shape} {f.dtype}")
        if sizes is not None and ((sizes < 3).any() or int((sizes - 2).sum()) != f.shape[0]):
            raise ValueError(f"Mesh.polygon_sizes (sum of sizes - 2 = {int((sizes - 2).sum())}) "
                             f"does not match the {f.shape[0]} triangles")

    @property
    def n_vertices(self) -> int:
        return int(self.vertices.shape[0])

    @property
    def n_faces(self) -> int:
        """Faces as the file has them (polygons count once)."""
        return int(self.faces.shape[0] if self.polygon_sizes is None else self.polygon_sizes.size)

    def polygons_flat(self) -> tuple[np.ndarray, np.ndarray]:
        """The file's faces as (flat (sum(sizes),) int64, sizes (p,) int64), winding kept.

        Inverse of `fan_triangulate`: each fan's first row gives (v0, v1, v2), every further row
        adds its last vertex.
        """
        faces = self.faces
        if self.polygon_sizes is None:
            return faces.reshape(-1), np.full(faces.shape[0], 3, dtype=np.int64)
        sizes = self.polygon_sizes
        n_tri = sizes - 2
        is_first = np.zeros(faces.shape[0], dtype=bool)
        is_first[np.cumsum(n_tri) - n_tri] = True
        emitted = np.where(is_first, 3, 1)  # values each row contributes to flat
        at = np.cumsum(emitted) - emitted
        flat = np.empty(int(emitted.sum()), dtype=np.int64)
        flat[at[is_first]] = faces[is_first, 0]
        flat[at[is_first] + 1] = faces[is_first, 1]
        flat[at + emitted - 1] = faces[:, 2]
        return flat, sizes

    def polygons(self) -> list[np.ndarray]:
        """The file's faces as a list of vertex-index arrays (for small meshes and tests)."""
        flat, sizes = self.polygons_flat()
        return np.split(flat, np.cumsum(sizes)[:-1])

    def with_vertices(self, vertices: np.ndarray, name: str | None = None) -> Mesh:
        """The same faces over new vertex positions (same shape)."""
        return replace(self, vertices=vertices, name=self.name if name is None else name)

    def with_faces(self, faces: np.ndarray) -> Mesh:
        """The same vertices with re-wound faces (same count and fan layout)."""
        return replace(self, faces=faces)


def fan_triangulate(flat: np.ndarray, sizes: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray | None]:
    """Fan-triangulate polygons given as one flat index array, vectorised.

    flat : (sum(sizes),) int64, the polygons' vertex indices one after another.
    sizes : (p,) int64, vertices of each polygon, all >= 3 (reporting smaller ones is the
        reader's job).
    Returns (faces (sum(sizes - 2), 3) int64, polygon_sizes): None when every polygon is a
    triangle, else ``sizes`` — the layout `Mesh` documents.
    """
    flat = np.asarray(flat, dtype=np.int64)
    sizes = np.asarray(sizes, dtype=np.int64)
    if (sizes == 3).all():
        return flat.reshape(-1, 3), None
    first = np.cumsum(sizes) - sizes  # offset of each polygon's v0 in flat
    n_tri = sizes - 2
    polygon = np.repeat(np.arange(sizes.size), n_tri)
    # row r of polygon p is (v0, v_k, v_k+1) with k = 1 + (r - first row of p)
    k = 1 + np.arange(polygon.size) - np.repeat(np.cumsum(n_tri) - n_tri, n_tri)
    base = first[polygon]
    faces = np.stack([flat[base], flat[base + k], flat[base + k + 1]], axis=1)
    return faces, sizes.copy()
