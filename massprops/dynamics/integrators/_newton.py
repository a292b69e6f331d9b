"""Compiled Newton machinery: a small dense LU factorisation with partial pivoting (no
allocation, so it can live inside a step loop: the systems' implicit steps, `compiled
.systems_fixed`, and the splitting methods' damped kicks, `_subflows`), and the stopping rule's
tolerances of simplified Newton iterations (Hairer & Wanner, Solving ODEs II, IV.8)."""

from __future__ import annotations

import math

from massprops.dynamics.compiled.jit import inner


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


NEWTON_TOL = 1e-14
"""(Local, compiled into the kernels: see massprops.tolerances.) Stop when the predicted remaining
correction η‖Δ‖ is below this (‖·‖: max over components of |Δ_i| / the scale of i's block, see the
package contract)."""
ROUNDOFF = 1e-14
"""A correction this small (same norm) is round-off: converged, whatever the rate says."""
