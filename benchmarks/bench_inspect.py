"""Speed of `massprops inspect` against its peers, side by side in one run.

1. A closed torus of ~1M triangles is written as binary STL; three whole processes read it and
   compute volume, centre of mass and inertia: massprops (`inspect --json`), trimesh
   (load + mass_properties) and a plain numpy floor (np.fromfile + the vectorised sums about the
   origin, no checks at all). Best of --repeat runs; peak memory (max RSS) of each process.
2. Start-up: `massprops inspect small.obj --json` against `python -c "import numpy"`.

Prints times and ratios (massprops / floor; target <= 1.5 for both).

    python benchmarks/bench_inspect.py [--triangles 1000000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

FLOOR = r"""
import sys, numpy as np
rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
v = np.fromfile(sys.argv[1], dtype=rec, offset=84)["v"].astype(np.float64)
a, b, c = v[:, 0], v[:, 1], v[:, 2]
det = np.einsum("ij,ij->i", a, np.cross(b, c))
vol = det.sum() / 6
s = a + b + c
com = det @ s / (24 * vol)
m2 = np.empty((3, 3))
for i in range(3):
    for j in range(i, 3):
        m2[i, j] = m2[j, i] = det @ (a[:, i] * a[:, j] + b[:, i] * b[:, j] + c[:, i] * c[:, j]
                                     + s[:, i] * s[:, j]) / 120
print(vol, com, np.trace(m2) * np.eye(3) - m2 - vol * (com @ com * np.eye(3) - np.outer(com, com)))
"""

TRIMESH = r"""
import sys, trimesh
m = trimesh.load(sys.argv[1], process=False)
p = m.mass_properties
print(p["volume"], p["center_mass"], p["inertia"])
"""


def torus_soup(n_triangles: int, major: float = 1.0, minor: float = 0.3) -> np.ndarray:
    """(m, 3, 3) float32 triangles of a closed, outward torus grid (2·nu·nv triangles)."""
    nv = max(3, int(np.sqrt(n_triangles / 4)))
    nu = max(3, n_triangles // (2 * nv))
    u = 2 * np.pi * np.arange(nu) / nu
    v = 2 * np.pi * np.arange(nv) / nv
    uu, vv = np.meshgrid(u, v, indexing="ij")
    r = major + minor * np.cos(vv)
    pts = np.stack([r * np.cos(uu), r * np.sin(uu), minor * np.sin(vv)], axis=-1)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    i1, j1 = (i + 1) % nu, (j + 1) % nv
    p00, p10, p11, p01 = pts[i, j], pts[i1, j], pts[i1, j1], pts[i, j1]
    t1 = np.stack([p00, p10, p11], axis=-2).reshape(-1, 3, 3)
    t2 = np.stack([p00, p11, p01], axis=-2).reshape(-1, 3, 3)
    return np.concatenate([t1, t2]).astype(np.float32)


def write_binary_stl(path: Path, tris: np.ndarray) -> None:
    rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    data = np.zeros(len(tris), dtype=rec)
    data["v"] = tris
    with open(path, "wb") as fh:
        fh.write(b"massprops benchmark".ljust(80, b" "))
        fh.write(np.uint32(len(tris)).tobytes())
        data.tofile(fh)


def run(cmd: list[str], repeat: int) -> tuple[float, float]:
    """Best wall time (s) and peak RSS (MiB) of a whole process over ``repeat`` runs."""
    best, peak = float("inf"), 0.0
    for _ in range(repeat):
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        _, status, usage = os.wait4(proc.pid, 0)
        elapsed = time.perf_counter() - t0
        if os.waitstatus_to_exitcode(status) != 0:
            raise SystemExit(f"failed: {' '.join(cmd)}\n{proc.stderr.read().decode()}")
        proc.stderr.close()
        best, peak = min(best, elapsed), max(peak, usage.ru_maxrss / 1024)
    return best, peak


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--triangles", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    py = sys.executable
    with tempfile.TemporaryDirectory() as tmp:
        stl = Path(tmp) / "torus.stl"
        tris = torus_soup(args.triangles)
        write_binary_stl(stl, tris)
        print(f"binary STL: {len(tris):,} triangles, {stl.stat().st_size / 2**20:.1f} MiB")
        rows = {
            "numpy floor": run([py, "-c", FLOOR, str(stl)], args.repeat),
            "massprops": run([py, "-m", "massprops", "inspect", "--json", str(stl)], args.repeat),
            "trimesh": run([py, "-c", TRIMESH, str(stl)], args.repeat),
        }
        floor = rows["numpy floor"][0]
        print(f"{'whole process':<14}{'time [s]':>10}{'/ floor':>10}{'peak RSS [MiB]':>16}")
        for name, (t, mem) in rows.items():
            print(f"{name:<14}{t:>10.3f}{t / floor:>10.2f}{mem:>16.0f}")

        small = Path(tmp) / "tetra.obj"
        small.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
        t_np, _ = run([py, "-c", "import numpy"], args.repeat + 2)
        t_mp, _ = run([py, "-m", "massprops", "inspect", "--json", str(small)], args.repeat + 2)
        print(f"start-up: inspect small.obj --json {t_mp:.3f} s, python -c 'import numpy' "
              f"{t_np:.3f} s, ratio {t_mp / t_np:.2f} (target <= 1.5)")


if __name__ == "__main__":
    main()
