"""Compiled pieces the step loops share: the force-and-torque call of the splitting kicks, the
quaternion projection, finiteness, the dense-output bookkeeping (start rows, NaN fill), the
NaN-aware max of Newton's norms, and the equal-step grid of a fixed-step segment (the splitting
methods', and the systems engine's, `compiled.systems_fixed`).
"""

from __future__ import annotations

import math

from massprops.dynamics.compiled.jit import inner
from massprops.dynamics.exact import QUATERNION_RENORM
from massprops.dynamics.forces import force_torque

EPS = 2.220446049250313e-16
"""float64 machine epsilon (numba-friendly literal of tolerances.EPS)."""

STEP_UNDERFLOW = 1e-14
"""A step below this fraction of the time scale max(|t|, t1 - t0) is round-off: status 2."""

@inner
def ft(y, o, active, codes, params):
    """forces.force_torque, compiled once and cached: the splitting kicks call it from three
    places, which would otherwise each compile it."""
    return force_torque(y, o, active, codes, params)


@inner
def copy_into(src, dst):
    """dst[i] := src[i] for every i of the 1-D array src. A loop, not ``dst[:] = src``: numba
    compiles an array-to-slice assignment with its shape-mismatch error message, whose string
    formatting machinery was ~2 s of a first compile."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@inner
def quat_offset(n):
    """Index of q[0] in a state of length n (13: full layout, 7: rotation only)."""
    return 6 if n == 13 else 0

@inner
def project_quaternion(y, o):
    """Re-normalise the quaternion y[o:o+4] in place (projection onto the unit sphere) once its
    squared norm is off 1 by more than QUATERNION_RENORM (why not always: see there).

    A quaternion whose norm is zero or not finite is no rotation any more (a diverged step: the
    division would turn an overflowing one into [0, 0, 0, 0], finite and wrong): y[o] is set to
    NaN so that the kernel's finiteness check stops there."""
    n2 = y[o] * y[o] + y[o + 1] * y[o + 1] + y[o + 2] * y[o + 2] + y[o + 3] * y[o + 3]
    s = math.sqrt(n2)
    if not (s > 0.0 and s < math.inf):
        y[o] = math.nan
    elif abs(n2 - 1.0) > QUATERNION_RENORM:
        for i in range(o, o + 4):
            y[i] /= s


@inner
def all_finite(a):
    """True if no entry of the 1-D array ``a`` is NaN or infinite."""
    for i in range(a.shape[0]):
        if not math.isfinite(a[i]):
            return False
    return True

@inner
def worst(a, b):
    """max(a, b), and NaN if either is: Python's and numba's max(0.0, nan) is 0.0, so a NaN
    correction would pass a Newton convergence test as zero (it did: a stiff spring's stage
    Jacobians gave NaN corrections that "converged" to a NaN state)."""
    if a != a or b != b:
        return math.nan
    return a if a >= b else b

@inner
def emit_start(y, t0, t_out, y_out):
    """Rows whose time is t0 (the segment start) get y itself; return the next row."""
    k = 0
    while k < t_out.shape[0] and t_out[k] <= t0:
        copy_into(y, y_out[k])
        k += 1
    return k


@inner
def fill_nan(y_out, k):
    """Rows from k on (times after the state became unusable) are NaN, never stale data."""
    for j in range(k, y_out.shape[0]):
        for i in range(y_out.shape[1]):
            y_out[j, i] = math.nan

@inner
def step_count(t0, t1, h):
    """Equal steps of at most ``h`` that land on ``t1``: ceil((t1 - t0) / h), at least 1.

    A ratio within 1e-12 of an integer counts as that integer, so (1.1 - 0) / 0.1 =
    11.000000000000002 gives 11 steps, not 12 (the simulate module cuts chunks on this grid).
    """
    return max(1, math.ceil((t1 - t0) / h * (1.0 - 1e-12)))
