"""What the systems' step loop does between stages, compiled: the workspace, the right-hand side
ẏ = [q̇, u̇], the post-step projection onto Φ = 0 and Φ̇ = 0 (Newton with the least
kinetic-energy corrections, `systems_loops.min_norm`), and the singular-pose test between two
accepted steps (`accept`, whose docstring gives the rule; docs/systems.md, "Singular poses").
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import array_inner, array_jit, inlined
from massprops.dynamics.compiled.systems_layout import (
    D_BODIES,
    D_JOINTS,
    D_M,
    D_NQ,
    D_NV,
    P_COUPLINGS,
    P_DIMS,
    P_JOINTS,
    P_TOLERANCES,
    T_PROJECTION_ATOL,
    T_SINGULAR_MARGIN,
    W_B,
    W_DELTA,
    W_G,
    W_KEEP,
    W_PHI,
    W_QR,
    W_ROWS,
    W_SINGULAR,
    W_SVD_U,
)
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
    """The scratch arrays of every kernel, in `systems_layout`'s order (its ``W_*`` names give
    each one's slot and meaning; tests/test_systems_compiled.py checks each shape by name)."""
    dims = prog[P_DIMS]
    nq, nv, m, n, nj = dims[D_NQ], dims[D_NV], dims[D_M], dims[D_BODIES], dims[D_JOINTS]
    p, kk = max(m, nv), min(m, nv)
    nqc = nq if prog[P_COUPLINGS].shape[0] else 0  # the coordinates, kept only for couplings' rows
    return (np.zeros((n, 3, 3)),  # W_ROT
            np.zeros((n, 3)),  # W_COM
            np.zeros((n, 6)),  # W_VEL
            np.zeros((n, 6)),  # W_ACC
            np.zeros((n, INERTIA_SIZE)),  # W_INERTIA
            np.zeros((6, nv)),  # W_MOTION
            np.zeros((nj, 3)),  # W_JOINT_POINTS
            np.zeros((n, 6)),  # W_BIAS
            np.zeros((4, 3, 3)),  # W_M3
            np.zeros((16, 3)),  # W_V3
            np.zeros((6, 6)),  # W_M6
            np.zeros((n, 6)),  # W_LOADS
            np.zeros(nv),  # W_TAU
            np.zeros((n, 6, 6)),  # W_ART_INERTIA
            np.zeros((n, 6)),  # W_ART_BIAS
            np.zeros(nv),  # W_ABA_U
            np.zeros((nj, 6, 6)),  # W_ABA_DINV
            np.zeros((nj, 6, 6)),  # W_ABA_UMAT
            np.zeros((2, 6, 6)),  # W_M6_PAIR
            np.zeros(m),  # W_PHI
            np.zeros(m),  # W_GDOT
            np.zeros((m, 6)),  # W_ROW_B
            np.zeros((m, 6)),  # W_ROW_A
            np.zeros((m, nv)),  # W_G
            np.zeros((nv, nv)),  # W_MASS
            np.zeros((nv, nv)),  # W_CHOL
            np.zeros((m, nv)),  # W_B
            np.zeros((p, p)),  # W_QR
            np.zeros((p, p)),  # W_SVD_WORK
            np.zeros(p),  # W_SINGULAR
            np.zeros(1 + p, dtype=np.int64),  # W_KEEP
            np.zeros((m, kk)),  # W_SVD_U
            np.zeros((nv, kk)),  # W_SVD_V
            np.zeros(nv),  # W_COLUMN
            np.zeros(nqc),  # W_Q
            np.zeros(nv),  # W_H
            np.zeros(m),  # W_ROWS
            np.zeros(max(nq, nv)),  # W_DELTA
            np.zeros(1 + p, dtype=np.int64),  # W_ORDER
            np.zeros(p),  # W_REFLECTORS
            np.zeros((n, INERTIA_SIZE)),  # W_COMPOSITE
            np.zeros((kk, kk)),  # W_Z
            np.zeros(3))  # W_REFERENCE


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
    ji = at(pp, P_JOINTS)
    nq = at(pp, P_DIMS)[D_NQ]
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
    ji = at(pp, P_JOINTS)
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
    ji = at(pp, P_JOINTS)
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
    nq, m = at(pp, P_DIMS)[D_NQ], at(pp, P_DIMS)[D_M]
    moved[0] = moved[1] = 0.0
    if m == 0:
        return OK
    q, u = y[:nq], y[nq:]
    normalize(pp, q)
    atol = at(pp, P_TOLERANCES)[T_PROJECTION_ATOL]
    phi, g, delta, row = at(wp, W_PHI), at(wp, W_G), at(wp, W_DELTA), at(wp, W_ROWS)
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
    (det(U_prevᵀ B B_prevᵀ U_prev) ≤ 0) or is below `T_SINGULAR_MARGIN` (NEAR_SINGULAR_MARGIN) of
    the largest (fstats[6] the smallest such ratio, fstats[2] the run's), else OK; the step's B and
    kept U become the last accepted (istats[5] their rank)."""
    bm, uo, keep, x = at(wp, W_B), at(wp, W_SVD_U), at(wp, W_KEEP), at(wp, W_QR)
    sv = at(wp, W_SINGULAR)
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
    if least < at(pp, P_TOLERANCES)[T_SINGULAR_MARGIN] * top:
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
    loops = at(pp, P_DIMS)[D_M] > 0  # the projection ended with poses and factors at y's q
    if not loops:  # (its Newton steps renormalise the quaternions they turn)
        normalize(pp, y[:at(pp, P_DIMS)[D_NQ]])
    fstats[0] = max(fstats[0], moved[0])
    fstats[1] = max(fstats[1], moved[1])
    status = _rhs(pp, wp, tw, y, f, istats[6], loops)
    istats[1] += 1
    if status != OK:
        fail(istats, fstats, yfail, status, t, y)
        return status
    if accept(pp, wp, acc_b, acc_u, istats, fstats, t) == CROSSED:
        fstats[4] = t_start if fstats[6] > at(pp, P_TOLERANCES)[T_SINGULAR_MARGIN] else t
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
