"""Small dense linear algebra for the systems' kernels, in loops (no LAPACK call, no allocation):
for the few-by-few matrices of a mechanism a LAPACK call through numba costs more in copies and
dispatch than the arithmetic.

- `cholesky`: M = L Lᵀ of the leading n×n block (False if a pivot is not positive);
- `lower_solve`, `upper_solve`: L x = b and Lᵀ x = b in place;
- `jacobi_svd`: one-sided (Hestenes) Jacobi SVD of a p×k block, X V = W with orthogonal columns
  (σ_j = |w_j|): backward stable and accurate to round-off in every singular value, as LAPACK's
  (a column at round-off level of ‖X‖_F, a repeated constraint's, is not rotated further: its
  direction is noise and it would never pass the orthogonality test);
- `pivoted_qr`, `apply_q`: Householder QR with column pivoting (LAPACK's dgeqp3, unblocked), the
  rank-revealing factorisation each right-hand side uses: a few reflections where the SVD needs
  sweeps (the SVD stays for the singular-pose test at accepted states, `systems_step.accept`);
- `det`: a determinant by LU with partial pivoting.
"""

from __future__ import annotations

import math

from massprops.dynamics.compiled.jit import array_inner, inlined

SWEEPS = 60
"""Most Jacobi sweeps; a few-by-few matrix converges in 5-10 (quadratically), this only bounds a
NaN input's work."""

ORTHOGONAL = 2.220446049250313e-16
"""Two columns count as orthogonal once |w_iᵀ w_j| ≤ this × |w_i| |w_j| (one ulp: Hestenes'
criterion, as in LAPACK's dgesvj)."""


@inlined
def cholesky(a, low, n):
    """low[:n, :n] (lower part) = the Cholesky factor of a[:n, :n]; False if not positive
    definite (a NaN pivot goes on, giving NaN, as numpy's factor of a NaN matrix does)."""
    for j in range(n):
        s = a[j, j]
        for k in range(j):
            s -= low[j, k] * low[j, k]
        if s <= 0.0:
            return False
        d = math.sqrt(s)
        low[j, j] = d
        for i in range(j + 1, n):
            s = a[i, j]
            for k in range(j):
                s -= low[i, k] * low[j, k]
            low[i, j] = s / d
    return True


@inlined
def lower_solve(low, b, n):
    """b[:n] = L⁻¹ b[:n]."""
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= low[i, k] * b[k]
        b[i] = s / low[i, i]


@inlined
def upper_solve(low, b, n):
    """b[:n] = L⁻ᵀ b[:n]."""
    for i in range(n - 1, -1, -1):
        s = b[i]
        for k in range(i + 1, n):
            s -= low[k, i] * b[k]
        b[i] = s / low[i, i]


@array_inner
def jacobi_svd(x, p, k, v, sv):
    """x[:p, :k] -> W = X V (orthogonal columns), v[:k, :k] the rotations, sv[:k] = |w_j|."""
    fro = 0.0
    for i in range(k):
        for j in range(k):
            v[i, j] = 1.0 if i == j else 0.0
        for r in range(p):
            fro += x[r, i] * x[r, i]
    noise = ORTHOGONAL * ORTHOGONAL * fro  # a column this small is round-off: left alone
    for _ in range(SWEEPS):
        rotated = False
        for i in range(k - 1):
            for j in range(i + 1, k):
                alpha = beta = gamma = 0.0
                for r in range(p):
                    alpha += x[r, i] * x[r, i]
                    beta += x[r, j] * x[r, j]
                    gamma += x[r, i] * x[r, j]
                if gamma == 0.0 or min(alpha, beta) <= noise \
                        or abs(gamma) <= ORTHOGONAL * math.sqrt(alpha * beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                t = math.copysign(1.0, zeta) / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
                c = 1.0 / math.sqrt(1.0 + t * t)
                s = c * t
                for r in range(p):
                    xi, xj = x[r, i], x[r, j]
                    x[r, i] = c * xi - s * xj
                    x[r, j] = s * xi + c * xj
                for r in range(k):
                    vi, vj = v[r, i], v[r, j]
                    v[r, i] = c * vi - s * vj
                    v[r, j] = s * vi + c * vj
        if not rotated:
            break
    for j in range(k):
        s = 0.0
        for r in range(p):
            s += x[r, j] * x[r, j]
        sv[j] = math.sqrt(s)


@array_inner
def pivoted_qr(x, rows, cols, order, tau, rtol):
    """x[:rows, :cols] P = Q R in place: R on and above the diagonal, reflector k's vector below
    it (its leading 1 implied), tau[k] its factor (H_k = I − tau_k v_k v_kᵀ, Q = H_0 H_1 ...);
    order[1 + j] = the original index of column j. The factorisation stops at the first
    |R_kk| ≤ rtol |R_00| (the rank, returned and kept in order[0]; a NaN column stops it too).

    The pivot is the remaining column of largest norm below row k, recomputed at every k rather
    than downdated: the matrices are few-by-few, and downdated norms cancel (LAPACK guards its
    downdating with a recomputation for that reason)."""
    for j in range(cols):
        order[1 + j] = j
    top = 0.0
    rank = min(rows, cols)
    for k in range(min(rows, cols)):
        best, p = -1.0, k
        for j in range(k, cols):
            s = 0.0
            for r in range(k, rows):
                s += x[r, j] * x[r, j]
            if s > best:
                best, p = s, j
        if p != k:
            order[1 + k], order[1 + p] = order[1 + p], order[1 + k]
            for r in range(rows):
                x[r, k], x[r, p] = x[r, p], x[r, k]
        alpha = math.sqrt(best)
        if k == 0:
            top = alpha
        if not alpha > rtol * top:
            rank = k
            break
        x0 = x[k, k]
        beta = -math.copysign(alpha, x0)  # the sign that adds, never cancels
        v0 = x0 - beta
        tau[k] = (beta - x0) / beta
        for r in range(k + 1, rows):
            x[r, k] /= v0
        x[k, k] = beta
        for j in range(k + 1, cols):
            s = x[k, j]
            for r in range(k + 1, rows):
                s += x[r, k] * x[r, j]
            s *= tau[k]
            x[k, j] -= s
            for r in range(k + 1, rows):
                x[r, j] -= s * x[r, k]
    order[0] = rank
    return rank


@inlined
def apply_q(x, tau, rank, rows, w, transpose):
    """w[:rows] = Q w (transpose: Qᵀ w), Q the first ``rank`` reflections of `pivoted_qr`."""
    for n in range(rank):
        k = n if transpose else rank - 1 - n
        s = w[k]
        for r in range(k + 1, rows):
            s += x[r, k] * w[r]
        s *= tau[k]
        w[k] -= s
        for r in range(k + 1, rows):
            w[r] -= s * x[r, k]


@array_inner
def det(a, n):
    """det a[:n, :n] (a is overwritten by its LU factors)."""
    out = 1.0
    for c in range(n):
        piv = c
        for r in range(c + 1, n):
            if abs(a[r, c]) > abs(a[piv, c]):
                piv = r
        if a[piv, c] == 0.0:
            return 0.0
        if piv != c:
            out = -out
            for j in range(n):
                a[c, j], a[piv, j] = a[piv, j], a[c, j]
        out *= a[c, c]
        for r in range(c + 1, n):
            f = a[r, c] / a[c, c]
            for j in range(c + 1, n):
                a[r, j] -= f * a[c, j]
    return out
