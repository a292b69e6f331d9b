"""The force program: a scene's force terms as a table that the compiled right-hand side walks.

Only the terms a scene has are in the table, so an absent term costs nothing: a scene with no
torque-producing term never runs torque code, and `ForceProgram.translation_closed_form` tells the
caller when the centre of mass needs no integration at all (every force constant in world).

State layout (what every integrator kernel steps):
    full (13):     y = [r (3) world m, v (3) world m/s, q (4) principal->world [w,x,y,z],
                        omega (3) principal frame rad/s]
    rotation (7):  y = [q (4), omega (3)]   when translation is closed form
Lever arms are precomputed in the principal frame (origin at the COM), body-frame vectors are
rotated into it once here, so the hot loop never touches the mesh frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from massprops.dynamics._elementwise import where
from massprops.dynamics.model import Drag, Gravity, PointForce, RigidBody, Scene, Spring, Torque

GRAVITY, FORCE_WORLD, FORCE_BODY, TORQUE_WORLD, TORQUE_BODY, SPRING, DRAG, JOINT = range(8)
NPAR = 10
"""Parameters per term (row of `ForceProgram.params`):
GRAVITY      [0:3] m·g (N, world)
FORCE_WORLD  [0:3] F (N, world)      [3:6] lever arm s' (m, principal)  [6] 1 if s' != 0
FORCE_BODY   [0:3] F' (N, principal) [3:6] s'                          [6] 1 if s' != 0
TORQUE_WORLD [0:3] τ (N·m, world)
TORQUE_BODY  [0:3] τ' (N·m, principal)
SPRING       [0:3] anchor (m, world) [3:6] s' [6] 1 if s' != 0 [7] k (N/m) [8] rest length (m)
             [9] damping c (N·s/m)
DRAG         [0] linear (N·s/m)  [1] angular (N·m·s)
JOINT        [0] 1 if the torque across the principal z axis is taken out (a hinge) [1] 1 if
             the program is a heavy symmetric top that `exact` solves (massprops.dynamics.joints)
"""


@dataclass(frozen=True, eq=False)
class ForceProgram:
    """A scene's forces, compiled. Arrays are what the numba kernels take.

    codes : (k,) int64 term codes; params : (k, NPAR) float64; windows : (k, 2) float64 [start, end)
    mass : kg; inertia : (3,) principal moments kg·m²
    has_torque : some term can produce a torque (else the rotation is torque-free)
    translation_closed_form : every force is constant in world (gravity, world-frame forces), so
        the COM moves in closed form, piecewise between window edges
    stiffest_rate : 1/s, the largest rate among spring/damper/drag terms (0 if none): the
        explicit-step limit is about 2.8 / stiffest_rate for RK4
    joints : for a body held by joints, the `massprops.dynamics.joints.reduction.JointModel`
        whose equivalent pinned body this program describes (None: a free body)
    """

    codes: np.ndarray
    params: np.ndarray
    windows: np.ndarray
    mass: float
    inertia: np.ndarray
    has_torque: bool
    translation_closed_form: bool
    stiffest_rate: float
    # a held body's `joints.reduction.JointModel` (not named here: that package imports this
    # one), else None
    joints: Any = None

    @property
    def exact_solvable(self) -> bool:
        """`exact` applies: torque-free with constant forces, or a held body whose motion the
        joints package has in closed form (the heavy symmetric top)."""
        if self.joints is not None and self.joints.closed_form:
            return True
        return not self.has_torque and self.translation_closed_form

    def active(self, t_mid: float) -> np.ndarray:
        """(k,) bool: which terms act on a segment containing ``t_mid`` (between window edges)."""
        return (self.windows[:, 0] <= t_mid) & (t_mid < self.windows[:, 1])

    def breakpoints(self, t0: float, t1: float) -> np.ndarray:
        """Sorted window edges strictly inside (t0, t1): where the right-hand side jumps."""
        edges = self.windows[np.isfinite(self.windows)]
        return np.unique(edges[(edges > t0) & (edges < t1)])

    def constant_force(self, active: np.ndarray) -> np.ndarray:
        """(3,) N, world: the total force while ``active`` (valid if translation_closed_form).
        Zero for a held body: its joint's reaction keeps the held point in place."""
        if self.joints is not None:
            return np.zeros(3)
        rows = active & ((self.codes == GRAVITY) | (self.codes == FORCE_WORLD))
        return self.params[rows, 0:3].sum(axis=0)


