"""Compile every stepping kernel into this package's ``_prebuilt`` folder: setup.py's build step
(`prebuilt` says how the shipped kernels are used).

    python -m massprops.dynamics.compiled.build [--only rk4,dop853,systems]
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from massprops.dynamics.compiled import compiling
from massprops.dynamics.compiled.prebuilt import (
    FOLDER,
    MANIFEST,
    PACKAGE,
    _cache_subpath,
    made_with,
)
from massprops.dynamics.integrators import INTEGRATORS


def build(names: list[str] | None = None, jobs: int = 2) -> int:
    """Compile the kernels of the integrators ``names`` (default: every stepping one and the
    systems' kernel, `compiling.SYSTEMS`) of the package this module is in and store
    them in `FOLDER`; returns the number of files.
    ``jobs`` processes compile side by side (one kernel is one process's work)."""
    kernels = compiling.compiled_names(names or [*INTEGRATORS, compiling.SYSTEMS])
    scratch = Path(tempfile.mkdtemp(prefix="massprops-prebuild-"))
    try:
        shares = compiling.balanced(kernels, jobs)  # the systems' kernel alone takes ~120 s
        env = dict(os.environ, NUMBA_CACHE_DIR=str(scratch),
                   PYTHONPATH=os.pathsep.join([str(PACKAGE.parent),
                                               os.environ.get("PYTHONPATH", "")]))
        code = ("import sys; from massprops.dynamics.compiled.compiling import helper_main; "
                "helper_main(sys.argv[1:])")
        procs = [subprocess.Popen([sys.executable, "-c", code, *share], env=env, cwd=PACKAGE.parent)
                 for share in shares if share]
        if any(p.wait() != 0 for p in procs):
            raise RuntimeError("compiling a kernel failed")
        shutil.rmtree(FOLDER, ignore_errors=True)
        folders = {_cache_subpath(d): d.relative_to(PACKAGE).as_posix()
                   for d in {p.parent for p in PACKAGE.rglob("*.py")}}
        count, stored = 0, []
        for cached in scratch.iterdir():
            rel = folders.get(cached.name)
            if rel is None:  # compiled code of a file outside the package: not ours to ship
                continue
            shutil.copytree(cached, FOLDER / rel)
            stored.append(rel)
            count += sum(1 for _ in cached.iterdir())
        (FOLDER / MANIFEST).write_text(json.dumps(made_with() | {"folders": sorted(stored)}))
        return count
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def main(argv: list[str]) -> None:
    names = None
    if argv[:1] == ["--only"] and len(argv) == 2:
        names = argv[1].split(",")
    elif argv:
        sys.exit("usage: python -m massprops.dynamics.compiled.build [--only rk4,dop853,systems]")
    print(f"massprops: prebuilt {build(names)} kernel cache files into {FOLDER}")


if __name__ == "__main__":
    main(sys.argv[1:])
