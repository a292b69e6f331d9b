"""Speed of `massprops inspect` over many files: --jobs 2 against one process and against
trimesh's loop, side by side in one run.

A dataset is generated into benchmarks/_data/batch (git-ignored; reused when its manifest
matches): --small meshes of 100-20000 triangles (tori and UV spheres, log-uniform sizes, half
OBJ with 6 decimals as exporters write them, half binary STL, each moved and turned at random)
and --large meshes of 100k-1M triangles.
Every mesh is closed and outward, so every tool computes every file. Three whole processes
read the same file list:

- massprops, one process: ``massprops inspect --files-from LIST --format csv --jobs 1``;
- massprops, parallel: the same with ``--jobs N`` (default 2);
- trimesh's loop: one Python process doing ``trimesh.load(f)`` + ``mass_properties`` per file.

Best of --repeat runs (interleaved, so a load spike from other users hits all three alike);
the script prints files/s of each and the ratios (targets: jobs N / one process >= 1.8 for
N = 2 on a 2-core machine; jobs N / trimesh >= 4). It also checks that the parallel CSV equals
the one-process CSV byte for byte, and that massprops and trimesh agree on every volume.

With --dask W the same batch also runs on a local Dask cluster of W one-thread worker processes
(`--scheduler`), checked against the one-process CSV, and the script prints files/s per worker:
the rate the README extrapolates from.

    python benchmarks/bench_batch.py [--small 1000] [--large 8] [--jobs 2] [--repeat 3] [--dask W]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent / "_data" / "batch"

TRIMESH_LOOP = r"""
import sys, trimesh
out = []
for line in open(sys.argv[1]):
    m = trimesh.load(line.rstrip("\n"))
    p = m.mass_properties
    out.append((p["volume"], p["center_mass"].tolist(), p["inertia"].tolist()))
print(len(out), sum(v for v, _, _ in out))
"""


def torus(nu: int, nv: int, major: float = 1.0, minor: float = 0.35
          ) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (nu·nv, 3), faces (2·nu·nv, 3)) of a closed, outward torus about z."""
    u = 2 * np.pi * np.arange(nu) / nu
    v = 2 * np.pi * np.arange(nv) / nv
    uu, vv = np.meshgrid(u, v, indexing="ij")
    r = major + minor * np.cos(vv)
    pts = np.stack([r * np.cos(uu), r * np.sin(uu), minor * np.sin(vv)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    a, b = i * nv + j, ((i + 1) % nu) * nv + j
    c, d = ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                            np.stack([a, c, d], -1).reshape(-1, 3)])
    return pts, faces


