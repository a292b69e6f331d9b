"""What the systems' step loop does between stages, compiled: the workspace, the right-hand side
ẏ = [q̇, u̇], the post-step projection onto Φ = 0 and Φ̇ = 0 (Newton with the least
kinetic-energy corrections, `systems_loops.min_norm`), and the singular-pose test between two
accepted steps (`accept`, whose docstring gives the rule; docs/systems.md, "Singular poses").
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import array_inner, array_jit, inlined
from massprops.dynamics.compiled.systems_linalg import det
from massprops.dynamics.compiled.systems_loops import (
    LINALG,
    OK,
    accelerations,
    decompose,
    factor,
    min_norm,
    terms,
)
from massprops.dynamics.compiled.systems_tree import FREE, INERTIA_SIZE, SPHERICAL, poses
from massprops.dynamics.compiled.unowned import at, by_ref

UNDERFLOW, STEP_LIMIT, CROSSED, UNCLOSED = 1, 2, 4, 5
"""Status codes besides systems_loops' OK, SINGULAR and LINALG."""

PROJECT_ITERATIONS = 12
"""Newton steps of the post-step projection (System.project's default)."""



@array_jit
def workspace(prog):
    """The scratch arrays of every kernel (indices are the kernels' contract, see the names)."""
    dims = prog[0]
    nq, nv, m, n, nj = dims[0], dims[1], dims[2], dims[3], dims[4]
    p, kk = max(m, nv), min(m, nv)
    nqc = nq if prog[23].shape[0] else 0  # the coordinates, kept only for couplings' rows
    return (np.zeros((n, 3, 3)), np.zeros((n, 3)), np.zeros((n, 6)), np.zeros((n, 6)),  # 0-3
            np.zeros((n, INERTIA_SIZE)), np.zeros((6, nv)), np.zeros((nj, 3)),  # 4-6
            np.zeros((n, 6)),  # 7
            np.zeros((4, 3, 3)), np.zeros((16, 3)), np.zeros((6, 6)), np.zeros((n, 6)),  # 8-11
            np.zeros(nv), np.zeros((n, 6, 6)), np.zeros((n, 6)), np.zeros(nv),  # 12-15
            np.zeros((nj, 6, 6)), np.zeros((nj, 6, 6)), np.zeros((2, 6, 6)), np.zeros(m),  # 16-19
            np.zeros(m), np.zeros((m, 6)), np.zeros((m, 6)), np.zeros((m, nv)),  # 20-23
            np.zeros((nv, nv)), np.zeros((nv, nv)), np.zeros((m, nv)), np.zeros((p, p)),  # 24-27
            np.zeros((p, p)), np.zeros(p), np.zeros(1 + p, dtype=np.int64),  # 28-30
            np.zeros((m, kk)), np.zeros((nv, kk)), np.zeros(nv), np.zeros(nqc),  # 31-34
            np.zeros(nv), np.zeros(m), np.zeros(max(nq, nv)), np.zeros(nq + nv),  # 35-38
            np.zeros(1 + p, dtype=np.int64), np.zeros(p), np.zeros((n, INERTIA_SIZE)),  # 39-41
            np.zeros((kk, kk)), np.zeros(3))  # 42-43


@array_jit
def rhs(prog, ws, t, y, out, rank0):
    """out = ẏ at (t, y); the status of `systems_loops.accelerations`."""
    return rhs_ref(by_ref(prog), by_ref(ws), t, y, out, rank0)


@array_inner
def rhs_ref(pp, wp, t, y, out, rank0):
    """`rhs` with the program and workspace by reference (`unowned.by_ref`, made once by a step
    loop: passing the two tuples themselves costs ~0.5 µs a call, a quarter of a small system's
    right-hand side)."""
    return _rhs(pp, wp, t, y, out, rank0, False)


@inlined
def _rhs(pp, wp, t, y, out, rank0, posed):
    """`rhs_ref`; ``posed``: the workspace holds the poses and factors at y's q
    (`systems_loops.accelerations`)."""
    ji = at(pp, 1)
    nq = at(pp, 0)[0]
    q, u = y[:nq], y[nq:]
    status = accelerations(pp, wp, t, q, u, out[nq:], rank0, posed)
    for k in range(ji.shape[0]):
        kind, iq, iu, nqj = ji[k, 0], ji[k, 3], ji[k, 4], ji[k, 5]
        if kind == SPHERICAL:
            _quat_rate(q, iq, u, iu, out)
        elif kind == FREE:
            for i in range(3):
                out[iq + i] = u[iu + i]
            _quat_rate(q, iq + 3, u, iu + 3, out)
        else:
            for i in range(nqj):
                out[iq + i] = u[iu + i]
    return status


