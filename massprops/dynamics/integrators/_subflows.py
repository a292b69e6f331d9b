"""The two sub-flows the splitting integrators compose: the drift (no forces: exact free rigid body
and coasting centre of mass) and the kick (forces with the configuration frozen).

State layouts as in the package contract: full (13) [r, v, q, ω'] with the quaternion at o = 6,
rotation-only (7) [q, ω'] with o = 0. ω' is in the principal frame, q rotates principal -> world.

Kick state z: the velocities the kick changes, z = (v, ω') (6) in the full layout, z = ω' (3) in
the rotation-only one, with the mass matrix M = diag(m, m, m, J'1, J'2, J'3) (or diag(J')). Force
index i of z_i in ``force_torque``'s 6-tuple (fx, fy, fz, nx, ny, nz): i (full) or 3 + i
(rotation-only).
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import inlined_jit, inner, jit
from massprops.dynamics.exact import free_rotation_kernel
from massprops.dynamics.forces import DRAG, JOINT, SPRING
from massprops.dynamics.integrators._newton import lu_factor, lu_solve
from massprops.dynamics.integrators._shared import ft

SPRING_STIFFNESS, SPRING_DAMPING = 7, 9
"""Columns of a SPRING row of ``params`` (see forces.NPAR): k (N/m) and c (N·s/m)."""


# --- the program split into its configuration part and its velocity part -----------------------
@jit
def kick_program(active, codes, params, mass, inertia, o):
    """The force program split for the kick, once per segment. Returns the tuple
    (codes, active_c, params_c, active_d, params_d, mass, inertia, o, has_c, has_d, has_any):

    active_c/params_c: every active term with its velocity dependence removed (drag off, spring
    damping c = 0): a force that depends on (r, q) only, constant during a kick.
    active_d/params_d: the velocity-dependent part alone (drag, spring damping with k = 0): a
    force exactly linear in z, f = B z, so B's columns are its values at unit vectors.
    has_c/has_d: each part has an active term; has_any: some term is active at all.
    A joint's row (a held body, massprops.dynamics.joints) is in both parts: it takes out what
    the joint carries from each part's total, which is linear, so the parts still add up.
    """
    k = codes.shape[0]
    active_c = np.zeros(k, dtype=np.bool_)
    active_d = np.zeros(k, dtype=np.bool_)
    params_c = params.copy()
    params_d = params.copy()
    has_c = has_d = has_any = False
    for i in range(k):
        if not active[i]:
            continue
        if codes[i] == JOINT:
            active_c[i] = active_d[i] = True
            continue
        has_any = True
        if codes[i] == DRAG:
            active_d[i] = has_d = True
        elif codes[i] == SPRING:
            params_c[i, SPRING_DAMPING] = 0.0
            params_d[i, SPRING_STIFFNESS] = 0.0
            active_c[i] = has_c = True
            if params[i, SPRING_DAMPING] != 0.0:
                active_d[i] = has_d = True
        else:
            active_c[i] = has_c = True
    return (codes, active_c, params_c, active_d, params_d, mass, inertia, o, has_c, has_d,
            has_any)


@jit
def kick_work(n):
    """Scratch arrays of the kick for a state of length n: (ytmp (n,), b (nz, nz), a (nz, nz),
    piv (nz,) int64, rhs (nz,), z0 (nz,), fc (nz,)), nz = 6 (full) or 3 (rotation-only)."""
    nz = 6 if n == 13 else 3
    return (np.empty(n), np.empty((nz, nz)), np.empty((nz, nz)), np.empty(nz, dtype=np.int64),
            np.empty(nz), np.empty(nz), np.empty(nz))


@inner
def z_index(i, o):
    """Index in the state of the kick variable z_i (v then ω' in the full layout, ω' only in the
    rotation-only one)."""
    if o == 6:
        return 3 + i if i < 3 else 7 + i
    return 4 + i


@inner
def z_mass(i, mass, inertia, o):
    """The diagonal of M for z_i: m for a velocity component, J'_j for ω'_j."""
    if o == 6:
        return mass if i < 3 else inertia[i - 3]
    return inertia[i]


# --- the kick ----------------------------------------------------------------------------------
@inlined_jit
def kick(y, tau_a, tau_b, kp, wk):
    """Two consecutive kicks of lengths tau_a then tau_b (s, either sign) at the configuration of
    y, applied to y in place; returns the number of ``force_torque`` evaluations.

    Without damping the kick is exact and the two merge into one. With damping each is one
    implicit-midpoint step of the linear ODE M ż = F_c + B z (`damped_kick`).
    """
    if kp[9]:
        return damped_kick(y, tau_a, tau_b, kp, wk)
    if kp[8]:
        # Inlined into the step (inline="always") and arrays picked out one by one: a call that
        # unpacks the whole tuple pays a reference count per array, several times the force
        # evaluation itself (measured: 280 -> 130 ns per kick with gravity).
        exact_kick(y, tau_a + tau_b, kp[0], kp[1], kp[2], kp[5], kp[6], kp[7])
        return 1
    return 0


@inlined_jit
def exact_kick(y, tau, codes, active_c, params_c, mass, inertia, o):
    """z += tau M⁻¹ F_c(r, q): the exact flow of the configuration-dependent forces."""
    f6 = ft(y, o, active_c, codes, params_c)
    if o == 6:
        for i in range(3):
            y[3 + i] += tau * f6[i] / mass
    for i in range(3):
        y[o + 4 + i] += tau * f6[3 + i] / inertia[i]


@inner
def damped_kick(y, tau_a, tau_b, kp, wk):
    """The kicks of `kick` when a velocity-dependent term is active: F_c and B once at this
    configuration, then one implicit-midpoint step per nonzero length. Returns evaluations."""
    codes, active_c, params_c, _, _, _, _, o, has_c, _, _ = kp
    ytmp, b, a, piv, rhs, z0, fc = wk
    nz = fc.shape[0]
    shift = 0 if o == 6 else 3
    nfev = 0
    if has_c:
        f6 = ft(y, o, active_c, codes, params_c)
        nfev += 1
        for i in range(nz):
            fc[i] = f6[i + shift]
    else:
        for i in range(nz):
            fc[i] = 0.0
    nfev += damping_matrix(y, kp, ytmp, b)
    for tau in (tau_a, tau_b):
        if tau != 0.0 and not midpoint_kick(y, tau, kp, b, a, piv, rhs, z0, fc):
            for i in range(nz):  # the implicit step has no solution: say so with NaN
                y[z_index(i, o)] = math.nan
            break
    return nfev


@inner
def damping_matrix(y, kp, ytmp, b):
    """b (nz, nz) := B, the velocity part's force per unit z at the configuration of y (exact:
    that force is linear in z). Returns the evaluations used (nz)."""
    codes, _, _, active_d, params_d, _, _, o, _, _, _ = kp
    nz = b.shape[0]
    shift = 0 if o == 6 else 3
    for i in range(y.shape[0]):
        ytmp[i] = y[i]
    for j in range(nz):
        for i in range(nz):
            ytmp[z_index(i, o)] = 1.0 if i == j else 0.0
        f6 = ft(ytmp, o, active_d, codes, params_d)
        for i in range(nz):
            b[i, j] = f6[i + shift]
    return nz


@inner
def midpoint_kick(y, tau, kp, b, a, piv, rhs, z0, fc):
    """One implicit-midpoint step of M ż = F_c + B z over tau, in closed form:
    (M - tau/2 B) Δz = tau (F_c + B z0). False if that matrix is singular (a backward step,
    tau < 0, through a damping pole: |tau| × damping rate ~ 2)."""
    _, _, _, _, _, mass, inertia, o, _, _, _ = kp
    nz = fc.shape[0]
    for i in range(nz):
        z0[i] = y[z_index(i, o)]
    for i in range(nz):
        acc = fc[i]
        for j in range(nz):
            acc += b[i, j] * z0[j]
            a[i, j] = -0.5 * tau * b[i, j]
        a[i, i] += z_mass(i, mass, inertia, o)
        rhs[i] = tau * acc
    if not lu_factor(a, piv):
        return False
    lu_solve(a, piv, rhs)
    for i in range(nz):
        y[z_index(i, o)] = z0[i] + rhs[i]
    return True


# --- the drift ---------------------------------------------------------------------------------
@jit
def drift_work():
    """Scratch arrays of the drift: (q0 (4,), w0 (3,), times (1,), out_q (1, 4), out_w (1, 3))."""
    return np.empty(4), np.empty(3), np.empty(1), np.empty((1, 4)), np.empty((1, 3))


@inlined_jit
def drift(y, tau, inertia, dw):
    """The torque-free, force-free flow over tau (s, either sign), in place: r += tau v (full
    layout) and (q, ω') the exact free rigid body (`exact.free_rotation_kernel`; inertia (3,)
    ascending principal moments). A non-finite q or ω' is left to the caller's finiteness check
    (the closed form is not evaluated on it)."""
    q0, w0, times, out_q, out_w = dw
    n = y.shape[0]
    o = 6 if n == 13 else 0
    if o == 6:
        for i in range(3):
            y[i] += tau * y[3 + i]
    finite = True
    for i in range(4):
        q0[i] = y[o + i]
        finite = finite and math.isfinite(q0[i])
    for i in range(3):
        w0[i] = y[o + 4 + i]
        finite = finite and math.isfinite(w0[i])
    if not finite:
        y[o + 4] = math.nan
        return
    times[0] = tau
    free_rotation_kernel(inertia, q0, w0, times, out_q, out_w)
    for i in range(4):
        y[o + i] = out_q[0, i]
    for i in range(3):
        y[o + 4 + i] = out_w[0, i]
