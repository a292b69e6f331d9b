"""Jacobi elliptic functions and Legendre elliptic integrals, accurate up to m = 1.

Why our own: ``scipy.special.ellipj`` uses an approximation near m = 1 that is wrong past the
quarter period (scipy issue 8480), and every routine that takes m alone forms 1 - m by
cancellation. Here the complementary parameter ``m1 = 1 - m`` can be passed explicitly, and every
formula uses it where 1 - m would appear, so m = 1 - 1e-12 costs no digits. (Measured against
mpmath: scipy's ellipj is off by 6e-11 at m1 = 1e-6, 6e-8 at 1e-9 and returns cn = 3e13 at
1e-12; its elliprj is within 1e-15 where the free body needs it but 2e-13 over the arguments
`carlson_rj` accepts. Ours are within a few ulps everywhere, and need no scipy import.)

Methods:
- K(m) by the arithmetic-geometric mean of (1, sqrt(m1)).
- sn, cn, dn: u is reduced modulo 2K into [-K, K], then by the quarter-period shift into
  [0, K/2]; there the Maclaurin series of 1 - cn and 1 - dn at u/2^n (<= 2^-7) is doubled n times
  with duplication formulas written as sums of positive terms (Fukushima's idea of carrying the
  complements), so sn, cn, dn keep their relative accuracy, including dn ~ sqrt(m1) near K.
- F, Π: Carlson's symmetric integrals R_F, R_J (Carlson 1995, "Numerical computation of real or
  complex elliptic integrals", Numer. Algorithms 10) after reducing φ modulo π, so the cost does
  not grow with φ.

One implementation, two uses (see ``massprops.dynamics._elementwise``): the kernels
(``k_from_m1``, ``jacobi``, ``jacobi_reduced``, ``rf``, ``rd``, ``rj``, ``rc1``, ``legendre_f``,
``legendre_pi_minus_f``) are plain Python over numpy, elementwise in their arguments (the
parameter m, m1, K of ``jacobi_reduced`` is a float): the exact solution evaluates them on arrays
of output times, and the splitting integrators' compiled loops run the same source compiled for
floats. The array functions (``ellipk``, ``ellipj``, ``ellipf``, ``ellippi``, ``carlson_rf``,
``carlson_rd``, ``carlson_rj``) validate, broadcast, and evaluate with numpy only.
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics._elementwise import (
    any_,
    count,
    elementwise,
    exponent,
    ldexp,
    scalar_form,
    where,
)
from massprops.errors import UsageError

__all__ = [
    "carlson_rd", "carlson_rf", "carlson_rj", "ellipf", "ellipj", "ellipk", "ellippi",
    "jacobi", "jacobi_reduced", "k_from_m1", "legendre_f", "legendre_pi_minus_f",
    "rc1", "rd", "rf", "rj",
]

_EPS = 2.220446049250313e-16
_PARAM_ATOL = 4 * _EPS
"""(Local, compiled into the kernels: see massprops.tolerances.) m + m1 may differ from 1 by
rounding only: a larger gap means the caller passed two different parameters."""

_SERIES_MAX_EXP = -7
"""The Maclaurin series is used at |u| <= 2^-7: its first omitted term, about 0.03 u^8 relative,
is then below 4e-19."""

_CARLSON_RTOL = _EPS
"""(Local, compiled into the kernels: see massprops.tolerances.) Relative truncation error allowed
in Carlson's series (his parameter r)."""

_RF_Q = (3.0 * _CARLSON_RTOL) ** (-1.0 / 6.0)
_RJ_Q = (0.25 * _CARLSON_RTOL) ** (-1.0 / 6.0)
_MAX_ITER = 200
"""Carlson's duplication shrinks the spread of the arguments fourfold per step; even arguments
1e-300 apart converge in about 30 steps, so 200 only guards against NaN input."""


# --- complete integral -------------------------------------------------------------------------
@elementwise
def k_from_m1(m1):
    """K(m), the quarter period, from the complementary parameter m1 = 1 - m in [0, 1].

    K = π / (2 AGM(1, sqrt(m1))); m1 = 0 gives +inf. Relative error ~1e-16 for every m1.
    """
    a, b = 1.0 + 0.0 * m1, np.sqrt(np.maximum(m1, 0.0))
    for _ in range(_MAX_ITER):
        go = a - b > 2.0 * _EPS * a
        if not any_(go):
            break
        a, b = where(go, 0.5 * (a + b), a), where(go, np.sqrt(a * b), b)
    return where(m1 > 0.0, math.pi / (a + b), math.inf)


