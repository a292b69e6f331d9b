"""Independent truth for the repair tests: exact rational moments (fractions) of boxes, closed
triangle meshes and polygons, and the closed forms of walls. Nothing here imports massprops."""

from __future__ import annotations

import math
from fractions import Fraction as Q

import numpy as np


class Moments:
    """Exact ∫1, ∫x_i, ∫x_i x_j over a solid (about the world origin), as fractions; + and -
    combine solids (inclusion-exclusion), ``scaled`` multiplies by a rational."""

    def __init__(self, volume, first, second):
        self.volume, self.first, self.second = volume, list(first), [list(r) for r in second]

    def __add__(self, other):
        return Moments(self.volume + other.volume,
                       [a + b for a, b in zip(self.first, other.first)],
                       [[a + b for a, b in zip(r, s)] for r, s in zip(self.second, other.second)])

    def __neg__(self):
        return Moments(-self.volume, [-a for a in self.first],
                       [[-a for a in r] for r in self.second])

    def __sub__(self, other):
        return self + (-other)

    def scaled(self, k):
        k = Q(k)
        return Moments(k * self.volume, [k * a for a in self.first],
                       [[k * a for a in r] for r in self.second])

    def com(self) -> np.ndarray:
        return np.array([float(a / self.volume) for a in self.first])

    def inertia(self) -> np.ndarray:
        """J about the centre of mass, unit density: tr(M) I - M with M = ∫ s sᵀ, s = x - c."""
        c = [a / self.volume for a in self.first]
        m = [[self.second[i][j] - self.volume * c[i] * c[j] for j in range(3)] for i in range(3)]
        tr = m[0][0] + m[1][1] + m[2][2]
        return np.array([[float((tr if i == j else 0) - m[i][j]) for j in range(3)]
                         for i in range(3)])


def box(lo, hi) -> Moments:
    lo, hi = [Q(float(x)) for x in lo], [Q(float(x)) for x in hi]
    v = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2])
    c = [(a + b) / 2 for a, b in zip(lo, hi)]
    sq = [(b * b + a * b + a * a) / 3 for a, b in zip(lo, hi)]
    second = [[v * (sq[i] if i == j else c[i] * c[j]) for j in range(3)] for i in range(3)]
    return Moments(v, [v * x for x in c], second)


def box_intersection(*boxes):
    lo = np.max([b[0] for b in boxes], axis=0)
    hi = np.min([b[1] for b in boxes], axis=0)
    return (lo, hi) if np.all(hi > lo) else None


def mesh(vertices, faces) -> Moments:
    """Exact moments of a closed, outward triangle mesh (its float coordinates taken exactly)."""
    vq = [[Q(float(x)) for x in v] for v in np.asarray(vertices, dtype=float)]
    vol = Q(0)
    first = [Q(0)] * 3
    second = [[Q(0)] * 3 for _ in range(3)]
    for f in np.asarray(faces):
        a, b, c = (vq[int(i)] for i in f)
        d = (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
             + a[2] * (b[0] * c[1] - b[1] * c[0]))
        s = [a[i] + b[i] + c[i] for i in range(3)]
        vol += d / 6
        first = [first[i] + d * s[i] / 24 for i in range(3)]
        for i in range(3):
            for j in range(3):
                second[i][j] += d * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j] + s[i] * s[j]) / 120
    return Moments(vol, first, second)


TET_FACES = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]


def tetrahedron(points) -> Moments:
    """Exact moments of the tetrahedron with these 4 corners (any order)."""
    p = np.asarray(points, dtype=float)
    m = mesh(p, TET_FACES)
    return m if m.volume > 0 else mesh(p, [f[::-1] for f in TET_FACES])


def polygon_plate(xy) -> tuple[Q, list, list]:
    """Exact area, ∫(x, y) and ∫(x², y², xy) of a simple polygon (k, 2), counter-clockwise
    (Green's theorem: the standard shoelace sums)."""
    p = [[Q(float(a)) for a in q] for q in np.asarray(xy, dtype=float)]
    area, fx, fy, xx, yy, xy2 = (Q(0),) * 6
    for i in range(len(p)):
        x0, y0 = p[i]
        x1, y1 = p[(i + 1) % len(p)]
        c = x0 * y1 - x1 * y0
        area += c / 2
        fx += (x0 + x1) * c / 6
        fy += (y0 + y1) * c / 6
        xx += (x0 * x0 + x0 * x1 + x1 * x1) * c / 12
        yy += (y0 * y0 + y0 * y1 + y1 * y1) * c / 12
        xy2 += (x0 * y1 + 2 * x0 * y0 + 2 * x1 * y1 + x1 * y0) * c / 24
    return area, [fx, fy], [xx, yy, xy2]


def prism(xy, z0, z1) -> Moments:
    """Exact moments of the prism polygon × [z0, z1]."""
    area, (fx, fy), (xx, yy, xy) = polygon_plate(xy)
    z0, z1 = Q(float(z0)), Q(float(z1))
    h = z1 - z0
    zc = (z0 + z1) / 2
    zz = (z1 * z1 + z1 * z0 + z0 * z0) / 3
    v = area * h
    second = [[xx * h, xy * h, fx * h * zc], [xy * h, yy * h, fy * h * zc],
              [fx * h * zc, fy * h * zc, v * zz]]
    return Moments(v, [fx * h, fy * h, v * zc], second)


def regular_polygon(n: int, apothem: float) -> np.ndarray:
    """(n, 2) corners of the regular n-gon with this apothem, counter-clockwise, a corner on +x
    rotated by half a step so that an edge faces +x."""
    r = apothem / math.cos(math.pi / n)
    t = 2 * math.pi * (np.arange(n) + 0.5) / n
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1)


def spherical_shell(r_in: float, r_out: float, rho: float = 1.0) -> tuple[float, float]:
    """(mass, moment of inertia about any diameter) of a thick spherical shell."""
    m = rho * 4 / 3 * math.pi * (r_out**3 - r_in**3)
    return m, 0.4 * m * (r_out**5 - r_in**5) / (r_out**3 - r_in**3)
