"""numba, for the dynamics kernels: the decorators, the plain-Python functions compiled code calls,
and the lean start of numba the CLI uses. The only module of the package that imports numba at
its top; only the stepping integrators import it (``massprops inspect`` and the closed-form
``exact`` path stay numba-free).

Decorators. ``kernel`` marks an integrator's entry kernel, the one compiled function Python calls
per segment; ``jit`` a compiled helper that Python also calls (tests do); ``inner`` a compiled
helper called only from compiled code. All cache their machine code on disk, in a folder keyed by a
hash of the package's sources (`massprops.dynamics.compiled.cache`; numba's settings and the
environment untouched). ``inner`` helpers get no CPython wrapper: the wrapper (argument unboxing
for every argument type) is a large part of a small function's compile time and is never used for
them; a first ``simulate`` compiles ~25% less code.

Plain Python compiled where called. The right-hand side (``forces.rhs``, ``forces.force_torque``,
``forces.quat_matrix``) and the closed-form free rigid body (every function marked
``_elementwise.elementwise`` in elliptic.py and exact.py) are written once as plain Python, so the
modules that define them import no numba (the exact solution evaluates them with numpy). Importing
this module registers them with numba (``register_jitable``): a compiled kernel calling
``rhs`` compiles that source inside its own compilation and caches it with it. They use numpy's
error model (a division by zero gives inf or NaN, as in numpy), and the elementwise helpers get
their float forms (``_elementwise.SCALAR_FORMS``). Calls between compiled functions are resolved
by global name at compile time.
"""

from __future__ import annotations

import sys

from numba import njit
from numba.extending import overload, register_jitable

from massprops.dynamics import _elementwise, elliptic, exact, forces  # noqa: F401
from massprops.dynamics.compiled.cache import cached


def _cached_njit(**options):
    """A decorator: numba's njit with massprops' kernel cache (compiled.cache says where)."""
    return lambda fn: cached(njit(cache=False, **options)(fn))


jit = _cached_njit()
"""Decorator: a compiled helper that Python may also call (uses only floats, ints, tuples,
float64 arrays, numpy scalars functions and the math module)."""

inner = _cached_njit(no_cpython_wrapper=True, no_cfunc_wrapper=True)
"""Decorator: a compiled helper called only from compiled code (calling it from Python raises)."""

inlined = njit(inline="always")
"""Decorator: a compiled helper whose body numba copies into its caller (one call site, or a
few). Every separately compiled function that calls a large one (the right-hand side, the free
rotation) makes LLVM optimise that large one once more, when it is linked in; a caller that is
inlined instead costs only its own body's typing."""

inlined_jit = _cached_njit(inline="always")
"""Decorator: inlined into its compiled callers like `inlined`, and callable from Python too (its
own compiled form cached like `jit`'s)."""

kernel = _cached_njit(nogil=True)
"""Decorator of an integrator's entry kernel, the one compiled function Python calls per segment.
It releases the GIL while it runs, so that simulate's error-estimate companion run steps on a
second core at the same time as the main run (the functions it calls need no flag: the GIL is
released once, around the whole compiled call)."""

COMPILED_OPTIONS = {"error_model": "numpy"}
"""Options of the plain-Python functions compiled where called (see the module doc)."""

array_jit = _cached_njit(**COMPILED_OPTIONS)
"""Decorator: like `jit`, with numpy's error model (x / 0.0 is inf or NaN, as in numpy): the
systems' plain array functions (`compiled.systems_*`), written to give numpy's numbers."""

array_inner = _cached_njit(no_cpython_wrapper=True, no_cfunc_wrapper=True, _nrt=False,
                           **COMPILED_OPTIONS)
"""Decorator: like `inner`, with numpy's error model, and compiled without numba's reference
counting (numba's ``_nrt`` flag): such a function may not allocate an array (numba refuses to
compile one that does). numba emits an out-of-line call to NRT_incref/NRT_decref for every array
and view a function holds, ~110 calls in one pass of the systems' kinematics, even on the
`unowned` views whose count is a null test: measured, a third of the four-bar's kinematics
(1.04 → 0.78 µs). The systems' inner kernels only read and write arrays their callers own."""

array_kernel = _cached_njit(nogil=True, **COMPILED_OPTIONS)
"""Decorator: like `kernel`, with numpy's error model (the systems' step loop)."""


def _register() -> None:
    for fn in (forces.quat_matrix, forces.force_torque, forces.rhs, *_elementwise.FUNCTIONS):
        register_jitable(**COMPILED_OPTIONS)(fn)  # type: ignore[type-var]  # numba's stub: any callable
    for generic, scalar in _elementwise.SCALAR_FORMS.items():
        overload(generic, jit_options=COMPILED_OPTIONS, strict=False)(  # type: ignore[arg-type]
            lambda *args, _scalar=scalar: _scalar)


_register()

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


__all__ = ["COMPILED_OPTIONS", "LEAN_SKIPPED", "array_inner", "array_jit", "array_kernel",
           "inlined", "inlined_jit", "inner", "jit", "kernel", "start_numba_lean"]