# --- Jacobi elliptic functions --------------------------------------------------------------------
@elementwise
def _jacobi_half(v, m, m1):
    """(sn, cn, dn)(v | m) for 0 <= v <= K/2, each to a few ulps relative (m, m1 floats).

    y = 1 - cn and z = 1 - dn come from the series at x = v / 2^n, then n duplications
    u -> 2u with the complement forms 1 - cn(2u) = 2 sn² dn² / den, 1 - dn(2u) = 2 m sn² cn² / den,
    den = cn² + sn² dn² (= 1 - m sn⁴), all sums of positive terms. cn and dn themselves are
    taken as 1 - y, 1 - z while those are >= 1/2 and otherwise carried by the (also
    cancellation-free) forms cn(2u) = (cn² - k' sn²)(cn² + k' sn²)/den,
    dn(2u) = (cn⁴ + m1 sn² (1 + cn²))/den, with k' = sqrt(m1). n differs per element: the
    duplications run to the largest n, each element doubling only its own n times.
    """
    n = np.maximum(exponent(v) - _SERIES_MAX_EXP, 0)
    x = ldexp(v, -n)
    x2 = x * x
    y = x2 * (0.5 - x2 * ((1.0 + 4.0 * m) / 24.0 - x2 * (
        (1.0 + m * (44.0 + 16.0 * m)) / 720.0
        - x2 * (1.0 + m * (408.0 + m * (912.0 + 64.0 * m))) / 40320.0)))
    z = m * x2 * (0.5 - x2 * ((4.0 + m) / 24.0 - x2 * (
        (16.0 + m * (44.0 + m)) / 720.0
        - x2 * (64.0 + m * (912.0 + m * (408.0 + m))) / 40320.0)))
    c, d = 1.0 - y, 1.0 - z
    kp = math.sqrt(m1)
    for i in range(count(n)):
        go = i < n
        s2 = y * (2.0 - y)
        c2 = c * c
        den = c2 + s2 * d * d
        y_new = 2.0 * s2 * d * d / den
        z_new = 2.0 * z * (2.0 - z) * c2 / den
        c_new = (c2 - kp * s2) * (c2 + kp * s2) / den
        d_new = (c2 * c2 + m1 * s2 * (1.0 + c2)) / den
        c = where(go, where(y_new <= 0.5, 1.0 - y_new, c_new), c)
        d = where(go, where(z_new <= 0.5, 1.0 - z_new, d_new), d)
        y, z = where(go, y_new, y), where(go, z_new, z)
    return np.sqrt(y * (2.0 - y)), c, d


@elementwise
def jacobi_reduced(u, m, m1, kk):
    """Reduce u to ur = u - 2 j K in [-K, K] and evaluate there.

    u : float or array; m, m1 = 1 - m, kk = K(m) floats (``k_from_m1(m1)``, passed in so that
    callers evaluating many u compute it once).
    Returns (j, sn(ur), cn(ur), dn(ur)) with j a float integer; then sn(u) = (-1)^j sn(ur),
    cn(u) = (-1)^j cn(ur), dn(u) = dn(ur), am(u) = j π + atan2(sn(ur), cn(ur)), and
    cn(ur) >= 0. m1 = 0 (K infinite) gives j = 0 and tanh, sech, sech. NaN or infinite u gives
    NaN throughout.
    """
    finite = np.abs(u) < math.inf
    if m1 <= 0.0:
        e = np.exp(-np.abs(u))
        sech = 2.0 * e / (1.0 + e * e)
        sech = where(finite, sech, math.nan)
        return where(finite, 0.0, math.nan), where(finite, np.tanh(u), math.nan), sech, sech
    j = np.floor(u / (2.0 * kk) + 0.5)
    ur = u - 2.0 * j * kk
    w = np.abs(ur)
    near = w <= 0.5 * kk
    # Quarter-period shift beyond K/2: sn(K - v) = cd v, cn(K - v) = k' sd v, dn(K - v) = k' nd v.
    sv, cv, dv = _jacobi_half(where(near, w, np.maximum(kk - w, 0.0)), m, m1)
    kp = math.sqrt(m1)
    s = where(near, sv, cv / dv)
    c = where(near, cv, kp * sv / dv)
    d = where(near, dv, kp / dv)
    return (where(finite, j, math.nan), where(finite, np.copysign(s, ur), math.nan),
            where(finite, c, math.nan), where(finite, d, math.nan))


