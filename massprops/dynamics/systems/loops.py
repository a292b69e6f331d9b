"""Cut joints: the constraints Φ(q) = 0 of the joints not in the spanning tree.

Each cut joint is a list of primitive constraints between a point or direction fixed in its
first body a and one fixed in its second body b (world at t = 0, stored in body frames):
- ``point``: x_b - x_a = 0 (3 rows, m);
- ``perp``: L (R_a e)·(R_b n) = 0 (1 row; L the system size, so every row is in metres);
- ``line``: (x_b - x_a)·(R_a e) = 0 (1 row: b's point stays on a's line or plane);
- ``dist``: (|x_b - x_a|² - ℓ²) / (2ℓ) = 0 (1 row, a massless rod of length ℓ).
A revolute joint is a point and two perps (a's two normals against b's axis), a spherical joint a
point, a universal joint a point and one perp, a cylindrical joint two lines and two perps, a
prismatic joint those and one perp against the turn about the axis, a fixed joint a point and
three perps. For each row the velocity Jacobian is a pair of spatial forces (ρ_b, ρ_a) with
Φ̇ = ρ_b·V_b + ρ_a·V_a (so G = ρ_b J_b + ρ_a J_a) and the joint's reaction on b is Σ λ ρ_b;
``terms`` also gives Φ̈ at u̇ = 0 (the acceleration bias), exactly, from the body motions.
A `Coupling` (a description's mimic or joint equality) is one more row after them, linear in
the tree coordinates.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np

from massprops.dynamics.systems.model import WORLD
from massprops.dynamics.systems.tree import cross


@dataclass(frozen=True, eq=False)
class Primitive:
    """kind, bodies a, b (WORLD allowed), local vectors: ``pa``/``pb`` points (body frames; for
    the world: world), ``ea``/``nb`` directions, ``length`` (dist), ``joint`` (cut index)."""

    kind: str
    a: int
    b: int
    pa: np.ndarray
    pb: np.ndarray
    ea: np.ndarray
    nb: np.ndarray
    length: float
    joint: int

    @property
    def rows(self) -> int:
        return 3 if self.kind == "point" else 1


@dataclass(frozen=True, eq=False)
class Coupling:
    """A linear relation of tree coordinates, one constraint row Φ = scale (Σ c q[iq] − constant)
    (``terms`` ((iq, iu, c), ...); scale: the system size where the relation is in radians, so
    that every row is in metres), G's row scale c at each iu, Φ̈ at u̇ = 0 zero. It acts on the
    joints, not on bodies: its reaction is a generalised force on each joint, as a drive's."""

    name: str
    terms: tuple
    constant: float
    scale: float


