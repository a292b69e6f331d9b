"""DOP853 over a system's y = [q, u], compiled: the whole step loop of one segment, called by
its compiled entry (`systems_kernel.step_dop853`).

The method of `dynamics.systems.integrate` (the project's tableau, dop853.f's error norm and step
control): after each accepted step what every method does (`systems_step.settle`: the end
projected onto Φ = 0, Φ̇ = 0 and renormalised, f evaluated there (FSAL), the singular-pose
test), and where output times fall inside the step the dense output is built from its start
and its projected end and each sample projected in turn (`systems_step.project_sample`).

istats: [steps, evaluations, rejected, status, next output index, rank of the last accepted
step's B (-1: none yet), rank of G at the start (-1: unchecked)]; fstats: [largest position
correction, largest velocity correction, singularity margin, time of a failure, start of the
failing step, residual left unclosed, smallest margin at an accepted state]. A failure stops
the segment with its status (codes in `systems_step`); ``yfail`` then holds the state where it
happened. A stage where M is no longer positive definite (LINALG: a step so far beyond
stability that the stage state flew off, M about the origin lost to round-off, e.g. the first
step HINIT guesses on a stiff system) is a rejected step, as an infinite error is; only the
step falling to round-off (UNDERFLOW) then ends the run.
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import array_inner, inlined
from massprops.dynamics.compiled.systems_step import (
    CROSSED,
    LINALG,
    OK,
    STEP_LIMIT,
    UNDERFLOW,
    accept,
    fail,
    project_sample,
    rhs_ref,
    settle,
)
from massprops.dynamics.compiled.unowned import by_ref
from massprops.dynamics.integrators._dop853_tableau import BHH, ER, A, B, C, D
from massprops.dynamics.integrators._shared import STEP_UNDERFLOW

E3 = B - BHH
SAFE, FAC_MIN, FAC_MAX = 0.8, 1.0 / 3.0, 6.0
"""Step control: the next step aims at SAFE of the step the error estimate allows, changing by a
factor in [FAC_MIN, FAC_MAX]. dop853.f's 0.9 left the systems' samples rejecting ~1 step in 5
(the step kept overshooting the allowed one); at 0.8 under 1 in 100 are, and each sample needs
5-18 % fewer evaluations at equal true error, 1e-6 to 1e-10 (0.7 did no better): measured on
the six system samples (docs/performance.md)."""


@array_inner
def _stage(y, h, k, s, out):
    """out = y + h Σ_{j<s} A[s, j] k[j]: the sum runs along the rows of k (contiguous) and skips
    the tableau's zeros (16 of the 66 below the diagonal); each entry's sum keeps j's
    order, so the numbers are those of the plain loop."""
    n = y.size
    for i in range(n):
        out[i] = 0.0
    for j in range(s):
        a = A[s, j]
        if a != 0.0:
            for i in range(n):
                out[i] += a * k[j, i]
    for i in range(n):
        out[i] = y[i] + h * out[i]


@inlined
def scratch(n):
    """The step loop's own arrays for a state of n entries (`segment`'s ``scratch``)."""
    return (np.empty((16, n)), np.empty(n), np.empty(n), np.empty((8, n)), np.zeros(3))


@array_inner
def segment(prog, ws, scratch, arrays, t0, t1, rtol, max_steps, owners):
    """Integrate arrays' y (in place) from t0 to t1 at ``rtol``, samples at
    t_out[istats[4]:] into y_out (`systems_kernel.step_dop853` gives the arguments; the arrays
    are views numba does not reference-count, `unowned`)."""
    y, scales, t_out, y_out, istats, fstats, acc_b, acc_u, yfail = arrays
    k, ytmp, ynew, cont, moved = scratch
    n = y.size
    rank0 = istats[6]
    # every load is on or off throughout a segment (segments end at the window edges), so the
    # windows are judged at its middle: a stage on the end t1 must not see the next one's loads
    tw = 0.5 * (t0 + t1)
    pp, wp = by_ref(prog), by_ref(ws)  # the right-hand side's arguments (`systems_step.rhs_ref`)
    status = rhs_ref(pp, wp, tw, y, k[0], rank0)
    istats[1] += 1
    if status != OK:
        fail(istats, fstats, yfail, status, t0, y)
        return
    if accept(pp, wp, acc_b, acc_u, istats, fstats, t0) == CROSSED:  # starts at the pose
        fstats[4] = t0
        fail(istats, fstats, yfail, CROSSED, t0, y)
        return
    hmax = t1 - t0
    # the initial step (Hairer's HINIT)
    dnf = dny = 0.0
    for i in range(n):
        sk = rtol * scales[i]
        dnf += (k[0, i] / sk) ** 2
        dny += (y[i] / sk) ** 2
    h = 1e-6 if (dnf <= 1e-10 or dny <= 1e-10) else 0.01 * math.sqrt(dny / dnf)
    h = min(h, hmax)
    for i in range(n):
        ytmp[i] = y[i] + h * k[0, i]
    status = rhs_ref(pp, wp, tw, ytmp, k[1], rank0)
    istats[1] += 1
    if status != OK:
        fail(istats, fstats, yfail, status, t0 + h, ytmp)
        return
    der2 = 0.0
    for i in range(n):
        der2 += ((k[1, i] - k[0, i]) / (rtol * scales[i])) ** 2
    der2 = math.sqrt(der2) / h
    der12 = max(der2, math.sqrt(dnf))
    h1 = max(1e-6, h * 1e-3) if der12 <= 1e-15 else (0.01 / der12) ** (1.0 / 8.0)
    h = min(100.0 * h, h1, hmax)
    t, rejected = t0, False
    nout = t_out.size
    t_last = t0 + h  # the time of the last right-hand side (a projection failure's time)
    while t < t1:
        last = t + 1.01 * h >= t1
        if last:
            h = t1 - t
        if h <= STEP_UNDERFLOW * max(abs(t), t1):  # (integrate._failure says what it means)
            fail(istats, fstats, yfail, UNDERFLOW, t, y)
            return
        if istats[0] >= max_steps:
            fail(istats, fstats, yfail, STEP_LIMIT, t, y)
            return
        wild = False
        for s in range(1, 12):
            _stage(y, h, k, s, ytmp)
            t_last = t + h * C[s]
            status = rhs_ref(pp, wp, tw, ytmp, k[s], rank0)
            if status == LINALG:  # a stage thrown far off (M lost to round-off there): the
                wild = True       # step is far beyond stability, as an infinite error says
                istats[1] += s
                break
            if status != OK:
                istats[1] += s
                fail(istats, fstats, yfail, status, t_last, ytmp)
                return
        if wild:
            h *= FAC_MIN
            rejected = True
            istats[2] += 1
            continue
        istats[1] += 11
        err5 = err3 = 0.0
        for i in range(n):
            xb = xe = x3 = 0.0
            for j in range(12):
                xb += B[j] * k[j, i]
                xe += ER[j] * k[j, i]
                x3 += E3[j] * k[j, i]
            ynew[i] = y[i] + h * xb
            sk = rtol * max(scales[i], abs(ynew[i]))
            err5 += (xe / sk) ** 2
            err3 += (x3 / sk) ** 2
        deno = err5 + 0.01 * err3
        if deno == 0.0:
            deno = 1.0
        err = abs(h) * err5 / math.sqrt(n * deno)
        if not math.isfinite(err):
            err = math.inf
        if err <= 1.0:
            t_new = t1 if last else t + h
            # the last stage was evaluated at t + h, within the step's error of ynew: its
            # factors serve the projection's first correction (`systems_step.project_ref`)
            if settle(pp, wp, ynew, k[12], t, t_new, tw, moved, istats, fstats, acc_b, acc_u,
                      yfail, True) != OK:
                return
            kout = istats[4]
            if kout < nout and t_out[kout] <= t_new:
                for s in range(13, 16):
                    _stage(y, h, k, s, ytmp)
                    t_last = t + h * C[s]
                    status = rhs_ref(pp, wp, tw, ytmp, k[s], rank0)
                    if status != OK:
                        fail(istats, fstats, yfail, status, t_last, ytmp)
                        return
                istats[1] += 3
                _dense(y, ynew, h, k, cont)
                while kout < nout and t_out[kout] <= t_new:
                    row = y_out[kout]
                    _dense_row(cont, (t_out[kout] - t) / h, row)
                    if project_sample(pp, wp, row, t_out[kout], moved, istats, fstats,
                                      yfail) != OK:
                        return
                    kout += 1
                istats[4] = kout
            for i in range(n):
                y[i] = ynew[i]
                k[0, i] = k[12, i]
                scales[i] = max(scales[i], abs(y[i]))
            t = t_new
            istats[0] += 1
            fac = max(1.0 / FAC_MAX, min(1.0 / FAC_MIN, err ** 0.125 / SAFE))
            h_next = min(h / fac, t1 - t0)
            h = min(h_next, h) if rejected else h_next
            rejected = False
        else:
            h = h / min(1.0 / FAC_MIN, err ** 0.125 / SAFE)
            rejected = True
            istats[2] += 1


@array_inner
def _dense(y, ynew, h, k, cont):
    """dop853.f's 7th-order dense-output coefficients of the step from y to ynew."""
    for i in range(y.size):
        ydiff = ynew[i] - y[i]
        bspl = h * k[0, i] - ydiff
        cont[0, i], cont[1, i], cont[2, i] = y[i], ydiff, bspl
        cont[3, i] = ydiff - h * k[12, i] - bspl
        for r in range(4):
            x = 0.0
            for j in range(16):
                x += D[r, j] * k[j, i]
            cont[4 + r, i] = h * x


@array_inner
def _dense_row(cont, s, out):
    s1 = 1.0 - s
    for i in range(out.size):
        par = cont[4, i] + s * (cont[5, i] + s1 * (cont[6, i] + s * cont[7, i]))
        out[i] = cont[0, i] + s * (cont[1, i] + s1 * (cont[2, i] + s * (cont[3, i] + s1 * par)))
