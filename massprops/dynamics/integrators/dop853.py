"""DOP853: Dormand & Prince's explicit Runge-Kutta pair of order 8(5,3), adaptive, with the
7th-order dense output (Hairer, Nørsett & Wanner, Solving ODEs I, §II.10, and their dop853.f).
The right-hand side is autonomous (forces do not depend on t inside a segment), so the stage
abscissae c are not needed here.

What each step does, as in dop853.f:
- 12 stages (the 13th, f at the new point, is the next step's first: FSAL);
- error: the 5th-order estimate e5 = h Σ ER_j k_j and the 3rd-order one e3 = h Σ (b_j - bhh_j) k_j,
  scaled by sk_i = rtol × S_b (the per-block scale of the package contract), combined as
  err = ‖e5‖² / sqrt(n (‖e5‖² + 0.01 ‖e3‖²)) (RMS norms), which is ~‖e5‖ where the 3rd-order
  estimate is small and tends to the 8th-order error as e5 overestimates it;
- accepted if err <= 1; new step h·min(6, max(1/3, 0.9 err^(-1/8))) (no step increase right
  after a rejection), never beyond the segment; the initial step from Hairer's HINIT;
- on acceptance the quaternion is projected, f is evaluated there (the FSAL stage), and only if
  an output time falls inside the step the 3 extra stages and the dense-output coefficients are
  computed (from the projected end point, so the interpolant ends exactly on it).
Error estimate returned: Σ over accepted steps of max_i |e5_i| × sqrt(‖e5‖² / (‖e5‖² +
0.01 ‖e3‖²)), the same correction as in err, in absolute units of the state.
A NaN/inf in a trial step counts as a failed error test (the step is cut by 3); status 1 is set
only if that goes on down to round-off, status 2 if the step underflows otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import inlined, inner, kernel
from massprops.dynamics.integrators._dop853_tableau import BHH, ER, A, B, D
from massprops.dynamics.integrators._shared import (
    all_finite,
    blocks,
    copy_into,
    emit_start,
    f,
    fill_nan,
    grow_scales,
    project_quaternion,
    quat_offset,
    ratio,
    start_scales,
    too_small,
)
from massprops.dynamics.integrators.base import (
    NFEV,
    REJECTED,
    STATUS,
    STATUS_NONFINITE,
    STATUS_STEP_LIMIT,
    STATUS_STEP_UNDERFLOW,
    STEPS,
    IntegratorSpec,
    segment_runner,
)

E3 = B - BHH
"""(12,) weights of the 3rd-order error estimate."""
SAFE, FAC_MIN, FAC_MAX = 0.9, 1.0 / 3.0, 6.0
"""dop853.f's defaults: safety factor, and bounds of the step-size ratio h_new / h."""


@inner
def _stages(y, h, k, first, last, prog, tmp):
    """k[s] = f(y + h Σ_j A[s, j] k[j]) for s in first..last-1 (k (16, n), rows < first given)."""
    n = y.shape[0]
    for s in range(first, last):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += A[s, j] * k[j, i]
            tmp[i] = y[i] + h * acc
        f(tmp, prog, k[s])


@inner
def _error_norms(k, h, ynew, blk, scales, rtol, trial):
    """(err, local_abs) of a trial step: err the scaled mixed norm of dop853.f (<= 1: accept),
    local_abs the absolute max-norm estimate. ``trial`` (4,) is scratch for the block scales
    including the trial end point."""
    n = ynew.shape[0]
    copy_into(scales, trial)
    grow_scales(ynew, blk, trial)
    err5 = err3 = emax = 0.0
    for i in range(n):
        e5 = e3 = 0.0
        for j in range(12):
            e5 += ER[j] * k[j, i]
            e3 += E3[j] * k[j, i]
        sk = rtol * trial[blk[i]]
        r5 = ratio(e5, sk)
        r3 = ratio(e3, sk)
        err5 += r5 * r5
        err3 += r3 * r3
        emax = max(emax, abs(e5))
    deno = err5 + 0.01 * err3
    if deno <= 0.0:
        deno = 1.0
    err = abs(h) * err5 / math.sqrt(n * deno)
    local = abs(h) * emax * math.sqrt(err5 / deno)
    if not (math.isfinite(err) and math.isfinite(local)):
        return math.inf, math.inf
    return err, local


@inlined
def _initial_step(y, f0, rtol, hmax, blk, scales, prog, y1, f1):
    """Hairer's HINIT for order 8: h ~ 0.01 × (time scale of y from f and from f's change).
    Components with a zero scale (a block that is exactly zero) are left out. 1 evaluation."""
    n = y.shape[0]
    dnf = dny = 0.0
    for i in range(n):
        sk = rtol * scales[blk[i]]
        if sk > 0.0:
            dnf += (f0[i] / sk) ** 2
            dny += (y[i] / sk) ** 2
    h = 1e-6 if (dnf <= 1e-10 or dny <= 1e-10) else 0.01 * math.sqrt(dny / dnf)
    h = min(h, hmax)
    for i in range(n):
        y1[i] = y[i] + h * f0[i]
    f(y1, prog, f1)
    der2 = 0.0
    for i in range(n):
        sk = rtol * scales[blk[i]]
        if sk > 0.0:
            der2 += ((f1[i] - f0[i]) / sk) ** 2
    der12 = max(math.sqrt(der2) / h, math.sqrt(dnf))
    if not math.isfinite(der12):
        return min(1e-6, hmax)
    h1 = max(1e-6, h * 1e-3) if der12 <= 1e-15 else (0.01 / der12) ** (1.0 / 8.0)
    return min(100.0 * h, h1, hmax)


