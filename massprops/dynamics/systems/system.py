"""The equations of a system: applied loads, accelerations and multipliers, projection, reactions.

M u̇ + h(q, u) = τ + Gᵀλ (h from RNEA with u̇ = 0 and the applied body loads, τ the joints' own
springs, dampers and drives), G u̇ = -Φ̈(u̇ = 0). With M = L Lᵀ and B = G L⁻ᵀ = U Σ Vᵀ:
λ = U Σ⁺² Uᵀ r (minimum norm where rows repeat), r = -Φ̈₀ - G M⁻¹(τ - h); u̇ = M⁻¹(τ - h + Gᵀλ).
Singular values below CONSTRAINT_RANK_RTOL of the largest are zero; the rank fixes the degrees
of freedom (nv - rank) and redundant rows (m - rank). Projection: δ = -L⁻ᵀ B⁺ Φ (the smallest
correction in the kinetic-energy metric), Newton until Φ is at round-off; the same for Φ̇.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from massprops import tolerances
from massprops.dynamics.systems import cutjoint
from massprops.dynamics.systems import tree as tr
from massprops.dynamics.systems.assemble import Tree
from massprops.dynamics.systems.falling import Falling
from massprops.dynamics.systems.loops import terms
from massprops.dynamics.systems.model import WORLD, SystemScene
from massprops.dynamics.systems.program import build_program
from massprops.dynamics.systems.tree import cross
from massprops.errors import ComputationError

EPS = tolerances.EPS


class SingularPose(ComputationError):
    """The constraint Jacobian lost rank during the run (a dead point) or the projection failed."""


class UnclosedLoop(SingularPose):
    """The projection could not close the loops: ``residual`` (m), the largest |Φ| it left."""

    def __init__(self, message: str, residual: float) -> None:
        super().__init__(message)
        self.residual = residual


@dataclass(frozen=True, eq=False)
class Solution:
    """udot (nv,), lam (m,), rank of G, kinematics with the true accelerations, the cut
    joints' spatial-force rows on their second and first bodies (loops.terms)."""

    udot: np.ndarray
    lam: np.ndarray
    rank: int
    kin: tr.Kinematics
    rho_b: np.ndarray
    rho_a: np.ndarray


