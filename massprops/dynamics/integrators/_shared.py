"""Compiled pieces every kernel shares: the right-hand side call, the quaternion projection, the
per-block error scales, finiteness, and the dense-output bookkeeping (cubic Hermite, NaN fill).

``prog`` below is the tuple (active, codes, params, mass, inertia, rot_only) a kernel passes on
to `massprops.dynamics.forces.rhs` unchanged.
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import inner
from massprops.dynamics.exact import QUATERNION_RENORM
from massprops.dynamics.forces import force_torque, rhs

R_BLOCK, V_BLOCK, Q_BLOCK, W_BLOCK = range(4)
"""Blocks of the state, for error scales: position, velocity, quaternion, angular velocity."""

EPS = 2.220446049250313e-16
"""float64 machine epsilon (numba-friendly literal of tolerances.EPS)."""

STEP_UNDERFLOW = 1e-14
"""A step below this fraction of the time scale max(|t|, t1 - t0) is round-off: status 2."""


@inner
def f(y, prog, out):
    """out = ẏ(y) for the program ``prog``; see forces.rhs."""
    rhs(y, prog[0], prog[1], prog[2], prog[3], prog[4], prog[5], out)


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
def blocks(n):
    """(n,) int64 block id of each state component (R_BLOCK ... W_BLOCK)."""
    o = quat_offset(n)
    b = np.empty(n, dtype=np.int64)
    for i in range(n):
        if i < o:
            b[i] = R_BLOCK if i < 3 else V_BLOCK
        elif i < o + 4:
            b[i] = Q_BLOCK
        else:
            b[i] = W_BLOCK
    return b


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
def start_scales(y, blk, scales, floors):
    """scales (4,) := largest |component| of each block of y, at least ``floors`` (4,) (the
    body size, size/duration, 1/duration: a block that is zero plus round-off noise would
    otherwise ask for noise-level accuracy and stall the step); the quaternion's scale is 1."""
    copy_into(floors, scales)
    grow_scales(y, blk, scales)
    scales[Q_BLOCK] = 1.0


@inner
def grow_scales(y, blk, scales):
    """scales[b] := max(scales[b], |y_i|) over the components of each block (running max)."""
    for i in range(y.shape[0]):
        a = abs(y[i])
        if a > scales[blk[i]]:
            scales[blk[i]] = a
    scales[Q_BLOCK] = 1.0


@inner
def worst(a, b):
    """max(a, b), and NaN if either is: Python's and numba's max(0.0, nan) is 0.0, so a NaN
    correction would pass a Newton convergence test as zero (it did: a stiff spring's stage
    Jacobians gave NaN corrections that "converged" to a NaN state)."""
    if a != a or b != b:
        return math.nan
    return a if a >= b else b


@inner
def ratio(e, s):
    """e / s for an error e and a scale s >= 0, with 0 / 0 = 0 (a block that is exactly zero and
    has no error) and e / 0 = inf (an error where there is nothing to compare it with)."""
    if s > 0.0:
        return e / s
    return 0.0 if e == 0.0 else math.inf


@inner
def hermite_row(ya, fa, yb, fb, h, s, out, o):
    """out = the cubic Hermite interpolant at fraction s of a step of length h from (ya, fa) to
    (yb, fb) (values and derivatives), its quaternion re-normalised."""
    s1 = 1.0 - s
    h00 = (1.0 + 2.0 * s) * s1 * s1
    h10 = s * s1 * s1 * h
    h01 = s * s * (3.0 - 2.0 * s)
    h11 = -s * s * s1 * h
    for i in range(out.shape[0]):
        out[i] = h00 * ya[i] + h10 * fa[i] + h01 * yb[i] + h11 * fb[i]
    project_quaternion(out, o)


@inner
def emit_hermite(ya, fa, yb, fb, ta, tb, t_out, y_out, k, o):
    """Fill y_out rows from k on whose times are <= tb (the step ta -> tb); return the next k."""
    h = tb - ta
    while k < t_out.shape[0] and t_out[k] <= tb:
        if t_out[k] >= tb:
            copy_into(yb, y_out[k])
        else:
            hermite_row(ya, fa, yb, fb, h, (t_out[k] - ta) / h, y_out[k], o)
        k += 1
    return k


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
def too_small(h, t, t0, t1):
    """True if the step h is round-off compared with the time scale (status 2)."""
    return abs(h) < STEP_UNDERFLOW * max(abs(t), t1 - t0)


@inner
def step_count(t0, t1, h):
    """Equal steps of at most ``h`` that land on ``t1``: ceil((t1 - t0) / h), at least 1.

    A ratio within 1e-12 of an integer counts as that integer, so (1.1 - 0) / 0.1 =
    11.000000000000002 gives 11 steps, not 12 (the simulate module cuts chunks on this grid).
    """
    return max(1, math.ceil((t1 - t0) / h * (1.0 - 1e-12)))


@inner
def piece(t, tb, hs):
    """(h, t_next): the next piece of length ~hs of a step that ends at tb. The last piece ends
    exactly on tb; it keeps the length hs where the two differ by round-off of t only, so an
    implicit method's factorised matrix for hs stays valid."""
    if t + 1.0001 * hs >= tb:
        rest = tb - t
        if abs(rest - hs) <= 4.0 * EPS * max(abs(t), abs(tb)):
            return hs, tb
        return rest, tb
    return hs, t + hs
