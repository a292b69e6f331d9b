"""The one numba decorator for the scalar kernels of the exact free rigid body (elliptic.py,
exact.py), so the splitting integrators can call them inside their compiled step loops.

``jit`` compiles lazily (on the first call with given argument types) and caches the machine
code on disk (massprops.dynamics points numba's cache at a folder keyed by a hash of the
package's sources). Calls between decorated functions are resolved by global name at compile
time, so a kernel calling ``rj`` calls the compiled ``rj``. Errors follow numba's default
("python") model, as the plain Python functions did: a division by zero raises
ZeroDivisionError instead of giving inf. Importing this module imports numba: only the dynamics
modules import it, never the mesh side (``massprops inspect`` stays numba-free).
"""

from __future__ import annotations

from numba import njit

jit = njit(cache=True)
"""Decorator: ``@jit`` on a function that uses only floats, ints, tuples, float64 arrays and the
math module."""

__all__ = ["jit"]
