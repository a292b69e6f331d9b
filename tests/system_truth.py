"""Independent references for two system samples, derived by hand (nothing from massprops).

- **Double pendulum** (`sample_scenes/double_pendulum.yaml`): two rods in the x-z plane hinged
  about y, as a compound pendulum in absolute angles φ1, φ2 measured from the downward vertical
  (the hinge's turn about +y, so φ1 = shoulder, φ2 = shoulder + elbow):
      T = ½ (m1 a1² + I1 + m2 L1²) φ1'² + ½ (m2 a2² + I2) φ2'² + m2 L1 a2 cos(φ1 − φ2) φ1' φ2',
      V = −(m1 a1 + m2 L1) g cos φ1 − m2 a2 g cos φ2,
  a1, a2 the centres of mass' distances from their hinges, L1 the hinge-to-hinge length, I the
  moments about y through the centres of mass.
- **Four-bar** (`sample_scenes/four_bar.yaml`): one degree of freedom, the crank's line angle ψ
  in the x-z plane (measured from +x towards +z; the joint A's coordinate is ψ0 − ψ, a turn about
  +y). For each ψ the coupler and rocker angles β, φ close the loop a e(ψ) + b e(β) = d + c e(φ)
  (two circles' intersection on the assembly's branch; Freudenstein's equation holds); their
  first and second ψ-derivatives follow from differentiating the loop twice. Each body's centre
  of mass turns rigidly with its line (offset radius and angle from the scene's numbers), so
      J(ψ) ψ'' = −C(ψ) ψ'² + Q(ψ),  J = Σ m |∂x/∂ψ|² + I (∂θ/∂ψ)²,
  C = Σ m ∂x/∂ψ · ∂²x/∂ψ² + I ∂θ/∂ψ ∂²θ/∂ψ², Q = Σ m g · ∂x/∂ψ (the one-coordinate Lagrange
  equation).

Every number is the scene file's binary float taken exactly. Each problem is written once over a
`Num` (math or mpmath), so the same equations give a fast float64 right-hand side (for scipy)
and a 30-digit one, integrated by `gbs`: Gragg-Bulirsch-Stoer extrapolation (modified midpoint
rule, Aitken-Neville in h²) with a fixed macro step, order 2k.
"""

from __future__ import annotations

import math

import mpmath as mp

# sample_scenes/double_pendulum.yaml
DP = {"m1": 1.0, "m2": 1.0, "I1": 0.08336666666666666, "I2": 0.08336666666666666,
      "a1": 0.5, "a2": 0.5, "L1": 1.0, "g": 9.81,
      "shoulder": 1.0471975511965976, "elbow": -0.5235987755982988, "duration": 10.0}

# sample_scenes/four_bar.yaml: joint points and centres of mass in (x, z), masses, I_yy
FB = {"A": (0.0, 0.0), "B": (0.5000000000000001, 0.8660254037844386),
      "C": (3.016007650436934, 2.4999487505001956), "D": (3.0, 0.0),
      "com": {"crank": (0.25000000000000006, 0.4330127018922193),
              "coupler": (1.758003825218467, 1.6829870771423172),
              "rocker": (3.0080038252184673, 1.2499743752500978)},
      "mass": {"crank": 1.0, "coupler": 3.0, "rocker": 2.5},
      "Iyy": {"crank": 0.08336666666666666, "coupler": 2.250100000000001,
              "rocker": 1.3021666666666667},
      "g": 9.81, "rate_A": 2.0, "duration": 5.0}


class _Math:
    """The float64 number kit (math)."""

    sin, cos, sqrt, atan2 = math.sin, math.cos, math.sqrt, math.atan2

    @staticmethod
    def num(x):
        return float(x)


class _Mp:
    """The mpmath number kit (precision set by mp.mp.dps)."""

    sin, cos, sqrt, atan2 = mp.sin, mp.cos, mp.sqrt, mp.atan2

    @staticmethod
    def num(x):
        return mp.mpf(x)


def double_pendulum_rhs(kit=_Math):
    """f(t, y) for y = [φ1, φ2, φ1', φ2'] (absolute angles, rad, rad/s)."""
    n = kit.num
    m1, m2, i1, i2 = n(DP["m1"]), n(DP["m2"]), n(DP["I1"]), n(DP["I2"])
    a1, a2, l1, g = n(DP["a1"]), n(DP["a2"]), n(DP["L1"]), n(DP["g"])
    m11, m22, k = m1 * a1 * a1 + i1 + m2 * l1 * l1, m2 * a2 * a2 + i2, m2 * l1 * a2
    w1g, w2g = (m1 * a1 + m2 * l1) * g, m2 * a2 * g
    sin, cos = kit.sin, kit.cos

    def f(t, y):
        p1, p2, u1, u2 = y
        s, c = sin(p1 - p2), cos(p1 - p2)
        m12 = k * c
        r1 = -k * s * u2 * u2 - w1g * sin(p1)
        r2 = k * s * u1 * u1 - w2g * sin(p2)
        det = m11 * m22 - m12 * m12
        return [u1, u2, (r1 * m22 - m12 * r2) / det, (m11 * r2 - m12 * r1) / det]

    return f


