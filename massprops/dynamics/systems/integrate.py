"""DOP853 for systems, with a projection after every step and 7th-order dense output.

The registry's kernels cannot take a system (see DESIGN.md, "Systems of bodies"): they are
compiled around the one-body state y = [r, v, q, ω] (13 or 7 entries, a quaternion at a fixed
offset, error blocks by that layout) and call ``forces.rhs`` with the force table. This is the
same method (the project's own tableau, dop853.f's error norm and step control) over
y = [q, u] of any length, in numpy: after each accepted step the quaternion coordinates are
renormalised and (q, u) projected onto Φ = 0, Φ̇ = 0 (System.project); the dense output of a
step is built from its start and its projected end, and each sample is projected in turn.
The error scale of component i is rtol × max(running max |y_i|, floor_i).
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.integrators._dop853_tableau import BHH, ER, A, B, C, D
from massprops.dynamics.systems import tree as tr

E3 = B - BHH
SAFE, FAC_MIN, FAC_MAX = 0.9, 1.0 / 3.0, 6.0
MAX_STEPS = 2_000_000


class Run:
    """Samples ``y_out`` (n_out, ny) at ``t_out``, steps, evaluations, rejected steps, the
    largest projection corrections (position tangent, velocity) and the failure (None)."""

    def __init__(self, n_out: int, ny: int) -> None:
        self.y_out = np.full((n_out, ny), np.nan)
        self.steps = self.nfev = self.rejected = 0
        self.moved_q = self.moved_u = 0.0
        self.failure: BaseException | None = None
        self.t_reached = 0.0


def integrate(system, y0: np.ndarray, t_out: np.ndarray, rtol: float, floors: np.ndarray,
              windows: np.ndarray, max_steps: int = MAX_STEPS) -> Run:
    """Integrate from t = 0 over [0, t_out[-1]], stepping onto each window edge in ``windows``
    (sorted times where the loads jump). A SingularPose or a non-finite state stops the run:
    ``Run.failure`` holds it and the samples before it are kept."""
    run = Run(len(t_out), y0.size)
    edges = [0.0, *[w for w in windows if 0 < w < t_out[-1]], float(t_out[-1])]
    y = y0.copy()
    scales = np.maximum(np.abs(y), floors)
    kout = 0
    while kout < len(t_out) and t_out[kout] <= 0.0:
        run.y_out[kout] = y
        kout += 1
    try:
        for t0, t1 in zip(edges[:-1], edges[1:]):
            y, kout = _segment(system, y, t0, t1, rtol, scales, floors, t_out, kout, run,
                               max_steps)
            run.t_reached = t1
    except (ArithmeticError, np.linalg.LinAlgError) as exc:
        run.failure = exc
    return run


def _segment(system, y, t0, t1, rtol, scales, floors, t_out, kout, run, max_steps):
    nq = system.nq
    n = y.size
    k = np.empty((16, n))
    k[0] = system.rhs(t0, y)
    run.nfev += 1
    system.accept(t0, t0)
    h = _initial_step(system, y, k[0], t0, rtol, t1 - t0, scales)
    run.nfev += 1
    t, rejected = t0, False
    while t < t1:
        last = t + 1.01 * h >= t1
        if last:
            h = t1 - t
        if h <= 1e-14 * max(abs(t), t1):
            raise ArithmeticError(f"step size underflow at t = {t:.6g} s")
        if run.steps >= max_steps:
            raise ArithmeticError(f"step limit {max_steps} reached at t = {t:.6g} s")
        for s in range(1, 12):
            k[s] = system.rhs(t + h * _C[s], y + h * (A[s, :s] @ k[:s]))
        run.nfev += 11
        ynew = y + h * (B @ k[:12])
        sk = rtol * np.maximum(scales, np.abs(ynew))
        e5 = ER[:12] @ k[:12] / sk
        e3 = E3 @ k[:12] / sk
        err5, err3 = float(e5 @ e5), float(e3 @ e3)
        deno = err5 + 0.01 * err3 or 1.0
        err = abs(h) * err5 / math.sqrt(n * deno)
        if not math.isfinite(err):
            err = math.inf
        if err <= 1.0:
            t_new = t1 if last else t + h
            yproj, dq, du = system.project(ynew)
            tr.normalize(system.tree, yproj[:nq])
            run.moved_q, run.moved_u = max(run.moved_q, dq), max(run.moved_u, du)
            k[12] = system.rhs(t_new, yproj)
            run.nfev += 1
            system.accept(t, t_new)  # raises at a singular pose crossed inside the step
            if kout < len(t_out) and t_out[kout] <= t_new:
                for s in range(13, 16):
                    k[s] = system.rhs(t + h * _C[s], y + h * (A[s, :s] @ k[:s]))
                run.nfev += 3
                cont = _dense(y, yproj, h, k)
                while kout < len(t_out) and t_out[kout] <= t_new:
                    sample = _dense_row(cont, (t_out[kout] - t) / h)
                    sample, _, _ = system.project(sample)
                    run.y_out[kout] = sample
                    kout += 1
            y = yproj
            k[0] = k[12]
            scales = np.maximum(scales, np.abs(y))
            t = t_new
            run.steps += 1
            fac = max(1.0 / FAC_MAX, min(1.0 / FAC_MIN, err ** 0.125 / SAFE))
            h_next = min(h / fac, t1 - t0)
            h = min(h_next, h) if rejected else h_next
            rejected = False
        else:
            h = h / min(1.0 / FAC_MIN, err ** 0.125 / SAFE)
            rejected = True
            run.rejected += 1
    return y, kout


def _initial_step(system, y, f0, t0, rtol, hmax, scales):
    sk = rtol * scales
    dnf = float(np.sum((f0 / sk) ** 2))
    dny = float(np.sum((y / sk) ** 2))
    h = 1e-6 if (dnf <= 1e-10 or dny <= 1e-10) else 0.01 * math.sqrt(dny / dnf)
    h = min(h, hmax)
    f1 = system.rhs(t0 + h, y + h * f0)
    der2 = math.sqrt(float(np.sum(((f1 - f0) / sk) ** 2))) / h
    der12 = max(der2, math.sqrt(dnf))
    h1 = max(1e-6, h * 1e-3) if der12 <= 1e-15 else (0.01 / der12) ** (1.0 / 8.0)
    return min(100.0 * h, h1, hmax)


def _dense(y, ynew, h, k):
    ydiff = ynew - y
    bspl = h * k[0] - ydiff
    cont = np.empty((8, y.size))
    cont[0], cont[1], cont[2] = y, ydiff, bspl
    cont[3] = ydiff - h * k[12] - bspl
    cont[4:8] = h * (D[:4, :16] @ k[:16])
    return cont


def _dense_row(cont, s):
    s1 = 1.0 - s
    par = cont[4] + s * (cont[5] + s1 * (cont[6] + s * cont[7]))
    return cont[0] + s * (cont[1] + s1 * (cont[2] + s * (cont[3] + s1 * par)))


_C = np.asarray(C, dtype=float)
"""The stages' times as fractions of the step."""
