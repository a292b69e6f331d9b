"""Jacobi elliptic functions and Legendre elliptic integrals, accurate up to m = 1.

Why our own: ``scipy.special.ellipj`` uses an approximation near m = 1 that is wrong past the
quarter period (scipy issue 8480), and every routine that takes m alone forms 1 - m by
cancellation. Here the complementary parameter ``m1 = 1 - m`` can be passed explicitly, and every
formula uses it where 1 - m would appear, so m = 1 - 1e-12 costs no digits.

Methods:
- K(m) by the arithmetic-geometric mean of (1, sqrt(m1)).
- sn, cn, dn: u is reduced modulo 2K into [-K, K], then by the quarter-period shift into
  [0, K/2]; there the Maclaurin series of 1 - cn and 1 - dn at u/2^n (<= 2^-7) is doubled n times
  with duplication formulas written as sums of positive terms (Fukushima's idea of carrying the
  complements), so sn, cn, dn keep their relative accuracy, including dn ~ sqrt(m1) near K.
- F, Π: Carlson's symmetric integrals R_F, R_J (Carlson 1995, "Numerical computation of real or
  complex elliptic integrals", Numer. Algorithms 10) after reducing φ modulo π, so the cost does
  not grow with φ.

The scalar kernels (``k_from_m1``, ``jacobi``, ``jacobi_reduced``, ``rf``, ``rd``, ``rj``, ``rc1``,
``legendre_f``, ``legendre_pi_minus_f``) use only floats and the math module and are compiled
with numba (``massprops.dynamics._jit``), so compiled kernels can call them; the array functions
(``ellipk``, ``ellipj``, ``ellipf``, ``ellippi``, ``carlson_rf``, ``carlson_rd``, ``carlson_rj``)
validate and broadcast.
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics._jit import jit
from massprops.errors import UsageError

__all__ = [
    "carlson_rd", "carlson_rf", "carlson_rj", "ellipf", "ellipj", "ellipk", "ellippi",
    "jacobi", "jacobi_reduced", "k_from_m1", "legendre_f", "legendre_pi_minus_f",
    "rc1", "rd", "rf", "rj",
]

_EPS = 2.220446049250313e-16
_PARAM_ATOL = 4 * _EPS
"""m + m1 may differ from 1 by rounding only: a larger gap means the caller passed two different
parameters."""

_SERIES_MAX_EXP = -7
"""The Maclaurin series is used at |u| <= 2^-7: its first omitted term, about 0.03 u^8 relative,
is then below 4e-19."""

_CARLSON_RTOL = _EPS
"""Relative truncation error allowed in Carlson's series (his parameter r)."""

_RF_Q = (3.0 * _CARLSON_RTOL) ** (-1.0 / 6.0)
_RJ_Q = (0.25 * _CARLSON_RTOL) ** (-1.0 / 6.0)
_MAX_ITER = 200
"""Carlson's duplication shrinks the spread of the arguments fourfold per step; even arguments
1e-300 apart converge in about 30 steps, so 200 only guards against NaN input."""


# --- complete integral -------------------------------------------------------------------------
@jit
def k_from_m1(m1: float) -> float:
    """K(m), the quarter period, from the complementary parameter m1 = 1 - m in [0, 1].

    K = π / (2 AGM(1, sqrt(m1))); m1 = 0 gives +inf. Relative error ~1e-16 for every m1.
    """
    if m1 <= 0.0:
        return math.inf
    a, b = 1.0, math.sqrt(m1)
    for _ in range(_MAX_ITER):
        if a - b <= 2.0 * _EPS * a:
            break
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return math.pi / (a + b)


