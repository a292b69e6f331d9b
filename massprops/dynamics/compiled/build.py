"""Compile every stepping kernel into the kernels' cache, for any CPU of this architecture
(`PORTABLE_ENV`), and store them in this package's ``_prebuilt`` folder: setup.py's build step
(`prebuilt` says how the shipped kernels are used).

    python -m massprops.dynamics.compiled.build [--only dop853,fixed,splitting]

The kernels compile into the same cache folder a run would use (`cache`), so building the same
sources again (a reinstall, the test extra's install) loads them in seconds instead of compiling.
"""

from __future__ import annotations

import os
import sys

from massprops.dynamics.compiled import cache, compiling, prebuilt

PORTABLE_ENV = {"NUMBA_CPU_NAME": cache.PORTABLE_CPU, "NUMBA_CPU_FEATURES": ""}
"""numba's settings of the build's processes: code for any CPU of this architecture, which the
kernels' cache loads on every one (`cache.PORTABLE_CPU`), so that a wheel moved to another
machine, or a build folder shared by several, compiles nothing."""


def build(names: list[str] | None = None, jobs: int = 2) -> int:
    """Load or compile the kernels of the integrators ``names`` (default: every stepping one and
    the systems' kernel) of the package this module is in, ``jobs`` processes side by side, and
    store the cache folder's kernels in `prebuilt.FOLDER`; returns the number of files."""
    env = dict(os.environ, **PORTABLE_ENV, PYTHONPATH=os.pathsep.join(
        p for p in (str(cache.PACKAGE.parent), os.environ.get("PYTHONPATH")) if p))
    compiling.ready_side_by_side(names, jobs, env=env)
    return prebuilt.store(cache.cache_root(), cache.digest())


def main(argv: list[str]) -> None:
    names = None
    if argv[:1] == ["--only"] and len(argv) == 2:
        names = argv[1].split(",")
    elif argv:
        sys.exit("usage: python -m massprops.dynamics.compiled.build "
                 "[--only dop853,fixed,splitting]")
    print(f"massprops: prebuilt {build(names)} kernel cache files into {prebuilt.FOLDER}")


if __name__ == "__main__":
    main(sys.argv[1:])
