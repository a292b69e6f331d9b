"""Kernels compiled when the package is built and shipped inside it, so that the first run on the
machine that installed it loads them from disk instead of compiling (a few seconds per kernel).

numba keeps the machine code of a function in ``NUMBA_CACHE_DIR/<folder>_<sha1 of the folder's
absolute path>/``. At build time (setup.py's build step, `build`), every stepping kernel is
compiled in the package being built into a scratch cache, and its files are stored under
``_prebuilt/<folder relative to the package>/`` with a manifest of the numba, numpy and Python
that made them. At run time `seed` copies them once into the cache folder numba will look in
for the installed files (only a folder massprops manages: a NUMBA_CACHE_DIR the user chose is
left as it is).

Validity is numba's, not ours: numba uses a cached entry only when its index matches the numba
version, the source file's content hash, the function's bytecode and this CPU (target triple,
CPU name and features). A wheel built on another machine or with another numba leaves entries
numba does not use, and the first run compiles as it would have (with its notice). The manifest
only avoids copying files numba would ignore. Building them: `massprops.dynamics.compiled.build`.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2]
"""The folder of the `massprops` package these kernels belong to."""

FOLDER = Path(__file__).resolve().parent / "_prebuilt"
MANIFEST = "manifest.json"
MARKER = ".prebuilt-seeded"
"""Left in a cache folder, one per installed copy of the package (named after the copy's numba
subfolder), once `seed` has looked at it for that copy (copied or not): it never copies twice,
so kernels a user deletes are compiled, not restored. Per copy, because the folder is shared by
every copy of the same sources (keyed by their hash) while numba keeps each copy's kernels
under its own path: one marker for all left a second venv of the same version compiling."""


def made_with() -> dict:
    """The versions a prebuilt cache is tied to (more than numba checks: numpy's ABI too)."""
    import numba
    import numpy as np

    return {"numba": numba.__version__, "numpy": np.__version__.rsplit(".", 1)[0],
            "python": sys.version.split()[0]}


def _cache_subpath(folder: Path) -> str:
    """numba's name for the cache folder of the sources in ``folder`` (its own rule)."""
    from numba.core.caching import _CacheLocator

    return _CacheLocator.get_suitable_cache_subpath(str(folder / "__init__.py"))


def seed(cache: Path) -> int:
    """Copy the shipped kernels into numba's cache folder ``cache`` unless it was seeded before
    or they were made with other versions; returns the number of files copied. Never raises
    for want of files or permissions: the kernels are then compiled on first use."""
    try:
        marker = cache / f"{MARKER}-{_cache_subpath(PACKAGE)}"
        if marker.exists():
            return 0
        manifest = json.loads((FOLDER / MANIFEST).read_text())
    except (OSError, ValueError, ImportError):
        return 0
    count = 0
    # a manifest or numba layout not as expected, or a cache we cannot write: what was not
    # copied is compiled on first use (and, with no marker, the copy is tried again next time)
    with contextlib.suppress(OSError, ImportError, KeyError, TypeError):
        folders = manifest.pop("folders")
        if manifest == made_with():
            for rel in folders:
                count += _copy_missing(FOLDER / rel, cache / _cache_subpath(PACKAGE / rel))
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