# --- Jacobi elliptic functions --------------------------------------------------------------------
@jit
def _jacobi_half(v: float, m: float, m1: float) -> tuple[float, float, float]:
    """(sn, cn, dn)(v | m) for 0 <= v <= K/2, each to a few ulps relative.

    y = 1 - cn and z = 1 - dn come from the series at x = v / 2^n, then n duplications
    u -> 2u with the complement forms 1 - cn(2u) = 2 sn² dn² / den, 1 - dn(2u) = 2 m sn² cn² / den,
    den = cn² + sn² dn² (= 1 - m sn⁴), all sums of positive terms. cn and dn themselves are
    taken as 1 - y, 1 - z while those are >= 1/2 and otherwise carried by the (also
    cancellation-free) forms cn(2u) = (cn² - k' sn²)(cn² + k' sn²)/den,
    dn(2u) = (cn⁴ + m1 sn² (1 + cn²))/den, with k' = sqrt(m1).
    """
    if v == 0.0:
        return 0.0, 1.0, 1.0
    n = max(0, math.frexp(v)[1] - _SERIES_MAX_EXP)
    x = math.ldexp(v, -n)
    x2 = x * x
    y = x2 * (0.5 - x2 * ((1.0 + 4.0 * m) / 24.0 - x2 * (
        (1.0 + m * (44.0 + 16.0 * m)) / 720.0
        - x2 * (1.0 + m * (408.0 + m * (912.0 + 64.0 * m))) / 40320.0)))
    z = m * x2 * (0.5 - x2 * ((4.0 + m) / 24.0 - x2 * (
        (16.0 + m * (44.0 + m)) / 720.0
        - x2 * (64.0 + m * (912.0 + m * (408.0 + m))) / 40320.0)))
    c, d = 1.0 - y, 1.0 - z
    kp = math.sqrt(m1)
    for _ in range(n):
        s2 = y * (2.0 - y)
        c2 = c * c
        den = c2 + s2 * d * d
        y_new = 2.0 * s2 * d * d / den
        z_new = 2.0 * z * (2.0 - z) * c2 / den
        c_new = (c2 - kp * s2) * (c2 + kp * s2) / den
        d_new = (c2 * c2 + m1 * s2 * (1.0 + c2)) / den
        y, z = y_new, z_new
        c = 1.0 - y if y <= 0.5 else c_new
        d = 1.0 - z if z <= 0.5 else d_new
    return math.sqrt(y * (2.0 - y)), c, d


@jit
def jacobi_reduced(u: float, m: float, m1: float, kk: float) -> tuple[float, float, float, float]:
    """Reduce u to ur = u - 2 j K in [-K, K] and evaluate there.

    kk : K(m), from ``k_from_m1(m1)`` (passed in so callers evaluating many u compute it once).
    Returns (j, sn(ur), cn(ur), dn(ur)) with j a float integer; then sn(u) = (-1)^j sn(ur),
    cn(u) = (-1)^j cn(ur), dn(u) = dn(ur), am(u) = j π + atan2(sn(ur), cn(ur)), and
    cn(ur) >= 0. m1 = 0 (K infinite) gives j = 0 and tanh, sech, sech.
    """
    if not abs(u) < math.inf:  # NaN or infinite u: no meaningful reduction
        return math.nan, math.nan, math.nan, math.nan
    if m1 <= 0.0:
        e = math.exp(-abs(u))
        sech = 2.0 * e / (1.0 + e * e)
        return 0.0, math.tanh(u), sech, sech
    j = float(math.floor(u / (2.0 * kk) + 0.5))
    ur = u - 2.0 * j * kk
    w = abs(ur)
    if w <= 0.5 * kk:
        s, c, d = _jacobi_half(w, m, m1)
    else:
        # Quarter-period shift: sn(K - v) = cd(v), cn(K - v) = k' sd(v), dn(K - v) = k' nd(v).
        sv, cv, dv = _jacobi_half(max(kk - w, 0.0), m, m1)
        kp = math.sqrt(m1)
        s, c, d = cv / dv, kp * sv / dv, kp / dv
    return j, math.copysign(s, ur), c, d


@jit
def jacobi(u: float, m: float, m1: float) -> tuple[float, float, float, float]:
    """(sn, cn, dn, am)(u | m) for 0 <= m <= 1 with m1 = 1 - m given explicitly."""
    j, s, c, d = jacobi_reduced(u, m, m1, k_from_m1(m1))
    sign = -1.0 if j % 2.0 != 0.0 else 1.0
    return sign * s, sign * c, d, j * math.pi + math.atan2(s, c)


# --- Carlson's symmetric integrals ---------------------------------------------------------------
@jit
def rf(x: float, y: float, z: float) -> float:
    """R_F(x, y, z) = ½ ∫₀^∞ dt / sqrt((t+x)(t+y)(t+z)); x, y, z >= 0, at most one zero.

    Carlson's duplication to relative accuracy ~1e-16; two zero arguments give +inf.
    """
    if not (x >= 0.0 and y >= 0.0 and z >= 0.0):
        return math.nan
    if (x == 0.0 and y == 0.0) or (y == 0.0 and z == 0.0) or (z == 0.0 and x == 0.0):
        return math.inf
    a0 = (x + y + z) / 3.0
    dx, dy, dz = a0 - x, a0 - y, a0 - z
    q = _RF_Q * max(abs(dx), abs(dy), abs(dz))
    a, fac = a0, 1.0
    for _ in range(_MAX_ITER):
        if fac * q < abs(a):
            break
        sx, sy, sz = math.sqrt(x), math.sqrt(y), math.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        x, y, z, a = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam), 0.25 * (a + lam)
        fac *= 0.25
    xx, yy = fac * dx / a, fac * dy / a
    zz = -(xx + yy)
    e2 = xx * yy - zz * zz
    e3 = xx * yy * zz
    return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / math.sqrt(a)


