"""One function body for numpy arrays and for compiled scalars.

The closed-form free rigid body (elliptic.py, exact.py) is evaluated in two settings: at all the
output times of a run at once, with numpy (the ``exact`` integrator: no compiler, numba is not
even imported), and at one instant per call inside the splitting integrators' compiled step
loops. Its formulas are written once, as plain Python over numpy that works elementwise:

- values that vary per instant (the argument u, sn, cn, dn, ...) may be arrays or floats;
  parameters of the motion (m, m1, K, the moments) are always floats, so ordinary ``if`` tests on
  them work in both settings;
- a choice per element is `where` (np.where; both sides are evaluated, so they must be cheap,
  and a NaN or inf in the side not taken is harmless: numpy callers evaluate under
  ``np.errstate(all="ignore")``, compiled code uses numpy's error model);
- a loop whose trip count differs per element runs to the largest count (`count`) or while any
  element is unfinished (`any_`), and finished elements keep their values through `where`;
- the few operations numba has no numpy form for go through the helpers below (`exponent`,
  `ldexp`), and a choice between expensive branches (transcendental functions) has a scalar form
  with a real ``if`` (`scalar_form`), so compiled code never evaluates the branch it skips.

``massprops.dynamics.compiled.jit`` (the only module that imports numba) registers every
function marked `elementwise` with numba (``register_jitable``) and gives each helper its scalar
form, so a compiled kernel that calls ``jacobi_reduced`` compiles this very source for floats.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

FUNCTIONS: list[Callable] = []
"""The functions marked `elementwise`, in definition order (``compiled.jit`` registers them)."""

SCALAR_FORMS: dict[Callable, Callable] = {}
"""numpy helper -> the function numba compiles in its place for float arguments."""


def elementwise(fn: Callable) -> Callable:
    """Mark ``fn`` as written in the elementwise style above: numpy callers call it as it is,
    compiled code gets it compiled for floats. Returns ``fn`` unchanged."""
    FUNCTIONS.append(fn)
    return fn


def scalar_form(generic: Callable) -> Callable[[Callable], Callable]:
    """Decorator: the decorated plain-float function is what compiled code runs for ``generic``."""
    def register(scalar: Callable) -> Callable:
        SCALAR_FORMS[generic] = scalar
        return scalar
    return register


def where(flags, a, b):
    """a where ``flags`` is set, else b (``np.where``; compiled: a plain ``if``, since numba's
    np.where on floats returns a 0-d array, an allocation per call)."""
    return np.where(flags, a, b)


@scalar_form(where)
def _where_scalar(flags, a, b):
    return a if flags else b


def count(n) -> int:
    """Trip count of a loop whose per-element counts are ``n`` (int array or int): the largest."""
    return int(np.max(n)) if np.size(n) else 0


@scalar_form(count)
def _count_scalar(n):
    return n


def any_(flags) -> bool:
    """Whether any element of ``flags`` (bool array or bool) is set."""
    return bool(np.any(flags))


@scalar_form(any_)
def _any_scalar(flags):
    return flags


def exponent(v):
    """The binary exponent e of v = f · 2^e, 0.5 <= |f| < 1 (0 for v = 0), elementwise."""
    return np.frexp(v)[1]


@scalar_form(exponent)
def _exponent_scalar(v):
    return math.frexp(v)[1]


def ldexp(v, n):
    """v · 2^n, exact (elementwise)."""
    return np.ldexp(v, n)


@scalar_form(ldexp)
def _ldexp_scalar(v, n):
    return math.ldexp(v, n)
