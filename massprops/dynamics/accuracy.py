"""How far apart two runs are, in the contract's one-number metric, and the honest global error
estimate every `simulate` run reports.

The metric (CONTRACT, precision): the largest of position error / body size, orientation angle
error (rad), velocity error / velocity scale, angular-velocity error / angular-velocity scale,
taken over the sample times both runs have. Scales come from the reference run, with floors that
keep them meaningful for a body at rest: one body size per run duration for velocities, one
radian per run duration for angular velocities.

The estimate is global, not a local tolerance: a companion run of the same method at another
setting, compared in that metric.
- fixed step h, order p: companions step 2h and 4h (together 3/4 of the run's cost) and
  Richardson's rule with the observed ratio ρ = |y_2h - y_4h| / |y_h - y_2h| gives
  err(h) ≈ |y_h - y_2h| / (ρ - 1), ρ clipped to [2, 2^p]. In the asymptotic regime ρ = 2^p and
  this is the classical rule. Where the differences are not truncation error of order p (round-off
  amplified near a separatrix, an implicit method's Newton floor, order reduction on a stiff
  mode) ρ falls short of 2^p, and dividing by 2^p - 1 would understate the error up to 63-fold:
  the estimate grows towards |y_h - y_2h| itself, the size of such errors. Where the order
  itself can fall (Radau IIA on a stiff problem: to its stage order 3), ρ is clipped to 2^3
  even when the coarser pair showed more: the ratio shrinks as h does. A ratio beyond 2·2^p,
  or a 4h run that diverged, says the same from the other side (h is not in the asymptotic
  regime): the estimate is then |y_h - y_2h|;
- adaptive rtol: the companion runs at rtol / ADAPTIVE_TIGHTENING, whose error is ~20× smaller,
  so |y - y_tight| is the main run's error to ~5%;
- exact: no truncation; the bound is the round-off of evaluating the closed form,
  EXACT_ROUNDOFF · eps · (1 + |ω|max · t) in angle, plus eps in the position.

Companions can agree by chance where no run follows the motion, so a stepped run's estimate is
never below what its method does to the rotation it steps (`rotation_floor`): at |ω| h far
beyond a method's reach, each step of an explicit method multiplies a quaternion by its
stability polynomial R(i |ω| h / 2), dominated by its top term (rk4's (|ω| h / 2)⁴ / 24, real):
renormalised, the body does not turn at all, at h, 2h and 4h alike, while a torque about a
principal axis makes ω linear in t, which every Runge-Kutta method integrates exactly; the
three runs then agree to round-off (a torqued body over 1e12 s at rk4 steps of 1e9 s, turned
by 1.7e23 rad: estimate 1.5e-14).
"""

from __future__ import annotations

import cmath
import functools
import math
from dataclasses import dataclass

import numpy as np

from massprops.errors import setting_ref
from massprops.rotation import rotation_angle_between

ADAPTIVE_TIGHTENING = 20.0
"""rtol divisor of the adaptive companion run: ~1.45× its steps for DOP853 (steps ∝ rtol^-1/8)."""

EXACT_ROUNDOFF = 16.0
"""ulps of angle per radian turned that the closed form may lose (measured: ≤ 3 at |ω|t = 100
against a 40-digit reference; 16 leaves room for the elliptic arguments' rounding)."""


@dataclass(frozen=True)
class Scales:
    """size (m), velocity (m/s), angular velocity (rad/s) that make each error relative."""

    size: float
    velocity: float
    angular_velocity: float

    @classmethod
    def of(cls, size: float, traj, duration: float) -> Scales:
        with np.errstate(over="ignore"):  # a run-away trajectory: inf scales, errors then 0/inf
            w = float(np.max(np.linalg.norm(traj.angular_velocity, axis=1)))
            v = float(np.max(np.linalg.norm(traj.velocity, axis=1)))
        v_scale = max(v, size * w, size / duration)
        return cls(size, v_scale, max(w, 1.0 / duration))


def state_error(a, b, scales: Scales) -> float:
    """The contract's error between trajectories ``a`` and ``b`` at the times both have (inf when
    either ran away: huge finite states overflow to inf, not to a warning)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return _state_error(a, b, scales)


def _state_error(a, b, scales: Scales) -> float:
    common, ia, ib = np.intersect1d(a.t, b.t, return_indices=True)
    if common.size == 0:
        return float("inf")
    parts = [
        np.linalg.norm(a.position[ia] - b.position[ib], axis=1) / scales.size,
        rotation_angle_between(a.orientation[ia], b.orientation[ib]),
        np.linalg.norm(a.velocity[ia] - b.velocity[ib], axis=1) / scales.velocity,
        np.linalg.norm(a.angular_velocity[ia] - b.angular_velocity[ib], axis=1)
        / scales.angular_velocity,
    ]
    worst = max(float(np.max(p)) for p in parts)
    return worst if np.isfinite(worst) else float("inf")


UNRESOLVED_ESTIMATE = 0.1
"""An error estimate at or above this (the contract's metric: a tenth of the size, of a radian,
of the largest speed) says the run did not follow the motion: its numbers are not results, and
a warning says so (the fuzzers found exit-0 runs whose estimates were 2.6 to 21)."""


def estimate_note(source: str, estimate: float | None, method: str, kind: str) -> str | None:
    """The warning for a run whose error ``estimate`` is UNRESOLVED_ESTIMATE or more (None
    otherwise); ``kind``: the method's, which setting would help."""
    if estimate is None or not estimate >= UNRESOLVED_ESTIMATE:
        return None
    fix = (f"tighten {setting_ref('rtol')}" if kind == "adaptive"
           else f"shorten {setting_ref('step')}")
    return (f"{source}: the {method} run's error estimate is {estimate:.2g} (a fraction of the "
            f"size, of a radian, of the speeds): it did not follow the motion, its numbers are "
            f"not to be trusted; {fix}")