@jit
def rc1(e: float, one_plus_e: float) -> float:
    """R_C(1, 1 + e) for e > -1, given 1 + e separately (accurate even when it is tiny).

    atan(sqrt(e))/sqrt(e) for e > 0; atanh(t)/t, t = sqrt(-e), for e < 0, written
    log((1 + t)/sqrt(1 + e))/t once t > 1/2 (no cancellation as t -> 1); the series
    1 - e/3 + e²/5 - ... for |e| < 1e-3 (its first omitted term is below 1e-16).
    """
    if abs(e) < 1e-3:
        return 1.0 - e * (1.0 / 3.0 - e * (0.2 - e * (1.0 / 7.0 - e * (1.0 / 9.0 - e / 11.0))))
    if e > 0.0:
        r = math.sqrt(e)
        return math.atan(r) / r
    r = math.sqrt(-e)
    if r < 0.5:
        return math.atanh(r) / r
    return math.log((1.0 + r) / math.sqrt(one_plus_e)) / r


@jit
def _series_rj(xx: float, yy: float, zz: float, pp: float) -> float:
    """Carlson's fifth-order series shared by R_J and R_D (pp: the p deviation)."""
    e2 = xx * yy + xx * zz + yy * zz - 3.0 * pp * pp
    e3 = xx * yy * zz + 2.0 * e2 * pp + 4.0 * pp * pp * pp
    e4 = (2.0 * xx * yy * zz + e2 * pp + 3.0 * pp * pp * pp) * pp
    e5 = xx * yy * zz * pp * pp
    return (1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0 - 3.0 * e4 / 22.0
            - 9.0 * e2 * e3 / 52.0 + 3.0 * e5 / 26.0)


@jit
def rj(x: float, y: float, z: float, p: float) -> float:
    """R_J(x, y, z, p) = 3/2 ∫₀^∞ dt / ((t+p) sqrt((t+x)(t+y)(t+z))); x, y, z >= 0 (at most one
    zero), p > 0. Carlson's duplication with the R_C(1, 1 + e_m) terms, relative error ~1e-15."""
    if not (x >= 0.0 and y >= 0.0 and z >= 0.0 and p > 0.0):
        return math.nan
    if (x == 0.0 and y == 0.0) or (y == 0.0 and z == 0.0) or (z == 0.0 and x == 0.0):
        return math.inf
    a0 = (x + y + z + 2.0 * p) / 5.0
    dx, dy, dz, dp = a0 - x, a0 - y, a0 - z, a0 - p
    delta = (p - x) * (p - y) * (p - z)
    q = _RJ_Q * max(abs(dx), abs(dy), abs(dz), abs(dp))
    a, fac, total = a0, 1.0, 0.0
    for _ in range(_MAX_ITER):
        if fac * q < abs(a):
            break
        sx, sy, sz, sp = math.sqrt(x), math.sqrt(y), math.sqrt(z), math.sqrt(p)
        lam = sx * sy + sx * sz + sy * sz
        dm = (sp + sx) * (sp + sy) * (sp + sz)
        # 1 + e_m = (d_m² + δ_m)/d_m² = 2 sqrt(p)(p + λ)/d_m: written so, it does not cancel
        # when p is much smaller than x, y, z (then e_m -> -1).
        e = fac * fac * fac * delta / (dm * dm)
        total += fac * rc1(e, 2.0 * sp * (p + lam) / dm) / dm
        x, y, z = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam)
        p, a = 0.25 * (p + lam), 0.25 * (a + lam)
        fac *= 0.25
    xx, yy, zz = fac * dx / a, fac * dy / a, fac * dz / a
    pp = -0.5 * (xx + yy + zz)
    return fac * _series_rj(xx, yy, zz, pp) / (a * math.sqrt(a)) + 6.0 * total


