"""One run of a one-body kernel (the splitting methods and the closed form, `integrators`) at one
setting: the segments between force-window edges, walked in chunks (Ctrl-C and the progress bar
are served between them), dense samples, failures. The time-stepping methods run on the systems
engine (`simulate`, `systems.run`).

The translation of the centre of mass is closed form when every force is constant in world
(ForceProgram.translation_closed_form): only [q_p, omega'] is then integrated.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

import numpy as np

from massprops.dynamics import budget
from massprops.dynamics.forces import ForceProgram
from massprops.dynamics.model import Scene
from massprops.dynamics.program import initial_principal_state
from massprops.errors import ComputationError, setting_ref
from massprops.tolerances import QUATERNION_NORM_ATOL

CHUNK_STEPS = 50_000
"""Steps per compiled call (~0.05 s): between calls Ctrl-C and the progress bar are served.
Chunks are sized by step counts, never by timers, so results do not depend on the machine."""


@dataclass(frozen=True)
class Failure:
    """Why a run ended short of its end: ``method`` ``verb`` ("diverged" or "stopped") at ``t``
    (s) because ``what``; ``advice`` says what to change. ``str()`` is the sentence."""

    method: str
    verb: str
    t: float
    what: str
    advice: str

    def __str__(self) -> str:
        return f"{self.method} {self.verb} at t = {self.t:.6g} s: {self.what}; {self.advice}"


@dataclass(frozen=True, eq=False)
class RawRun:
    """One integration in the principal frame: samples t (n,), y (n, 13) up to where it got
    (every row finite, its quaternion a rotation: see `run_once`), stats [steps, nfev, rejected,
    njev, status], wall and warm-up seconds, failure message, and short_err: the kernels' own
    local error estimates (absolute, max-norm over the state) summed over the fixed-step
    segments of one or two steps, which a 2h companion run cannot see. ``exhausted``: the
    failure is the run bound (massprops.dynamics.budget), not a divergence."""

    t: np.ndarray
    y: np.ndarray
    stats: np.ndarray
    wall: float
    warmup: float
    failure: Failure | None
    interrupted: bool
    short_err: float = 0.0
    exhausted: bool = False


def run_once(scene: Scene, program: ForceProgram, spec, setting: float, t_out: np.ndarray,
             progress: Callable[[float], None] | None = None,
             max_steps: int | None = None) -> RawRun:
    """Integrate ``scene`` once with ``spec`` at ``setting``, sampled at ``t_out``; a run that
    reaches ``max_steps`` (default budget.MAX_STEPS) stops there (``exhausted``)."""
    runner = _Runner(spec, program, setting, progress, scene.time.duration)
    runner.max_steps = max_steps
    y_out, t_reached, interrupted = runner.run(initial_principal_state(scene), t_out)
    keep = t_out <= t_reached
    t_kept, y_kept = t_out[keep], y_out[keep]
    if t_kept[-1] < t_reached:  # interrupted or failed between samples: keep the last state
        last = cast(np.ndarray, runner.y_last)  # set by every segment the run began
        t_kept, y_kept = np.append(t_kept, t_reached), np.vstack([y_kept, last])
    failure = runner.failure
    bad = unusable_rows(y_kept)
    if bad.any():  # no kernel should let one through; never hand it on as a state
        first = int(np.argmax(bad))
        if first == 0:
            raise ComputationError(f"{spec.name}: the initial state is not finite: {y_kept[0]}")
        failure = failure or Failure(spec.name, "diverged", float(t_kept[first]),
                                     "the state became NaN, infinite or no rotation",
                                     stability_hint(program, setting, spec.name))
        t_kept, y_kept = t_kept[:first], y_kept[:first]
    return RawRun(t_kept, y_kept, runner.stats, runner.wall, runner.warmup, failure,
                  interrupted, runner.short_err, runner.exhausted)


def unusable_rows(y: np.ndarray) -> np.ndarray:
    """(n,) bool: rows of principal-frame states (n, 13) that are not finite or whose quaternion
    is no rotation (norm far from 1)."""
    with np.errstate(over="ignore", invalid="ignore"):
        norm = np.sqrt(np.sum(y[:, 6:10] ** 2, axis=1))
        return ~np.isfinite(y).all(axis=1) | ~(np.abs(norm - 1.0) <= QUATERNION_NORM_ATOL)


def stability_hint(program: ForceProgram, setting: float, name: str) -> str:
    """The likely cause of a divergence of ``name`` at step/rtol ``setting``: the step against
    the scene's stiffest rate."""
    rate = program.stiffest_rate
    if rate > 0:
        return (f"the stiffest term has rate {rate:.3g}/s, so explicit steps must stay below "
                f"~{2.8 / rate:.3g} s (step here: {setting:.3g}); use integrator implicit or a "
                "smaller step")
    return "try a smaller step or tolerance"


def budget_advice(program: ForceProgram) -> str:
    """What to change when a fixed-step run needs more steps than the run bound."""
    advice = f"raise {setting_ref('time.step')} or shorten time.duration"
    if program.stiffest_rate > 0:
        advice += (f"; the stiffest term has rate {program.stiffest_rate:.3g}/s: integrator "
                   "implicit steps over it")
    if not program.has_torque and program.translation_closed_form:
        advice += "; the scene is torque-free: integrator exact takes no steps"
    return advice


