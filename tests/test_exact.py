"""The exact free rigid body and its elliptic functions, against independent truth.

Oracles: mpmath at 30 digits for the elliptic functions and integrals (and for scipy's known
failure near m = 1, scipy issue 8480); numerical integration of Euler's equations and the
quaternion kinematics (scipy DOP853 at rtol = atol = 1e-13, and a 30-digit Taylor series where the
motion is too ill-conditioned for DOP853); the period 4K(m)/rate derived here from Landau &
Lifshitz §37; the closed-form precession of a symmetric top; conservation laws at t = 1e6 s.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from massprops.dynamics.elliptic import (
    carlson_rd,
    carlson_rf,
    carlson_rj,
    ellipf,
    ellipj,
    ellipk,
    ellippi,
)
from massprops.dynamics.exact import free_rotation, free_rotation_step, free_translation
from massprops.errors import UnphysicalInertiaError, UsageError
from massprops.rotation import quat_from_rotvec, quat_multiply, quat_rotate, rotation_angle_between

EPS = np.finfo(float).eps

# The complementary parameter m1 = 1 - m as exact decimal strings: m = 1 - 1e-12 is not a float.
M1_GRID = {"m=0": "1", "m=1e-12": "0.999999999999", "m=0.5": "0.5", "m=1-1e-12": "1e-12",
           "m=1-1e-30": "1e-30", "m=1": "0"}


def _m_pair(m1_text: str) -> tuple[mpmath.mpf, float, float]:
    m1 = mpmath.mpf(m1_text)
    return 1 - m1, float(1 - m1), float(m1)


# --- Jacobi elliptic functions -------------------------------------------------------------------
@pytest.mark.parametrize("m1_text", M1_GRID.values(), ids=M1_GRID.keys())
def test_jacobi_functions_against_mpmath(m1_text):
    u_grid = [0.0, 1e-9, 0.3, 1.0, 2.5, -7.3, 30.0, -123.456, 1e4]
    with mpmath.workdps(80):  # m = 1 - 1e-30 needs 30 of the digits
        m, m_f, m1_f = _m_pair(m1_text)
        quarter = mpmath.ellipk(m) if m1_text != "0" else mpmath.inf
        sn, cn, dn, am = ellipj(u_grid, m_f, m1_f)
        for k, u in enumerate(u_grid):
            ref = [mpmath.ellipfun(kind, u, m) for kind in ("sn", "cn", "dn")]
            tol = 3 * EPS * max(1.0, abs(u))  # the rounding of u itself is eps·|u|
            for got, want in zip((sn[k], cn[k], dn[k]), ref):
                assert abs(got - want) <= tol, (u, got, want)
            if ref[2] > 1e-300:  # dn keeps its relative accuracy down to sqrt(m1)
                assert abs(dn[k] - ref[2]) <= tol * ref[2] + 1e-300
            # am: sin am = sn, cos am = cn, and am - πu/(2K) stays within (-π/2, π/2).
            base = mpmath.atan2(ref[0], ref[1])
            drift = mpmath.pi * u / (2 * quarter) if quarter != mpmath.inf else 0
            am_ref = base + 2 * mpmath.pi * mpmath.nint((drift - base) / (2 * mpmath.pi))
            assert abs(am[k] - am_ref) <= 2 * tol * max(1.0, abs(am[k]))


def test_scipy_issue_8480_case():
    """scipy.special.ellipj(50, 0.99999999997**2) returned cn = -3.9e10."""
    k = 0.99999999997
    m1 = (1 - k) * (1 + k)  # 1 - k² without cancellation
    sn, cn, dn, _ = ellipj(50.0, k * k, m1)
    with mpmath.workdps(40):
        m = 1 - mpmath.mpf(m1)
        for got, kind in zip((sn, cn, dn), ("sn", "cn", "dn")):
            assert abs(got - mpmath.ellipfun(kind, 50, m)) < 100 * EPS


@pytest.mark.parametrize("m1_text", ["1", "0.5", "1e-12", "1e-100", "1e-300"],
                         ids=["m=0", "m=0.5", "m=1-1e-12", "m=1-1e-100", "m=1-1e-300"])
def test_quarter_period_against_mpmath(m1_text):
    with mpmath.workdps(340):
        m, m_f, m1_f = _m_pair(m1_text)
        assert abs(ellipk(m_f, m1_f) / mpmath.ellipk(m) - 1) < 2 * EPS
    assert ellipk(1.0) == math.inf


PHI_GRID = [0.0, 0.1, 1.0, 1.5707963, 2.5, -7.0, 50.0, -1000.0]
N_GRID = [-1e3, -0.7, 0.0, 0.5, 0.9]


@pytest.mark.parametrize("m1_text", M1_GRID.values(), ids=M1_GRID.keys())
def test_legendre_integrals_against_mpmath(m1_text):
    """F and Π over the grid, |φ| up to 1000 (reduced modulo π). The allowance is the
    conditioning: eps·(|value| + |φ| |∂value/∂φ|), the rounding of φ propagated."""
    with mpmath.workdps(80):
        m, m_f, m1_f = _m_pair(m1_text)
        phis = [p for p in PHI_GRID if m1_text != "0" or abs(p) < math.pi / 2]
        for phi in phis:
            delta = mpmath.sqrt(1 - m * mpmath.sin(phi) ** 2)
            f_ref = mpmath.ellipf(phi, m)
            tol = 3 * EPS * (abs(f_ref) + abs(phi) / delta)
            assert abs(ellipf(phi, m_f, m1_f) - f_ref) <= tol, phi
            for n in N_GRID:
                p_ref = mpmath.ellippi(n, phi, m)
                slope = 1 / (delta * abs(1 - n * mpmath.sin(phi) ** 2))
                tol = 4 * EPS * (abs(p_ref) + abs(phi) * slope)
                assert abs(ellippi(n, phi, m_f, m1_f) - p_ref) <= tol, (phi, n)


@pytest.mark.slow
def test_carlson_integrals_against_mpmath():
    rng = np.random.default_rng(7)
    args = 10.0 ** rng.uniform(-20, 5, size=(120, 4))
    args[::5, 0] = 0.0  # one zero argument is allowed
    with mpmath.workdps(30):
        for x, y, z, p in args:
            assert abs(carlson_rf(x, y, z) / mpmath.elliprf(x, y, z) - 1) < 8 * EPS
            assert abs(carlson_rd(x, y, z) / mpmath.elliprd(x, y, z) - 1) < 8 * EPS
            assert abs(carlson_rj(x, y, z, p) / mpmath.elliprj(x, y, z, p) - 1) < 8 * EPS


def test_elliptic_argument_errors():
    with pytest.raises(UsageError, match=r"m in \[0, 1\]"):
        ellipj(1.0, 1.5)
    with pytest.raises(UsageError, match="m1 = 1 - m"):
        ellipj(1.0, 0.5, 0.25)
    with pytest.raises(UsageError, match="n < 1"):
        ellippi(1.0, 0.3, 0.5)


# --- references for the free rigid body ---------------------------------------------------------
def _rhs(_t, y, inertia):
    """Euler's equations I ω̇ = (I ω) × ω and q̇ = ½ q ⊗ (0, ω), principal frame."""
    w, (qw, qx, qy, qz) = y[:3], y[3:]
    wx, wy, wz = w
    return np.concatenate([np.cross(inertia * w, w) / inertia, 0.5 * np.array([
        -qx * wx - qy * wy - qz * wz, qw * wx + qy * wz - qz * wy,
        qw * wy - qx * wz + qz * wx, qw * wz + qx * wy - qy * wx])])


