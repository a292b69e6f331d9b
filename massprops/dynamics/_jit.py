"""The numba decorators of the dynamics kernels, and the lean start of numba the CLI uses.

``jit`` (the scalar kernels of the exact free rigid body, elliptic.py and exact.py, which the
splitting integrators call inside their compiled step loops) compiles lazily (on the first call
with given argument types) and caches the machine code on disk (massprops.dynamics points numba's
cache at a folder keyed by a hash of the package's sources). Calls between decorated functions
are resolved by global name at compile time, so a kernel calling ``rj`` calls the compiled
``rj``. Errors follow numba's default ("python") model, as the plain Python functions did: a
division by zero raises ZeroDivisionError instead of giving inf. Importing this module imports
numba: only the dynamics modules import it, never the mesh side (``massprops inspect`` stays
numba-free).
"""

from __future__ import annotations

import sys

from numba import njit

jit = njit(cache=True)
"""Decorator: ``@jit`` on a function that uses only floats, ints, tuples, float64 arrays and the
math module."""

kernel = njit(cache=True, nogil=True)
"""Decorator of an integrator's entry kernel, the one compiled function Python calls per segment.
It releases the GIL while it runs, so that simulate's error-estimate companion run steps on a
second core at the same time as the main run (the functions it calls need no flag: the GIL is
released once, around the whole compiled call)."""

LEAN_SKIPPED = ("cffi", "scipy.linalg.cython_blas")
"""What `start_numba_lean` keeps numba from importing: its cffi support (cffi and pycparser,
~70 ms, imported only because cffi is installed) and its BLAS probe (scipy.linalg, ~160 ms, for
np.dot & co.). Our kernels call neither: they use loops, scalars and the math module only."""


def start_numba_lean() -> None:
    """Initialise numba's CPU target now, without its cffi support and BLAS probe (see
    `LEAN_SKIPPED`): for a process that runs only massprops' kernels, i.e. the CLI.

    numba imports its optional extensions when the first kernel is compiled or loaded from its
    cache; that is ~0.2 s of the ~0.75 s a ``massprops simulate`` process may take (the scipy
    script it races pays none of it). Each module is made unimportable just for that moment
    (``sys.modules[name] = None``) and restored right after, so later imports work as usual.
    What stays switched off in this process: numba's cffi types (``cffi_utils.SUPPORTED``), and
    np.convolve/np.correlate in compiled code use their plain loop instead of BLAS (np.dot and
    np.linalg still find BLAS on first use). Never call this where users' own numba code may
    run (library use): a library import keeps full numba. A no-op once numba has compiled or
    loaded anything, and for a module already imported (it costs nothing more then).
    """
    if "numba.np.arraymath" in sys.modules:  # numba's target is already initialised
        return
    try:
        from numba.core.registry import cpu_target
    except ImportError:  # a numba without this layout: initialise the usual way, later
        return
    hidden = [name for name in LEAN_SKIPPED if name not in sys.modules]
    for name in hidden:
        sys.modules[name] = None  # type: ignore[assignment]  # `import name` raises ImportError
    try:
        cpu_target.target_context.refresh()  # what the first compile or cache load would do
    finally:
        for name in hidden:
            if sys.modules.get(name, 0) is None:
                del sys.modules[name]


__all__ = ["LEAN_SKIPPED", "jit", "kernel", "start_numba_lean"]