RESOLVES_NOTHING = math.pi
"""The estimate of a run whose steps turn a body beyond what its method follows: π, the largest
orientation error there is (the contract's metric), for an orientation that says nothing of
where the body is; above UNRESOLVED_ESTIMATE, so the run's warning says its numbers are not to
be trusted."""


def _stability(tableau: tuple, z: complex) -> complex:
    """R(z) = 1 + z bᵀ (I − z A)⁻¹ 1 of a Runge-Kutta step (A, b): the factor one step of
    length h applies to y' = λ y, z = h λ."""
    a, b = np.array(tableau[0], dtype=complex), np.array(tableau[1], dtype=complex)
    stages = np.linalg.solve(np.eye(len(b)) - z * a, np.ones(len(b)))
    return complex(1.0 + z * (b @ stages))


def turn_error(tableau: tuple, turn: float) -> float:
    """rad: the orientation error one step of method ``tableau`` makes on a body turning at a
    constant rate by ``turn`` rad per step. Its quaternion obeys q' = ½ q ⊗ (0, ω), whose pairs
    of components turn as y' = i (|ω| / 2) y: one step multiplies them by R(i turn / 2) where
    the truth is exp(i turn / 2), so, renormalised, the step turns the body by 2 arg R instead
    of ``turn``."""
    ratio = _stability(tableau, 0.5j * turn) * cmath.exp(-0.5j * turn)
    return 2.0 * abs(cmath.phase(ratio)) if ratio != 0 else math.pi


@functools.cache
def followed_turn(tableau: tuple) -> float:
    """rad: the turn per step from which method ``tableau`` no longer follows a rotation, the
    first turn where `turn_error` reaches a radian (found on a 2 % grid from 1e-3 rad: rk4 4.8,
    midpoint 4.3, Radau IIA 10, dop853 11). Up to it the per-step error grows steadily from 0;
    beyond it the phase the method gives a step is as good as any (it wraps round, and can be
    small again by chance)."""
    turn = 1e-3
    while turn < 1e3 and turn_error(tableau, turn) < 1.0:
        turn *= 1.02
    return turn


def rotation_floor(tableau: tuple | None, turn: float, steps: int) -> float:
    """The least error estimate (contract metric) of a run of ``steps`` steps of method
    ``tableau`` (None: a method that turns a body exactly, or takes no steps: 0) whose steps
    turn a body by ``turn`` rad on average: the steps' errors on that rotation alone,
    ``steps`` × `turn_error` (the smallest sum of the steps' errors for a given total turn,
    the error growing faster than the turn), at most RESOLVES_NOTHING, and that from
    `followed_turn` on: such a run resolves nothing, whatever its companions say."""
    if tableau is None or steps <= 0 or not turn > 0.0:
        return 0.0
    if not turn < followed_turn(tableau):
        return RESOLVES_NOTHING
    return min(RESOLVES_NOTHING, steps * turn_error(tableau, turn))


def companion_settings(kind: str, setting: float) -> tuple[float, ...]:
    """Settings of the companion runs behind a run's error estimate: (2h, 4h) for a fixed step
    h, (rtol / ADAPTIVE_TIGHTENING,) for an adaptive rtol, () for a closed form."""
    if kind == "fixed":
        return 2.0 * setting, 4.0 * setting
    if kind == "adaptive":
        return (setting / ADAPTIVE_TIGHTENING,)
    return ()


def global_estimate(kind: str, order: int, d_run: float, d_companions: float | None,
                    assumed_order: int | None = None) -> float:
    """The error estimate of a run from the distances (contract metric) between the run and its
    first companion (``d_run``) and between the first and the second companion
    (``d_companions``; None when there is none or it diverged). See the module doc.
    ``assumed_order`` (default ``order``): the highest order the rule may credit the run with,
    lower for a method whose order can fall on stiff problems (IntegratorSpec.estimate_order);
    the non-asymptotic test still uses the classical ``order``."""
    if kind != "fixed":
        return d_run
    asymptotic = 2.0**order
    if d_companions is None or not d_companions < math.inf:
        return d_run
    if d_run == 0.0:
        return 0.0
    ratio = d_companions / d_run
    if ratio > 2.0 * asymptotic:
        return d_run
    credited = 2.0 ** (assumed_order or order)
    return d_run / (min(max(ratio, 2.0), credited) - 1.0)


def exact_roundoff(traj, scales: Scales) -> float:
    """Round-off bound of the closed-form solution over ``traj`` (see the module doc)."""
    eps = float(np.finfo(float).eps)
    with np.errstate(over="ignore"):
        turned = float(np.max(np.linalg.norm(traj.angular_velocity, axis=1))) * float(traj.t[-1])
        reach = float(np.max(np.linalg.norm(traj.position, axis=1))) / scales.size
    return EXACT_ROUNDOFF * eps * (1.0 + turned) + 4 * eps * (1.0 + reach)