@jit
def rd(x: float, y: float, z: float) -> float:
    """R_D(x, y, z) = R_J(x, y, z, z); x, y >= 0 (not both zero), z > 0. Carlson's duplication."""
    if not (x >= 0.0 and y >= 0.0 and z > 0.0):
        return math.nan
    if x == 0.0 and y == 0.0:
        return math.inf
    a0 = (x + y + 3.0 * z) / 5.0
    dx, dy, dz = a0 - x, a0 - y, a0 - z
    q = _RJ_Q * max(abs(dx), abs(dy), abs(dz))
    a, fac, total = a0, 1.0, 0.0
    for _ in range(_MAX_ITER):
        if fac * q < abs(a):
            break
        sx, sy, sz = math.sqrt(x), math.sqrt(y), math.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        total += fac / (sz * (z + lam))
        x, y, z, a = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam), 0.25 * (a + lam)
        fac *= 0.25
    xx, yy = fac * dx / a, fac * dy / a
    zz = -(xx + yy) / 3.0
    return fac * _series_rj(xx, yy, zz, zz) / (a * math.sqrt(a)) + 3.0 * total


# --- Legendre integrals from the sine and cosine of the amplitude --------------------------------
@jit
def legendre_f(s: float, c: float, m1: float) -> float:
    """F(φ | m) for |φ| <= π/2 given s = sin φ, c = cos φ >= 0 and m1 = 1 - m.

    F = s R_F(c², c² + m1 s², 1): 1 - m s² is formed as c² + m1 s², a sum of positive terms, and
    passing c (not φ) keeps full relative accuracy when φ is within 1e-8 of ±π/2.
    """
    c2 = c * c
    return s * rf(c2, c2 + m1 * s * s, 1.0)


@jit
def legendre_pi_minus_f(n: float, s: float, c: float, d: float) -> float:
    """Π(n; φ | m) - F(φ | m) for |φ| <= π/2, n < 1, given s = sin φ, c = cos φ >= 0 and
    d = sqrt(1 - m s²) (dn when φ = am u): (n/3) s³ R_J(c², d², 1, 1 - n s²).

    Computed directly, not as a difference, so it keeps its relative accuracy for tiny n.
    """
    if n == 0.0 or s == 0.0:
        return 0.0
    return n / 3.0 * s * s * s * rj(c * c, d * d, 1.0, 1.0 - n * s * s)


@jit
def _reduce_amplitude(phi: float) -> tuple[float, float, float]:
    """φ = j π + φr with |φr| <= π/2: returns (j, sin φr, cos φr) with cos φr >= 0."""
    if not abs(phi) < math.inf:
        return math.nan, math.nan, math.nan
    # Halves round toward zero, so φ = ±π/2 stays in the first period (finite F even at m = 1).
    x = phi / math.pi
    j = float(math.ceil(x - 0.5)) if x > 0.0 else float(math.floor(x + 0.5))
    r = phi - j * math.pi
    return j, math.sin(r), abs(math.cos(r))


@jit
def _f_scalar(phi: float, m1: float) -> float:
    j, s, c = _reduce_amplitude(phi)
    if j == 0.0:
        return legendre_f(s, c, m1)
    return 2.0 * j * k_from_m1(m1) + legendre_f(s, c, m1)


@jit
def _pi_scalar(n: float, phi: float, m: float, m1: float) -> float:
    if not n < 1.0:
        return math.nan
    j, s, c = _reduce_amplitude(phi)
    d = math.sqrt(c * c + m1 * s * s)
    if n < -math.sqrt(m):
        # Large negative n: Π is small while F is large, so F + (Π - F) would cancel. Use
        # Π(n) + Π(m/n) = F + atan2(s sqrt(pq), c d)/sqrt(pq), p = 1 - n, q = 1 - m/n (DLMF
        # 19.7.9 with its R_C written out), whose characteristic m/n is small.
        nn = m / n
        r = math.sqrt((1.0 - n) * (1.0 - nn))
        inner = math.atan2(s * r, c * d) / r - legendre_pi_minus_f(nn, s, c, d)
        if j == 0.0:
            return inner
        complete = 0.5 * math.pi / r - (nn / 3.0 * rj(0.0, m1, 1.0, 1.0 - nn) if nn != 0 else 0.0)
        return 2.0 * j * complete + inner
    inner = legendre_f(s, c, m1) + legendre_pi_minus_f(n, s, c, d)
    if j == 0.0:
        return inner
    complete = k_from_m1(m1) + (n / 3.0 * rj(0.0, m1, 1.0, 1.0 - n) if n != 0.0 else 0.0)
    return 2.0 * j * complete + inner