def sphere(n_lat: int, n_lon: int, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of a closed, outward UV sphere (2 poles + rings)."""
    theta = np.pi * np.arange(1, n_lat) / n_lat
    phi = 2 * np.pi * np.arange(n_lon) / n_lon
    tt, pp = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], -1)
    pts = np.concatenate([[[0, 0, 1]], ring.reshape(-1, 3), [[0, 0, -1]]]) * radius
    south, rings = len(pts) - 1, n_lat - 1
    k = np.arange(n_lon)
    faces = [np.stack([np.zeros(n_lon, int), 1 + k, 1 + (k + 1) % n_lon], -1)]
    for r in range(rings - 1):
        top, bottom = 1 + r * n_lon, 1 + (r + 1) * n_lon
        faces.append(np.stack([top + k, bottom + k, bottom + (k + 1) % n_lon], -1))
        faces.append(np.stack([top + k, bottom + (k + 1) % n_lon, top + (k + 1) % n_lon], -1))
    last = 1 + (rings - 1) * n_lon
    faces.append(np.stack([np.full(n_lon, south), last + (k + 1) % n_lon, last + k], -1))
    return pts, np.concatenate(faces)


def shape(triangles: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A torus or sphere of about ``triangles`` triangles, turned and moved at random."""
    if rng.random() < 0.5:
        nv = max(3, int(math.sqrt(triangles / 6)))
        pts, faces = torus(max(3, triangles // (2 * nv)), nv)
    else:
        n_lat = max(3, int(math.sqrt(triangles / 4)))
        pts, faces = sphere(n_lat, max(3, triangles // (2 * n_lat)))
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))  # a rotation: the winding stays outward
    return pts @ q.T * rng.uniform(0.01, 2.0) + rng.uniform(-5, 5, 3), faces


def write_obj(path: Path, pts: np.ndarray, faces: np.ndarray) -> None:
    """OBJ with 6 decimals, as common exporters (Blender, most CAD tools) write it."""
    with open(path, "w") as f:
        f.write("".join(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in pts.tolist()))
        f.write("".join(f"f {a} {b} {c}\n" for a, b, c in (faces + 1).tolist()))


def write_stl(path: Path, pts: np.ndarray, faces: np.ndarray) -> None:
    rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    data = np.zeros(len(faces), dtype=rec)
    data["v"] = pts[faces]
    with open(path, "wb") as fh:
        fh.write(b"massprops batch benchmark".ljust(80, b" "))
        fh.write(np.uint32(len(faces)).tobytes())
        data.tofile(fh)


def make_dataset(small: int, large: int, seed: int = 12) -> list[Path]:
    """The benchmark's files (generated once per (small, large, seed)), in a stable order."""
    manifest = DATA / "manifest.json"
    key = {"small": small, "large": large, "seed": seed, "version": 2}
    if manifest.exists() and json.loads(manifest.read_text()).get("key") == key:
        return [DATA / name for name in json.loads(manifest.read_text())["files"]]
    DATA.mkdir(parents=True, exist_ok=True)
    for old in DATA.iterdir():
        old.unlink()
    rng = np.random.default_rng(seed)
    names = []
    sizes = [("small", int(math.exp(rng.uniform(math.log(100), math.log(20000)))))
             for _ in range(small)]
    sizes += [("large", int(rng.uniform(1e5, 1e6))) for _ in range(large)]
    order = rng.permutation(len(sizes))  # large files scattered through the list
    for n, k in enumerate(order):
        kind, triangles = sizes[k]
        pts, faces = shape(triangles, rng)
        ext = ".obj" if rng.random() < 0.5 else ".stl"
        name = f"{n:05d}_{kind}_{len(faces)}{ext}"
        (write_obj if ext == ".obj" else write_stl)(DATA / name, pts, faces)
        names.append(name)
    manifest.write_text(json.dumps({"key": key, "files": names}))
    return [DATA / name for name in names]


def timed(cmd: list[str], out: Path | None = None) -> tuple[float, float]:
    """(wall seconds, CPU seconds of the whole process tree: user + system, workers included)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    with open(out or os.devnull, "wb") as sink:
        subprocess.run(cmd, check=True, stdout=sink, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--small", type=int, default=1000)
    parser.add_argument("--large", type=int, default=8)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-trimesh", action="store_true")
    parser.add_argument("--dask", type=int, default=0, metavar="W",
                        help="also run on a local Dask cluster of W one-thread workers "
                             "(--scheduler; needs massprops[dask]) and print files/s per worker")
    args = parser.parse_args()

    files = make_dataset(args.small, args.large)
    total_mb = sum(f.stat().st_size for f in files) / 2**20
    with tempfile.TemporaryDirectory() as tmp:
        listing = Path(tmp) / "files.txt"
        listing.write_text("".join(f"{f}\n" for f in files))
        base = [sys.executable, "-m", "massprops", "inspect", "--files-from", str(listing),
                "--format", "csv", "--quiet"]
        runs = {"massprops --jobs 1": base + ["--jobs", "1"],
                f"massprops --jobs {args.jobs}": base + ["--jobs", str(args.jobs)]}
        if not args.no_trimesh:
            script = Path(tmp) / "trimesh_loop.py"
            script.write_text(TRIMESH_LOOP)
            runs["trimesh loop"] = [sys.executable, str(script), str(listing)]
        one, many = Path(tmp) / "one.csv", Path(tmp) / "many.csv"
        timed(runs["massprops --jobs 1"], one)  # warm the page cache and bytecode too
        timed(runs[f"massprops --jobs {args.jobs}"], many)
        if one.read_bytes() != many.read_bytes():
            sys.exit("FAIL: the parallel CSV differs from the one-process CSV")
        if not args.no_trimesh:
            _check_volumes(one, files)
        best = {name: math.inf for name in runs}
        cpu = {name: math.inf for name in runs}
        load = [os.getloadavg()[0]]
        for _ in range(args.repeat):
            for name, cmd in runs.items():
                wall, used = timed(cmd)
                best[name], cpu[name] = min(best[name], wall), min(cpu[name], used)
        if args.dask:
            best[f"dask, {args.dask} workers"] = _dask_best(base, args.dask, args.repeat, one)
        load.append(os.getloadavg()[0])

    n = len(files)
    print(f"{n} files ({args.small} small, {args.large} large), {total_mb:.0f} MB; "
          f"{os.cpu_count()} cores (load average {load[0]:.1f} before, {load[1]:.1f} after: "
          f"other users' work slows the parallel run most); best of {args.repeat}, whole "
          "processes")
    for name, t in best.items():
        used = f"   CPU {cpu[name]:6.2f} s" if name in cpu else ""
        print(f"  {name:22s} {t:7.2f} s  {n / t:8.1f} files/s{used}")
    if args.dask:
        t = best[f"dask, {args.dask} workers"]
        print(f"dask: {n / t / args.dask:.1f} files/s per worker (one thread each; the "
              "scheduler, client and workers all on this machine)")
    one_t, many_t = best["massprops --jobs 1"], best[f"massprops --jobs {args.jobs}"]
    print(f"--jobs {args.jobs} / one process: {one_t / many_t:.2f}x (target >= 1.8 on 2 cores); "
          f"CPU spent by --jobs {args.jobs} / one process: "
          f"{cpu[f'massprops --jobs {args.jobs}'] / cpu['massprops --jobs 1']:.2f}x")
    if not args.no_trimesh:
        tri = best["trimesh loop"]
        print(f"--jobs {args.jobs} / trimesh loop: {tri / many_t:.2f}x (target >= 4); "
              f"one process / trimesh loop: {tri / one_t:.2f}x")


def _dask_best(base: list[str], workers: int, repeat: int, reference: Path) -> float:
    """Best wall time of the batch on a local Dask cluster; its CSV must equal ``reference``.
    The workers start with a 128 MiB malloc trim threshold, as the README's recipe says (dask's
    own 64 KiB costs massprops 35-45 % CPU)."""
    from distributed import LocalCluster

    os.environ["MALLOC_TRIM_THRESHOLD_"] = str(128 * 2**20)  # read by the nanny at spawn
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=":0") as cluster:
        cmd = [*base, "--scheduler", cluster.scheduler_address]
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "dask.csv"
            timed(cmd, out)
            if out.read_bytes() != reference.read_bytes():
                sys.exit("FAIL: the Dask CSV differs from the one-process CSV")
        return min(timed(cmd)[0] for _ in range(repeat))


def _check_volumes(csv_path: Path, files: list[Path]) -> None:
    """massprops and trimesh agree on every volume (a benchmark of different answers would
    compare nothing)."""
    import csv

    import trimesh

    rows = list(csv.DictReader(open(csv_path)))
    for row, f in zip(rows, files):
        if row["error"]:
            sys.exit(f"FAIL: massprops could not read {f}: {row['error']}")
    for row in rows[:: max(1, len(rows) // 50)]:
        theirs = trimesh.load(row["file"]).volume
        if not math.isclose(float(row["volume"]), theirs, rel_tol=1e-6):
            sys.exit(f"FAIL: {row['file']}: volume {row['volume']} against trimesh's {theirs}")


if __name__ == "__main__":
    main()
