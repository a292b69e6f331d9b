"""The heavy symmetric (Lagrange) top in closed form: nutation by Jacobi elliptic functions,
precession and spin by elliptic integrals of the third kind. Cost per instant independent of t.

The body turns about a fixed point P; its inertia about P is symmetric, transverse moment A and
axial moment C about the unit body axis e3 pointing from P to the centre of mass at distance l;
a uniform field pulls with the constant force F = m g (world). Let k = -F/|F| be the upward
vertical, u = cos θ = e3·k, ω3 = ω·e3 (constant: no torque about e3), a = C ω3 / A,
b = (H_P·k) / A (constant: no torque about the vertical), β = 2 |F| l / A > 0. Energy and the two
momenta give the nutation equation (Goldstein §5.7; Whittaker, Analytical Dynamics §71)

    u̇² = f(u) = (1 - u²)(α - β u) - (b - a u)²,      α - β u0 = |ω⊥|²,

a cubic with roots u1 <= u0 <= u2 <= 1 <= u3: u = u1 + (u2 - u1) sn²(λ t + τ0 | m),
m = (u2 - u1)/(u3 - u1), λ = sqrt(β (u3 - u1)) / 2. The roots are found as offsets x = u - u0
from the Taylor coefficients of f at u0 computed from the state itself (f(u0) = u̇0²,
f'(u0) = -2 u0 |ω⊥|² - β (1 - u0²) + 2 a (b - a u0)), so a nearly double root (a top close to
steady precession) keeps its digits: the amplitude u2 - u1 comes out as a square root of a sum
of positive terms, never as a difference of two roots.

The attitude is written with half angles instead of Euler angles (z-x-z: precession φ, nutation
θ, spin ψ): with σ = (φ + ψ)/2 and δ = (φ - ψ)/2, the quaternion top -> vertical frame is

    q = (cos(θ/2) cos σ, sin(θ/2) cos δ, sin(θ/2) sin δ, cos(θ/2) sin σ),
    σ̇ = (ω3 - a)/2 + (a + b) / (2 (1 + u)),   δ̇ = (a - ω3)/2 + (b - a) / (2 (1 - u)),

so each rate has one pole, at the pole of the sphere where its own half angle vanishes
(Klein & Sommerfeld's Cayley-Klein parameters). ∫ dt / (1 ± u) is an incomplete elliptic
integral of the third kind, Π(n±; am τ | m) / ((1 ± u1) λ), n+ = -(u2 - u1)/(1 + u1) <= 0,
n- = (u2 - u1)/(1 - u1) in [0, 1); Π is written with Carlson's R_J at the exactly formed argument
p = (1 ± u)/(1 ± u1), and, for n+ < -sqrt(m) (the axis passing near the downward vertical),
through DLMF 19.7.9, as massprops.dynamics.elliptic does. τ is reduced modulo 2K and whole
periods are added in closed form, so the cost does not grow with t.

A trajectory through a pole of the sphere (b = a: through the upward vertical, e.g. a top
released upright; b = -a: through the downward one, e.g. a spherical pendulum swinging in a
plane) has that root exactly (u2 = 1 or u1 = -1) and the half-angle sine or cosine there changes
sign smoothly (it is taken as sqrt((u2 - u1)/2)·cn or ·sn rather than a square root of 1 ∓ u).
A turning point near a pole is refined from the cubic's Taylor form at that pole, so 1 ∓ u keeps
its relative accuracy there too. Accuracy: round-off, ~eps·|ω| t in angle (against a 30-digit
mpmath reference: 3e-13 at 100 s for a 30 rad/s top, 2e-12 for a 200 rad/s one; ~5e-13 against
a tight integration for a top passing 2e-5 rad from the upward vertical).
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.elliptic import carlson_rf, carlson_rj, ellipj, ellipk
from massprops.rotation import matrix_to_quat, quat_conjugate, quat_multiply

__all__ = ["LagrangeTop", "lagrange_top"]


def _signed_permutation(axis: int, sign: float) -> np.ndarray:
    """A proper signed permutation whose third column is sign·e_axis (exact entries)."""
    if axis == 2:
        cols = ([1.0, 0, 0], [0, sign, 0], [0, 0, sign])
    else:  # axis 0: (e_y, sign e_z, sign e_x) is right-handed
        cols = ([0, 1.0, 0], [0, 0, sign], [sign, 0, 0])
    return np.array(cols).T


def _vertical_frame(k: np.ndarray) -> np.ndarray:
    """Columns (w1, w2, k): a proper frame whose third axis is the unit vector k (world)."""
    helper = np.eye(3)[int(np.argmin(np.abs(k)))]
    w1 = np.cross(helper, k)
    w1 /= np.linalg.norm(w1)
    return np.column_stack([w1, np.cross(k, w1), k])


class LagrangeTop:
    """One heavy symmetric top and its initial state; ``at(t)`` evaluates the motion.

    moments : (3,) kg·m², principal moments about the fixed point (two equal: the pair's mean is
        used), frame "E" (principal axes about the point). lever : (3,) m, the centre of mass
        relative to the point, E frame, along the symmetric axis. force : (3,) N, world, the
        constant field force m g. q0 : (4,) E -> world. w0 : (3,) rad/s, E frame.
    """

    def __init__(self, moments, lever, force, q0, w0):
        moments = np.asarray(moments, dtype=np.float64)
        lever = np.asarray(lever, dtype=np.float64)
        s = 2 if abs(moments[1] - moments[0]) <= abs(moments[2] - moments[1]) else 0
        pair = [i for i in range(3) if i != s]
        self.a_moment = 0.5 * (moments[pair[0]] + moments[pair[1]])
        self.c_moment = float(moments[s])
        length = float(np.linalg.norm(lever))
        weight = float(np.linalg.norm(force))
        # E -> top frame T (third axis from the point to the centre of mass) -> vertical frame W
        r_et = _signed_permutation(s, 1.0 if lever[s] >= 0 else -1.0)
        self.q_et = matrix_to_quat(r_et)
        self.r_et = r_et
        self.q_w = matrix_to_quat(_vertical_frame(-np.asarray(force, float) / weight))
        self.beta = 2.0 * weight * length / self.a_moment
        q_t = quat_multiply(quat_multiply(quat_conjugate(self.q_w), np.asarray(q0, float)),
                            self.q_et)
        self._setup(q_t / np.linalg.norm(q_t), r_et.T @ np.asarray(w0, float))

    # --- the constants of the motion -----------------------------------------------------------
    def _setup(self, q: np.ndarray, w: np.ndarray) -> None:
        q0, q1, q2, q3 = q
        c2, s2 = q0 * q0 + q3 * q3, q1 * q1 + q2 * q2  # cos²(θ/2), sin²(θ/2)
        w1, w2, w3 = w
        a = self.c_moment * w3 / self.a_moment
        beta = self.beta
        opu0, omu0 = 2.0 * c2, 2.0 * s2  # 1 + u0, 1 - u0 (no cancellation near the poles)
        u0 = c2 - s2
        k1, k2 = 2.0 * (q1 * q3 - q0 * q2), 2.0 * (q2 * q3 + q0 * q1)  # k in the top frame
        wp2 = w1 * w1 + w2 * w2           # |ω⊥|² = α - β u0
        bau = w1 * k1 + w2 * k2           # b - a u0 = ω⊥·k
        udot = w2 * k1 - w1 * k2          # u̇0 = (ω × e3)·k
        bma = bau - a * omu0              # b - a = H·(k - e3)/A
        bpa = bau + a * opu0              # b + a = H·(k + e3)/A
        # f(u0 + x) = β x³ + c2 x² + c1 x + c0
        cc0 = udot * udot
        cc1 = -2.0 * u0 * wp2 - beta * opu0 * omu0 + 2.0 * a * bau
        cc2 = 2.0 * beta * u0 - wp2 - a * a
        # the same cubic in y = 1 - u about the top (f(1) = -(b - a)²) and y = 1 + u about the
        # bottom (f(-1) = -(b + a)²): α ∓ β = |ω⊥|² ∓ β (1 ∓ u0)
        amb, apb = wp2 - beta * omu0, wp2 + beta * opu0
        top = (-bma * bma, 2.0 * amb - 2.0 * a * bma, 2.0 * beta - amb - a * a, -beta)
        bottom = (-bpa * bpa, 2.0 * apb + 2.0 * a * bpa, -apb - 2.0 * beta - a * a, beta)
        x1, x2, x3, omu2, opu1 = _roots(beta, cc2, cc1, cc0, (top, bottom), omu0, opu0,
                                        bma == 0.0, bpa == 0.0)
        delta = x2 - x1
        self.x1, self.delta = x1, delta
        self.opu1, self.omu2 = opu1, omu2   # 1 + u1, 1 - u2 (>= 0), to full relative accuracy
        self.omu1 = omu2 + delta            # 1 - u1 >= u2 - u1
        span = x3 - x1
        self.m = delta / span if span > 0 else 0.0
        self.m1 = (x3 - x2) / span if span > 0 else 1.0
        self.lam = 0.5 * math.sqrt(beta * span)
        self.kk = float(ellipk(self.m, self.m1)) if self.m1 > 0 else math.inf
        self.w3, self.a, self.bma, self.bpa, self.bau = w3, a, bma, bpa, bau
        # initial phase: sn²(τ0) = (u0 - u1)/(u2 - u1), sign of sn cn = sign of u̇0. τ0 = F(φ0)
        # is formed from sn and cn themselves (F = s R_F(c², d², 1)), not from the angle φ0: a
        # start next to a turning point near a pole has cn0 tiny, the angle would keep it only
        # to eps absolutely, and δ̇ ~ 1/(1 - u) there turns that into a wrong δ after the pass
        sn0, cn0, dn0 = 0.0, 1.0, 1.0
        if delta > 0:
            sn0 = math.sqrt(max(-x1, 0.0) / delta)
            cn0 = math.sqrt(max(x2, 0.0) / delta)
            sn0 = -sn0 if udot < 0 else sn0
            dn0 = math.sqrt(cn0 * cn0 + self.m1 * sn0 * sn0)
        self.tau0 = sn0 * float(carlson_rf(cn0 * cn0, dn0 * dn0, 1.0)) if sn0 else 0.0
        # through a pole: the half-angle sine (cosine) is sqrt(Δ/2) cn (sn), signed
        self.eps_s = -1.0 if (self.omu2 == 0.0 and delta > 0 and x2 == 0.0) else 1.0
        self.eps_c = -1.0 if udot < 0 else 1.0
        sig0 = math.atan2(q3, q0)
        dlt0 = math.atan2(q2, q1)
        if s2 == 0.0:   # on the upward vertical: δ is the direction the axis leaves in
            dlt0 = sig0 + math.atan2(w2, w1)
        if c2 == 0.0:   # on the downward vertical: σ likewise
            sig0 = math.pi + dlt0 - math.atan2(w2, w1)
        self.sig0, self.dlt0 = sig0, dlt0
        start = (np.zeros(1), np.array([sn0]), np.array([cn0]), np.array([dn0]))  # at τ0 itself
        self.g_plus0 = self._plus(*start)[0][0] if bpa != 0.0 and delta > 0 else 0.0
        self.g_minus0 = self._minus(*start)[0] if bma != 0.0 and delta > 0 else 0.0

    # --- elliptic pieces -----------------------------------------------------------------------
    def _reduced(self, tau: np.ndarray):
        """(j, sn, cn, dn) at τ reduced to [-K, K]: τ = 2 j K + τr (cn >= 0)."""
        if math.isinf(self.kk):
            j, tr = np.zeros_like(tau), tau
        else:
            j = np.floor(tau / (2.0 * self.kk) + 0.5)
            tr = tau - 2.0 * j * self.kk
        sn, cn, dn, _ = ellipj(tr, self.m, self.m1)
        return j, sn, np.abs(cn), dn

    def _pi_minus_f(self, n, p, one_minus_n, j, sn, cn, dn):
        """Π(n; am τ | m) - τ = (n/3) s³ R_J(c², d², 1, p) + 2 j (Π(n|m) - K), with the reduced
        (j, sn, cn, dn) and p = 1 - n s² formed exactly by the caller."""
        if n == 0.0:
            return np.zeros_like(sn)
        inner = n / 3.0 * sn ** 3 * carlson_rj(cn * cn, dn * dn, 1.0, p)
        if math.isinf(self.kk) or not np.any(j):
            return inner
        return inner + 2.0 * j * (n / 3.0 * float(carlson_rj(0.0, self.m1, 1.0, one_minus_n)))

    def _plus(self, j, sn, cn, dn):
        """Π(n+; am τ | m) - τ (direct: bool True) or Π itself (False), n+ = -Δ/(1 + u1);
        ∫ dt / (1 + u) = (Π(τ) - Π(τ0)) / (λ (1 + u1))."""
        n = -self.delta / self.opu1
        one_minus_n = (self.opu1 + self.delta) / self.opu1
        p = (self.opu1 + self.delta * sn * sn) / self.opu1
        if n >= -math.sqrt(self.m):
            return self._pi_minus_f(n, p, one_minus_n, j, sn, cn, dn), True
        # DLMF 19.7.9: Π(n; φ) = atan2(s √(pq), c d)/√(pq) - (Π(m/n; φ) - F(φ)), q = 1 - m/n;
        # Π(n; am τ) is then small and carries no -τ to cancel
        nn = self.m / n
        one_minus_nn = 1.0 + self.m * self.opu1 / self.delta
        r = math.sqrt(one_minus_n * one_minus_nn)
        rest = self._pi_minus_f(nn, 1.0 - nn * sn * sn, one_minus_nn, j, sn, cn, dn)
        return np.arctan2(sn * r, cn * dn) / r + j * math.pi / r - rest, False

    def _minus(self, j, sn, cn, dn):
        """Π(n-; am τ | m) - τ, n- = Δ/(1 - u1) in [0, 1)."""
        n = self.delta / self.omu1
        one_minus_n = self.omu2 / self.omu1
        p = (self.omu2 + self.delta * cn * cn) / self.omu1
        return self._pi_minus_f(n, p, one_minus_n, j, sn, cn, dn)

    # --- the motion ------------------------------------------------------------------------------
    def at(self, t) -> tuple[np.ndarray, np.ndarray]:
        """(q (n, 4) E -> world, ω (n, 3) rad/s E frame) at the instants t (n,) s."""
        t = np.asarray(t, dtype=np.float64)
        tau = self.lam * t + self.tau0
        j, s, c, d = self._reduced(tau)
        sign = np.where(j % 2.0 != 0.0, -1.0, 1.0)
        sn_t, cn_t = sign * s, sign * c
        delta = self.delta
        opu = self.opu1 + delta * s * s      # 1 + u
        omu = self.omu2 + delta * c * c      # 1 - u
        half = math.sqrt(0.5 * delta)
        ch = half * sn_t * self.eps_c if self.opu1 == 0.0 else np.sqrt(0.5 * opu)
        sh = half * cn_t * self.eps_s if self.omu2 == 0.0 else np.sqrt(0.5 * omu)
        sig = self.sig0 + 0.5 * (self.w3 - self.a) * t
        dlt = self.dlt0 + 0.5 * (self.a - self.w3) * t
        if self.bpa != 0.0:  # ½ (a + b) ∫ dt / (1 + u)
            g, direct = self._plus(j, s, c, d) if delta > 0 else (np.zeros_like(t), True)
            lin = t / self.opu1 if direct else 0.0
            sig = sig + 0.5 * self.bpa * (lin + (g - self.g_plus0) / (self.lam * self.opu1))
        if self.bma != 0.0:  # ½ (b - a) ∫ dt / (1 - u)
            g = self._minus(j, s, c, d) if delta > 0 else np.zeros_like(t)
            dlt = dlt + 0.5 * self.bma * (t / self.omu1 + (g - self.g_minus0)
                                          / (self.lam * self.omu1))
        q_t = np.stack([ch * np.cos(sig), sh * np.cos(dlt), sh * np.sin(dlt),
                        ch * np.sin(sig)], axis=-1)
        # body rates: ω1 + i ω2 = e^{-iψ} (θ̇ + i φ̇ sin θ), ψ = σ - δ, sin θ = 2 sh ch
        udot = 2.0 * delta * self.lam * s * c * d
        theta_dot, phi_sin = self._rates(udot, sh, ch, sn_t, cn_t, d, s)
        psi = sig - dlt
        cp, sp = np.cos(psi), np.sin(psi)
        w_t = np.stack([theta_dot * cp + phi_sin * sp, -theta_dot * sp + phi_sin * cp,
                        np.full_like(t, self.w3)], axis=-1)
        q_e = quat_multiply(quat_multiply(self.q_w, q_t), quat_conjugate(self.q_et))
        return q_e, w_t @ self.r_et.T

    def _rates(self, udot, sh, ch, sn_t, cn_t, d, s):
        """(θ̇, φ̇ sin θ) without dividing by a half angle that passes through zero."""
        delta, lam, a = self.delta, self.lam, self.a
        half = math.sqrt(0.5 * delta)
        with np.errstate(divide="ignore", invalid="ignore"):
            generic = -udot / (2.0 * sh * ch)
            # sin(θ/2) = half cn ε_s: θ̇ = 2 d(sh)/dt / ch;  cos(θ/2) = half sn ε_c: θ̇ = -2 ch'/sh
            top = 2.0 * (-half * self.eps_s * sn_t * d * lam) / ch
            bottom = -2.0 * (half * self.eps_c * cn_t * d * lam) / sh
            if self.omu2 == 0.0 and self.opu1 == 0.0:
                theta_dot = np.where(np.abs(ch) >= np.abs(sh), top, bottom)
            elif self.omu2 == 0.0:
                theta_dot = top
            elif self.opu1 == 0.0:
                theta_dot = bottom
            else:
                theta_dot = generic
            # φ̇ sin θ = (b - a u)/sin θ = (b - a)/(2 sh ch) + a sh/ch = (b + a)/(2 sh ch) - a ch/sh
            b_minus_au = self.bau - a * (self.x1 + delta * s * s)
            if self.bma == 0.0 and self.bpa == 0.0:
                phi_sin = np.zeros_like(sh)
            elif self.bma == 0.0:
                phi_sin = a * sh / ch
            elif self.bpa == 0.0:
                phi_sin = -a * ch / sh
            else:
                phi_sin = b_minus_au / (2.0 * sh * ch)
        return theta_dot, phi_sin


def _roots(beta, c2, c1, c0, pole_coefficients, omu0, opu0, through_top, through_bottom):
    """Roots x1 <= 0 <= x2 <= x3 of β x³ + c2 x² + c1 x + c0 (x = u - u0).

    The largest lies at or beyond u = 1 (f(1) = -(b - a)² <= 0) and the cubic is convex beyond
    it, so Newton from an upper bound converges monotonically; deflation gives the other two,
    each to ~eps·|x3| absolutely. A turning point closer to a pole than the nutation amplitude is
    then refined by Newton on the Taylor form of f at that pole (``pole_coefficients``), which
    gives 1 - u2 (1 + u1) to full relative accuracy: the closed form needs that distance, not
    the root. A root exactly on a pole (the motion passes through it) is set exactly.
    """
    x = max(omu0, 0.0) + 1.0 + max(abs(c2), abs(c1), abs(c0)) / beta
    for _ in range(200):
        p = ((beta * x + c2) * x + c1) * x + c0
        dp = (3.0 * beta * x + 2.0 * c2) * x + c1
        step = p / dp if dp > 0.0 else 0.0
        if not step > 0.0:  # round-off reached: the iterates no longer decrease
            break
        x -= step
    x3 = x
    # β (x - x3)(x² + p x + r): r = x1 x2 = -c0/(β x3), and p = -(x1 + x2) from Vieta's
    # x1 x2 + x3 (x1 + x2) = c1/β rather than from x1 + x2 + x3 = -c2/β, which cancels when
    # the far root is large (a fast top: u3 ~ a²/β >> 1) and would leave the centre of the
    # nutation, hence the precession rate, wrong by ~eps·u3
    r = -c0 / (beta * x3) if x3 > 0.0 else c1 / beta
    pq = (r - c1 / beta) / x3 if x3 >= 1.0 else c2 / beta + x3
    sq = math.sqrt(max(pq * pq - 4.0 * r, 0.0))
    if pq >= 0.0:
        xa = -0.5 * (pq + sq)
        xb = r / xa if xa != 0.0 else 0.0
    else:
        xb = 0.5 * (sq - pq)
        xa = r / xb if xb != 0.0 else 0.0
    x1, x2 = min(xa, xb, 0.0), max(xa, xb, 0.0)
    top, bottom = pole_coefficients
    omu2, opu1 = omu0 - x2, opu0 + x1
    if through_top:  # u = 1 is a root: the upper turning point, or the far root u3 = 1
        if abs(x3 - omu0) < abs(x2 - omu0):
            x3 = omu0
        else:
            x2, omu2 = omu0, 0.0
    elif omu2 < x2 - x1:
        omu2 = _refine(top, omu2, omu0)
        x2 = omu0 - omu2
    if through_bottom:
        x1, opu1 = -opu0, 0.0
    elif opu1 < x2 - x1:
        opu1 = _refine(bottom, opu1, opu0)
        x1 = opu1 - opu0
    return x1, x2, max(x3, x2), omu2, opu1


def _refine(coefficients, y, upper):
    """The root y in [0, upper] of d0 + d1 y + d2 y² + d3 y³ near the estimate y (Newton,
    kept inside the bracket; a few steps from an estimate good to ~eps absolutely)."""
    d0, d1, d2, d3 = coefficients
    y = min(max(y, 0.0), upper)
    for _ in range(8):
        p = ((d3 * y + d2) * y + d1) * y + d0
        dp = (3.0 * d3 * y + 2.0 * d2) * y + d1
        if dp == 0.0:
            break
        new = min(max(y - p / dp, 0.0), upper)
        if new == y:
            break
        y = new
    return y


def lagrange_top(moments, lever, force, q0, w0, times) -> tuple[np.ndarray, np.ndarray]:
    """The heavy symmetric top about a fixed point at ``times`` (s, from the initial state):
    (q (n, 4) E -> world, ω (n, 3) rad/s in E). See `LagrangeTop` for the arguments."""
    return LagrangeTop(moments, lever, force, q0, w0).at(times)


def run_segment(y, t0, t1, program_arrays, t_out, y_out) -> tuple[float, float]:
    """`exact`'s run_segment for a heavy symmetric top's pinned program (rotation-only layout
    [q_E, ω'_E]; the program's FORCE_WORLD rows are the weight at the centre of mass, its
    JOINT row last). Fills y_out, moves y to t1; err 0 (no truncation)."""
    # deferred: keeps the closed form's import light (the exact path is numba-free)
    from massprops.dynamics.forces import FORCE_WORLD

    active, codes, params, _, inertia = program_arrays[:5]
    rows = (codes == FORCE_WORLD) & active
    force = params[rows, 0:3].sum(axis=0)
    lever = params[rows][0, 3:6]
    times = np.append(np.asarray(t_out, dtype=np.float64) - t0, t1 - t0)
    q, w = lagrange_top(inertia, lever, force, y[0:4], y[4:7], times)
    y_out[:, 0:4], y_out[:, 4:7] = q[:-1], w[:-1]
    y[0:4], y[4:7] = q[-1], w[-1]
    return 0.0, float(t1)
