"""Kernels compiled when the package is built and shipped inside it, so that the first run on the
machine that installed it loads them from disk instead of compiling (minutes for the systems'
kernel).

At build time (setup.py's build step, `build`) every stepping kernel is compiled into the
kernels' cache folder (`cache`: one folder per hash of the sources and versions, the kernels'
files named by their folder in the package), and that folder's files are stored under
``_prebuilt/`` with a manifest naming the hash. At run time `seed` copies them once into the
cache folder of this package, when its hash is the one they were built for (the same sources,
Python, numba and numpy).

Validity is numba's, not ours: numba uses a cached entry only when its index matches the numba
version, the source file's content hash, the function's bytecode and the CPU (target triple,
CPU name and features). The build compiles for a generic CPU of its architecture, which the
kernels' cache accepts on any CPU of it (`cache.PORTABLE_CPU`): a wheel built on another x86-64
machine loads here. One built for another architecture leaves entries that are not used, and
the first run compiles as it would have (with its notice). The manifest only avoids copying
files for other sources or versions.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
from pathlib import Path

FOLDER = Path(__file__).resolve().parent / "_prebuilt"
MANIFEST = "manifest.json"
MARKER = ".prebuilt-seeded"
"""Left in a cache folder once `seed` has looked at it (copied or not): it never copies twice,
so kernels a user deletes are compiled, not restored. One marker serves every copy of the
package, since all copies of the same sources share the folder's files."""


def store(cache: Path, digest: str) -> int:
    """Replace `FOLDER` by the kernels in the cache folder ``cache`` (made for the sources of hash
    ``digest``: every file in it belongs to them); returns the number of files stored."""
    shutil.rmtree(FOLDER, ignore_errors=True)
    count = 0
    for path in sorted(cache.rglob("*.nb[ic]")):  # numba's indexes and their data
        target = FOLDER / path.relative_to(cache)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, target)
        count += 1
    FOLDER.mkdir(exist_ok=True)
    (FOLDER / MANIFEST).write_text(json.dumps({"digest": digest}))
    return count


def seed(cache: Path, digest: str) -> int:
    """Copy the shipped kernels into the cache folder ``cache`` (of the sources of hash
    ``digest``) unless it was seeded before or they were built for other sources or versions;
    returns the number of files copied. Never raises for want of files or permissions: the
    kernels are then compiled on first use."""
    marker = cache / MARKER
    try:
        if marker.exists():
            return 0
        manifest = json.loads((FOLDER / MANIFEST).read_text())
    except (OSError, ValueError):
        return 0
    count = 0
    # a cache we cannot write: what was not copied is compiled on first use (and, with no
    # marker, the copy is tried again next time)
    with contextlib.suppress(OSError):
        if isinstance(manifest, dict) and manifest.get("digest") == digest:
            for folder in sorted({p.parent for p in FOLDER.rglob("*.nbi")}):
                count += _copy_missing(folder, cache / folder.relative_to(FOLDER))
        marker.touch()
    return count


def _copy_missing(source: Path, target: Path) -> int:
    """Copy the files of ``source`` that ``target`` lacks, each atomically; data files before
    indexes, so that a process reading concurrently never sees an index without its data."""
    target.mkdir(parents=True, exist_ok=True)
    count = 0
    for path in sorted(source.iterdir(), key=lambda p: p.suffix == ".nbi"):
        final = target / path.name
        if final.exists():
            continue
        partial = target / f".{path.name}.{os.getpid()}.part"
        shutil.copyfile(path, partial)
        os.replace(partial, final)
        count += 1
    return count