def _dop853(inertia, q0, w0, times, **events):
    inertia = np.asarray(inertia, float)
    sol = solve_ivp(_rhs, (0.0, float(np.max(times))), np.concatenate([w0, q0]), method="DOP853",
                    rtol=1e-13, atol=1e-13, t_eval=times, args=(inertia,), **events)
    q = sol.y[3:].T
    return q / np.linalg.norm(q, axis=1, keepdims=True), sol.y[:3].T, sol


def _taylor_reference(inertia, w0, q0, t_end, order=30, step=0.25):
    """ω and q at t_end by a 30-digit Taylor series method (the ODE is polynomial, so the
    coefficients follow from Cauchy products). For motions too sensitive for DOP853."""
    with mpmath.workdps(30):
        i1, i2, i3 = (mpmath.mpf(float(x)) for x in inertia)
        a = ((i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3)
        w = [mpmath.mpf(float(x)) for x in w0]
        q = [mpmath.mpf(float(x)) for x in q0]
        t, t_end = mpmath.mpf(0), mpmath.mpf(t_end)
        while t < t_end:
            dt = min(mpmath.mpf(step), t_end - t)
            ws, qs = [w], [q]
            for k in range(order):
                pairs = list(zip(ws, reversed(ws)))
                conv = [mpmath.fsum(p[(i + 1) % 3] * r[(i + 2) % 3] for p, r in pairs)
                        for i in range(3)]
                ws.append([a[i] * conv[i] / (k + 1) for i in range(3)])
                d = [mpmath.mpf(0)] * 4
                for (qw, qx, qy, qz), (wx, wy, wz) in zip(qs, reversed(ws[:k + 1])):
                    d[0] += -qx * wx - qy * wy - qz * wz
                    d[1] += qw * wx + qy * wz - qz * wy
                    d[2] += qw * wy - qx * wz + qz * wx
                    d[3] += qw * wz + qx * wy - qy * wx
                qs.append([x / (2 * (k + 1)) for x in d])
            w = [_horner([c[i] for c in ws], dt) for i in range(3)]
            q = [_horner([c[i] for c in qs], dt) for i in range(4)]
            t += dt
        norm = mpmath.sqrt(mpmath.fsum(x * x for x in q))
        return np.array([float(x) for x in w]), np.array([float(x / norm) for x in q])


def _horner(ascending, x):
    """Σ c_k x^k (coefficients lowest power first); mpmath.polyval's order is version-dependent."""
    acc = mpmath.mpf(0)
    for c in reversed(ascending):
        acc = acc * x + c
    return acc


Q0 = np.array([0.5, 0.1, -0.7, 0.3]) / np.linalg.norm([0.5, 0.1, -0.7, 0.3])

BODIES = {
    "major-axis-side": ([1.0, 2.0, 3.0], [0.2, 0.5, 1.0]),
    "minor-axis-side": ([1.0, 2.0, 3.0], [1.0, 0.5, 0.3]),
    "unsorted-moments": ([3.0, 1.0, 2.0], [0.3, -0.7, 0.4]),
    "oblate-top": ([1.0, 1.0, 2.0], [0.3, 0.4, 1.0]),
    "prolate-top": ([1.0, 2.0, 2.0], [1.0, 0.4, 0.3]),
    "sphere": ([2.0, 2.0, 2.0], [0.3, -0.2, 0.5]),
    "near-oblate-1e-9": ([1.0, 1.0 + 1e-9, 2.0], [0.8, 0.5, 1e-4]),
    "near-prolate-1e-9": ([1.0, 2.0 - 1e-9, 2.0], [1e-6, 0.5, 0.3]),
    "needle": ([1e-3, 1.0, 1.0005], [1.0, 0.2, 0.1]),
    "on-separatrix": ([2.0, 5.0, 6.0], [1.0, 0.3, -1.0]),  # D = 6·1·1 - 2·3·1 = 0 exactly
}


@pytest.mark.parametrize("inertia, omega0", BODIES.values(), ids=BODIES.keys())
def test_against_dop853(inertia, omega0):
    times = np.linspace(0.0, 20.0, 9)
    q_ref, w_ref, _ = _dop853(inertia, Q0, omega0, times)
    q, w = free_rotation(inertia, Q0, omega0, times)
    scale = np.linalg.norm(omega0)
    assert np.max(np.abs(w - w_ref)) <= 1e-11 * scale
    assert np.max(rotation_angle_between(q, q_ref)) <= 1e-10


NEAR_SEPARATRIX = {
    "intermediate-axis-1e-8-off": ([1.0, 2.0, 3.0], [1e-8, 1.0, 1e-8]),
    "separatrix-1e-8-off": ([2.0, 5.0, 6.0], [1.0 + 1e-8, 0.3, 1.0]),
}


@pytest.mark.slow
@pytest.mark.parametrize("inertia, omega0", NEAR_SEPARATRIX.values(), ids=NEAR_SEPARATRIX.keys())
def test_near_separatrix_against_30_digit_taylor(inertia, omega0):
    """Through a flip, 1e-8 from the separatrix: agreement to 1e-13 after 40 s."""
    w_ref, q_ref = _taylor_reference(inertia, omega0, Q0, 40.0)
    q, w = free_rotation(inertia, Q0, omega0, 40.0)
    assert np.max(np.abs(w - w_ref)) <= 1e-13 * np.linalg.norm(omega0)
    assert rotation_angle_between(q, q_ref) <= 1e-13


@pytest.mark.parametrize("inertia, omega0", [
    BODIES["major-axis-side"], BODIES["minor-axis-side"], BODIES["prolate-top"],
    BODIES["near-prolate-1e-9"], BODIES["on-separatrix"],
    *NEAR_SEPARATRIX.values()],
    ids=["major", "minor", "prolate-top", "near-prolate", "on-separatrix",
         *NEAR_SEPARATRIX.keys()])
def test_conservation_at_a_million_seconds(inertia, omega0):
    """World angular momentum H = A(q) I ω (a vector), energy and |q| at t = ±1e6 s."""
    inertia = np.asarray(inertia, float)
    times = np.array([0.0, 1e3, 1e6, 1e6 + 0.5, -1e6])
    q, w = free_rotation(inertia, Q0, omega0, times)
    h_world = quat_rotate(q, inertia * w)
    energy = np.sum(inertia * w * w, axis=-1)
    assert np.max(np.abs(h_world - h_world[0])) <= 1e-14 * np.linalg.norm(h_world[0])
    assert np.max(np.abs(energy - energy[0])) <= 1e-14 * energy[0]
    assert np.max(np.abs(np.linalg.norm(q, axis=-1) - 1)) <= 2 * EPS


def _landau(inertia, omega0):
    """Parameter and rate of ω'(t) from Landau & Lifshitz §37, in exact arithmetic (mpmath):
    for M² > 2EI2, m = (I2-I1)(2EI3-M²)/((I3-I2)(M²-2EI1)), rate² = (I3-I2)(M²-2EI1)/(I1I2I3);
    for M² < 2EI2 swap I1 and I3."""
    i1, i2, i3 = (mpmath.mpf(x) for x in inertia)
    w = [mpmath.mpf(x) for x in omega0]
    two_e = i1 * w[0] ** 2 + i2 * w[1] ** 2 + i3 * w[2] ** 2
    msq = (i1 * w[0]) ** 2 + (i2 * w[1]) ** 2 + (i3 * w[2]) ** 2
    if msq < two_e * i2:
        i1, i3 = i3, i1
    m = (i2 - i1) * (two_e * i3 - msq) / ((i3 - i2) * (msq - two_e * i1))
    rate = mpmath.sqrt((i3 - i2) * (msq - two_e * i1) / (i1 * i2 * i3))
    return m, rate


def test_dzhanibekov_flip_period():
    """A T-handle spun near its intermediate axis flips over and back with period 4K(m)/rate:
    the zero crossings of ω'_2 in a DOP853 solve are 2K/rate apart, and the exact solution has
    the same zeros and repeats after 4K/rate."""
    inertia, omega0 = [1.0, 2.0, 3.0], [0.02, 1.0, 0.01]
    with mpmath.workdps(30):
        m, rate = _landau(inertia, omega0)
        half = float(2 * mpmath.ellipk(m) / rate)

    def crossing(_t, y, _i):
        return y[1]

    _, _, sol = _dop853(inertia, Q0, omega0, [4 * half], events=crossing)
    zeros = sol.t_events[0]
    assert len(zeros) >= 3
    np.testing.assert_allclose(np.diff(zeros), half, rtol=1e-10)
    _, w = free_rotation(inertia, Q0, omega0, zeros)
    assert np.max(np.abs(w[:, 1])) < 1e-10
    _, w_mid = free_rotation(inertia, Q0, omega0, 0.5 * (zeros[1:] + zeros[:-1]))
    assert np.all(np.abs(np.abs(w_mid[:, 1]) - 1) < 0.01), "between flips: spinning about e2"
    assert np.all(w_mid[:-1, 1] * w_mid[1:, 1] < 0), "ω'_2 reverses at each flip"
    times = np.linspace(0.0, 7.0, 8)
    _, w0 = free_rotation(inertia, Q0, omega0, times)
    _, w1 = free_rotation(inertia, Q0, omega0, times + 2 * half)
    np.testing.assert_allclose(w1, w0, atol=1e-13)


@pytest.mark.parametrize("inertia, omega0, axis", [
    ([1.0, 1.0, 2.5], [0.4, 0.1, 1.3], 2),
    ([0.8, 3.0, 3.0], [1.1, -0.3, 0.5], 0),
], ids=["oblate-axis-3", "prolate-axis-1"])
def test_symmetric_top_precession(inertia, omega0, axis):
    """ω' turns about the symmetry axis at Ω = (I_s - I_t)/I_t ω_s; in the world, the symmetry
    axis turns about H at h/I_t (regular precession)."""
    inertia, omega0 = np.asarray(inertia), np.asarray(omega0)
    i_s, i_t = inertia[axis], inertia[(axis + 1) % 3]
    big_omega = (i_s - i_t) / i_t * omega0[axis]
    t1, t2 = [k for k in range(3) if k != axis]
    times = np.linspace(0.0, 50.0, 11)
    q, w = free_rotation(inertia, Q0, omega0, times)
    turned = np.arctan2(w[:, t2], w[:, t1]) - math.atan2(omega0[t2], omega0[t1])
    np.testing.assert_allclose(np.angle(np.exp(1j * (turned - big_omega * times))), 0, atol=1e-13)
    np.testing.assert_allclose(w[:, axis], omega0[axis], rtol=1e-15)
    h_body = inertia * omega0
    h = np.linalg.norm(h_body)
    e_h = quat_rotate(Q0, h_body / h)
    e_s = np.eye(3)[axis]
    expected = quat_rotate(quat_from_rotvec(np.outer(h / i_t * times, e_h)), quat_rotate(Q0, e_s))
    np.testing.assert_allclose(quat_rotate(q, e_s), expected, atol=1e-13)


@pytest.mark.parametrize("axis", [0, 1, 2], ids=["minor", "intermediate", "major"])
def test_principal_axis_spin_stays_put(axis):
    """Spin about a principal axis, even the unstable intermediate one, is held exactly."""
    inertia, rate = [1.0, 2.0, 3.0], 1.7
    omega0 = rate * np.eye(3)[axis]
    times = np.array([0.0, 1.0, 100.0, 1e6])
    q, w = free_rotation(inertia, Q0, omega0, times)
    np.testing.assert_array_equal(w, np.tile(omega0, (4, 1)))
    expected = quat_multiply(Q0, quat_from_rotvec(np.outer(times, omega0)))
    angles = rotation_angle_between(q, expected)
    assert np.all(angles <= 4 * EPS * (1 + rate * times))


@pytest.mark.parametrize("scale", [1e-200, 1e-8, 1e8, 1e200], ids=lambda s: f"{s:g}")
def test_rate_and_moment_scaling(scale):
    """ω -> s ω runs the same motion s times faster; multiplying the moments changes nothing."""
    inertia, omega0 = np.array([1.0, 2.0, 3.0]), np.array([0.4, -0.9, 0.3])
    times = np.linspace(0.0, 30.0, 7)
    q, w = free_rotation(inertia, Q0, omega0, times)
    q_s, w_s = free_rotation(inertia * 1e-5, Q0, scale * omega0, times / scale)
    np.testing.assert_allclose(w_s / scale, w, rtol=0, atol=1e-14)
    assert np.max(rotation_angle_between(q_s, q)) < 1e-13


@settings(max_examples=40, deadline=None)
@given(moments=st.tuples(*[st.floats(0.2, 1.0) for _ in range(3)]),
       omega0=st.tuples(*[st.floats(-2.0, 2.0) for _ in range(3)]),
       t1=st.floats(-30.0, 30.0), t2=st.floats(-30.0, 30.0))
def test_flow_property(moments, omega0, t1, t2):
    """Going t1 then t2 equals going t1 + t2 (the flow is a one-parameter group), and the
    stepping function is the same map: to round-off times the motion's own amplification of a
    round-off in the state at t1 (near the separatrix, spin about the intermediate axis, the
    flow amplifies it exponentially: hypothesis found 7e-12 at |ω| t = 36 against a
    linear-growth bound of 3.7e-12), measured by moving that state by a relative 1e-7."""
    q1, w1 = free_rotation(moments, Q0, omega0, t1)
    q2, w2 = free_rotation_step(moments, q1, w1, t2)
    q12, w12 = free_rotation(moments, Q0, omega0, t1 + t2)
    nudge = 1e-7
    qn, wn = free_rotation_step(moments, q1, w1 * (1.0 + nudge), t2)
    gain = max(np.max(np.abs(wn - w2)) / (nudge * np.linalg.norm(w1) or 1.0),
               rotation_angle_between(qn, q2) / nudge)
    scale = 1.0 + np.linalg.norm(omega0) * (abs(t1) + abs(t2))
    bound = 1e-13 * scale + 64 * EPS * gain * max(1.0, np.linalg.norm(omega0))
    assert np.max(np.abs(w2 - w12)) <= bound
    assert rotation_angle_between(q2, q12) <= bound


def test_free_translation_is_ballistic():
    r, v = free_translation([1.0, 2.0, 3.0], [0.5, 0.0, -1.0], [0.0, 0.0, -9.81], [0.0, 2.0])
    np.testing.assert_allclose(r, [[1.0, 2.0, 3.0], [2.0, 2.0, 3.0 - 2.0 - 19.62]], rtol=1e-15)
    np.testing.assert_allclose(v, [[0.5, 0.0, -1.0], [0.5, 0.0, -1.0 - 19.62]], rtol=1e-15)


def test_argument_errors():
    with pytest.raises(UnphysicalInertiaError, match="positive principal moments"):
        free_rotation([1.0, 0.0, 2.0], Q0, [1, 0, 0], 1.0)
    with pytest.raises(UsageError, match=r"expected omega0 of shape \(3,\), got \(2,\)"):
        free_rotation([1.0, 2.0, 3.0], Q0, [1, 0], 1.0)
    with pytest.raises(UsageError, match="non-zero"):
        free_rotation([1.0, 2.0, 3.0], [0, 0, 0, 0], [1, 0, 0], 1.0)
    with pytest.raises(UsageError, match="finite times"):
        free_rotation([1.0, 2.0, 3.0], Q0, [1, 0, 0], [0.0, math.nan])
