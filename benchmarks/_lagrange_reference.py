"""An independent reference for the heavy symmetric top: Euler angles (z-x-z) in mpmath at 30
digits, the nutation u = cos θ by Jacobi's sn from the cubic's roots (mpmath.polyroots), the
precession φ and the spin ψ by quadrature of their rates (mpmath.quad over one nutation period,
times the whole periods, plus the remainder). Shares nothing with massprops' closed form (half
angles, Π, Carlson integrals) but the physics.

Frames: the body's symmetry axis is body z, the pivot on it at distance l below the centre of
mass (the centre of mass at +l along body z from the pivot); world z is up (gravity -g z).
"""

from __future__ import annotations

import mpmath as mp
import numpy as np

mp.mp.dps = 30


def _quat_zxz(phi, theta, psi):
    """Body -> world quaternion (w, x, y, z) of z(φ) x(θ) z(ψ)."""
    c, s = mp.cos(theta / 2), mp.sin(theta / 2)
    return (c * mp.cos((phi + psi) / 2), s * mp.cos((phi - psi) / 2),
            s * mp.sin((phi - psi) / 2), c * mp.sin((phi + psi) / 2))


class LagrangeReference:
    """The top of transverse moment ``a_mom`` and axial moment ``c_mom`` about the pivot
    (kg·m²), weight × lever ``mgl`` (N·m), started at the body -> world quaternion q0 with body
    angular velocity w0 (rad/s). All inputs are taken as the exact binary values given."""

    def __init__(self, a_mom, c_mom, mgl, q0, w0):
        a_mom, c_mom, mgl = mp.mpf(a_mom), mp.mpf(c_mom), mp.mpf(mgl)
        q = [mp.mpf(float(x)) for x in q0]
        w1, w2, w3 = (mp.mpf(float(x)) for x in w0)
        theta = 2 * mp.atan2(mp.hypot(q[1], q[2]), mp.hypot(q[0], q[3]))
        sig, dlt = mp.atan2(q[3], q[0]), mp.atan2(q[2], q[1])
        self.phi0, self.psi0 = sig + dlt, sig - dlt
        psi = self.psi0
        theta_dot = w1 * mp.cos(psi) - w2 * mp.sin(psi)
        phi_sin = w1 * mp.sin(psi) + w2 * mp.cos(psi)  # φ̇ sin θ
        u0 = mp.cos(theta)
        self.w3, self.a = w3, c_mom * w3 / a_mom
        self.b = phi_sin * mp.sin(theta) + self.a * u0
        beta = 2 * mgl / a_mom
        alpha = theta_dot**2 + phi_sin**2 + beta * u0
        a, b = self.a, self.b
        # f(u) = (1 - u²)(α - β u) - (b - a u)²
        coeffs = [beta, -(alpha + a * a), 2 * a * b - beta, alpha - b * b]
        roots = sorted(mp.re(r) for r in mp.polyroots(coeffs, maxsteps=200, extraprec=200))
        self.u1, self.u2, u3 = roots
        self.m = (self.u2 - self.u1) / (u3 - self.u1)
        self.lam = mp.sqrt(beta * (u3 - self.u1)) / 2
        udot0 = -mp.sin(theta) * theta_dot
        s0 = mp.sqrt(max((u0 - self.u1) / (self.u2 - self.u1), 0))
        self.tau0 = mp.ellipf(mp.asin(min(s0, 1)), self.m) * (1 if udot0 >= 0 else -1)
        self.period = 2 * mp.ellipk(self.m) / self.lam
        rates = (self._phi_dot, self._psi_dot)
        self.per_period = [mp.quad(f, mp.linspace(0, self.period, 9)) for f in rates]

    def u(self, t):
        return self.u1 + (self.u2 - self.u1) * mp.ellipfun("sn", self.lam * t + self.tau0,
                                                           self.m) ** 2

    def _phi_dot(self, t):
        u = self.u(t)
        return (self.b - self.a * u) / (1 - u * u)

    def _psi_dot(self, t):
        return self.w3 - self.u(t) * self._phi_dot(t)

    def _angle(self, k: int, t):
        whole = mp.floor(t / self.period)
        rest = t - whole * self.period
        rate = (self._phi_dot, self._psi_dot)[k]
        part = mp.quad(rate, mp.linspace(0, rest, 9)) if rest > 0 else 0
        return whole * self.per_period[k] + part

    def at(self, t):
        """(q body -> world (4,), ω body (3,)) as float64 at the instant t (s)."""
        t = mp.mpf(t)
        u = self.u(t)
        theta = mp.acos(u)
        phi = self.phi0 + self._angle(0, t)
        psi = self.psi0 + self._angle(1, t)
        tau = self.lam * t + self.tau0
        sn, cn, dn = (mp.ellipfun(k, tau, self.m) for k in ("sn", "cn", "dn"))
        udot = 2 * (self.u2 - self.u1) * sn * cn * dn * self.lam
        theta_dot = -udot / mp.sin(theta)
        phi_sin = (self.b - self.a * u) / mp.sin(theta)
        w = (phi_sin * mp.sin(psi) + theta_dot * mp.cos(psi),
             phi_sin * mp.cos(psi) - theta_dot * mp.sin(psi), self.w3)
        return (np.array([float(x) for x in _quat_zxz(phi, theta, psi)]),
                np.array([float(x) for x in w]))
