"""Where massprops' own kernels keep their machine code, without touching the host process.

numba checks a cached kernel only against its own source file, so a kernel that calls a changed
function in another file (``forces.rhs``) would keep running stale machine code after an edit or
an upgrade. massprops' kernels therefore cache in a folder keyed by a hash of the dynamics
package's sources and of the Python, numba and numpy they run with:
``<base>/massprops/numba-<hash>/``, where the base is the NUMBA_CACHE_DIR the user set, else
``$XDG_CACHE_HOME`` (``~/.cache`` by default). Only massprops' kernels use it: their decorators
(`jit`) give each one a `KernelCache`, whose locator knows that folder. numba's config and the
environment are never changed, so a user's own numba functions cache where numba puts them.

Inside the folder a kernel's files are named by its source's place in the package
(``dynamics/compiled``), not by the absolute path numba's own locators hash: the folder's name
already fixes every source's content, and numba still checks each entry against its source
file's content hash, its bytecode and this CPU. So every copy of the same sources shares one set
of kernels: the build folder (setup.py compiles into this cache, so a second install of the same
sources loads instead of compiling), the installed package, a source checkout running its
tests, a second virtual environment.

Nothing is written on import. The first time a kernel is loaded or compiled, `cache_root` makes
the folder (a per-user temporary one if the base cannot be written), marks it as used, removes
folders of other sources unused for `UNUSED_CACHE_DAYS`, and copies in the kernels shipped with
the package (`prebuilt.seed`).
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path

from numba.core import config
from numba.core.caching import (
    CompileResultCacheImpl,
    FunctionCache,
    IndexDataCacheFile,
    _CacheLocator,
    _SourceFileBackedLocatorMixin,
)

from massprops.dynamics.compiled.prebuilt import seed

DYNAMICS = Path(__file__).resolve().parents[1]
"""The sources whose hash names the folder (every kernel and what it calls lives here)."""

NOT_COMPILED = ("systems",)
"""Sub-packages of dynamics that no kernel calls: an edit there keeps the kernels' folder."""

UNUSED_CACHE_DAYS = 30
"""A cache folder of other sources (an older version, another checkout) not used for this many
days is removed when a new one is made: each holds ~8 MB, and every upgrade makes one."""

PORTABLE_CPU = "generic"
"""The CPU name of portable kernels (numba's NUMBA_CPU_NAME, with no CPU features): the wheel's
prebuilt kernels are compiled for it (`build`), so that they load on any CPU of the
architecture they were built on. Measured, they run as fast as this CPU's own: the kernels are
scalar loops that the CPU's vector extensions do not speed up (docs/performance.md,
"Compiling")."""

PACKAGE = DYNAMICS.parent
"""The `massprops` package: a kernel's files are named by its source's folder relative to it."""


@functools.cache
def digest() -> str:
    """The hash that names the kernels' folder: the dynamics sources that kernels compile (their
    paths in the package and their bytes), the Python, and the numba and numpy versions (numba's
    index checks its own version; numpy's is checked here, for its ABI)."""
    import numba
    import numpy

    versions = (sys.version, numba.__version__, numpy.__version__.rsplit(".", 1)[0])
    digest = hashlib.sha256(repr(versions).encode())
    for path in sorted(DYNAMICS.rglob("*.py")):
        if path.relative_to(DYNAMICS).parts[0] in NOT_COMPILED:
            continue
        digest.update(path.relative_to(DYNAMICS).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def planned_root() -> Path:
    """The folder the kernels will cache in (nothing is created; see the module doc)."""
    base = (getattr(config, "CACHE_DIR", None) or os.environ.get("XDG_CACHE_HOME")
            or Path.home() / ".cache")  # CACHE_DIR: numba's config sets it at import
    return Path(base) / "massprops" / f"numba-{digest()}"


def kernel_subpath(py_file: str) -> str:
    """The folder, inside the cache folder, of the kernels defined in ``py_file``: its folder
    relative to the package (``dynamics/compiled``); the same for every copy of the package."""
    return Path(py_file).resolve().parent.relative_to(PACKAGE).as_posix()


_settle_lock = threading.Lock()


@functools.cache
def cache_root() -> Path:
    """The folder, made ready for use (see the module doc); called on the first load or compile."""
    with _settle_lock:
        target = planned_root()
        try:
            fresh = not target.is_dir()
            target.mkdir(parents=True, exist_ok=True)
            os.utime(target)  # "last used", for the pruning below (numba only reads a warm cache)
            if fresh:
                _prune_unused(target.parent, keep=target)
        except OSError:  # read-only home: a per-user temporary folder still caches within a boot
            target = Path(tempfile.gettempdir()) / f"massprops-numba-{digest()}"
            target.mkdir(parents=True, exist_ok=True)
        seed(target, digest())
        return target


def _prune_unused(parent: Path, keep: Path) -> None:
    cutoff = time.time() - UNUSED_CACHE_DAYS * 86400
    for old in parent.glob("numba-*"):
        if old != keep and old.is_dir() and old.stat().st_mtime < cutoff:
            shutil.rmtree(old, ignore_errors=True)


class _KernelLocator(_SourceFileBackedLocatorMixin, _CacheLocator):
    """numba's locator protocol for massprops' kernels: the source file's stamp (its content
    hash) as numba's own locators take it, the folder `kernel_subpath` under `planned_root` until
    `cache_root` settles it."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._subpath = kernel_subpath(py_file)
        self._cache_path = str(planned_root() / self._subpath)

    def get_cache_path(self):
        return self._cache_path

    @classmethod
    def from_function(cls, py_func, py_file):
        return cls(py_func, py_file)  # numba's own would make the folder now: on import


class _KernelCacheImpl(CompileResultCacheImpl):
    _locator_classes = [_KernelLocator]


class KernelCache(FunctionCache):
    """numba's per-function cache, in massprops' folder, settled on first use."""

    _impl_class = _KernelCacheImpl

    def __init__(self, py_func):
        super().__init__(py_func)
        self._settled = False

    def _settle(self) -> None:
        if self._settled:
            return
        locator = self._impl.locator
        path = str(cache_root() / locator._subpath)
        if path != self._cache_path:  # the home was read-only: the temporary folder
            locator._cache_path = self._cache_path = path
            self._cache_file = IndexDataCacheFile(cache_path=path,
                                                  filename_base=self._impl.filename_base,
                                                  source_stamp=locator.get_source_stamp())
        self._settled = True

    def load_overload(self, sig, target_context):
        self._settle()
        return super().load_overload(sig, target_context)

    def _load_overload(self, sig, target_context):
        """This CPU's own entry, else the portable one (`PORTABLE_CPU`) for the same sources,
        signature and architecture: code for a generic CPU of this architecture runs on every
        CPU of it."""
        data = super()._load_overload(sig, target_context)
        if data is None and self._enabled:
            sig_key, (triple, _, _), code = self._index_key(sig, target_context.codegen())
            data = self._cache_file.load((sig_key, (triple, PORTABLE_CPU, ""), code))
            if data is not None:
                data = self._impl.rebuild(target_context, data)
        return data

    def save_overload(self, sig, data):
        self._settle()
        return super().save_overload(sig, data)


def cached(dispatcher):
    """Give a numba dispatcher (made with ``cache=False``) massprops' kernel cache: what numba's
    ``cache=True`` does, ``dispatcher._cache = FunctionCache(py_func)``, with our locator."""
    dispatcher._cache = KernelCache(dispatcher.py_func)
    return dispatcher