class System:
    """A scene's tree, loops and loads; ``rhs`` is the ODE ẏ = f(t, y), y = [q (nq), u (nv)].
    ``scene`` and ``tree`` are about ``origin`` (3,) m world (`assemble.localized`): positions
    and points the outputs give add it back."""

    def __init__(self, scene: SystemScene, tree: Tree, origin: np.ndarray | None = None,
                 falling: Falling | None = None) -> None:
        self.scene, self.tree = scene, tree
        self.origin = np.zeros(3) if origin is None else np.asarray(origin, dtype=float)
        self.falling = falling  # the free-fall frame this system runs in (falling.py), or None
        self.nq, self.nv, self.m = tree.nq, tree.nv, sum(p.rows for p in tree.prims) + len(
            tree.couplings)
        bodies = tree.bodies
        # in the falling frame the fictitious force −m g cancels each weight
        gravity = np.zeros(3) if falling is not None else np.asarray(scene.gravity, float)
        self.weights = np.array([b.mass * gravity for b in bodies])
        self.force_local = [None if f.point is None else
                            bodies[f.body].rotation0.T @ (f.point - bodies[f.body].com0)
                            for f in scene.forces]
        self.spring_local = [[_local(bodies, s.a, s.points[0]), _local(bodies, s.b, s.points[1])]
                             for s in scene.springs]
        self.rank: int | None = None  # of G at the start; a drop later is a singular pose
        self.margin = 1.0  # smallest σ_min / σ_max of G M^(-1/2) kept over the run so far
        self.fastest_rate: float | None = None  # ρ(∂ẏ/∂y) at the start (systems.stiffness)
        self.time = 0.0
        self.blocks = subtrees(tree)  # M's diagonal blocks (MassFactor)
        self.program = build_program(self)  # the arrays the compiled step loop runs on

    # --- loads ----------------------------------------------------------------------------------
    def applied(self, t: float, kin: tr.Kinematics, q: np.ndarray, u: np.ndarray):
        """(fext (n, 6) spatial forces about O on each body, τ (nv,) joint loads); a loaded cut
        joint's load is a wrench pair in fext (`cutjoint`)."""
        n = len(self.tree.bodies)
        fext = np.zeros((n, 6))
        for i in range(n):
            fext[i, :3] = cross(kin.com[i], self.weights[i])
            fext[i, 3:] = self.weights[i]
        for f, local in zip(self.scene.forces, self.force_local):
            if not f.start <= t < f.end:
                continue
            r = kin.rotation[f.body]
            vec = r @ f.vector if f.frame == "body" else np.asarray(f.vector)
            if f.kind == "torque":
                fext[f.body, :3] += vec
            else:
                x = kin.com[f.body] + (r @ local if local is not None else 0.0)
                fext[f.body, :3] += cross(x, vec)
                fext[f.body, 3:] += vec
        for s, (la, lb) in zip(self.scene.springs, self.spring_local):
            xa, va = _point_state(kin, s.a, la)
            xb, vb = _point_state(kin, s.b, lb)
            d, dd = xb - xa, vb - va
            if s.rest_length == 0.0:
                force = -s.stiffness * d - s.damping * dd
            else:
                length = float(np.sqrt(d @ d))
                e = d / length if length > 0 else np.zeros(3)
                force = (-s.stiffness * (length - s.rest_length) - s.damping * (e @ dd)) * e
            for body, x, sign in ((s.b, xb, 1.0), (s.a, xa, -1.0)):
                if body != WORLD:
                    fext[body, :3] += sign * cross(x, force)
                    fext[body, 3:] += sign * force
        for d in self.scene.drags:  # in the world frame (`falling` leaves a dragged system there)
            w = kin.V[d.body, :3]
            f = -d.linear * (kin.V[d.body, 3:] + cross(w, kin.com[d.body]))
            fext[d.body, :3] += cross(kin.com[d.body], f) - d.angular * w
            fext[d.body, 3:] += f
        cutjoint.add_loads(self.tree, self.scene, t, kin, fext)
        tau = np.zeros(self.nv)
        for k in self.tree.loaded:
            j = self.tree.joints[k]
            sj = self.scene.joints[j.source]
            sign = -1.0 if j.reversed else 1.0
            coord, rate = sign * q[j.iq], sign * u[j.iu]
            load = -sj.stiffness * (coord - sj.rest) - sj.damping * rate
            if sj.start <= t < sj.end:
                load += sj.drive
            tau[j.iu] += sign * load
        return fext, tau

    # --- accelerations --------------------------------------------------------------------------
    def solve(self, t: float, y: np.ndarray, check: bool = True, full: bool = True) -> Solution:
        """Accelerations and multipliers at (t, y); raises SingularPose when G's rank fell.
        ``full``: also the kinematics at the true accelerations (for reactions)."""
        q, u = y[:self.nq], y[self.nq:]
        kin0 = tr.kinematics(self.tree, q, u)
        fext, tau = self.applied(t, kin0, q, u)
        h = tr.generalized(self.tree, kin0,
                           tr.transmitted(self.tree, tr.body_forces(self.tree, kin0, fext)))
        chol = MassFactor(tr.mass_matrix(self.tree, kin0), self.blocks)
        rhs = tau - h
        lam, rank = np.zeros(self.m), 0
        rho_b = rho_a = np.zeros((0, 6))
        if self.m:
            phi, g, gdot, rho_b, rho_a = terms(self.tree.prims, kin0, tr.jacobians(self.tree, kin0),
                                               self.nv, self.tree.size, self.tree.couplings, q)
            b = chol.lower(g.T).T  # G L⁻ᵀ
            uu, sv, _ = np.linalg.svd(b, full_matrices=False)
            keep = sv > tolerances.CONSTRAINT_RANK_RTOL * (sv[0] if sv.size else 0.0)
            rank = int(keep.sum())
            if check and rank:
                self.margin = min(self.margin, float(sv[rank - 1] / sv[0]))
            free = chol.solve(rhs)
            r = -gdot - g @ free
            coef = uu[:, keep].T @ r / sv[keep] ** 2
            lam = uu[:, keep] @ coef
            rhs = rhs + g.T @ lam
            if check and self.rank is not None and rank < self.rank:
                raise SingularPose(self.singular_message(t, uu[:, ~keep[:uu.shape[1]]]
                                                          if uu.shape[1] else uu))
        udot = chol.solve(rhs)
        kin = tr.with_accelerations(self.tree, kin0, udot) if full else kin0
        return Solution(udot, lam, rank, kin, rho_b, rho_a)

    def singular_message(self, t: float, directions: np.ndarray,
                          since: float | None = None) -> str:
        rows = np.abs(directions).max(axis=1) if directions.size else np.zeros(self.m)
        names, r = [], 0
        for p in self.tree.prims:
            if rows[r:r + p.rows].max(initial=0.0) > 0.1:
                name = self.scene.joints[self.tree.cut[p.joint]].name
                names.append(name) if name not in names else None
            r += p.rows
        for c in self.tree.couplings:
            if rows[r] > 0.1:
                names.append(c.name)
            r += 1
        named = ", ".join(names) or ", ".join(
            [*(self.scene.joints[k].name for k in self.tree.cut),
             *(c.name for c in self.tree.couplings)])
        when = f"t = {t:.6g} s" if since is None else f"between t = {since:.6g} and {t:.6g} s"
        return (f"{self.scene.source}: singular pose {when}: the loop closed by "
                f"joint(s) {named} lost a constraint direction there (the constraints no "
                "longer determine the motion beyond it: a change point, a dead point); stop "
                "before it or change the geometry")

    # --- projection -----------------------------------------------------------------------------
    def constraint(self, y: np.ndarray):
        """(Φ (m,), G (m, nv), M's `MassFactor`) at y."""
        q, u = y[:self.nq], y[self.nq:]
        kin = tr.kinematics(self.tree, q, u)
        phi, g, _, _, _ = terms(self.tree.prims, kin, tr.jacobians(self.tree, kin), self.nv,
                                self.tree.size, self.tree.couplings, q)
        return phi, g, MassFactor(tr.mass_matrix(self.tree, kin), self.blocks)

    def project(self, y: np.ndarray, fixed: tuple[set, set] = (set(), set()),
                iterations: int = 12) -> tuple[np.ndarray, float, float]:
        """y moved onto Φ = 0, Φ̇ = 0 (coordinates in ``fixed`` (q tangents, u) kept): the
        projected y and the sizes of the position and velocity corrections (max-norm)."""
        if not self.m:
            return y, 0.0, 0.0
        y = y.copy()
        tr.normalize(self.tree, y[:self.nq])
        size = self.tree.size
        atol = tolerances.PROJECTION_ATOL_ULPS * EPS * size
        moved_q = 0.0
        for _ in range(iterations):
            phi, g, chol = self.constraint(y)
            if np.abs(phi).max() <= atol:
                break
            delta = -_min_norm(g, chol, phi, fixed[0])
            moved_q += float(np.abs(delta).max())
            y[:self.nq] = tr.advance(self.tree, y[:self.nq], delta)
        else:
            phi, g, chol = self.constraint(y)
            if np.abs(phi).max() > 1e3 * atol:
                left = float(np.abs(phi).max())
                raise UnclosedLoop(f"{self.scene.source}: the joints cannot be closed at "
                                   f"t = {self.time:.6g} s (position residual {left:.3g} m "
                                   f"after {iterations} Newton steps): the loop cannot be "
                                   "assembled there", left)
        phi, g, chol = self.constraint(y)
        u = y[self.nq:]
        du = -_min_norm(g, chol, g @ u, fixed[1])
        y[self.nq:] = u + du
        return y, moved_q, float(np.abs(du).max()) if du.size else 0.0

    def residual(self, y: np.ndarray) -> tuple[float, float]:
        """Largest |Φ| (m) and |Φ̇| (m/s) at y."""
        if not self.m:
            return 0.0, 0.0
        phi, g, _ = self.constraint(y)
        return float(np.abs(phi).max()), float(np.abs(g @ y[self.nq:]).max())

    # --- energy -----------------------------------------------------------------------------------
    def energy(self, y: np.ndarray) -> float:
        """Kinetic + gravity + springs (bodies' and joints', tree and cut), J."""
        q, u = y[:self.nq], y[self.nq:]
        kin = tr.kinematics(self.tree, q, u)
        e = sum(0.5 * kin.V[i] @ kin.inertia[i] @ kin.V[i] for i in range(len(kin.com)))
        e -= float(np.sum(self.weights * (kin.com + kin.ref)))
        for s, (la, lb) in zip(self.scene.springs, self.spring_local):
            xa, _ = _point_state(kin, s.a, la)
            xb, _ = _point_state(kin, s.b, lb)
            d = xb - xa
            e += 0.5 * s.stiffness * (np.sqrt(d @ d) - s.rest_length) ** 2 if s.rest_length \
                else 0.5 * s.stiffness * (d @ d)
        for k in self.tree.loaded:
            j = self.tree.joints[k]
            sj = self.scene.joints[j.source]
            coord = (-1.0 if j.reversed else 1.0) * q[j.iq]
            e += 0.5 * sj.stiffness * (coord - sj.rest) ** 2
        return float(e + cutjoint.energy(self.tree, self.scene, kin))

    def conservative(self) -> bool:
        """Energy is conserved: no body forces or torques, no dampers, drag or drives."""
        if not self.cannot_gain_energy() or any(s.damping for s in self.scene.springs) \
                or any(d.linear or d.angular for d in self.scene.drags):
            return False
        return not any(j.damping for j in self.scene.joints)

    def cannot_gain_energy(self) -> bool:
        """No term does work on the system from outside: no body forces or torques, no drives
        (gravity, springs, dampers and drag only)."""
        return not (self.scene.forces or any(j.drive for j in self.scene.joints))