# --- array functions ------------------------------------------------------------------------------
def _broadcast_apply(kernel, n_out: int, *args) -> tuple[np.ndarray, ...]:
    """Apply a scalar kernel elementwise over broadcast float64 arrays; n_out outputs."""
    arrays = [np.asarray(a, dtype=np.float64) for a in args]
    b = np.broadcast(*arrays)
    out = np.empty((n_out, b.size))
    for k, vals in enumerate(b):
        res = kernel(*[float(v) for v in vals])
        out[:, k] = res
    return tuple(o.reshape(b.shape) for o in out)


def _parameters(m, m1) -> tuple[np.ndarray, np.ndarray]:
    """Validated (m, m1) arrays: 0 <= m <= 1, and m1 = 1 - m unless given (then consistent)."""
    m = np.asarray(m, dtype=np.float64)
    if not np.all((m >= 0.0) & (m <= 1.0)):
        raise UsageError(f"expected the parameter m in [0, 1], got {m[~((m >= 0) & (m <= 1))]}; "
                         "m = k² is the square of the modulus")
    if m1 is None:
        return m, 1.0 - m
    m1 = np.asarray(m1, dtype=np.float64)
    if not np.all((m1 >= 0.0) & (m1 <= 1.0)) or np.any(np.abs(m + m1 - 1.0) > _PARAM_ATOL):
        raise UsageError("expected m1 = 1 - m in [0, 1], got m + m1 != 1; "
                         "pass m1 only to give 1 - m without rounding")
    return m, m1


def ellipk(m, m1=None) -> np.ndarray:
    """Complete elliptic integral of the first kind K(m); m (...) in [0, 1], m1 = 1 - m optional
    (pass it near m = 1). Returns (...) float; +inf at m = 1."""
    _, m1 = _parameters(m, m1)
    return _broadcast_apply(k_from_m1, 1, m1)[0]


def ellipj(u, m, m1=None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Jacobi elliptic functions (sn, cn, dn, am)(u | m), u and m broadcast, 0 <= m <= 1.

    m1 = 1 - m may be passed explicitly (near m = 1 it carries the digits that m cannot). Absolute
    error ~1e-15 for |u| of order 1, growing like eps·|u| (the rounding of u itself), and dn
    keeps its relative accuracy down to sqrt(m1).
    """
    m, m1 = _parameters(m, m1)
    return _broadcast_apply(jacobi, 4, u, m, m1)


def ellipf(phi, m, m1=None) -> np.ndarray:
    """Incomplete elliptic integral of the first kind F(φ | m) = ∫₀^φ dθ / sqrt(1 - m sin²θ).

    phi (...) rad, any size (reduced modulo π, cost independent of φ); 0 <= m <= 1, m1 optional.
    """
    _, m1 = _parameters(m, m1)
    return _broadcast_apply(_f_scalar, 1, phi, m1)[0]


def ellippi(n, phi, m, m1=None) -> np.ndarray:
    """Incomplete elliptic integral of the third kind
    Π(n; φ | m) = ∫₀^φ dθ / ((1 - n sin²θ) sqrt(1 - m sin²θ)), n < 1 (the A&S sign of n).

    phi (...) rad, any size (reduced modulo π); 0 <= m <= 1, m1 optional.
    """
    n = np.asarray(n, dtype=np.float64)
    if not np.all(n < 1.0):
        raise UsageError(f"expected the characteristic n < 1, got {n[~(n < 1.0)]}; "
                         "n >= 1 makes the integrand singular (a principal value)")
    m, m1 = _parameters(m, m1)
    return _broadcast_apply(_pi_scalar, 1, n, phi, m, m1)[0]


def carlson_rf(x, y, z) -> np.ndarray:
    """Carlson's R_F(x, y, z), elementwise; x, y, z >= 0, at most one zero."""
    return _broadcast_apply(rf, 1, x, y, z)[0]


def carlson_rd(x, y, z) -> np.ndarray:
    """Carlson's R_D(x, y, z), elementwise; x, y >= 0 (not both zero), z > 0."""
    return _broadcast_apply(rd, 1, x, y, z)[0]


def carlson_rj(x, y, z, p) -> np.ndarray:
    """Carlson's R_J(x, y, z, p), elementwise; x, y, z >= 0 (at most one zero), p > 0."""
    return _broadcast_apply(rj, 1, x, y, z, p)[0]
