"""Meshes for the repair tests, built from coordinates (no massprops writer or repair involved)."""

from __future__ import annotations

import math

import numpy as np

from massprops.mesh import Mesh

# corners numbered 4x + 2y + z; triangles counter-clockwise seen from outside
BOX_TRIANGLES = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])


def box(lo=(0, 0, 0), hi=(1, 1, 1), *, inward=False, name="box") -> Mesh:
    v = np.array([[(lo[0], hi[0])[i >> 2], (lo[1], hi[1])[(i >> 1) & 1], (lo[2], hi[2])[i & 1]]
                  for i in range(8)], dtype=np.float64)
    f = BOX_TRIANGLES[:, ::-1] if inward else BOX_TRIANGLES
    return Mesh(v, f.astype(np.int64).copy(), name=name)


def join(*meshes: Mesh, name="joined") -> Mesh:
    offsets = np.cumsum([0] + [m.n_vertices for m in meshes[:-1]])
    return Mesh(np.concatenate([m.vertices for m in meshes]),
                np.concatenate([m.faces + o for m, o in zip(meshes, offsets)]), name=name)


def moved(mesh: Mesh, rotation=None, shift=(0.0, 0.0, 0.0)) -> Mesh:
    r = np.eye(3) if rotation is None else np.asarray(rotation)
    return mesh.with_vertices(mesh.vertices @ r.T + np.asarray(shift, dtype=float))


def rotation(axis, angle) -> np.ndarray:
    a = np.asarray(axis, dtype=float)
    a /= np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def icosphere(subdivisions: int, radius: float = 1.0, name="sphere") -> Mesh:
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return Mesh(np.asarray(s.vertices, dtype=np.float64), np.asarray(s.faces, dtype=np.int64),
                name=name)


def without(mesh: Mesh, rows) -> Mesh:
    keep = np.setdiff1d(np.arange(mesh.faces.shape[0]), rows)
    return Mesh(mesh.vertices, mesh.faces[keep], name=mesh.name)


def polygon_tube(n: int, apothem: float, height: float, name="tube") -> Mesh:
    """The side of a regular n-gon prism (no ends), outward, z from 0 to height."""
    r = apothem / math.cos(math.pi / n)
    t = 2 * math.pi * (np.arange(n) + 0.5) / n
    ring = np.stack([r * np.cos(t), r * np.sin(t)], axis=1)
    v = np.concatenate([np.column_stack([ring, np.zeros(n)]),
                        np.column_stack([ring, np.full(n, height)])])
    i = np.arange(n)
    j = (i + 1) % n
    f = np.concatenate([np.stack([i, j, j + n], 1), np.stack([i, j + n, i + n], 1)])
    return Mesh(v, f.astype(np.int64), name=name)


def fan_disc(xy, name="disc") -> Mesh:
    """A flat polygon (k, 2) in z = 0, fanned from its centroid of vertices."""
    k = len(xy)
    v = np.concatenate([np.column_stack([xy, np.zeros(k)]), [[*np.mean(xy, axis=0), 0.0]]])
    i = np.arange(k)
    f = np.stack([np.full(k, k), i, (i + 1) % k], 1)
    return Mesh(v.astype(np.float64), f.astype(np.int64), name=name)


def hemisphere_bowl(n: int = 32, rings: int = 8, name="bowl") -> Mesh:
    """An open hemispherical bowl of radius 1, z >= 0, outward: ``rings`` latitude rings of ``n``
    points from the rim (a regular n-gon at z = 0) up to a pole."""
    lat = (np.pi / 2) * np.arange(rings) / rings
    lon = 2 * np.pi * np.arange(n) / n
    v = [[math.cos(a) * math.cos(b), math.cos(a) * math.sin(b), math.sin(a)]
         for a in lat for b in lon] + [[0.0, 0.0, 1.0]]
    faces = []
    for r in range(rings - 1):
        for i in range(n):
            j = (i + 1) % n
            p, q, s_, t = r * n + i, r * n + j, (r + 1) * n + j, (r + 1) * n + i
            faces += [[p, q, s_], [p, s_, t]]
    pole = rings * n
    faces += [[(rings - 1) * n + i, (rings - 1) * n + (i + 1) % n, pole] for i in range(n)]
    return Mesh(np.array(v), np.array(faces, dtype=np.int64), name=name)