def _local(bodies, body: int, point: np.ndarray) -> np.ndarray:
    if body == WORLD:
        return np.asarray(point, float)
    b = bodies[body]
    return b.rotation0.T @ (point - b.com0)


def _point_state(kin: tr.Kinematics, body: int, local: np.ndarray):
    if body == WORLD:
        return local - kin.ref, np.zeros(3)
    x = kin.com[body] + kin.rotation[body] @ local
    return x, kin.V[body, 3:] + cross(kin.V[body, :3], x)


def subtrees(tree: Tree) -> list[np.ndarray]:
    """The rate indices of each subtree hanging from the world (tree joints, parents first): a
    joint's rate moves only its own subtree's bodies, so M is block diagonal over them."""
    root: dict[int, int] = {}
    groups: dict[int, list[int]] = {}
    for j in tree.joints:
        root[j.child] = j.child if j.parent == WORLD else root[j.parent]
        groups.setdefault(root[j.child], []).extend(range(j.iu, j.iu + j.nv))
    return [np.array(v, dtype=int) for v in groups.values() if v]


class MassFactor:
    """M = S Sᵀ, S the Cholesky factors of M's diagonal blocks (`subtrees`): a forest of n free
    bodies factors n 6 × 6 blocks, not one 6n × 6n matrix (300 free bodies: 0.5 s a sample in
    the outputs, dense). ``mass`` (nv, nv) kg, kg·m, kg·m² by coordinate."""

    def __init__(self, mass: np.ndarray, blocks: list[np.ndarray]) -> None:
        self.mass = mass
        self.blocks = [(idx, np.linalg.cholesky(mass[np.ix_(idx, idx)])) for idx in blocks]

    def lower(self, rhs: np.ndarray) -> np.ndarray:
        """S⁻¹ rhs (rhs (nv,) or (nv, k))."""
        out = np.zeros_like(rhs, dtype=float)
        for idx, low in self.blocks:
            out[idx] = np.linalg.solve(low, rhs[idx])
        return out

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """M⁻¹ rhs = S⁻ᵀ S⁻¹ rhs."""
        out = self.lower(rhs)
        for idx, low in self.blocks:
            out[idx] = np.linalg.solve(low.T, out[idx])
        return out


