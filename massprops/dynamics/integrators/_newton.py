"""Compiled Newton machinery the implicit methods share: the Jacobian of the right-hand side by
forward differences, and a small dense LU factorisation with partial pivoting (no allocation, so
it can live inside a step loop; the systems are 7x7 to 26x26)."""

from __future__ import annotations

import math

from massprops.dynamics.compiled.jit import inner
from massprops.dynamics.integrators._shared import EPS, copy_into, f


@inner
def fd_jacobian(y, f0, prog, jac, ytmp, ftmp):
    """jac (n, n) := ∂ẏ/∂y at y by forward differences, f0 = ẏ(y) given; n evaluations.

    The increment of component j is sqrt(EPS · max(1e-5, |y_j|)) (Hairer's RADAU5 choice),
    rounded so that y_j + δ - y_j is exactly δ. Returns False (jac incomplete) if an increment
    vanishes or is not finite: y_j beyond ~1e16 or not finite (a diverging Newton iterate).
    """
    n = y.shape[0]
    copy_into(y, ytmp)
    for j in range(n):
        yj = y[j]
        d = math.sqrt(EPS * max(1e-5, abs(yj)))
        ytmp[j] = yj + d
        d = ytmp[j] - yj
        if not (d > 0.0 and d < math.inf):
            return False
        f(ytmp, prog, ftmp)
        for i in range(n):
            jac[i, j] = (ftmp[i] - f0[i]) / d
        ytmp[j] = yj
    return True


@inner
def lu_factor(a, piv):
    """Factor the square matrix a in place (P a = L U, unit L below the diagonal, U on and above
    it); piv (m,) int64 records the row swaps. Returns False if a pivot is zero or not finite."""
    m = a.shape[0]
    for c in range(m):
        p = c
        big = abs(a[c, c])
        for r in range(c + 1, m):
            if abs(a[r, c]) > big:
                big = abs(a[r, c])
                p = r
        piv[c] = p
        if not (big > 0.0 and math.isfinite(big)):
            return False
        if p != c:
            for j in range(m):
                a[c, j], a[p, j] = a[p, j], a[c, j]
        inv = 1.0 / a[c, c]
        for r in range(c + 1, m):
            a[r, c] *= inv
            lrc = a[r, c]
            if lrc != 0.0:
                for j in range(c + 1, m):
                    a[r, j] -= lrc * a[c, j]
    return True


@inner
def lu_solve(a, piv, b):
    """Solve in place for b (m,) with the factors of `lu_factor`."""
    m = a.shape[0]
    for c in range(m):
        p = piv[c]
        if p != c:
            b[c], b[p] = b[p], b[c]
    for r in range(1, m):
        acc = b[r]
        for j in range(r):
            acc -= a[r, j] * b[j]
        b[r] = acc
    for r in range(m - 1, -1, -1):
        acc = b[r]
        for j in range(r + 1, m):
            acc -= a[r, j] * b[j]
        b[r] = acc / a[r, r]


# --- the stopping rule of simplified Newton iterations (Hairer & Wanner, Solving ODEs II, IV.8) --
MAX_ITER = 10
"""Iterations allowed per step before the step counts as failed."""
NEWTON_TOL = 1e-14
"""(Local, compiled into the kernels: see massprops.tolerances.) Stop when the predicted remaining
correction η‖Δ‖ is below this (‖·‖: max over components of |Δ_i| / the scale of i's block, see the
package contract)."""
ROUNDOFF = 1e-14
"""A correction this small (same norm) is round-off: converged, whatever the rate says."""

CONVERGED, DIVERGED, NONFINITE, GOING = 0, 1, 2, 3


@inner
def first_eta(eta_prev):
    """η for the first iteration's test, from the last step's rate (Hairer's max(η, eps)^0.8)."""
    return max(eta_prev, EPS) ** 0.8


@inner
def verdict(it, dnorm, norm_old, eta):
    """After iteration ``it`` (0-based) with correction norm ``dnorm`` (previous ``norm_old``,
    inf if none): (CONVERGED | DIVERGED | GOING, rate θ, η = θ / (1 - θ))."""
    theta = 0.0
    if not math.isfinite(dnorm):  # a block that was exactly zero has just got its first value
        return (GOING if it + 1 < MAX_ITER else DIVERGED), theta, eta
    if dnorm <= ROUNDOFF:
        return CONVERGED, theta, eta
    if it > 0 and math.isfinite(norm_old):
        theta = dnorm / norm_old
        if theta >= 0.99:
            return DIVERGED, theta, eta
        eta = theta / (1.0 - theta)
    if eta * dnorm <= NEWTON_TOL:
        return CONVERGED, theta, eta
    if it + 1 >= MAX_ITER or (
            it > 0 and theta ** (MAX_ITER - 1 - it) / (1.0 - theta) * dnorm > NEWTON_TOL):
        return DIVERGED, theta, eta  # cannot converge within MAX_ITER at this rate
    return GOING, theta, eta
