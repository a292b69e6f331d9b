"""Newton-Euler dynamics of one rigid body: scene, forces, integrators, exact solutions.

Importing this package points numba's on-disk cache at a folder keyed by a hash of this
package's sources. numba checks a cached kernel only against its own file, so a kernel that
calls a changed function in another file (``forces.rhs``) would otherwise keep running stale
machine code after an edit or an upgrade. That folder (`MANAGED_CACHE`) is the one the kernels
shipped with the package are copied into (``prebuilt``); a NUMBA_CACHE_DIR the user set is used
as it is. Nothing here imports numba itself.
"""

from __future__ import annotations

import hashlib
import os
import sys
import tempfile
from pathlib import Path

MANAGED_CACHE: Path | None = None
"""numba's cache folder when massprops chose it (None: the user's NUMBA_CACHE_DIR)."""


def _configure_numba_cache() -> None:
    global MANAGED_CACHE
    if "NUMBA_CACHE_DIR" in os.environ:  # the user's choice wins
        return
    here = Path(__file__).resolve().parent
    digest = hashlib.sha256(sys.version.encode())
    for path in sorted(here.rglob("*.py")):
        digest.update(path.relative_to(here).as_posix().encode())
        digest.update(path.read_bytes())
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    target = base / "massprops" / f"numba-{digest.hexdigest()[:16]}"
    try:
        fresh = not target.is_dir()
        target.mkdir(parents=True, exist_ok=True)
        os.utime(target)  # "last used", for the pruning below (numba only reads a warm cache)
        if fresh:
            _prune_unused(target.parent, keep=target)
    except OSError:  # read-only home: a per-user temporary folder still caches within a boot
        target = Path(tempfile.gettempdir()) / f"massprops-numba-{digest.hexdigest()[:16]}"
        target.mkdir(parents=True, exist_ok=True)
    os.environ["NUMBA_CACHE_DIR"] = str(target)
    MANAGED_CACHE = target
    if "numba" in sys.modules:  # imported before us: make it re-read its settings
        sys.modules["numba"].config.reload_config()


UNUSED_CACHE_DAYS = 30
"""A cache folder of other sources (an older version, another checkout) not used for this many
days is removed when a new one is made: each holds ~8 MB, and every upgrade makes one."""


def _prune_unused(parent: Path, keep: Path) -> None:
    import shutil
    import time

    cutoff = time.time() - UNUSED_CACHE_DAYS * 86400
    for old in parent.glob("numba-*"):
        if old != keep and old.is_dir() and old.stat().st_mtime < cutoff:
            shutil.rmtree(old, ignore_errors=True)


_configure_numba_cache()