class _Runner:
    """Walks the segments between window edges in chunks, filling the samples."""

    def __init__(self, spec, program: ForceProgram, setting: float, progress, duration: float):
        self.spec, self.program, self.setting = spec, program, setting
        self.progress, self.duration = progress, duration
        self.stats = np.zeros(5, dtype=np.int64)
        self.wall, self.warmup = 0.0, 0.0
        self.failure: Failure | None = None
        self.exhausted = False
        self.max_steps: int | None = None
        self.y_last = None
        self.t_now = 0.0
        self.short_err = 0.0

    def run(self, y0: np.ndarray, t_out: np.ndarray):
        p = self.program
        rot_only = p.translation_closed_form
        y_full = y0.copy()
        y_out = np.full((len(t_out), 13), np.nan)
        edges = np.concatenate([[0.0], p.breakpoints(0.0, self.duration), [self.duration]])
        self._warm_up(y0, rot_only)
        start = time.perf_counter()
        self.t_now, interrupted = 0.0, False
        try:
            for t0, t1 in zip(edges[:-1], edges[1:]):
                active = p.active(0.5 * (t0 + t1))
                self._segment(y_full, t0, t1, active, rot_only, t_out, y_out)
                if self.failure is not None:
                    break
        except KeyboardInterrupt:  # y_full and self.t_now hold the last finished chunk
            interrupted = True
        self.wall = time.perf_counter() - start
        self.y_last = y_full
        return y_out, self.t_now, interrupted

    def _warm_up(self, y0: np.ndarray, rot_only: bool) -> None:
        """Compile or load the kernel from cache on a tiny problem; timed apart from the run."""
        p = self.program
        start = time.perf_counter()
        y = (y0[6:] if rot_only else y0).copy()
        self.spec.run_segment(y, 0.0, 1e-9, self.setting if self.setting else 1e-9,
                              (p.active(0.0), p.codes, p.params, p.mass, p.inertia), rot_only,
                              np.empty(0), np.empty((0, y.size)), np.zeros(5, dtype=np.int64))
        self.warmup = time.perf_counter() - start

    def _segment(self, y_full, t0, t1, active, rot_only, t_out, y_out) -> None:
        """Advance y_full (13,) from t0 to t1 in chunks and fill the samples; self.t_now follows
        the time reached after every chunk (so Ctrl-C keeps it)."""
        p = self.program
        first = t0 == 0.0
        sel = np.flatnonzero((t_out >= t0) & (t_out <= t1) if first else
                             (t_out > t0) & (t_out <= t1))
        accel = cast(np.ndarray, p.constant_force(active) / p.mass if rot_only else None)
        # a segment of one or two steps (a force window shorter than the step) is stepped the
        # same way by a 2h companion, so its error is invisible to Richardson: keep the kernel's
        # own local estimate of it
        short = self.spec.kind == "fixed" and (t1 - t0) <= 2 * self.setting * (1 + 1e-12)
        t = t0
        length = CHUNK_STEPS * self.setting
        while t < t1:
            t_end = self._chunk_end(t, t0, t1, length)
            idx = sel[(t_out[sel] >= t) & (t_out[sel] <= t_end)] if t == t0 else \
                sel[(t_out[sel] > t) & (t_out[sel] <= t_end)]
            y = y_full[6:].copy() if rot_only else y_full.copy()
            ys = np.empty((idx.size, y.size))
            arrays = (active, p.codes, p.params, p.mass, p.inertia)
            err, t_reached = self.spec.run_segment(y, t, t_end, self.setting, arrays, rot_only,
                                                   t_out[idx], ys, self.stats)
            if rot_only:
                r0, v0 = y_full[0:3].copy(), y_full[3:6].copy()
                tau = t_out[idx] - t
                ys = np.hstack([r0 + np.outer(tau, v0) + 0.5 * np.outer(tau**2, accel),
                                v0 + np.outer(tau, accel), ys])
                dt = t_reached - t
                y_full[0:3] = r0 + v0 * dt + 0.5 * accel * dt * dt
                y_full[3:6] = v0 + accel * dt
                y_full[6:] = y
            else:
                y_full[:] = y
            good = t_out[idx] <= t_reached
            y_out[idx[good]] = ys[good]
            self.t_now = t_reached
            if short:
                self.short_err += err
            if self.stats[4] != 0 or t_reached < t_end:  # NaN, or stopped early
                self.failure = self._failure_message(t_reached)
                return
            why = budget.exhausted(int(self.stats[0]), t_end / self.duration, self.max_steps)
            if why is not None:
                self.failure = Failure(self.spec.name, "stopped", t_end, why,
                                       budget_advice(self.program))
                self.exhausted = True
                return
            if self.progress is not None:
                self.progress(t_end / self.duration)
            t = t_end

    def _chunk_end(self, t: float, t0: float, t1: float, length: float) -> float:
        """End of the next call: t + length on the segment's step grid; the closed form takes
        the whole segment (no steps: one evaluation per sample, its cost independent of t)."""
        if self.spec.kind == "exact":
            return t1
        n = max(1, math.ceil((t1 - t0) / self.setting * (1 - 1e-12)))
        h = (t1 - t0) / n
        k = round((t - t0) / h) + max(1, round(length / h))
        return t1 if k >= n else t0 + k * h

    def _failure_message(self, t_reached: float) -> Failure:
        status = int(self.stats[4])
        what = "the state became NaN or infinite" if status == 1 else \
            "the integrator stopped early"
        return Failure(self.spec.name, "diverged", t_reached, what,
                       stability_hint(self.program, self.setting, self.spec.name))