def _normals(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing ``axis`` to a right-handed orthonormal basis."""
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    e1 = cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    return e1, cross(axis, e1)


def primitives(joint, index: int, bodies) -> list[Primitive]:
    """The primitives of a cut ``joint`` (a SystemJoint; point and axes world at t = 0)."""
    def local(body: int, v: np.ndarray, point: bool) -> np.ndarray:
        if body == WORLD:
            return np.asarray(v, float).copy()
        b = bodies[body]
        return b.rotation0.T @ (v - b.com0) if point else b.rotation0.T @ v

    a, b, z = joint.a, joint.b, np.zeros(3)

    def prim(kind, pa=z, pb=z, ea=z, nb=z, length=0.0):
        return Primitive(kind, a, b, pa, pb, ea, nb, length, index)

    if joint.kind == "distance":
        pa, pb = joint.points
        return [prim("dist", local(a, pa, True), local(b, pb, True),
                     length=float(np.linalg.norm(pb - pa)))]
    p = joint.point
    pa, pb = local(a, p, True), local(b, p, True)
    out = []
    kind = joint.kind
    axis = joint.axes[0] if len(joint.axes) else np.array([0.0, 0.0, 1.0])
    e1, e2 = _normals(axis)
    if kind in ("spherical", "revolute", "universal", "fixed"):
        out.append(prim("point", pa, pb))
    else:  # cylindrical, prismatic: b's point stays on a's line
        out += [prim("line", pa, pb, ea=local(a, e, False)) for e in (e1, e2)]
    if kind in ("revolute", "cylindrical", "prismatic"):
        out += [prim("perp", ea=local(a, e, False), nb=local(b, axis, False)) for e in (e1, e2)]
    if kind == "prismatic":
        out.append(prim("perp", ea=local(a, e1, False), nb=local(b, e2, False)))
    if kind == "universal":
        out.append(prim("perp", ea=local(a, joint.axes[0], False),
                        nb=local(b, joint.axes[1], False)))
    if kind == "fixed":
        x, y, zz = np.eye(3)
        out += [prim("perp", ea=local(a, u, False), nb=local(b, v, False))
                for u, v in ((x, y), (y, zz), (zz, x))]
    return out


def _motion(kin, body: int):
    """(R, ω, v_O, ω̇0, v̇_O0) of a body (the world: identity and zeros)."""
    if body == WORLD:
        z = np.zeros(3)
        return np.eye(3), z, z, z, z
    return (kin.rotation[body], kin.V[body, :3], kin.V[body, 3:], kin.A[body, :3],
            kin.A[body, 3:])


def _point(kin, body: int, local: np.ndarray):
    """World position, velocity and acceleration (at the kinematics' A) of a body point."""
    r, w, vo, dw, dvo = _motion(kin, body)
    if body == WORLD:
        return local - kin.ref, np.zeros(3), np.zeros(3)
    x = kin.com[body] + r @ local
    v = vo + cross(w, x)
    return x, v, dvo + cross(dw, x) + cross(w, v)


def terms(prims: list[Primitive], kin, jac: np.ndarray, nv: int, size: float,
          couplings: Sequence[Coupling] = (), q: np.ndarray | None = None):
    """Φ (m,), G (m, nv), Φ̈ at the kinematics' accelerations (m,), and the spatial-force rows
    on b and on a (m, 6 each) for the reactions. ``kin`` must hold accelerations at u̇ = 0
    for the bias. The ``couplings``' rows (at the coordinates ``q``) come last."""
    m = sum(p.rows for p in prims) + len(couplings)
    phi, gdot = np.empty(m), np.empty(m)
    rho_b, rho_a = np.zeros((m, 6)), np.zeros((m, 6))
    row = 0
    for p in prims:
        ra, wa, _, dwa, _ = _motion(kin, p.a)
        rb, wb, _, dwb, _ = _motion(kin, p.b)
        if p.kind == "perp":
            e, n = ra @ p.ea, rb @ p.nb
            axis = cross(n, e)
            phi[row] = size * (e @ n)
            rho_b[row, :3], rho_a[row, :3] = size * axis, -size * axis
            gdot[row] = size * ((dwb - dwa) @ axis + (wb - wa) @ (cross(cross(wb, n), e)
                                                                  + cross(n, cross(wa, e))))
            row += 1
            continue
        xa, va, aa = _point(kin, p.a, p.pa)
        xb, vb, ab = _point(kin, p.b, p.pb)
        d, dd, ddd = xb - xa, vb - va, ab - aa
        if p.kind == "point":
            for k in range(3):
                e = np.eye(3)[k]
                rho_b[row + k] = np.concatenate([cross(xb, e), e])
                rho_a[row + k] = -np.concatenate([cross(xa, e), e])
            phi[row:row + 3], gdot[row:row + 3] = d, ddd
            row += 3
        elif p.kind == "line":
            e = ra @ p.ea
            we = cross(wa, e)
            phi[row] = d @ e
            rho_b[row] = np.concatenate([cross(xb, e), e])
            rho_a[row] = -np.concatenate([cross(xa, e), e])
            rho_a[row, :3] += cross(e, d)
            gdot[row] = ddd @ e + 2 * dd @ we + d @ (cross(dwa, e) + cross(wa, we))
            row += 1
        else:  # dist
            length = p.length
            phi[row] = (d @ d - length * length) / (2 * length)
            rho_b[row] = np.concatenate([cross(xb, d), d]) / length
            rho_a[row] = -np.concatenate([cross(xa, d), d]) / length
            gdot[row] = (dd @ dd + d @ ddd) / length
            row += 1
    g = np.zeros((m, nv))
    r = 0
    for p in prims:
        for k in range(p.rows):
            if p.b != WORLD:
                g[r + k] += rho_b[r + k] @ jac[p.b]
            if p.a != WORLD:
                g[r + k] += rho_a[r + k] @ jac[p.a]
        r += p.rows
    q = cast(np.ndarray, q)  # given wherever there are couplings
    for c in couplings:
        phi[r], gdot[r] = 0.0, 0.0
        for k, (iq, iu, coef) in enumerate(c.terms):
            phi[r] += c.scale * coef * q[iq] - (c.scale * c.constant if k == 0 else 0.0)
            g[r, iu] += c.scale * coef
        r += 1
    return phi, g, gdot, rho_b, rho_a