def _arm(body: RigidBody, point: np.ndarray | None) -> np.ndarray:
    """A body point (body coordinates, m) as a lever arm from the COM in the principal frame."""
    if point is None:
        return np.zeros(3)
    return body.principal_axes.T @ (np.asarray(point) - body.center_of_mass)


def compile_free_forces(scene: Scene) -> ForceProgram:
    """Turn the force terms of a scene's free body into a `ForceProgram` (one row per term, in
    scene order). Joints are not looked at: `massprops.dynamics.program.compile_forces` is the
    entry for any scene."""
    body = scene.body
    to_principal = body.principal_axes.T  # body -> principal
    i_min = float(body.principal_moments[0])
    rows, codes, windows = [], [], []
    has_torque, closed_form, rate = False, True, 0.0
    for term in scene.forces:
        p = np.zeros(NPAR)
        window = (-math.inf, math.inf)
        if isinstance(term, Gravity):
            code, p[0:3] = GRAVITY, body.mass * np.asarray(term.g)
        elif isinstance(term, PointForce):
            arm = _arm(body, term.point)
            code = FORCE_WORLD if term.frame == "world" else FORCE_BODY
            p[0:3] = term.vector if term.frame == "world" else to_principal @ term.vector
            p[3:6], p[6] = arm, float(np.any(arm != 0))
            has_torque |= bool(p[6])
            closed_form &= term.frame == "world"
            window = (term.start, term.end)
        elif isinstance(term, Torque):
            code = TORQUE_WORLD if term.frame == "world" else TORQUE_BODY
            p[0:3] = term.vector if term.frame == "world" else to_principal @ term.vector
            has_torque = True
            window = (term.start, term.end)
        elif isinstance(term, Spring):
            arm = _arm(body, term.point)
            code = SPRING
            p[0:3], p[3:6], p[6] = term.anchor, arm, float(np.any(arm != 0))
            p[7], p[8], p[9] = term.stiffness, term.rest_length, term.damping
            has_torque |= bool(p[6])
            closed_form = False
            lever2 = float(arm @ arm)
            rate = max(rate, math.sqrt(term.stiffness / body.mass),
                       math.sqrt(term.stiffness * lever2 / i_min), term.damping / body.mass,
                       term.damping * lever2 / i_min)
        elif isinstance(term, Drag):
            code, p[0], p[1] = DRAG, term.linear, term.angular
            has_torque |= term.angular != 0
            closed_form &= term.linear == 0
            rate = max(rate, term.linear / body.mass, term.angular / i_min)
        else:  # the scene parser only builds the kinds above
            raise TypeError(f"unknown force term {term!r}")
        rows.append(p)
        codes.append(code)
        windows.append(window)
    return ForceProgram(
        codes=np.array(codes, dtype=np.int64),
        params=np.array(rows, dtype=np.float64).reshape(-1, NPAR),
        windows=np.array(windows, dtype=np.float64).reshape(-1, 2),
        mass=body.mass, inertia=np.array(body.principal_moments, dtype=np.float64),
        has_torque=has_torque, translation_closed_form=closed_form, stiffest_rate=rate)


# --- the right-hand side: plain Python that compiled kernels compile where they call it ----------
# (massprops.dynamics.compiled.jit registers these three with numba; this module imports no numba)
def quat_matrix(q0, q1, q2, q3):
    """Rotation matrix entries (row-major 9-tuple) of the unit quaternion [q0, q1, q2, q3]."""
    return (1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2),
            2 * (q1 * q2 + q0 * q3), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 - q0 * q1),
            2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), 1 - 2 * (q1 * q1 + q2 * q2))