@inner
def _dense_coefficients(y, ynew, h, k, cont):
    """cont (8, n): the 7th-order interpolant of the step y -> ynew (k rows 0..15 complete)."""
    n = y.shape[0]
    for i in range(n):
        ydiff = ynew[i] - y[i]
        bspl = h * k[0, i] - ydiff
        cont[0, i] = y[i]
        cont[1, i] = ydiff
        cont[2, i] = bspl
        cont[3, i] = ydiff - h * k[12, i] - bspl
        for r in range(4):
            acc = 0.0
            for j in range(16):
                acc += D[r, j] * k[j, i]
            cont[4 + r, i] = h * acc


@inner
def _dense_row(cont, s, out, o):
    """out = the interpolant at fraction s of the step, quaternion re-normalised."""
    s1 = 1.0 - s
    for i in range(out.shape[0]):
        par = cont[4, i] + s * (cont[5, i] + s1 * (cont[6, i] + s * cont[7, i]))
        out[i] = cont[0, i] + s * (cont[1, i] + s1 * (cont[2, i] + s * (cont[3, i] + s1 * par)))
    project_quaternion(out, o)


@kernel
def _kernel(y, t0, t1, rtol, active, codes, params, mass, inertia, rot_only, t_out, y_out,
            stats, floors, max_steps):
    prog = (active, codes, params, mass, inertia, rot_only)
    n = y.shape[0]
    o = quat_offset(n)
    n_out = t_out.shape[0]
    kout = emit_start(y, t0, t_out, y_out)
    if t1 <= t0:
        return 0.0, t0
    blk = blocks(n)
    scales, trial = np.empty(4), np.empty(4)
    start_scales(y, blk, scales, floors)
    k = np.empty((16, n))
    cont = np.empty((8, n))
    ynew, tmp = np.empty(n), np.empty(n)
    hmax = t1 - t0
    f(y, prog, k[0])
    stats[NFEV] += 1
    if not all_finite(k[0]):
        stats[STATUS] = STATUS_NONFINITE
        fill_nan(y_out, kout)
        return 0.0, t0
    h = _initial_step(y, k[0], rtol, hmax, blk, scales, prog, ynew, tmp)
    stats[NFEV] += 1
    t, total, rejected, nonfinite = t0, 0.0, False, False
    while t < t1:
        last = t + 1.01 * h >= t1
        if last:
            h = t1 - t
        if too_small(h, t, t0, t1):
            stats[STATUS] = STATUS_NONFINITE if nonfinite else STATUS_STEP_UNDERFLOW
            break
        if stats[STEPS] >= max_steps:
            stats[STATUS] = STATUS_STEP_LIMIT
            break
        _stages(y, h, k, 1, 12, prog, tmp)  # literal ranges: constant loop bounds
        for i in range(n):
            acc = 0.0
            for j in range(12):
                acc += B[j] * k[j, i]
            ynew[i] = y[i] + h * acc
        stats[NFEV] += 11
        err, local = _error_norms(k, h, ynew, blk, scales, rtol, trial)
        nonfinite = not math.isfinite(err)
        fac = max(1.0 / FAC_MAX, min(1.0 / FAC_MIN, err ** 0.125 / SAFE))
        if err <= 1.0:
            project_quaternion(ynew, o)
            f(ynew, prog, k[12])
            stats[NFEV] += 1
            if not all_finite(k[12]):  # a finite state whose derivative is not: stop before it
                stats[STATUS] = STATUS_NONFINITE
                break
            t_new = t1 if last else t + h
            if kout < n_out and t_out[kout] <= t_new:
                _stages(y, h, k, 13, 16, prog, tmp)
                stats[NFEV] += 3
                _dense_coefficients(y, ynew, h, k, cont)
                while kout < n_out and t_out[kout] <= t_new:
                    _dense_row(cont, (t_out[kout] - t) / h, y_out[kout], o)
                    kout += 1
            copy_into(ynew, y)
            copy_into(k[12], k[0])
            grow_scales(y, blk, scales)
            t = t_new
            total += local
            stats[STEPS] += 1
            h_next = min(h / fac, hmax)
            h = min(h_next, h) if rejected else h_next
            rejected = False
        else:
            h = h / min(1.0 / FAC_MIN, err ** 0.125 / SAFE)
            rejected = True
            stats[REJECTED] += 1
    if t < t1:
        fill_nan(y_out, kout)
    return total, t


SPEC = IntegratorSpec(
    name="dop853", kind="adaptive", order=8,
    description="Dormand-Prince 8(5,3), adaptive step (time.rtol), 7th-order dense output",
    run_segment=segment_runner("dop853", "adaptive", _kernel, scaled=True),
    tableau=(tuple(map(tuple, A[:12, :12].tolist())), tuple(B.tolist())))