@inlined
def _quat_rate(q, o, w, iw, out):
    """out[o:o + 4] = ½ q[o:o + 4] ⊗ (0, w), w = w[iw:iw + 3] (on the moving side, `tree`)."""
    q0, q1, q2, q3 = q[o], q[o + 1], q[o + 2], q[o + 3]
    w0, w1, w2 = w[iw], w[iw + 1], w[iw + 2]
    out[o] = 0.5 * -(w0 * q1 + w1 * q2 + w2 * q3)
    out[o + 1] = 0.5 * (q0 * w0 + q2 * w2 - q3 * w1)
    out[o + 2] = 0.5 * (q0 * w1 + q3 * w0 - q1 * w2)
    out[o + 3] = 0.5 * (q0 * w2 + q1 * w1 - q2 * w0)


@inlined
def _quat_turn(q, o, rv, ir):
    """q[o:o + 4] = q[o:o + 4] ⊗ exp(rv), normalised (rv = rv[ir:ir + 3], moving side)."""
    angle = math.sqrt(rv[ir] ** 2 + rv[ir + 1] ** 2 + rv[ir + 2] ** 2)
    if angle == 0.0:
        return
    h = 0.5 * angle
    sh = math.sin(h) / angle
    p0, p1, p2, p3 = math.cos(h), sh * rv[ir], sh * rv[ir + 1], sh * rv[ir + 2]
    q0, q1, q2, q3 = q[o], q[o + 1], q[o + 2], q[o + 3]
    w = q0 * p0 - (q1 * p1 + q2 * p2 + q3 * p3)
    x = q0 * p1 + p0 * q1 + (q2 * p3 - q3 * p2)
    y = q0 * p2 + p0 * q2 + (q3 * p1 - q1 * p3)
    z = q0 * p3 + p0 * q3 + (q1 * p2 - q2 * p1)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    q[o], q[o + 1], q[o + 2], q[o + 3] = w / n, x / n, y / n, z / n


@array_inner
def normalize(pp, q):
    """Every quaternion coordinate of q renormalised in place (pp: the program by reference)."""
    ji = at(pp, 1)
    for k in range(ji.shape[0]):
        if ji[k, 0] == SPHERICAL or ji[k, 0] == FREE:
            o = ji[k, 3] + (3 if ji[k, 0] == FREE else 0)
            n = math.sqrt(q[o] ** 2 + q[o + 1] ** 2 + q[o + 2] ** 2 + q[o + 3] ** 2)
            for i in range(4):
                q[o + i] /= n


@array_inner
def _advance(pp, q, delta):
    """q moved by the tangent delta: coordinates add, quaternions turn by exp(δ) on their
    moving side (`tree.advance`)."""
    ji = at(pp, 1)
    for k in range(ji.shape[0]):
        kind, iq, iu, nqj = ji[k, 0], ji[k, 3], ji[k, 4], ji[k, 5]
        if kind == SPHERICAL:
            _quat_turn(q, iq, delta, iu)
        elif kind == FREE:
            for i in range(3):
                q[iq + i] += delta[iu + i]
            _quat_turn(q, iq + 3, delta, iu + 3)
        else:
            for i in range(nqj):
                q[iq + i] += delta[iu + i]


@array_jit
def project(prog, ws, y, iterations, moved):
    """y moved onto Φ = 0, Φ̇ = 0 in place (System.project without fixed coordinates): status;
    moved[0] the sum of the position corrections' max-norms, moved[1] the velocity's, moved[2]
    the residual left when the loop cannot be closed (status UNCLOSED)."""
    return project_ref(by_ref(prog), by_ref(ws), y, iterations, moved, False)


@array_inner
def project_ref(pp, wp, y, iterations, moved, stale):
    """`project` with the program and workspace by reference (`unowned.by_ref`): the step
    loops call it after every step, where passing the tuples themselves cost ~0.3 µs a call.

    ``stale``: the workspace holds M's factor and the pivoted QR of a nearby state (the step's
    last evaluation), and the first correction uses them (a simplified Newton step, which meets
    the residual test as an exact one would: the two states differ by about the step's local
    error) instead of factoring M at y's q. Every later pass, and the last, which the velocity
    projection and the right-hand side after it use, factors at its own q."""
    nq, m = at(pp, 0)[0], at(pp, 0)[2]
    moved[0] = moved[1] = 0.0
    if m == 0:
        return OK
    q, u = y[:nq], y[nq:]
    normalize(pp, q)
    atol = at(pp, 20)[2]
    phi, g, delta, row = at(wp, 19), at(wp, 23), at(wp, 37), at(wp, 36)
    nv = u.shape[0]
    done = 0
    stale = stale and iterations > 0
    while True:  # Newton on Φ: `iterations` corrections at most, then Φ must be near round-off
        poses(pp, q, wp)  # (terms' Φ̈ reads a stale motion: it is not used here)
        if stale:
            terms(pp, wp)  # Φ here; M's factor and the QR stay the nearby state's
        elif not factor(pp, wp):
            return LINALG
        residual = _largest(phi)
        if residual <= atol and stale:  # the velocity projection needs this q's factors
            stale = False
            if not factor(pp, wp):
                return LINALG
        if residual <= atol:
            break
        if done == iterations:
            if residual > 1e3 * atol:
                moved[2] = residual
                return UNCLOSED
            break
        min_norm(pp, wp, phi, delta)
        worst = 0.0
        for i in range(nv):
            delta[i] = -delta[i]
            worst = max(worst, abs(delta[i]))
        moved[0] += worst
        _advance(pp, q, delta)
        done += 1
        stale = False
    for i in range(m):
        x = 0.0
        for c in range(nv):
            x += g[i, c] * u[c]
        row[i] = x
    min_norm(pp, wp, row, delta)
    worst = 0.0
    for i in range(nv):
        u[i] -= delta[i]
        worst = max(worst, abs(delta[i]))
    moved[1] = worst
    return OK


