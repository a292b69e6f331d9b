"""Accuracy wherever the part sits: massprops against trimesh on a box moved far from the origin.

The box is 1 × 2 × 3 m with corners at d + {0, 1} × {0, 2} × {0, 3}, d = 10^k an integer, so
every coordinate is exactly representable: the stored vertices ARE the box, and its inertia about
the COM is the closed form m/12·(b²+c², ...).
Prints the relative error of the inertia (against the largest moment) and of the volume for
distances 1 to 1e9 box sizes, side by side.

    python benchmarks/accuracy_far.py
"""

from __future__ import annotations

import numpy as np

from massprops.mesh import Mesh
from massprops.mesh.integral import mass_properties

QUADS = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
TRIS = np.array([t for a, b, c, d in QUADS for t in ([a, b, c], [a, c, d])], dtype=np.int64)
SIZE = np.array([1.0, 2.0, 3.0])
EXACT_J = np.diag([SIZE[1] ** 2 + SIZE[2] ** 2, SIZE[0] ** 2 + SIZE[2] ** 2,
                   SIZE[0] ** 2 + SIZE[1] ** 2]) * SIZE.prod() / 12


def box(offset: float) -> np.ndarray:
    bits = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=np.float64)
    return bits * SIZE + offset  # offsets are integers < 2^53: every coordinate is exact


def main() -> None:
    import trimesh

    print(f"{'distance [sizes]':>16}  {'massprops J err':>15}  {'trimesh J err':>13}  "
          f"{'massprops V err':>15}  {'trimesh V err':>13}")
    for k in range(0, 10):
        d = float(10**k)
        v = box(d)
        ours = mass_properties(Mesh(v, TRIS, name="box"))
        tm = trimesh.Trimesh(v, TRIS, process=False)
        scale = EXACT_J.max()
        e_ours = np.abs(ours.inertia - EXACT_J).max() / scale
        e_tm = np.abs(tm.moment_inertia - EXACT_J).max() / scale
        print(f"{d:>16.0e}  {e_ours:>15.1e}  {e_tm:>13.1e}  "
              f"{abs(ours.volume - 6) / 6:>15.1e}  {abs(tm.volume - 6) / 6:>13.1e}")


if __name__ == "__main__":
    main()