def force_torque(y, o, active, codes, params):
    """Total force (world, N) and torque (principal, N·m): a 6-tuple (fx, fy, fz, nx, ny, nz).

    y : state in either layout; o : offset of q in y (6 full, 0 rotation-only: then there is no
    r/v-dependent term, since springs and linear drag rule out the closed-form translation).
    active : (k,) bool. Reads y by index: slicing here cost ~100 ns per call in reference counts.
    Written in the elementwise style (massprops.dynamics._elementwise): compiled for one state
    per call inside the kernels, and with numpy for many states at once (y (ny, n): each entry
    an (n,) array; a returned component that no term touches stays the float 0.0), e.g. the
    loads behind a held body's reactions at every sample.
    """
    w = (y[o + 4], y[o + 5], y[o + 6])
    fx = fy = fz = nx = ny = nz = 0.0
    a = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    have_a = False
    for i in range(codes.shape[0]):
        if not active[i]:
            continue
        c = codes[i]
        p = params[i]
        if c == GRAVITY:
            fx += p[0]
            fy += p[1]
            fz += p[2]
            continue
        if c == JOINT:  # always the last row: the reaction cancels what the joint carries
            fx = fy = fz = 0.0
            if p[0] != 0.0:
                nx = ny = 0.0
            continue
        if c == DRAG:
            if o == 6:
                fx -= p[0] * y[3]
                fy -= p[0] * y[4]
                fz -= p[0] * y[5]
            nx -= p[1] * w[0]
            ny -= p[1] * w[1]
            nz -= p[1] * w[2]
            continue
        if c == TORQUE_BODY:
            nx += p[0]
            ny += p[1]
            nz += p[2]
            continue
        if not have_a:
            a = quat_matrix(y[o], y[o + 1], y[o + 2], y[o + 3])
            have_a = True
        if c == TORQUE_WORLD:  # n' = Aᵀ τ
            nx += a[0] * p[0] + a[3] * p[1] + a[6] * p[2]
            ny += a[1] * p[0] + a[4] * p[1] + a[7] * p[2]
            nz += a[2] * p[0] + a[5] * p[1] + a[8] * p[2]
            continue
        if c == FORCE_BODY:  # F' given; world F = A F'
            bx, by, bz = p[0], p[1], p[2]
            fx += a[0] * bx + a[1] * by + a[2] * bz
            fy += a[3] * bx + a[4] * by + a[5] * bz
            fz += a[6] * bx + a[7] * by + a[8] * bz
        elif c == FORCE_WORLD:
            fx += p[0]
            fy += p[1]
            fz += p[2]
            bx = a[0] * p[0] + a[3] * p[1] + a[6] * p[2]
            by = a[1] * p[0] + a[4] * p[1] + a[7] * p[2]
            bz = a[2] * p[0] + a[5] * p[1] + a[8] * p[2]
        else:  # SPRING: point p_w = r + A s', velocity v + A (w × s')
            sx, sy, sz = p[3], p[4], p[5]
            dx = y[0] + a[0] * sx + a[1] * sy + a[2] * sz - p[0]
            dy = y[1] + a[3] * sx + a[4] * sy + a[5] * sz - p[1]
            dz = y[2] + a[6] * sx + a[7] * sy + a[8] * sz - p[2]
            ux, uy, uz = w[1] * sz - w[2] * sy, w[2] * sx - w[0] * sz, w[0] * sy - w[1] * sx
            ddx = y[3] + a[0] * ux + a[1] * uy + a[2] * uz
            ddy = y[4] + a[3] * ux + a[4] * uy + a[5] * uz
            ddz = y[5] + a[6] * ux + a[7] * uy + a[8] * uz
            k, rest, damp = p[7], p[8], p[9]
            if rest == 0.0:
                sfx, sfy, sfz = -k * dx - damp * ddx, -k * dy - damp * ddy, -k * dz - damp * ddz
            else:
                length = np.sqrt(dx * dx + dy * dy + dz * dz)
                # at length 0 the direction is undefined and d = 0: dividing by 1 gives e = 0,
                # so the axial force, which has no line, is 0
                safe = where(length == 0.0, 1.0, length)
                ex, ey, ez = dx / safe, dy / safe, dz / safe
                mag = -k * (length - rest) - damp * (ex * ddx + ey * ddy + ez * ddz)
                sfx, sfy, sfz = mag * ex, mag * ey, mag * ez
            fx += sfx
            fy += sfy
            fz += sfz
            bx = a[0] * sfx + a[3] * sfy + a[6] * sfz
            by = a[1] * sfx + a[4] * sfy + a[7] * sfz
            bz = a[2] * sfx + a[5] * sfy + a[8] * sfz
        if p[6] != 0.0:  # moment s' × F' of a force applied off the COM
            sx, sy, sz = p[3], p[4], p[5]
            nx += sy * bz - sz * by
            ny += sz * bx - sx * bz
            nz += sx * by - sy * bx
    return fx, fy, fz, nx, ny, nz


