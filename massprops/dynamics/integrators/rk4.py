"""The classical 4th-order Runge-Kutta method, fixed step, quaternion re-normalised after each step.

Dense output: the cubic Hermite interpolant through the step's end values and derivatives (its
derivative at the new point is the next step's first stage, so output costs no evaluation).
Error estimate: the last step is redone as two half steps; their difference d gives that step's
local error 16/15·|d| (Richardson, order 4), and the segment's estimate is that × the number of
steps (7 extra evaluations per segment).
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import inlined, inner, kernel
from massprops.dynamics.integrators._shared import (
    all_finite,
    copy_into,
    emit_hermite,
    emit_start,
    f,
    fill_nan,
    project_quaternion,
    quat_offset,
    step_count,
)
from massprops.dynamics.integrators.base import (
    NFEV,
    STATUS,
    STATUS_NONFINITE,
    STEPS,
    IntegratorSpec,
    segment_runner,
)


@inner
def rk4_step(y, k1, h, prog, out, k2, k3, k4, tmp):
    """out = one RK4 step of length h from y (with k1 = ẏ(y) given); 3 evaluations.

    All arrays (n,) float64; k2, k3, k4, tmp are scratch. The quaternion of out is projected.
    """
    n = y.shape[0]
    for i in range(n):
        tmp[i] = y[i] + 0.5 * h * k1[i]
    f(tmp, prog, k2)
    for i in range(n):
        tmp[i] = y[i] + 0.5 * h * k2[i]
    f(tmp, prog, k3)
    for i in range(n):
        tmp[i] = y[i] + h * k3[i]
    f(tmp, prog, k4)
    sixth = h / 6.0
    for i in range(n):
        out[i] = y[i] + sixth * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i])
    project_quaternion(out, quat_offset(n))


@inlined
def _richardson(y, fy, h, y_full, prog, k2, k3, k4, tmp, mid, fmid, end):
    """Local error (max-norm, absolute) of the RK4 step y -> y_full of length h: 16/15 of its
    difference from two half steps. 7 evaluations."""
    rk4_step(y, fy, 0.5 * h, prog, mid, k2, k3, k4, tmp)
    f(mid, prog, fmid)
    rk4_step(mid, fmid, 0.5 * h, prog, end, k2, k3, k4, tmp)
    d = 0.0
    for i in range(y.shape[0]):
        d = max(d, abs(y_full[i] - end[i]))
    return 16.0 / 15.0 * d


@kernel
def _kernel(y, t0, t1, h_req, active, codes, params, mass, inertia, rot_only, t_out, y_out,
            stats):
    prog = (active, codes, params, mass, inertia, rot_only)
    n = y.shape[0]
    o = quat_offset(n)
    n_out = t_out.shape[0]
    k = emit_start(y, t0, t_out, y_out)
    if t1 <= t0:
        return 0.0, t0
    m = step_count(t0, t1, h_req)
    h = (t1 - t0) / m
    fa, fb, ynew, cur = np.empty(n), np.empty(n), np.empty(n), y.copy()
    k2, k3, k4, tmp = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    y_last, f_last = np.empty(n), np.empty(n)
    f(cur, prog, fa)
    nfev = 1
    t_a = t0
    ok = all_finite(fa)
    i = 0
    while ok and i < m:
        t_b = t1 if i == m - 1 else t0 + (i + 1) * h
        rk4_step(cur, fa, h, prog, ynew, k2, k3, k4, tmp)
        f(ynew, prog, fb)
        nfev += 4
        if not (all_finite(ynew) and all_finite(fb)):
            ok = False
            break
        if k < n_out and t_out[k] <= t_b:
            k = emit_hermite(cur, fa, ynew, fb, t_a, t_b, t_out, y_out, k, o)
        if i == m - 1:
            copy_into(cur, y_last)
            copy_into(fa, f_last)
        cur, ynew = ynew, cur  # the new state becomes current: swap, no copy
        fa, fb = fb, fa
        t_a = t_b
        i += 1
    copy_into(cur, y)
    stats[STEPS] += i
    stats[NFEV] += nfev
    if not ok:
        stats[STATUS] = STATUS_NONFINITE
        fill_nan(y_out, k)
        return 0.0, t_a
    local = _richardson(y_last, f_last, h, y, prog, k2, k3, k4, tmp, ynew, fb, fa)
    stats[NFEV] += 7
    return (local * m if math.isfinite(local) else 0.0), t1


TABLEAU = (((0.0, 0.0, 0.0, 0.0), (0.5, 0.0, 0.0, 0.0), (0.0, 0.5, 0.0, 0.0),
            (0.0, 0.0, 1.0, 0.0)), (1 / 6, 1 / 3, 1 / 3, 1 / 6))
"""(A, b) of the classical method, the stages `rk4_step` (and the systems kernel) take."""

SPEC = IntegratorSpec(
    name="rk4", kind="fixed", order=4,
    description="classical Runge-Kutta 4, fixed step (time.step)",
    run_segment=segment_runner("rk4", "fixed", _kernel), tableau=TABLEAU)
