"""`midpoint`: the implicit midpoint rule y1 = y0 + h f((y0 + y1) / 2), fixed step, order 2,
symplectic and symmetric.

It keeps every quadratic invariant of the equations exactly (to the Newton tolerance): |q|², and
for a torque-free body the kinetic energy ½ ω·J'ω and |J'ω|², and the energy of a linear
spring-mass system. Its stability function R(z) = (1 + z/2) / (1 - z/2) has |R| = 1 on the
imaginary axis: a fast linear oscillation beyond the step (|hλ| >> 1, e.g. a stiff spring at
the COM) keeps its energy but not its phase (it turns by 2 atan(hω/2) per step instead of hω:
aliased), where `implicit` (Radau IIA) damps it out. An unresolved nonlinear mode (a stiff
spring off the COM that spins the body by radians per step) has no such guarantee: its energy
drifts either way. Use it for long conservative runs; use `implicit` to get rid of a stiff mode.

Newton: simplified iterations on (I - h/2 J) ΔZ = h f(y0 + Z/2) - Z for Z = y1 - y0, J by
forward differences re-used across steps (see `_newton` for the stopping rule); a failure with a
fresh J halves the step locally (pieces grow back after two clean steps). Dense output: cubic
Hermite from the step end values and derivatives (evaluated only for steps that contain an
output time). Error estimate: the last step is redone as two half steps; 4/3 of the difference
is its local error (Richardson, order 2), and the segment's estimate is that × the number of
steps.
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import inlined, inner, kernel
from massprops.dynamics.integrators._newton import (
    CONVERGED,
    DIVERGED,
    GOING,
    MAX_ITER,
    NONFINITE,
    fd_jacobian,
    first_eta,
    lu_factor,
    lu_solve,
    verdict,
)
from massprops.dynamics.integrators._shared import (
    all_finite,
    blocks,
    copy_into,
    emit_hermite,
    emit_start,
    f,
    fill_nan,
    grow_scales,
    piece,
    project_quaternion,
    quat_offset,
    ratio,
    start_scales,
    step_count,
    too_small,
    worst,
)
from massprops.dynamics.integrators.base import (
    NFEV,
    NJEV,
    REJECTED,
    STATUS,
    STATUS_NONFINITE,
    STATUS_STEP_LIMIT,
    STATUS_STEP_UNDERFLOW,
    STEPS,
    IntegratorSpec,
    segment_runner,
)

SLOW_RATE = 1e-3
"""Newton converging slower than this (after more than 2 iterations) asks for a new Jacobian."""


@inner
def _factor(jac, h, lu, piv):
    """LU factors of I - h/2 J."""
    n = jac.shape[0]
    for i in range(n):
        for j in range(n):
            lu[i, j] = -0.5 * h * jac[i, j]
        lu[i, i] += 1.0
    return lu_factor(lu, piv)


@inner
def _solve(y, h, z, prog, lu, piv, g, tmp, fz, blk, scales, trial, eta):
    """Simplified Newton for Z = y1 - y0 (start guess in z, updated in place).

    Returns (CONVERGED | DIVERGED | NONFINITE, iterations, rate θ, η, evaluations).
    """
    n = y.shape[0]
    eta = first_eta(eta)
    theta, norm_old = 0.0, math.inf
    for it in range(MAX_ITER):
        for i in range(n):
            tmp[i] = y[i] + 0.5 * z[i]
        f(tmp, prog, fz)
        if not all_finite(fz):
            return NONFINITE, it + 1, theta, eta, it + 1
        for i in range(n):
            g[i] = h * fz[i] - z[i]
        lu_solve(lu, piv, g)
        copy_into(scales, trial)
        for i in range(n):
            tmp[i] = y[i] + z[i] + g[i]
        grow_scales(tmp, blk, trial)
        dnorm = 0.0
        for i in range(n):
            dnorm = worst(dnorm, ratio(abs(g[i]), trial[blk[i]]))
            z[i] += g[i]
        state, theta, eta = verdict(it, dnorm, norm_old, eta)
        if state != GOING:
            return state, it + 1, theta, eta, it + 1
        if math.isfinite(dnorm):
            norm_old = dnorm
    return DIVERGED, MAX_ITER, theta, eta, MAX_ITER


@inlined
def _richardson(y, h, y_full, jac, prog, lu, piv, g, tmp, fz, blk, scales, trial, z, mid, end):
    """(local error of the step y -> y_full of length h: 4/3 of its difference from two half
    steps, max-norm; evaluations). 0 if a half step does not converge (never seen: half steps
    are easier than the full one that did)."""
    n = y.shape[0]
    o = quat_offset(n)
    if not _factor(jac, 0.5 * h, lu, piv):
        return 0.0, 0
    nfev = 0
    start = y
    for half in range(2):
        for i in range(n):
            z[i] = 0.5 * (y_full[i] - y[i])
        state, _, _, _, ev = _solve(start, 0.5 * h, z, prog, lu, piv, g, tmp, fz, blk, scales,
                                    trial, 1.0)
        nfev += ev
        if state != CONVERGED:
            return 0.0, nfev
        out = mid if half == 0 else end
        for i in range(n):
            out[i] = start[i] + z[i]
        project_quaternion(out, o)
        start = mid
    d = 0.0
    for i in range(n):
        d = max(d, abs(y_full[i] - end[i]))
    return 4.0 / 3.0 * d, nfev


@kernel
def _kernel(y, t0, t1, h_req, active, codes, params, mass, inertia, rot_only, t_out, y_out,
            stats, floors, max_steps):
    prog = (active, codes, params, mass, inertia, rot_only)
    n = y.shape[0]
    o = quat_offset(n)
    kout = emit_start(y, t0, t_out, y_out)
    if t1 <= t0:
        return 0.0, t0
    m = step_count(t0, t1, h_req)
    big_h = (t1 - t0) / m
    blk = blocks(n)
    scales, trial = np.empty(4), np.empty(4)
    start_scales(y, blk, scales, floors)
    fa, fb, ynew, tmp, tmp2, g = (np.empty(n), np.empty(n), np.empty(n), np.empty(n),
                                  np.empty(n), np.empty(n))
    z, y_last, mid = np.zeros(n), np.empty(n), np.empty(n)
    jac, lu, piv = np.empty((n, n)), np.empty((n, n)), np.empty(n, dtype=np.int64)
    f(y, prog, fa)
    stats[NFEV] += 1
    if not all_finite(fa):
        stats[STATUS] = STATUS_NONFINITE
        fill_nan(y_out, kout)
        return 0.0, t0
    fa_valid, fresh, h_lu, h_prev, h_last = True, False, 0.0, big_h, big_h
    eta, t, status, level, streak = 1.0, t0, 0, 0, 0
    for step in range(m):
        tb = t1 if step == m - 1 else t0 + (step + 1) * big_h
        hs = big_h * 0.5 ** level
        clean = True
        while t < tb and status == 0:
            if stats[STEPS] >= max_steps:  # Newton failures cut steps into pieces: bounded
                status = STATUS_STEP_LIMIT
                break
            h, t_next = piece(t, tb, hs)
            if not fresh and h_lu == 0.0:
                if not fa_valid:
                    f(y, prog, fa)
                    stats[NFEV] += 1
                    fa_valid = True
                fd_jacobian(y, fa, prog, jac, tmp, tmp2)
                stats[NJEV] += 1
                stats[NFEV] += n
                fresh = True
            factored = True
            if h != h_lu:
                factored = _factor(jac, h, lu, piv)
                h_lu = h if factored else 0.0
            outcome, iters, theta = DIVERGED, 0, 0.0
            if factored:
                for i in range(n):  # start from the last step's increment, scaled to this step
                    z[i] *= h / h_prev
                outcome, iters, theta, eta, ev = _solve(y, h, z, prog, lu, piv, g, tmp, fb, blk,
                                                        scales, trial, eta)
                stats[NFEV] += ev
            if outcome != CONVERGED:
                stats[REJECTED] += 1
                for i in range(n):
                    z[i] = 0.0
                h_prev = h
                if not fresh:  # a stale Jacobian may be the cause: refresh it, same step
                    h_lu = 0.0
                    continue
                hs, level, clean = 0.5 * h, level + 1, False
                if too_small(hs, t, t0, t1):
                    status = STATUS_NONFINITE if outcome == NONFINITE else STATUS_STEP_UNDERFLOW
                continue
            for i in range(n):
                ynew[i] = y[i] + z[i]
            project_quaternion(ynew, o)
            if not all_finite(ynew):
                status = STATUS_NONFINITE
                break
            if kout < t_out.shape[0] and t_out[kout] <= t_next:
                if not fa_valid:
                    f(y, prog, fa)
                    stats[NFEV] += 1
                f(ynew, prog, fb)
                stats[NFEV] += 1
                kout = emit_hermite(y, fa, ynew, fb, t, t_next, t_out, y_out, kout, o)
                copy_into(fb, fa)
                fa_valid = True
            else:
                fa_valid = False
            copy_into(y, y_last)
            copy_into(ynew, y)
            grow_scales(y, blk, scales)
            h_last, t = h, t_next
            stats[STEPS] += 1
            h_prev, fresh = h, False
            if iters > 2 and theta > SLOW_RATE:
                h_lu = 0.0  # converging slowly: a new Jacobian at the next step's start
        if status != 0:
            break
        streak = streak + 1 if clean else 0
        if level > 0 and streak >= 2:  # two clean steps in a row: try pieces twice as long
            level, streak = level - 1, 0
    if status != 0:
        stats[STATUS] = status
        fill_nan(y_out, kout)
        return 0.0, t
    local, ev = _richardson(y_last, h_last, y, jac, prog, lu, piv, g, tmp, fb, blk, scales, trial,
                            z, mid, ynew)
    stats[NFEV] += ev
    return (local * m if math.isfinite(local) else 0.0), t


SPEC = IntegratorSpec(
    name="midpoint", kind="fixed", order=2,
    description="implicit midpoint, fixed step (time.step): symplectic, keeps quadratic "
                "invariants",
    run_segment=segment_runner("midpoint", "fixed", _kernel, scaled=True), stiff=True,
    tableau=(((0.5,),), (1.0,)))