def rhs(y, active, codes, params, mass, inertia, rot_only, ydot):
    """ẏ of the Newton-Euler equations for either state layout (see module doc); writes ``ydot``.

    m r̈ = f (world);  J' ω̇' + ω' × J' ω' = n' (principal, J' = diag(inertia));  q̇ = ½ q ⊗ (0, ω').
    """
    o = 0 if rot_only else 6
    if codes.shape[0]:
        fx, fy, fz, nx, ny, nz = force_torque(y, o, active, codes, params)
    else:
        fx = fy = fz = nx = ny = nz = 0.0
    if not rot_only:
        ydot[0], ydot[1], ydot[2] = y[3], y[4], y[5]
        ydot[3], ydot[4], ydot[5] = fx / mass, fy / mass, fz / mass
    q0, q1, q2, q3 = y[o], y[o + 1], y[o + 2], y[o + 3]
    w0, w1, w2 = y[o + 4], y[o + 5], y[o + 6]
    ydot[o] = -0.5 * (q1 * w0 + q2 * w1 + q3 * w2)
    ydot[o + 1] = 0.5 * (q0 * w0 + q2 * w2 - q3 * w1)
    ydot[o + 2] = 0.5 * (q0 * w1 + q3 * w0 - q1 * w2)
    ydot[o + 3] = 0.5 * (q0 * w2 + q1 * w1 - q2 * w0)
    i0, i1, i2 = inertia[0], inertia[1], inertia[2]
    ydot[o + 4] = (nx - (i2 - i1) * w1 * w2) / i0
    ydot[o + 5] = (ny - (i0 - i2) * w2 * w0) / i1
    ydot[o + 6] = (nz - (i1 - i0) * w0 * w1) / i2


def energy(states: np.ndarray, program: ForceProgram, active: np.ndarray | None = None
           ) -> np.ndarray:
    """Total mechanical energy (J) of full-layout states (n, 13): kinetic + gravity + springs.

    Only meaningful for conservative scenes (the caller decides); numpy, not a hot path. A
    diverging run's finite but huge states overflow to inf here (the caller reports divergence)
    rather than raising a RuntimeWarning.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        return _energy(states, program, active)


def _energy(states: np.ndarray, program: ForceProgram, active: np.ndarray | None) -> np.ndarray:
    s = np.atleast_2d(states)
    r, v, q, w = s[:, 0:3], s[:, 3:6], s[:, 6:10], s[:, 10:13]
    e = 0.5 * program.mass * np.einsum("ij,ij->i", v, v)
    e += 0.5 * np.einsum("ij,j,ij->i", w, program.inertia, w)
    act = np.ones(len(program.codes), bool) if active is None else active
    for c, p, on in zip(program.codes, program.params, act):
        if not on:
            continue
        if c == GRAVITY:
            e -= r @ p[0:3]
        elif c == SPRING:
            a = _matrices(q)
            d = r + np.einsum("nij,j->ni", a, p[3:6]) - p[0:3]
            length = np.sqrt(np.einsum("ij,ij->i", d, d))
            e += 0.5 * p[7] * (length - p[8]) ** 2
    return e


def _matrices(q: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices of (n, 4) unit quaternions [w, x, y, z]."""
    return np.stack(quat_matrix_np(q), axis=-1).reshape(-1, 3, 3)


def quat_matrix_np(q: np.ndarray) -> tuple[np.ndarray, ...]:
    """Vectorised `quat_matrix`: nine (n,) arrays, row-major."""
    return quat_matrix(q[:, 0], q[:, 1], q[:, 2], q[:, 3])
