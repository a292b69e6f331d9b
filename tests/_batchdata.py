"""Meshes and process helpers for the batch tests (written as text here: no writer involved)."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
from conftest import box_vf


def torus_obj(path: Path, nu: int = 24, nv: int = 12, major: float = 1.0, minor: float = 0.3,
              shift=(0.0, 0.0, 0.0)) -> Path:
    """A closed, outward torus about z (2·nu·nv triangles) as OBJ text."""
    lines = []
    for i in range(nu):
        u = 2 * math.pi * i / nu
        for j in range(nv):
            v = 2 * math.pi * j / nv
            r = major + minor * math.cos(v)
            lines.append(f"v {r * math.cos(u) + shift[0]!r} {r * math.sin(u) + shift[1]!r} "
                         f"{minor * math.sin(v) + shift[2]!r}")
    for i in range(nu):
        for j in range(nv):
            a, b = i * nv + j, ((i + 1) % nu) * nv + j
            c, d = ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv
            lines.append(f"f {a + 1} {b + 1} {c + 1}")
            lines.append(f"f {a + 1} {c + 1} {d + 1}")
    path.write_text("\n".join(lines) + "\n")
    return path


def binary_stl_box(path: Path, size=(1.0, 2.0, 3.0)) -> Path:
    """A box [0, size] as binary STL (float32 coordinates: the input error bars are set)."""
    corners = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float) * size
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    tris = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    data = np.zeros(len(tris), dtype=rec)
    data["v"] = corners[np.array(tris)]
    path.write_bytes(b"box".ljust(80, b" ") + np.uint32(len(tris)).tobytes() + data.tobytes())
    return path


def mixed_batch(folder: Path, n: int = 12) -> list[Path]:
    """``n`` good meshes of a few kinds and sizes, one garbage file and one open mesh (in the
    middle), in a fixed order."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for k in range(n):
        if k % 3 == 0:
            paths.append(torus_obj(folder / f"m{k:02d}_torus.obj", 16 + 4 * k, 8 + k,
                                   shift=(k, -k, 0.5 * k)))
        elif k % 3 == 1:
            paths.append(box_vf(folder / f"m{k:02d}_box.vf", size=(1 + k, 2.0, 0.5),
                                offset=(k, 0, 0)))
        else:
            paths.append(binary_stl_box(folder / f"m{k:02d}_box.stl", size=(0.5, 1 + k, 2.0)))
    garbage = folder / "m50_garbage.obj"
    garbage.write_bytes(b"\x00\xff not a mesh \x00" * 10)
    open_mesh = folder / "m51_open.obj"
    open_mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n")
    middle = len(paths) // 2
    return paths[:middle] + [garbage] + paths[middle:middle + 1] + [open_mesh] \
        + paths[middle + 1:]


def descendants(pid: int) -> list[int]:
    """Every living process below ``pid`` (Linux /proc; zombies are dead and not counted)."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if fields[0] != "Z":
            children.setdefault(int(fields[1]), []).append(int(entry))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found
