"""Cost and accuracy of the repairs, side by side with peers, in one run.

1. cost (whole processes, binary STL of ~1M triangles, best of --repeat):
   - the default path, ``inspect --json`` on a closed torus: the reference every ratio uses;
   - ``--shell 0.002`` on that torus, against MuJoCo compiling the same mesh with
     ``<mesh inertia="shell">`` (MuJoCo's shell inertia: surface density, no thickness);
   - ``--union`` on two overlapping tori (~500k triangles each), against a plain manifold3d
     script (read, weld, two Manifolds, union, its volume: no exact integral, no error bar);
   - ``--fill-holes`` on the torus with 1000 triangles removed (1000 small holes), against
     trimesh (load, ``repair.fill_holes``, ``mass_properties``).
2. default path against the tree it started from (``--base DIR``: a checkout of that commit,
   e.g. ``git archive 03a7d64 | tar -x -C /tmp/base``): ``inspect --json`` on the torus, the two
   trees interleaved, best of --repeat each. Ratio ours / base (target <= 1).
3. MuJoCo: shell inertia of closed-form shapes (a sphere, an open tube, a closed box of plates;
   a flat disc) from massprops ``--shell`` (T = 1e-7: the T² terms vanish) and from
   MuJoCo, against the thin-shell closed forms of the SAME polyhedra (exact rational sums).

    python benchmarks/bench_repairs.py [--part cost,default,mujoco] [--triangles 1000000]
        [--repeat 3] [--base /tmp/base]
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_inspect import torus_soup, write_binary_stl  # noqa: E402

MANIFOLD = r"""
import sys, numpy as np, manifold3d as mf
rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
v = np.fromfile(sys.argv[1], dtype=rec, offset=84)["v"].astype(np.float64).reshape(-1, 3)
half = v.shape[0] // 2
parts = []
for chunk in (v[:half], v[half:]):
    u, inv = np.unique(chunk, axis=0, return_inverse=True)
    tris = inv.reshape(-1, 3).astype(np.uint64)
    parts.append(mf.Manifold(mf.Mesh64(vert_properties=u, tri_verts=tris)))
print(mf.Manifold.batch_boolean(parts, mf.OpType.Add).volume())
"""

MUJOCO = r"""
import sys, numpy as np, mujoco
rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
v = np.fromfile(sys.argv[1], dtype=rec, offset=84)["v"].astype(np.float64).reshape(-1, 3)
u, inv = np.unique(v, axis=0, return_inverse=True)  # MuJoCo wants an indexed mesh
spec = mujoco.MjSpec()  # its STL reader stops at 200,000 faces: the mesh goes in directly
mesh = spec.add_mesh(name="m", uservert=u.ravel().tolist(),
                     userface=inv.ravel().astype(int).tolist())
mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
body = spec.worldbody.add_body()
body.add_freejoint()
body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="m", density=1.0)
m = spec.compile()
print(m.body_mass[1], m.body_inertia[1])
"""

TRIMESH = r"""
import sys, trimesh
m = trimesh.load(sys.argv[1])
trimesh.repair.fill_holes(m)
p = m.mass_properties
print(m.is_watertight, p["volume"], p["inertia"][0, 0])
"""


def run(cmd: list[str], repeat: int, env: dict | None = None) -> float:
    """Best wall time (s) of a whole process over ``repeat`` runs."""
    best = math.inf
    for _ in range(repeat):
        start = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True, env=env)
        best = min(best, time.perf_counter() - start)
        if done.returncode != 0:
            raise SystemExit(f"{' '.join(cmd[:4])}...: exit {done.returncode}\n{done.stderr}")
    return best


def massprops(*args: str) -> list[str]:
    return [sys.executable, "-m", "massprops", "inspect", "--json", *args]


def files(folder: Path, triangles: int) -> dict[str, Path]:
    tris = torus_soup(triangles)
    out = {"torus": folder / "torus.stl", "two": folder / "two_tori.stl",
           "holed": folder / "holed.stl"}
    write_binary_stl(out["torus"], tris)
    half = torus_soup(triangles // 2)
    write_binary_stl(out["two"], np.concatenate([half, half + np.float32([0.7, 0.0, 0.0])]))
    rng = np.random.default_rng(0)
    write_binary_stl(out["holed"], np.delete(tris, rng.choice(len(tris), 1000, replace=False), 0))
    return out


def part_cost(folder: Path, triangles: int, repeat: int) -> None:
    f = files(folder, triangles)
    print(f"\n1. cost, whole processes, ~{triangles:,} triangles, best of {repeat} "
          f"(2 shared cores: load from other jobs inflates every row alike)")
    base = run(massprops(str(f["torus"])), repeat)
    rows = [("inspect (default, closed torus)", base, None)]
    rows.append(("inspect --shell 0.002", run(massprops("--shell", "0.002", str(f["torus"])),
                                               repeat), None))
    rows.append(("  MuJoCo <mesh inertia=shell>", _peer(MUJOCO, f["torus"], repeat), "peer"))
    rows.append(("inspect --union (two tori)", run(massprops("--union", str(f["two"])), repeat),
                 None))
    rows.append(("  manifold3d script (union volume only)", _peer(MANIFOLD, f["two"], repeat),
                 "peer"))
    rows.append(("inspect (default, two tori: overlap measured)", run(massprops(str(f["two"])),
                                                                       repeat), None))
    rows.append(("inspect --fill-holes (1000 holes)",
                 run(massprops("--fill-holes", str(f["holed"])), repeat), None))
    rows.append(("  trimesh fill_holes + mass_properties", _peer(TRIMESH, f["holed"], repeat),
                 "peer"))
    print(f"{'process':50s} {'wall [s]':>9s} {'/ default':>10s}")
    for name, t, _ in rows:
        print(f"{name:50s} {t:9.2f} {t / base:9.2f}x")


def _peer(script: str, path: Path, repeat: int) -> float:
    try:
        return run([sys.executable, "-c", script, str(path)], repeat)
    except SystemExit as exc:
        print(f"  (peer failed: {str(exc).splitlines()[-1][:100]})")
        return math.nan


def part_default(folder: Path, triangles: int, repeat: int, base_dir: str | None) -> None:
    print("\n2. default path, this tree against the base tree (interleaved)")
    if base_dir is None:
        print("  skipped: give --base DIR (a checkout of the commit to compare with)")
        return
    path = folder / "torus.stl"
    if not path.exists():
        write_binary_stl(path, torus_soup(triangles))
    here = str(Path(__file__).resolve().parent.parent)
    ours, theirs = math.inf, math.inf
    for _ in range(repeat):
        for tree in (here, base_dir):
            env = dict(os.environ, PYTHONPATH=tree)
            t = run([sys.executable, "-m", "massprops", "inspect", "--json", str(path)], 1, env)
            if tree == here:
                ours = min(ours, t)
            else:
                theirs = min(theirs, t)
    print(f"  this tree {ours:.3f} s, base {theirs:.3f} s: {ours / theirs:.3f}x (target <= 1; "
          f"differences under ~5 % are noise on a shared machine)")


def part_mujoco() -> None:
    """Thin-shell inertia of polyhedra: Σ over faces of the exact triangle integrals."""
    import mujoco

    from massprops.mesh import Mesh
    from massprops.repair.shell import shell_properties

    print("\n3. shell inertia against MuJoCo (surface density 1; massprops with T = 1e-7, so its "
          "T² terms are 1e-15): largest relative error of the principal moments against the "
          "polyhedron's exact thin shell")
    print(f"{'shape':28s} {'massprops':>12s} {'MuJoCo':>12s} {'massprops [ms]':>15s} "
          f"{'MuJoCo [ms]':>12s}")
    t_shell = 1e-7
    for name, (v, f) in _shapes().items():
        exact = _thin_shell_moments(v, f)
        start = time.perf_counter()
        p = shell_properties(Mesh(v, f, name=name), t_shell, density=1 / t_shell).properties
        ours_ms = 1e3 * (time.perf_counter() - start)
        ours = np.sort(p.principal_moments)  # its T² terms: ~1e-15 relative at T = 1e-7
        try:
            start = time.perf_counter()
            theirs = np.sort(_mujoco_shell(mujoco, v, f))
            theirs_ms = f"{1e3 * (time.perf_counter() - start):12.1f}"
            theirs_err = f"{np.max(np.abs(theirs - exact) / exact):12.1e}"
        except Exception as exc:  # noqa: BLE001 - report MuJoCo's refusal as it is
            theirs_err, theirs_ms = "refused", ""
            print(f"  MuJoCo on {name}: {str(exc).splitlines()[0][:90]}")
        print(f"{name:28s} {np.max(np.abs(ours - exact) / exact):12.1e} {theirs_err:>12s} "
              f"{ours_ms:15.1f} {theirs_ms:>12s}")


def _shapes() -> dict:
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    n = 64
    t = 2 * np.pi * np.arange(n) / n
    ring = np.c_[np.cos(t), np.sin(t)]
    tube_v = np.vstack([np.c_[ring, np.zeros(n)], np.c_[ring, np.full(n, 2.0)]])
    i = np.arange(n)
    j = (i + 1) % n
    tube_f = np.vstack([np.c_[i, j, j + n], np.c_[i, j + n, i + n]])
    cube = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    disc_v = np.vstack([np.c_[ring, np.zeros(n)], [[0, 0, 0]]])
    disc_f = np.c_[np.full(n, n), i, j]
    return {"sphere (icosphere 4)": (np.asarray(s.vertices), np.asarray(s.faces)),
            "open tube (64-gon)": (tube_v, tube_f),
            "closed box 1x2x3": (np.asarray(cube.vertices), np.asarray(cube.faces)),
            "flat disc (64-gon)": (disc_v, disc_f)}


def _thin_shell_moments(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Principal moments of the polyhedron as a surface of density 1 (fractions per face)."""
    from fractions import Fraction as Q

    area, first = Q(0), [Q(0)] * 3
    second = [[Q(0)] * 3 for _ in range(3)]
    for tri in f:
        p = [[Q(float(x)) for x in v[k]] for k in tri]
        e1 = [p[1][i] - p[0][i] for i in range(3)]
        e2 = [p[2][i] - p[0][i] for i in range(3)]
        n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
             e1[0] * e2[1] - e1[1] * e2[0]]
        a = Q(math.sqrt(float(sum(x * x for x in n)))) / 2  # the one rounding: the square root
        s = [p[0][i] + p[1][i] + p[2][i] for i in range(3)]
        area += a
        first = [first[i] + a * s[i] / 3 for i in range(3)]
        for i in range(3):
            for j in range(3):
                second[i][j] += a / 12 * (sum(q[i] * q[j] for q in p) + s[i] * s[j])
    c = [x / area for x in first]
    m = np.array([[float(second[i][j] - area * c[i] * c[j]) for j in range(3)] for i in range(3)])
    return np.sort(np.linalg.eigvalsh(np.trace(m) * np.eye(3) - m))


def _mujoco_shell(mujoco, v: np.ndarray, f: np.ndarray) -> np.ndarray:
    xml = (f'<mujoco><asset><mesh name="m" vertex="{" ".join(map(repr, v.ravel().tolist()))}" '
           f'face="{" ".join(map(str, f.ravel().tolist()))}" inertia="shell"/></asset>'
           '<worldbody><body><freejoint/><geom type="mesh" mesh="m" density="1"/></body>'
           '</worldbody></mujoco>')
    return np.asarray(mujoco.MjModel.from_xml_string(xml).body_inertia[1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", default="cost,default,mujoco")
    ap.add_argument("--triangles", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--base", default=None)
    args = ap.parse_args()
    parts = args.part.split(",")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if "cost" in parts:
            part_cost(folder, args.triangles, args.repeat)
        if "default" in parts:
            part_default(folder, args.triangles, args.repeat, args.base)
    if "mujoco" in parts:
        part_mujoco()


if __name__ == "__main__":
    main()