def double_pendulum_start(kit=_Math):
    n = kit.num
    p1 = n(DP["shoulder"])
    return [p1, p1 + n(DP["elbow"]), n(0), n(0)]


def double_pendulum_energy(y, kit=_Math):
    """J: T + V of a state [φ1, φ2, φ1', φ2'] (for checks)."""
    n = kit.num
    m1, m2, i1, i2 = n(DP["m1"]), n(DP["m2"]), n(DP["I1"]), n(DP["I2"])
    a1, a2, l1, g = n(DP["a1"]), n(DP["a2"]), n(DP["L1"]), n(DP["g"])
    p1, p2, u1, u2 = y
    t = ((m1 * a1 * a1 + i1 + m2 * l1 * l1) * u1 * u1 + (m2 * a2 * a2 + i2) * u2 * u2) / 2 \
        + m2 * l1 * a2 * kit.cos(p1 - p2) * u1 * u2
    return t - (m1 * a1 + m2 * l1) * g * kit.cos(p1) - m2 * a2 * g * kit.cos(p2)


class FourBar:
    """The four-bar reduced to its crank line angle ψ (x-z plane, from +x towards +z)."""

    def __init__(self, kit=_Math) -> None:
        self.kit = k = kit
        n = k.num
        ax, az = (n(v) for v in FB["A"])
        bx, bz = (n(v) - o for v, o in zip(FB["B"], (ax, az)))
        cx, cz = (n(v) - o for v, o in zip(FB["C"], (ax, az)))
        dx, dz = (n(v) - o for v, o in zip(FB["D"], (ax, az)))
        self.d = (dx, dz)
        self.a = k.sqrt(bx * bx + bz * bz)
        self.b = k.sqrt((cx - bx) ** 2 + (cz - bz) ** 2)
        self.c = k.sqrt((cx - dx) ** 2 + (cz - dz) ** 2)
        self.psi0 = k.atan2(bz, bx)
        beta0, phi0 = k.atan2(cz - bz, cx - bx), k.atan2(cz - dz, cx - dx)
        # the assembly's branch: the side of the line B -> D that C is on
        self.branch = 1 if (dx - bx) * (cz - bz) - (dz - bz) * (cx - bx) < 0 else -1
        self.mass = {b: n(FB["mass"][b]) for b in FB["mass"]}
        self.iyy = {b: n(FB["Iyy"][b]) for b in FB["Iyy"]}
        self.g = n(FB["g"])
        com = {b: tuple(n(v) for v in FB["com"][b]) for b in FB["com"]}
        # each centre of mass as radius r and angle offset δ from its body's line angle
        self.off = {}
        for body, (ox, oz), line in (("crank", (ax - ax, az - az), self.psi0),
                                     ("coupler", (bx, bz), beta0),
                                     ("rocker", (dx, dz), phi0)):
            px, pz = com[body][0] - ax - ox, com[body][1] - az - oz
            self.off[body] = (k.sqrt(px * px + pz * pz), k.atan2(pz, px) - line)

    def angles(self, psi):
        """(β, φ) closing the loop at crank angle ψ, on the assembly's branch."""
        k = self.kit
        bx, bz = self.a * k.cos(psi), self.a * k.sin(psi)
        dx, dz = self.d
        ex, ez = dx - bx, dz - bz
        r2 = ex * ex + ez * ez
        r = k.sqrt(r2)
        along = (self.b * self.b - self.c * self.c + r2) / (2 * r)
        across = k.sqrt(self.b * self.b - along * along)
        ux, uz = ex / r, ez / r
        # C = B + along u + across n, n = u turned so that C sits on the assembly's side
        sgn = -self.branch
        cx = bx + along * ux - sgn * across * uz
        cz = bz + along * uz + sgn * across * ux
        return k.atan2(cz - bz, cx - bx), k.atan2(cz - dz, cx - dx)

    def _solve2(self, beta, phi, rx, rz):
        """(x, y) with x b e⊥(β) − y c e⊥(φ) = (rx, rz)."""
        k = self.kit
        m11, m21 = -self.b * k.sin(beta), self.b * k.cos(beta)
        m12, m22 = self.c * k.sin(phi), -self.c * k.cos(phi)
        det = m11 * m22 - m12 * m21
        return (rx * m22 - m12 * rz) / det, (m11 * rz - m21 * rx) / det

    def rhs(self):
        """f(t, y) for y = [ψ, ψ']."""
        k = self.kit
        sin, cos = k.sin, k.cos
        a = self.a
        mass, iyy, g = self.mass, self.iyy, self.g

        def f(t, y):
            psi, w = y
            beta, phi = self.angles(psi)
            # loop, differentiated: a e⊥(ψ) + b β1 e⊥(β) − c φ1 e⊥(φ) = 0
            b1, p1 = self._solve2(beta, phi, a * sin(psi), -a * cos(psi))
            # twice: b β2 e⊥(β) − c φ2 e⊥(φ) = a e(ψ) + b β1² e(β) − c φ1² e(φ)
            rx = a * cos(psi) + self.b * b1 * b1 * cos(beta) - self.c * p1 * p1 * cos(phi)
            rz = a * sin(psi) + self.b * b1 * b1 * sin(beta) - self.c * p1 * p1 * sin(phi)
            b2, p2 = self._solve2(beta, phi, rx, rz)
            jj = cc = qq = 0
            for body, ang, d1, d2 in (("crank", psi, 1, 0), ("coupler", beta, b1, b2),
                                      ("rocker", phi, p1, p2)):
                r, delta = self.off[body]
                th = ang + delta
                # the centre of mass' ψ-derivatives: r e(θ) turning with its line
                jx, jz = -r * sin(th) * d1, r * cos(th) * d1
                hx = -r * cos(th) * d1 * d1 - r * sin(th) * d2
                hz = -r * sin(th) * d1 * d1 + r * cos(th) * d2
                if body == "coupler":  # plus the point B = a e(ψ) it hangs on
                    jx, jz = jx - a * sin(psi), jz + a * cos(psi)
                    hx, hz = hx - a * cos(psi), hz - a * sin(psi)
                m, inertia = mass[body], iyy[body]
                jj = jj + m * (jx * jx + jz * jz) + inertia * d1 * d1
                cc = cc + m * (jx * hx + jz * hz) + inertia * d1 * d2
                qq = qq - m * g * jz
            return [w, (qq - cc * w * w) / jj]

        return f

    def start(self):
        """[ψ0, ψ'0]: the joint A turns at +rate about +y, so ψ' = −rate."""
        return [self.psi0, -self.kit.num(FB["rate_A"])]

    def joint_a(self, psi):
        """The joint A's coordinate (the crank's turn about +y from the assembly), rad."""
        return self.psi0 - psi

    def freudenstein(self, psi, phi):
        """Residual of K1 cos φ − K2 cos ψ + K3 − cos(ψ − φ) (ground along +x, A at the
        origin); 0 on the loop."""
        k = self.kit
        a, b, c, d = self.a, self.b, self.c, self.d[0]
        k1, k2, k3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
        return k1 * k.cos(phi) - k2 * k.cos(psi) + k3 - k.cos(psi - phi)