@elementwise
def jacobi(u, m, m1):
    """(sn, cn, dn, am)(u | m) for 0 <= m <= 1 with m1 = 1 - m given explicitly (floats)."""
    j, s, c, d = jacobi_reduced(u, m, m1, k_from_m1(m1))
    sign = where(j % 2.0 != 0.0, -1.0, 1.0)
    return sign * s, sign * c, d, j * math.pi + np.arctan2(s, c)


# --- Carlson's symmetric integrals ---------------------------------------------------------------
@elementwise
def _two_zero(x, y, z):
    """At least two of x, y, z are zero (the integrals diverge)."""
    return ((x == 0.0) & (y == 0.0)) | ((y == 0.0) & (z == 0.0)) | ((z == 0.0) & (x == 0.0))


@elementwise
def rf(x, y, z):
    """R_F(x, y, z) = ½ ∫₀^∞ dt / sqrt((t+x)(t+y)(t+z)); x, y, z >= 0, at most one zero.

    Carlson's duplication to relative accuracy ~1e-16; two zero arguments give +inf.
    """
    valid = (x >= 0.0) & (y >= 0.0) & (z >= 0.0)
    diverges = _two_zero(x, y, z)
    live = valid & np.logical_not(diverges)
    a0 = (x + y + z) / 3.0
    dx, dy, dz = a0 - x, a0 - y, a0 - z
    q = _RF_Q * np.maximum(np.maximum(np.abs(dx), np.abs(dy)), np.abs(dz))
    a, fac = a0, 1.0 + 0.0 * a0
    for _ in range(_MAX_ITER):
        go = live & (fac * q >= np.abs(a))
        if not any_(go):
            break
        sx, sy, sz = np.sqrt(x), np.sqrt(y), np.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        x, y, z = where(go, 0.25 * (x + lam), x), where(go, 0.25 * (y + lam), y), \
            where(go, 0.25 * (z + lam), z)
        a, fac = where(go, 0.25 * (a + lam), a), where(go, 0.25 * fac, fac)
    xx, yy = fac * dx / a, fac * dy / a
    zz = -(xx + yy)
    e2 = xx * yy - zz * zz
    e3 = xx * yy * zz
    value = (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / np.sqrt(a)
    return where(valid, where(diverges, math.inf, value), math.nan)


@elementwise
def _rc1_series(e):
    """R_C(1, 1 + e) = 1 - e/3 + e²/5 - ..., for |e| < 1e-3 (first omitted term below 1e-16)."""
    return 1.0 - e * (1.0 / 3.0 - e * (0.2 - e * (1.0 / 7.0 - e * (1.0 / 9.0 - e / 11.0))))


@elementwise
def _rc1_atan(e):
    """R_C(1, 1 + e) = atan(sqrt(e)) / sqrt(e), e > 0."""
    r = np.sqrt(e)
    return np.arctan(r) / r


@elementwise
def _rc1_atanh(e):
    """R_C(1, 1 + e) = atanh(t) / t, t = sqrt(-e) < 1/2."""
    r = np.sqrt(-e)
    return np.arctanh(r) / r


@elementwise
def _rc1_log(e, one_plus_e):
    """R_C(1, 1 + e) = log((1 + t) / sqrt(1 + e)) / t, t = sqrt(-e) >= 1/2: no cancellation as
    t -> 1, given 1 + e separately."""
    r = np.sqrt(-e)
    return np.log((1.0 + r) / np.sqrt(one_plus_e)) / r


def rc1(e, one_plus_e):
    """R_C(1, 1 + e) for e > -1, given 1 + e separately (accurate even when it is tiny).

    atan(sqrt(e))/sqrt(e) for e > 0; atanh(t)/t, t = sqrt(-e), for e < 0, written
    log((1 + t)/sqrt(1 + e))/t once t > 1/2 (no cancellation as t -> 1); the series
    1 - e/3 + e²/5 - ... for |e| < 1e-3. Elementwise over arrays; each element is evaluated by
    its own branch only (compiled code: `_rc1_scalar`).
    """
    e, ope = np.broadcast_arrays(np.asarray(e, dtype=np.float64),
                                 np.asarray(one_plus_e, dtype=np.float64))
    out = np.empty(e.shape)
    series = np.abs(e) < 1e-3
    positive = ~series & (e > 0.0)
    small = ~series & ~positive & (e > -0.25)
    rest = ~(series | positive | small)
    out[series] = _rc1_series(e[series])
    out[positive] = _rc1_atan(e[positive])
    out[small] = _rc1_atanh(e[small])
    out[rest] = _rc1_log(e[rest], ope[rest])
    return out


@scalar_form(rc1)
def _rc1_scalar(e, one_plus_e):
    if abs(e) < 1e-3:
        return _rc1_series(e)
    if e > 0.0:
        return _rc1_atan(e)
    if e > -0.25:
        return _rc1_atanh(e)
    return _rc1_log(e, one_plus_e)


@elementwise
def _series_rj(xx, yy, zz, pp):
    """Carlson's fifth-order series shared by R_J and R_D (pp: the p deviation)."""
    e2 = xx * yy + xx * zz + yy * zz - 3.0 * pp * pp
    e3 = xx * yy * zz + 2.0 * e2 * pp + 4.0 * pp * pp * pp
    e4 = (2.0 * xx * yy * zz + e2 * pp + 3.0 * pp * pp * pp) * pp
    e5 = xx * yy * zz * pp * pp
    return (1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0 - 3.0 * e4 / 22.0
            - 9.0 * e2 * e3 / 52.0 + 3.0 * e5 / 26.0)


@elementwise
def rj(x, y, z, p):
    """R_J(x, y, z, p) = 3/2 ∫₀^∞ dt / ((t+p) sqrt((t+x)(t+y)(t+z))); x, y, z >= 0 (at most one
    zero), p > 0. Carlson's duplication with the R_C(1, 1 + e_m) terms, relative error ~1e-15."""
    valid = (x >= 0.0) & (y >= 0.0) & (z >= 0.0) & (p > 0.0)
    diverges = _two_zero(x, y, z)
    live = valid & np.logical_not(diverges)
    a0 = (x + y + z + 2.0 * p) / 5.0
    dx, dy, dz, dp = a0 - x, a0 - y, a0 - z, a0 - p
    delta = (p - x) * (p - y) * (p - z)
    q = _RJ_Q * np.maximum(np.maximum(np.abs(dx), np.abs(dy)),
                           np.maximum(np.abs(dz), np.abs(dp)))
    a, fac, total = a0, 1.0 + 0.0 * a0, 0.0 * a0
    for _ in range(_MAX_ITER):
        go = live & (fac * q >= np.abs(a))
        if not any_(go):
            break
        sx, sy, sz, sp = np.sqrt(x), np.sqrt(y), np.sqrt(z), np.sqrt(p)
        lam = sx * sy + sx * sz + sy * sz
        dm = (sp + sx) * (sp + sy) * (sp + sz)
        # 1 + e_m = (d_m² + δ_m)/d_m² = 2 sqrt(p)(p + λ)/d_m: written so, it does not cancel
        # when p is much smaller than x, y, z (then e_m -> -1).
        e = fac * fac * fac * delta / (dm * dm)
        total = where(go, total + fac * rc1(e, 2.0 * sp * (p + lam) / dm) / dm, total)
        x, y, z = where(go, 0.25 * (x + lam), x), where(go, 0.25 * (y + lam), y), \
            where(go, 0.25 * (z + lam), z)
        p, a = where(go, 0.25 * (p + lam), p), where(go, 0.25 * (a + lam), a)
        fac = where(go, 0.25 * fac, fac)
    xx, yy, zz = fac * dx / a, fac * dy / a, fac * dz / a
    pp = -0.5 * (xx + yy + zz)
    value = fac * _series_rj(xx, yy, zz, pp) / (a * np.sqrt(a)) + 6.0 * total
    return where(valid, where(diverges, math.inf, value), math.nan)


@elementwise
def rd(x, y, z):
    """R_D(x, y, z) = R_J(x, y, z, z); x, y >= 0 (not both zero), z > 0. Carlson's duplication."""
    valid = (x >= 0.0) & (y >= 0.0) & (z > 0.0)
    diverges = (x == 0.0) & (y == 0.0)
    live = valid & np.logical_not(diverges)
    a0 = (x + y + 3.0 * z) / 5.0
    dx, dy, dz = a0 - x, a0 - y, a0 - z
    q = _RJ_Q * np.maximum(np.maximum(np.abs(dx), np.abs(dy)), np.abs(dz))
    a, fac, total = a0, 1.0 + 0.0 * a0, 0.0 * a0
    for _ in range(_MAX_ITER):
        go = live & (fac * q >= np.abs(a))
        if not any_(go):
            break
        sx, sy, sz = np.sqrt(x), np.sqrt(y), np.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        total = where(go, total + fac / (sz * (z + lam)), total)
        x, y, z = where(go, 0.25 * (x + lam), x), where(go, 0.25 * (y + lam), y), \
            where(go, 0.25 * (z + lam), z)
        a, fac = where(go, 0.25 * (a + lam), a), where(go, 0.25 * fac, fac)
    xx, yy = fac * dx / a, fac * dy / a
    zz = -(xx + yy) / 3.0
    value = fac * _series_rj(xx, yy, zz, zz) / (a * np.sqrt(a)) + 3.0 * total
    return where(valid, where(diverges, math.inf, value), math.nan)


# --- Legendre integrals from the sine and cosine of the amplitude --------------------------------
@elementwise
def legendre_f(s, c, m1):
    """F(φ | m) for |φ| <= π/2 given s = sin φ, c = cos φ >= 0 and m1 = 1 - m.

    F = s R_F(c², c² + m1 s², 1): 1 - m s² is formed as c² + m1 s², a sum of positive terms, and
    passing c (not φ) keeps full relative accuracy when φ is within 1e-8 of ±π/2.
    """
    c2 = c * c
    return s * rf(c2, c2 + m1 * s * s, 1.0)


@elementwise
def legendre_pi_minus_f(n, s, c, d):
    """Π(n; φ | m) - F(φ | m) for |φ| <= π/2, n < 1, given s = sin φ, c = cos φ >= 0 and
    d = sqrt(1 - m s²) (dn when φ = am u): (n/3) s³ R_J(c², d², 1, 1 - n s²).

    Computed directly, not as a difference, so it keeps its relative accuracy for tiny n; it is
    exactly 0 for n = 0 or s = 0.
    """
    return n / 3.0 * s * s * s * rj(c * c, d * d, 1.0, 1.0 - n * s * s)


# --- the array functions (numpy only) -------------------------------------------------------------
def _reduce_amplitude(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """φ = j π + φr with |φr| <= π/2: returns (j, sin φr, cos φr) with cos φr >= 0."""
    x = phi / math.pi
    # Halves round toward zero, so φ = ±π/2 stays in the first period (finite F even at m = 1).
    j = np.where(x > 0.0, np.ceil(x - 0.5), np.floor(x + 0.5))
    r = phi - j * math.pi
    return j, np.sin(r), np.abs(np.cos(r))


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


def _per_parameter(fn, n_out: int, args: list, m: np.ndarray, m1: np.ndarray
                   ) -> tuple[np.ndarray, ...]:
    """Evaluate fn(*args_subset, m, m1) -> n_out arrays over broadcast arrays, once per distinct
    parameter pair (the kernels take the parameter as a float)."""
    arrays = np.broadcast_arrays(*[np.asarray(a, dtype=np.float64) for a in args], m, m1)
    shape = arrays[0].shape
    flat = [a.reshape(-1) for a in arrays]
    out = [np.empty(flat[0].size) for _ in range(n_out)]
    pairs, which = np.unique(np.stack([flat[-2], flat[-1]], axis=1), axis=0, return_inverse=True)
    which = which.reshape(-1)
    with np.errstate(all="ignore"):  # elementwise kernels evaluate both sides of each choice
        for k, (mk, m1k) in enumerate(pairs):
            sel = which == k
            res = fn(*[a[sel] for a in flat[:-2]], float(mk), float(m1k))
            for o, r in zip(out, res if n_out > 1 else (res,)):
                o[sel] = r
    return tuple(o.reshape(shape) for o in out)


def ellipk(m, m1=None) -> np.ndarray:
    """Complete elliptic integral of the first kind K(m); m (...) in [0, 1], m1 = 1 - m optional
    (pass it near m = 1). Returns (...) float; +inf at m = 1."""
    _, m1 = _parameters(m, m1)
    with np.errstate(all="ignore"):
        return np.asarray(k_from_m1(m1), dtype=np.float64)


def ellipj(u, m, m1=None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Jacobi elliptic functions (sn, cn, dn, am)(u | m), u and m broadcast, 0 <= m <= 1.

    m1 = 1 - m may be passed explicitly (near m = 1 it carries the digits that m cannot). Absolute
    error ~1e-15 for |u| of order 1, growing like eps·|u| (the rounding of u itself), and dn
    keeps its relative accuracy down to sqrt(m1).
    """
    m, m1 = _parameters(m, m1)
    sn, cn, dn, am = _per_parameter(jacobi, 4, [u], m, m1)
    return sn, cn, dn, am


def _f_elementwise(phi, m, m1):
    j, s, c = _reduce_amplitude(phi)
    return np.where(j != 0.0, 2.0 * j * k_from_m1(m1), 0.0) + legendre_f(s, c, m1)


def ellipf(phi, m, m1=None) -> np.ndarray:
    """Incomplete elliptic integral of the first kind F(φ | m) = ∫₀^φ dθ / sqrt(1 - m sin²θ).

    phi (...) rad, any size (reduced modulo π, cost independent of φ); 0 <= m <= 1, m1 optional.
    """
    m, m1 = _parameters(m, m1)
    return _per_parameter(_f_elementwise, 1, [phi], m, m1)[0]


def _pi_elementwise(n, phi, m, m1):
    j, s, c = _reduce_amplitude(phi)
    d = np.sqrt(c * c + m1 * s * s)
    out = np.empty(np.shape(n))
    # Large negative n: Π is small while F is large, so F + (Π - F) would cancel. Use
    # Π(n) + Π(m/n) = F + atan2(s sqrt(pq), c d)/sqrt(pq), p = 1 - n, q = 1 - m/n (DLMF 19.7.9
    # with its R_C written out), whose characteristic m/n is small.
    big = n < -math.sqrt(m)
    nb, jb, sb, cb, db = n[big], j[big], s[big], c[big], d[big]
    nn = m / nb
    r = np.sqrt((1.0 - nb) * (1.0 - nn))
    complete = 0.5 * math.pi / r - nn / 3.0 * rj(0.0, m1, 1.0, 1.0 - nn)
    out[big] = (np.where(jb != 0.0, 2.0 * jb * complete, 0.0) + np.arctan2(sb * r, cb * db) / r
                - legendre_pi_minus_f(nn, sb, cb, db))
    ns, js, ss, cs, ds = n[~big], j[~big], s[~big], c[~big], d[~big]
    complete = k_from_m1(m1) + np.where(ns != 0.0, ns / 3.0 * rj(0.0, m1, 1.0, 1.0 - ns), 0.0)
    out[~big] = (np.where(js != 0.0, 2.0 * js * complete, 0.0) + legendre_f(ss, cs, m1)
                 + legendre_pi_minus_f(ns, ss, cs, ds))
    return out


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
    return _per_parameter(_pi_elementwise, 1, [n, phi], m, m1)[0]


def _carlson(fn, *args) -> np.ndarray:
    arrays = np.broadcast_arrays(*[np.asarray(a, dtype=np.float64) for a in args])
    with np.errstate(all="ignore"):
        return np.asarray(fn(*arrays), dtype=np.float64)


def carlson_rf(x, y, z) -> np.ndarray:
    """Carlson's R_F(x, y, z), elementwise; x, y, z >= 0, at most one zero."""
    return _carlson(rf, x, y, z)


def carlson_rd(x, y, z) -> np.ndarray:
    """Carlson's R_D(x, y, z), elementwise; x, y >= 0 (not both zero), z > 0."""
    return _carlson(rd, x, y, z)


def carlson_rj(x, y, z, p) -> np.ndarray:
    """Carlson's R_J(x, y, z, p), elementwise; x, y, z >= 0 (at most one zero), p > 0."""
    return _carlson(rj, x, y, z, p)
