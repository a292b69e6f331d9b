"""A massprops scene as scipy's solve_ivp sees it: the peer every benchmark against scipy shares.

`numpy_rhs` turns a scene's force terms into the plain-numpy right-hand side of ``_scipy_rhs``
(state [r, v, q, omega'] in the principal frame, like massprops' kernels), constant parts summed
once, nothing interpreted per call; `solve` integrates a scene with solve_ivp. scipy's
integrators know nothing of the unit quaternion, so NOTHING renormalises q during a scipy run
(|q| drifts with the truncation error); states are normalised only when turned into the
contract's frames (frames.to_world), exactly as massprops' own samples are. Force windows
(start/end) split the run into segments, each integrated by its own solve_ivp call, as massprops
splits its runs.

`check_same_equations` compares this model with massprops' compiled right-hand side before any
timing, so a benchmark can never compare two different problems.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from _scipy_rhs import NumpyRhs, cross
from scipy.integrate import solve_ivp

from massprops.dynamics.forces import rhs
from massprops.dynamics.model import Drag, Gravity, PointForce, Scene, Spring, Torque
from massprops.dynamics.program import compile_forces, initial_principal_state

SCIPY_MIN_RTOL = 100 * np.finfo(float).eps
"""solve_ivp raises rtol below this to this (with a warning): ladders stop here."""


class BudgetExceeded(Exception):
    """A scipy run used more right-hand-side evaluations than its budget."""


def _acts(term, t_mid: float) -> bool:
    return getattr(term, "start", -np.inf) <= t_mid < getattr(term, "end", np.inf)


def _arm(body, point) -> np.ndarray:
    """Lever arm (3,) m from the COM, principal frame, of a body point (None: the COM)."""
    if point is None:
        return np.zeros(3)
    return body.principal_axes.T @ (np.asarray(point, dtype=float) - body.center_of_mass)


def numpy_rhs(scene: Scene, t_mid: float = 0.0) -> NumpyRhs:
    """The right-hand side of ``scene`` on a segment where the terms acting at ``t_mid`` act (no
    window edge inside); body-frame inputs are rotated to the principal frame once, here."""
    body = scene.body
    to_p = body.principal_axes.T  # body -> principal
    force, torque, torque_world, body_force = (np.zeros(3) for _ in range(4))
    world_forces, world_arms, springs = [], [], []
    drag_linear = drag_angular = 0.0
    for term in scene.forces:
        if not _acts(term, t_mid):
            continue
        if isinstance(term, Gravity):
            force += body.mass * np.asarray(term.g)
        elif isinstance(term, Torque) and term.frame == "body":
            torque += to_p @ term.vector
        elif isinstance(term, Torque):
            torque_world += term.vector
        elif isinstance(term, PointForce) and term.frame == "body":
            f_p = to_p @ term.vector  # constant in the body: its moment is constant too
            body_force += f_p
            torque += cross(_arm(body, term.point), f_p)
        elif isinstance(term, PointForce):
            force += term.vector
            arm = _arm(body, term.point)
            if np.any(arm):
                world_forces.append(term.vector)
                world_arms.append(arm)
        elif isinstance(term, Spring):
            springs.append((term.anchor, _arm(body, term.point), term.stiffness,
                            term.rest_length, term.damping))
        elif isinstance(term, Drag):
            drag_linear += term.linear
            drag_angular += term.angular
    return NumpyRhs(body.mass, body.principal_moments, force, torque, torque_world, body_force,
                    world_forces, world_arms, springs, drag_linear, drag_angular)


def check_same_equations(scene: Scene, samples: int = 5) -> None:
    """Raise SystemExit unless `numpy_rhs` and massprops' compiled rhs agree to 1e-12 at random
    states, on every segment between force-window edges."""
    p = compile_forces(scene)
    edges = np.concatenate([[0.0], p.breakpoints(0.0, scene.time.duration),
                            [scene.time.duration]])
    rng = np.random.default_rng(0)
    out = np.empty(13)
    for t_mid in 0.5 * (edges[:-1] + edges[1:]):
        model = numpy_rhs(scene, t_mid)
        for _ in range(samples):
            y = rng.normal(size=13)
            y[6:10] /= np.linalg.norm(y[6:10])
            rhs(y, p.active(t_mid), p.codes, p.params, p.mass, p.inertia, False, out)
            ours = model(t_mid, y)
            if not np.allclose(out, ours, rtol=1e-12, atol=1e-12 * np.abs(out).max()):
                raise SystemExit(f"{scene.source}: the numpy right-hand side differs from the "
                                 f"compiled one by {np.abs(out - ours).max():.3g}")


@dataclass(frozen=True)
class ScipyRun:
    """One solve_ivp run of a scene: t (n,) s, y (n, 13) principal-frame states at the asked
    times (by scipy's dense output), nfev summed over segments, wall s of the solve_ivp calls
    only, and status: "ok", "budget" (stopped at the evaluation budget) or scipy's message."""

    t: np.ndarray
    y: np.ndarray
    nfev: int
    wall: float
    status: str


def block_atol(rtol: float, scales: np.ndarray) -> np.ndarray:
    """(13,) atol: rtol × each block's scale (r, v, q, omega'), massprops' per-block rule."""
    return rtol * np.repeat(scales, [3, 3, 4, 3])


def block_scales(scene, truth) -> np.ndarray:
    """(4,) largest |component| of r, v, q, omega' blocks along the reference, with floors (one
    body size, one size per run, one radian per run) for a block that stays near zero."""
    duration, size = scene.time.duration, scene.body.size
    w_p = truth.angular_velocity_body @ scene.body.principal_axes  # omega' = Rᵀ omega_body
    return np.array([max(np.abs(truth.position).max(), size),
                     max(np.abs(truth.velocity).max(), size / duration), 1.0,
                     max(np.abs(w_p).max(), 1.0 / duration)])


def solve(scene: Scene, method: str, rtol: float, t_out: np.ndarray, scales: np.ndarray,
          max_nfev: int | None = None) -> ScipyRun:
    """Integrate ``scene`` with solve_ivp(method) at ``rtol`` and atol = `block_atol`, sampled
    at ``t_out`` (sorted, within [0, duration]).

    scales : (4,) the r, v, q, omega' block scales (m, m/s, 1, rad/s).
    max_nfev : stop (status "budget") once a run has used this many evaluations.
    """
    duration = scene.time.duration
    edges = np.concatenate([[0.0], compile_forces(scene).breakpoints(0.0, duration),
                            [duration]])
    y = initial_principal_state(scene)
    ts, ys, nfev, wall = [], [], 0, 0.0
    for t0, t1 in zip(edges[:-1], edges[1:]):
        model = numpy_rhs(scene, 0.5 * (t0 + t1))
        fun = model if max_nfev is None else _budgeted(model, max_nfev - nfev)
        inside = (t_out >= t0) & (t_out <= t1) if t0 == 0.0 else (t_out > t0) & (t_out <= t1)
        t_eval = np.union1d(t_out[inside], [t1])  # t1 too: the next segment starts there
        start = time.perf_counter()
        try:
            sol = solve_ivp(fun, (t0, t1), y, method=method, rtol=rtol,
                            atol=block_atol(rtol, scales), t_eval=t_eval)
        except BudgetExceeded:
            wall += time.perf_counter() - start
            return ScipyRun(np.array(ts), np.zeros((0, 13)), max_nfev, wall, "budget")
        wall += time.perf_counter() - start
        nfev += sol.nfev
        if sol.status != 0:
            return ScipyRun(np.array(ts), np.zeros((0, 13)), nfev, wall, str(sol.message))
        keep = np.isin(sol.t, t_out[inside])
        ts.extend(sol.t[keep])
        ys.extend(sol.y.T[keep])
        y = sol.y[:, -1]
    return ScipyRun(np.array(ts), np.array(ys).reshape(-1, 13), nfev, wall, "ok")


def _budgeted(model: NumpyRhs, budget: int):
    """``model`` that raises BudgetExceeded on its (budget + 1)-th call."""
    calls = 0

    def fun(t, y):
        nonlocal calls
        calls += 1
        if calls > budget:
            raise BudgetExceeded
        return model(t, y)

    return fun