def gbs(f, y0, t_end, steps: int, levels: int = 12):
    """Integrate y' = f(t, y) from 0 to t_end in ``steps`` equal macro steps, each by
    Gragg-Bulirsch-Stoer extrapolation over ``levels`` modified-midpoint runs with 2, 4, ...
    substeps (order 2 levels). Works on lists of mpf or floats; returns the list at t_end."""
    num = mp.mpf if isinstance(y0[0], mp.mpf) else float
    big_h = num(t_end) / steps
    y = list(y0)
    t = big_h * 0
    for _ in range(steps):
        table: list[list] = []
        f0 = f(t, y)
        for j in range(levels):
            n = 2 * (j + 1)
            h = big_h / n
            z0 = y
            z1 = [a + h * b for a, b in zip(y, f0)]
            for i in range(1, n):
                fz = f(t + i * h, z1)
                z0, z1 = z1, [a + 2 * h * b for a, b in zip(z0, fz)]
            fz = f(t + big_h, z1)
            row = [[(a + b + h * c) / 2 for a, b, c in zip(z0, z1, fz)]]
            for m in range(1, j + 1):
                ratio = num((j + 1) ** 2) / ((j + 1 - m) ** 2) - 1
                prev, cur = table[j - 1][m - 1], row[m - 1]
                row.append([c + (c - p) / ratio for c, p in zip(cur, prev)])
            table.append(row)
        y = table[-1][-1]
        t = t + big_h
    return y


def double_pendulum_reference(t_end: float, dps: int = 30, steps_per_s: int = 20,
                              levels: int = 12):
    """[shoulder, elbow] (rad) at t_end, mpmath at ``dps`` digits."""
    with mp.workdps(dps):
        y = gbs(double_pendulum_rhs(_Mp), double_pendulum_start(_Mp), t_end,
                max(1, round(steps_per_s * t_end)), levels)
        return [y[0], y[1] - y[0]]


def four_bar_reference(t_end: float, dps: int = 30, steps_per_s: int = 40, levels: int = 12):
    """The joint A's coordinate (rad) at t_end, mpmath at ``dps`` digits."""
    with mp.workdps(dps):
        bar = FourBar(_Mp)
        y = gbs(bar.rhs(), bar.start(), t_end, max(1, round(steps_per_s * t_end)), levels)
        return bar.joint_a(y[0])
