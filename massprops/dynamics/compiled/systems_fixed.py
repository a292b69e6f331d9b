"""The registry's fixed-step methods over a system's y = [q, u], compiled: the step loop of one
segment, called by its compiled entry (`systems_kernel.step_fixed`).

The registry's methods (`dynamics.integrators.stepped`: ``rk4``, order 4; ``midpoint``, the
implicit midpoint rule, order 2, symplectic; ``implicit``, 3-stage Radau IIA, order 5, L-stable)
over the right-hand side of a system program (`systems_step.rhs`), with what a system adds after
every step, as `systems_dop853` does: the quaternion coordinates renormalised, (q, u)
projected onto Φ = 0 and Φ̇ = 0 (`systems_step.project`), f evaluated at the projected end, the
singular-pose test (`systems_step.accept`). Samples inside a step come from the cubic Hermite
interpolant of its projected ends (values and derivatives), each projected in turn.

Steps: n = ceil((t1 - t0) / h) equal steps that land on t1 (`integrators._shared.step_count`).
The implicit methods solve their stage equations by simplified Newton iterations with the
Jacobian ∂ẏ/∂y by forward differences at the step's start (n evaluations; Radau's 3n × 3n
system I − h A ⊗ J is factorised whole: systems are small), corrections measured against the
error scales (each component's floor and running max): they stop when the predicted remaining
correction η‖Δ‖ is below NEWTON_TOL, or the correction is at round-off. Where Radau's Newton
fails with the Jacobian at the step's start (it turns within the step: a stiff spring on a
fast-spinning body), the step is tried with the three stage Jacobians J(y + Z_s), re-evaluated
at the iterate while it converges slowly, and they stay in use for RETRY_FIRST steps, doubling up to
RETRY_MAX each time the one Jacobian fails again. Where Newton still fails, the step is taken
again in 2, 4, ... MAX_PIECES pieces, each a full step (projected, tested); beyond that the run
stops with UNDERFLOW. The number of pieces persists: it halves after two clean steps (a
heavy_top_damped.yaml run without that and the stage Jacobians: 80,000 pieces, 42,000 tried
and cut again, 4.5e6 evaluations).

istats and fstats as in `systems_dop853`: istats[0] the steps taken (each piece one), istats[2]
the pieces tried and taken again smaller; the run bound counts both (each costs a Jacobian).
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import array_inner, inlined
from massprops.dynamics.compiled.systems_loops import LINALG
from massprops.dynamics.compiled.systems_step import (
    CROSSED,
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
from massprops.dynamics.integrators._newton import NEWTON_TOL, ROUNDOFF, lu_factor, lu_solve
from massprops.dynamics.integrators._shared import EPS, step_count, worst
from massprops.dynamics.integrators.stepped import RADAU_A as _RADAU_ROWS

RK4, MIDPOINT, RADAU = 0, 1, 2
"""Method codes of `segment` (and of `systems_kernel.step_fixed`)."""

METHODS = {"rk4": RK4, "midpoint": MIDPOINT, "implicit": RADAU}
"""Registry names -> method codes."""

ITERATIONS = 20
"""Newton iterations allowed per step (they start from an explicit Euler guess, not from the
last step's collocation polynomial: a few more may be needed than such a start would take)."""

MAX_PIECES = 64
"""Pieces a step may be cut into where Newton fails before the run stops."""

DIVERGED = 7
"""Status: the step's end is not finite, or M stopped being positive definite on the way (a
step beyond an explicit method's stability)."""

NEWTON_FAILED = -1
"""Internal status of a step whose Newton iterations failed (then cut into pieces)."""

RADAU_A = np.array(_RADAU_ROWS)
"""(3, 3) Radau IIA's matrix (the registry's tableau, `integrators.stepped`)."""

RADAU_C = np.array([RADAU_A[0].sum(), RADAU_A[1].sum(), 1.0])
"""(3,) Radau IIA's nodes (the row sums of A)."""

STAGE_SLOW = 0.1
"""With stage Jacobians, a rate above this re-evaluates them at the current iterate."""

STAGE_REFRESHES = 2
"""Re-evaluations of the stage Jacobians allowed within one attempt of a step."""

RETRY_FIRST, RETRY_MAX = 4, 256
"""Steps taken with stage Jacobians before the one-Jacobian iteration is tried again: RETRY_FIRST
after it last worked, doubling (up to RETRY_MAX) each time it fails again."""

LEVEL, STREAK, STAGE, CALM, RETRY, TRYING = range(6)
MODE_SIZE = 6
"""The step loop's memory across steps (``scratch``'s last array): pieces per step 2^LEVEL and
the clean steps at that level; Radau's stage-Jacobian mode, the steps taken in it, the steps
it lasts (RETRY) and whether the one-Jacobian iteration is on trial again."""


@inlined
def scratch(n, method):
    """The step loop's own arrays for a state of n entries (`segment`'s ``scratch``)."""
    ns = 3 * n if method == RADAU else n
    mode = np.zeros(MODE_SIZE, dtype=np.int64)
    mode[RETRY] = RETRY_FIRST
    return (np.empty((4, n)), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
            np.empty((n, n)), np.empty((ns, ns)), np.zeros(ns, dtype=np.int64),
            np.empty((3, n)), np.empty(ns), np.zeros(3), np.empty(n), np.empty(n), mode)


@array_inner
def segment(prog, ws, scratch, arrays, t0, t1, h_req, method, max_steps, owners):
    """Integrate arrays' y (in place) from t0 to t1 in equal steps of at most h_req with
    ``method``, samples at t_out[istats[4]:] into y_out; arrays' ``scales`` (n,) are the Newton
    norm's: each component's floor and running max |y_i| (updated here, as DOP853's). The
    arguments come from `systems_kernel.step_fixed` (views numba does not reference-count)."""
    y, scales, t_out, y_out, istats, fstats, acc_b, acc_u, yfail = arrays
    k, fa, fb, ya, ynew, jac, big, piv, z, dz, moved, ytmp, ftmp, mode = scratch
    n = y.size
    rank0 = istats[6]
    # every load is on or off throughout a segment (segments end at the window edges), so the
    # windows are judged at its middle: a stage on the end t1 must not see the next one's loads
    # (Radau's last stage there made the slider-crank's drive end O(h) wrong: order 1)
    tw = 0.5 * (t0 + t1)
    pp, wp = by_ref(prog), by_ref(ws)  # the right-hand side's arguments (`systems_step.rhs_ref`)
    status = rhs_ref(pp, wp, tw, y, fa, rank0)
    istats[1] += 1
    if status != OK:
        fail(istats, fstats, yfail, status, t0, y)
        return
    if accept(pp, wp, acc_b, acc_u, istats, fstats, t0) == CROSSED:  # starts at the pose
        fstats[4] = t0
        fail(istats, fstats, yfail, CROSSED, t0, y)
        return
    m = step_count(t0, t1, h_req)
    h = (t1 - t0) / m
    for i in range(m):
        ta = t0 + i * h
        tb = t1 if i == m - 1 else t0 + (i + 1) * h
        for c in range(n):
            ya[c], k[0, c] = y[c], fa[c]  # the step's start, kept for a retry in pieces
        kout0 = istats[4]
        pieces, clean = 1 << mode[LEVEL], True
        while True:
            status = OK
            for p in range(pieces):
                tp = ta + (tb - ta) * p / pieces
                if istats[0] + istats[2] >= max_steps:  # every piece tried counts: a Jacobian
                    fail(istats, fstats, yfail, STEP_LIMIT, tp, y)
                    return
                tq = tb if p == pieces - 1 else ta + (tb - ta) * (p + 1) / pieces
                status = _step(pp, wp, scratch, arrays, method, tp, tq, tw, rank0)
                if status != OK:
                    break
                istats[0] += 1
            if status != NEWTON_FAILED:
                break
            istats[0] -= p  # the p pieces accepted before the one that failed, and that one,
            istats[2] += p + 1  # are taken again smaller: tried, not steps
            pieces, clean = 2 * pieces, False
            mode[LEVEL] += 1
            if pieces > MAX_PIECES:
                fail(istats, fstats, yfail, UNDERFLOW, ta, ya)
                return
            for c in range(n):
                y[c], fa[c] = ya[c], k[0, c]
            istats[4] = kout0
        if status != OK:
            return  # _step recorded the failure
        mode[STREAK] = mode[STREAK] + 1 if clean else 0
        if mode[LEVEL] > 0 and mode[STREAK] >= 2:  # two clean steps: pieces twice as long
            mode[LEVEL], mode[STREAK] = mode[LEVEL] - 1, 0


@array_inner
def _step(pp, wp, scratch, arrays, method, ta, tb, tw, rank0):
    """One step of ``method`` from (ta, y, fa) to tb: y, fa become the projected end and its
    derivative, samples inside written; OK, NEWTON_FAILED (nothing changed), or a failure's
    status (recorded). Every evaluation judges the load windows at ``tw``; pp, wp: the program
    and workspace by reference (`unowned.by_ref`, made by `segment`)."""
    y, scales, t_out, y_out, istats, fstats, acc_b, acc_u, yfail = arrays
    k, fa, fb, ya, ynew, jac, big, piv, z, dz, moved, ytmp, ftmp, mode = scratch
    n = y.size
    h = tb - ta
    staged = method == RADAU and mode[STAGE] == 1
    if method == RK4:
        status = _rk4(pp, wp, tw, h, y, fa, k, ytmp, ynew, rank0)
        istats[1] += 3
    elif staged:
        status, evals = _implicit(pp, wp, scratch, method, tw, h, y, scales, rank0, True)
        istats[1] += evals
    else:
        status = _jacobian(pp, wp, tw, y, fa, scales, jac, ytmp, ftmp, rank0)
        istats[1] += n
        if status == OK:
            status, evals = _implicit(pp, wp, scratch, method, tw, h, y, scales, rank0, False)
            istats[1] += evals
        if status == NEWTON_FAILED and method == RADAU:  # J turns within the step: the stage
            staged = True  # Jacobians, for this step and a while
            mode[STAGE], mode[CALM] = 1, 0
            if mode[TRYING]:
                mode[RETRY], mode[TRYING] = min(2 * mode[RETRY], RETRY_MAX), 0
            status, evals = _implicit(pp, wp, scratch, method, tw, h, y, scales, rank0, True)
            istats[1] += evals
    if status == NEWTON_FAILED:
        return status
    if status == LINALG or (status == OK and not _finite(ynew)):
        # M stops being positive definite only at a state gone wild (NaN or 1e300 angles
        # reach M first); the implicit methods' iterates gone wild are NEWTON_FAILED already
        status = DIVERGED
    if status != OK:
        fail(istats, fstats, yfail, status, tb, ynew)
        return status
    status = settle(pp, wp, ynew, fb, ta, tb, tw, moved, istats, fstats, acc_b, acc_u, yfail,
                    False)  # the last evaluation (a stage, a Newton iterate) may be a step away
    if status != OK:
        return status
    kout = istats[4]
    while kout < t_out.size and t_out[kout] <= tb:
        row = y_out[kout]
        _hermite(y, fa, ynew, fb, h, (t_out[kout] - ta) / h, row)
        status = project_sample(pp, wp, row, t_out[kout], moved, istats, fstats, yfail)
        if status != OK:
            return status
        kout += 1
    istats[4] = kout
    for c in range(n):
        y[c], fa[c] = ynew[c], fb[c]
        scales[c] = max(scales[c], abs(y[c]))
    if staged:
        mode[CALM] += 1
        if mode[CALM] >= mode[RETRY]:  # the one Jacobian again, on trial
            mode[STAGE], mode[TRYING] = 0, 1
    elif mode[TRYING]:
        mode[RETRY], mode[TRYING] = RETRY_FIRST, 0
    return OK


@array_inner
def _rk4(pp, wp, tw, h, y, f0, k, ytmp, out, rank0):
    """out = the classical RK4 step of length h from y, f0 = ẏ there; k[1:4] its other stages
    (loads judged at ``tw``)."""
    n = y.size
    for s in range(1, 4):
        c = 0.5 if s < 3 else 1.0
        for i in range(n):
            ytmp[i] = y[i] + c * h * (k[s - 1, i] if s > 1 else f0[i])
        status = rhs_ref(pp, wp, tw, ytmp, k[s], rank0)
        if status != OK:
            for i in range(n):
                out[i] = ytmp[i]
            return status
    for i in range(n):
        out[i] = y[i] + h / 6.0 * (f0[i] + 2.0 * k[1, i] + 2.0 * k[2, i] + k[3, i])
    return OK


@array_inner
def _jacobian(pp, wp, tw, y, f0, scales, jac, ytmp, ftmp, rank0):
    """jac (n, n) = ∂ẏ/∂y at y (loads at ``tw``) by forward differences (f0 = ẏ there). The
    increment of component j is √EPS × its error scale (floor and running max, ≥ |y_j|),
    rounded so that y_j + δ − y_j is exactly δ: Hairer's √(EPS max(1e-5, |y_j|)) is 5e-11 for
    a rate at rest, where a stiff spring's ẏ ~ 1e7 has round-off 1e-9, and the column came out
    as noise."""
    n = y.size
    for i in range(n):
        ytmp[i] = y[i]
    for j in range(n):
        yj = y[j]
        ytmp[j] = yj + math.sqrt(EPS) * max(scales[j], abs(yj))
        d = ytmp[j] - yj
        status = rhs_ref(pp, wp, tw, ytmp, ftmp, rank0)
        ytmp[j] = yj
        if status != OK:
            return status
        for i in range(n):
            jac[i, j] = (ftmp[i] - f0[i]) / d
    return OK


@array_inner
def _implicit(pp, wp, scratch, method, tw, h, y, scales, rank0, stage):
    """ynew by simplified Newton on the stage equations: Radau IIA, Z (3, n) with
    Z − h (A ⊗ I) F(y + Z) = 0, ynew = y + Z_3; the midpoint rule, w = y1 − y with
    w − h f(t + h/2, y + w/2) = 0 (in z[0]). The Newton matrix from ``jac`` (J at y), or with
    ``stage`` (Radau) from the stage Jacobians J(y + Z_s) at the first iterate, evaluated anew
    at the iterate (at most STAGE_REFRESHES times) while it converges slower than STAGE_SLOW
    or not at all. (status, evaluations)."""
    k, fa, fb, ya, ynew, jac, big, piv, z, dz, moved, ytmp, ftmp, mode = scratch
    n = y.size
    st = 3 if method == RADAU else 1
    for r in range(st):
        c = RADAU_C[r] if method == RADAU else 1.0
        for i in range(n):
            z[r, i] = h * c * fa[i]  # the explicit Euler guess: a first correction of O(h²)
    if not stage:
        _newton_matrix(big, jac, h, method, -1)
        if not lu_factor(big, piv):
            return NEWTON_FAILED, 0
    # η = 1 at the first iteration: nothing predicts the rate yet, so a step converges after
    # one iteration only on a correction at round-off
    evals, eta, norm_old = 0, 1.0, math.inf
    refresh, refreshes = stage, 0
    for it in range(ITERATIONS):
        for s in range(st):  # the stage derivatives F(y + Z_s), in k[1:]
            for i in range(n):
                ytmp[i] = y[i] + (z[s, i] if method == RADAU else 0.5 * z[0, i])
            status = rhs_ref(pp, wp, tw, ytmp, k[1 + s], rank0)
            evals += 1
            if status == LINALG:  # an iterate gone wild: not the system's fault
                return NEWTON_FAILED, evals
            if status != OK:
                for i in range(n):
                    ynew[i] = ytmp[i]  # where it failed, for the message
                return status, evals
        if refresh:  # the stage Jacobians at this iterate (ynew holds each stage's state)
            refresh = False
            for s in range(st):
                for i in range(n):
                    ynew[i] = y[i] + z[s, i]
                status = _jacobian(pp, wp, tw, ynew, k[1 + s], scales, jac, ytmp, ftmp, rank0)
                evals += n
                if status != OK:  # a Jacobian at an iterate gone wild
                    return NEWTON_FAILED, evals
                _newton_matrix(big, jac, h, method, s)
            if not lu_factor(big, piv):
                return NEWTON_FAILED, evals
            norm_old = math.inf  # a new matrix: the last rate says nothing about it
        for r in range(st):  # the residual −(Z − h A F), solved for the correction
            for i in range(n):
                x = z[r, i]
                for s in range(st):
                    x -= h * (RADAU_A[r, s] if method == RADAU else 1.0) * k[1 + s, i]
                dz[r * n + i] = -x
        lu_solve(big, piv, dz)
        dnorm = 0.0
        for r in range(st):
            for i in range(n):
                z[r, i] += dz[r * n + i]
        for i in range(n):  # each component against the largest it has been, or is at the end
            sc = max(scales[i], abs(y[i] + z[st - 1, i]))
            for r in range(st):
                dnorm = worst(dnorm, abs(dz[r * n + i]) / sc)
        if not math.isfinite(dnorm):
            return NEWTON_FAILED, evals
        if math.isfinite(norm_old):
            theta = dnorm / norm_old
            if stage and theta > STAGE_SLOW and refreshes < STAGE_REFRESHES \
                    and it + 1 < ITERATIONS and dnorm > ROUNDOFF:
                refresh, refreshes = True, refreshes + 1  # Jacobians at the current iterate
                continue
            if theta >= 0.99:
                return NEWTON_FAILED, evals
            eta = theta / (1.0 - theta)
        norm_old = dnorm
        if dnorm <= ROUNDOFF or eta * dnorm <= NEWTON_TOL:
            for i in range(n):
                ynew[i] = y[i] + z[st - 1, i]
            return OK, evals
    return NEWTON_FAILED, evals


@inlined
def _newton_matrix(big, jac, h, method, col):
    """The Newton matrix I − h (A ⊗ I) diag(J_s) (the midpoint rule: I − h/2 J), all of it
    from the one J = ``jac`` (``col`` < 0) or its column block ``col`` from J_col = ``jac``."""
    n = jac.shape[0]
    st = 3 if method == RADAU else 1
    for r in range(st):
        for s in range(st):
            if col >= 0 and s != col:
                continue
            a = RADAU_A[r, s] if method == RADAU else 0.5
            for i in range(n):
                for j in range(n):
                    big[r * n + i, s * n + j] = -h * a * jac[i, j]
                big[r * n + i, s * n + i] += 1.0 if r == s else 0.0


@array_inner
def _finite(v):
    for x in v:
        if not math.isfinite(x):
            return False
    return True


@array_inner
def _hermite(y0, f0, y1, f1, h, s, out):
    """out = the cubic Hermite interpolant of (y0, f0) at s = 0 and (y1, f1) at s = 1."""
    h00 = (1.0 + 2.0 * s) * (1.0 - s) ** 2
    h10 = s * (1.0 - s) ** 2
    h01 = s * s * (3.0 - 2.0 * s)
    h11 = s * s * (s - 1.0)
    for i in range(out.size):
        out[i] = h00 * y0[i] + h10 * h * f0[i] + h01 * y1[i] + h11 * h * f1[i]