def _min_norm(g: np.ndarray, chol: MassFactor, residual: np.ndarray,
              fixed: set) -> np.ndarray:
    """The tangent δ of least kinetic-energy norm with G δ = residual, δ_i = 0 for i in
    ``fixed``: L⁻ᵀ (G L⁻ᵀ)⁺ residual on the free coordinates."""
    nv = g.shape[1]
    free = np.array([i for i in range(nv) if i not in fixed], dtype=int)
    out = np.zeros(nv)
    if free.size == 0:
        return out
    gf = g[:, free]
    cf = np.linalg.cholesky(chol.mass[np.ix_(free, free)])
    b = np.linalg.solve(cf, gf.T).T
    uu, sv, vt = np.linalg.svd(b, full_matrices=False)
    keep = sv > tolerances.CONSTRAINT_RANK_RTOL * (sv[0] if sv.size else 0.0)
    z = vt[keep].T @ ((uu[:, keep].T @ residual) / sv[keep])
    out[free] = np.linalg.solve(cf.T, z)
    return out


def spectral_radius(system, y: np.ndarray, t: float = 0.0) -> float:
    """ρ(∂ẏ/∂y) at (t, y), 1/s: the spectral radius of the right-hand side's Jacobian by forward
    differences: the n + 1 states evaluated in one call of the compiled outputs' entry (its
    RATES mode: the right-hand side the runs step), `stiffness.fastest_rate` at the start; the
    caller has that entry ready (`compiling.prepare`)."""
    n = y.size
    states = np.repeat(y[None, :], n + 1, axis=0)
    for j in range(n):
        states[j + 1, j] += math.sqrt(tolerances.EPS) * max(1.0, abs(y[j]))
    f = _rates(system, t, states)
    jac = (f[1:] - f[0]).T / (np.diagonal(states[1:]) - y)
    return float(np.abs(np.linalg.eigvals(jac)).max(initial=0.0))


def _rates(system, t: float, states: np.ndarray) -> np.ndarray:
    """ẏ (k, n) at the states (k, n), all at time t: the compiled right-hand side, and where it
    fails at a state (M not positive definite there, a rank drop) the numpy solve, which says
    what went wrong or gives the rates."""
    # deferred: numba's kernels, only where a rate is asked for (auto, an estimate, a failure)
    from massprops.dynamics.compiled.systems_kernel import evaluate_samples
    from massprops.dynamics.compiled.systems_outputs import RATES
    from massprops.dynamics.compiled.systems_step import OK

    out, start = np.empty_like(states), 0
    while start < len(states):
        istats = np.array([0, 0, 0, OK, 0, -1, -1], dtype=np.int64)
        rest = len(states) - start
        evaluate_samples(system.program, np.full(rest, float(t)), states[start:], out[start:],
                         istats, RATES)
        if istats[3] == OK:
            break
        k = start + int(istats[4])
        y = states[k]
        udot = system.solve(t, y, check=False, full=False).udot  # says what went wrong
        out[k] = np.concatenate([tr.qdot(system.tree, y[:system.nq], y[system.nq:]), udot])
        start = k + 1
    return out
