"""Regenerate the bundled sample meshes (python sample_meshes/generate.py).

Every shape here has closed-form mass properties, written out in sample_meshes/README.md and
checked by tests/test_samples.py from the formulas (not from this program's output).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from massprops.io import write_mesh
from massprops.mesh import Mesh
from massprops.mesh.value import fan_triangulate

HERE = Path(__file__).resolve().parent

# Quads of an axis-aligned box with corners indexed by bits (x, y, z): index = x + 2y + 4z,
# counter-clockwise seen from outside.
BOX_QUADS = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
BOX_TRIANGLES = [t for a, b, c, d in BOX_QUADS for t in ([a, b, c], [a, c, d])]


def box_vertices(size: tuple[float, float, float], center=(0.0, 0.0, 0.0)) -> np.ndarray:
    bits = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=np.float64)
    return (bits - 0.5) * np.asarray(size) + np.asarray(center)


def rot_z(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def mesh(vertices, polygons, name: str) -> Mesh:
    sizes = np.array([len(p) for p in polygons])
    faces, sizes = fan_triangulate(np.concatenate([np.asarray(p) for p in polygons]), sizes)
    return Mesh(np.asarray(vertices, dtype=np.float64), faces, sizes, name=name)


def notes_cuboid() -> Mesh:
    """The notes' slide-14 example: 3×2×2 cuboid centred at the origin, turned 30° about z."""
    return mesh(box_vertices((3.0, 2.0, 2.0)) @ rot_z(30.0).T, BOX_TRIANGLES, "cuboid")


def cube() -> Mesh:
    """Unit cube [0, 1]³ with quad faces."""
    return mesh(box_vertices((1.0, 1.0, 1.0), (0.5, 0.5, 0.5)), BOX_QUADS, "cube")


def tetrahedron() -> Mesh:
    """Corner tetrahedron (0,0,0), (a,0,0), (0,b,0), (0,0,c) with a, b, c = 1, 2, 3."""
    v = [[0, 0, 0], [1, 0, 0], [0, 2, 0], [0, 0, 3]]
    return mesh(v, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], "tetrahedron")


def hexagonal_prism(n: int = 6, radius: float = 1.0, height: float = 2.0) -> Mesh:
    """Regular n-gon prism: circumradius ``radius`` in the xy-plane, z in [-h/2, h/2], n-gon
    caps."""
    ang = 2 * np.pi * np.arange(n) / n
    ring = np.stack([radius * np.cos(ang), radius * np.sin(ang)], axis=1)
    v = np.vstack([np.column_stack([ring, np.full(n, -height / 2)]),
                   np.column_stack([ring, np.full(n, height / 2)])])
    sides = [[i, (i + 1) % n, n + (i + 1) % n, n + i] for i in range(n)]
    return mesh(v, [list(range(n - 1, -1, -1)), list(range(n, 2 * n)), *sides], "prism")


def polyhedral_torus(n: int = 24, major: float = 2.0, half: float = 0.5) -> Mesh:
    """Square cross-section [R-a, R+a]×[-a, a] swept in n straight segments about z: every face is
    a planar trapezoid, so the solid is an exact polyhedron (see README for its closed form)."""
    section = [(major - half, -half), (major + half, -half), (major + half, half),
               (major - half, half)]  # counter-clockwise in the (r, z) half-plane
    ang = 2 * np.pi * np.arange(n) / n
    v = np.array([[r * math.cos(t), r * math.sin(t), z] for t in ang for r, z in section])
    quads = []
    for i in range(n):
        j = (i + 1) % n
        for k in range(4):
            k1 = (k + 1) % 4
            # section edge k -> k1 is counter-clockwise in (r, z), so stepping in θ first faces out
            quads.append([4 * i + k, 4 * j + k, 4 * j + k1, 4 * i + k1])
    return mesh(v, quads, "torus")


def overlapping_boxes() -> Mesh:
    """Two cubes in one file that overlap (for --union): [0, 2]³ and [1, 3]³, sharing [1, 2]³."""
    a = box_vertices((2.0, 2.0, 2.0), (1.0, 1.0, 1.0))
    b = box_vertices((2.0, 2.0, 2.0), (2.0, 2.0, 2.0))
    quads = BOX_QUADS + [[i + 8 for i in q] for q in BOX_QUADS]
    return mesh(np.vstack([a, b]), quads, "overlapping_boxes")


def open_box() -> Mesh:
    """The unit cube [0, 1]³ without its top face (z = 1): a tray, for --fill-holes and --shell."""
    return mesh(box_vertices((1.0, 1.0, 1.0), (0.5, 0.5, 0.5)),
                [q for q in BOX_QUADS if q != [4, 5, 7, 6]], "open_box")


def cuboid_asset(path: Path) -> None:
    """A glTF asset for `inspect --write-physics`: the 3×2×2 cuboid, axis-aligned and centred at
    (1, 2, 3) in its mesh node's space (float32-exact), the node turned 30° about z in the
    scene (the motion is written in node space, so the turn must not show in it)."""
    import trimesh  # only this asset needs a glTF exporter

    box = trimesh.Trimesh(box_vertices((3.0, 2.0, 2.0), (1.0, 2.0, 3.0)), BOX_TRIANGLES,
                          process=False)
    turn = np.eye(4)
    turn[:3, :3] = rot_z(30.0)
    scene = trimesh.Scene()
    scene.add_geometry(box, node_name="cuboid", geom_name="cuboid", transform=turn)
    path.write_bytes(scene.export(file_type="glb"))


def main() -> None:
    cub = notes_cuboid()
    for ext in ("vf", "vtx", "obj", "stl"):
        write_mesh(cub, HERE / f"cuboid.{ext}", force=True)
    for shape in (cube(), tetrahedron(), hexagonal_prism(), polyhedral_torus(),
                  overlapping_boxes(), open_box()):
        write_mesh(shape, HERE / f"{shape.name}.obj", force=True)
    cuboid_asset(HERE / "cuboid.glb")


if __name__ == "__main__":
    main()
