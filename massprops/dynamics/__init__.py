"""Newton-Euler dynamics of one rigid body: scene, forces, integrators, exact solutions.

Importing this package points numba's on-disk cache at a folder keyed by a hash of this
package's sources. numba checks a cached kernel only against its own file, so a kernel that
calls a changed function in another file (``forces.rhs``) would otherwise keep running stale
machine code after an edit or an upgrade. Nothing here imports numba itself.
"""

from __future__ import annotations

import hashlib
import os
import sys
import tempfile
from pathlib import Path


def _configure_numba_cache() -> None:
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
        target.mkdir(parents=True, exist_ok=True)
    except OSError:  # read-only home: a per-user temporary folder still caches within a boot
        target = Path(tempfile.gettempdir()) / f"massprops-numba-{digest.hexdigest()[:16]}"
        target.mkdir(parents=True, exist_ok=True)
    os.environ["NUMBA_CACHE_DIR"] = str(target)
    if "numba" in sys.modules:  # imported before us: make it re-read its settings
        sys.modules["numba"].config.reload_config()


_configure_numba_cache()