@inlined
def _largest(v):
    out = 0.0
    for x in v:
        out = max(out, abs(x))
    return out


@array_inner
def accept(pp, wp, acc_b, acc_u, istats, fstats, t):
    """After the right-hand side at an accepted state (time t): CROSSED when a kept singular
    value of B = G L⁻ᵀ (`systems_loops.decompose`) changed sign since the last accepted step
    (det(U_prevᵀ B B_prevᵀ U_prev) ≤ 0) or is below prog[20][3] (NEAR_SINGULAR_MARGIN) of the
    largest (fstats[6] the smallest such ratio, fstats[2] the run's), else OK; the step's B and
    kept U become the last accepted (istats[5] their rank)."""
    bm, uo, keep, x, sv = at(wp, 26), at(wp, 31), at(wp, 30), at(wp, 27), at(wp, 29)
    m, nv = bm.shape[0], bm.shape[1]
    if m == 0:
        return OK
    decompose(pp, wp)
    if keep[0] == 0:
        return OK
    r = istats[5]
    status = OK
    top, least = 0.0, 1e300
    for j in range(min(m, nv)):
        top = max(top, sv[j])
        if keep[1 + j]:
            least = min(least, sv[j])
    if least < fstats[6] * top:
        fstats[6] = least / top
    fstats[2] = min(fstats[2], fstats[6])
    if least < at(pp, 20)[3] * top:
        status = CROSSED
    if r >= 0:
        for a in range(r):
            for b in range(r):
                s = 0.0
                for c in range(nv):
                    pa = 0.0
                    pb = 0.0
                    for i in range(m):
                        pa += acc_u[i, a] * bm[i, c]
                        pb += acc_b[i, c] * acc_u[i, b]
                    s += pa * pb
                x[a, b] = s
        if det(x, r) <= 0.0:
            status = CROSSED
    col = 0
    for j in range(min(m, nv)):
        if keep[1 + j]:
            for i in range(m):
                acc_u[i, col] = uo[i, j]
            col += 1
    for i in range(m):
        for c in range(nv):
            acc_b[i, c] = bm[i, c]
    istats[5] = col
    return status


@array_inner
def fail(istats, fstats, yfail, status, t, y):
    """Record a step loop's failure: its status, its time t and the state y where it happened
    (the layout of `systems_dop853`'s istats and fstats)."""
    istats[3] = status
    fstats[3] = t
    for i in range(y.size):
        yfail[i] = y[i]


@array_inner
def settle(pp, wp, y, f, t_start, t, tw, moved, istats, fstats, acc_b, acc_u, yfail, near):
    """What every method does after an accepted step from t_start to t (s), on its end y:
    y projected onto Φ = 0, Φ̇ = 0 and its quaternions renormalised, f = ẏ evaluated there
    (loads judged at tw), the singular-pose test (`accept`). OK, or the failure's status,
    recorded (`fail`); on CROSSED fstats[4] is where the crossing began (t itself when y is at
    the pose). ``near``: the method's last evaluation was within its error of y, and the
    projection's first correction may use its factors (`project_ref`'s ``stale``)."""
    status = project_ref(pp, wp, y, PROJECT_ITERATIONS, moved, near)
    if status != OK:
        fstats[5] = moved[2]
        fail(istats, fstats, yfail, status, t, y)
        return status
    loops = at(pp, 0)[2] > 0  # the projection ended with poses and factors at y's q
    if not loops:  # (its Newton steps renormalise the quaternions they turn)
        normalize(pp, y[:at(pp, 0)[0]])
    fstats[0] = max(fstats[0], moved[0])
    fstats[1] = max(fstats[1], moved[1])
    status = _rhs(pp, wp, tw, y, f, istats[6], loops)
    istats[1] += 1
    if status != OK:
        fail(istats, fstats, yfail, status, t, y)
        return status
    if accept(pp, wp, acc_b, acc_u, istats, fstats, t) == CROSSED:
        fstats[4] = t_start if fstats[6] > at(pp, 20)[3] else t
        fail(istats, fstats, yfail, CROSSED, t, y)
        return CROSSED
    return OK


@array_inner
def project_sample(pp, wp, row, t, moved, istats, fstats, yfail):
    """A dense-output sample ``row`` (at t) projected in place; OK or the failure, recorded."""
    status = project_ref(pp, wp, row, PROJECT_ITERATIONS, moved, False)
    if status != OK:
        fstats[5] = moved[2]
        fail(istats, fstats, yfail, status, t, row)
    return status
