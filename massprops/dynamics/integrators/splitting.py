"""Splitting integrators: exact free rotations (drifts) and force kicks, composed to order 2, 4, 6.

The Newton-Euler field is split as ẏ = D(y) + K(y) (sub-flows in `_subflows`):
- drift D, no force and no torque: the centre of mass coasts, r += τ v, and (q, ω') move as the
  free rigid body, evaluated in closed form by `massprops.dynamics.exact.free_rotation_kernel`
  (Jacobi elliptic functions; regular precession for a symmetric body). EXACT up to round-off
  for any τ and any spin rate: a needle or a disk spinning at 1e3 rad/s costs no step limit.
- kick K, forces and torques with the configuration (r, q) frozen: m v̇ = f, J' ω̇' = n' (the
  gyroscopic term ω' × J'ω' belongs to the drift). Terms that depend on (r, q) only (gravity,
  given forces and torques, the springs' elastic force) are then constant, so v += τ f/m,
  ω' += τ n'/J' (i.e. Π' = J'ω' += τ n') is their EXACT flow. Velocity-dependent terms (drag,
  spring damping) make the kick the linear ODE M ż = F_c + B z in z = (v, ω'), B constant while
  (r, q) are frozen; it is NOT solved exactly but by one implicit-midpoint step,
  (M - τB/2) Δz = τ (F_c + B z0), in closed form (one 6x6 solve): symmetric, second order, and
  never amplifying for τ > 0 however strong the damping. B comes from the damping terms alone,
  whose force is exactly linear in z, so it carries no finite-difference error.

Base step, Strang (order 2, symmetric): Φ_h = K(h/2) ∘ D(h) ∘ K(h/2). Higher orders compose it,
Ψ_h = Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h}, with palindromic γ (Σγ = 1): this keeps Ψ symmetric and raises
the order of any symmetric second-order base method (Hairer, Lubich & Wanner, Geometric Numerical
Integration, §V.3). Adjacent half kicks at one configuration merge into one force evaluation when
the kicks are exact (no damping active); with damping they stay two implicit-midpoint steps, as
merging them would break the composition's order conditions. The truncation error O(h^p) comes
from the non-commuting D and K (and from the damped kick); there is no other approximation.

Consequences: with no active force term a step is ONE drift (a composition of exact flows of one
field is that flow), so |H| in world, the kinetic energy and |q| = 1 hold to round-off whatever h.
With conservative forces every sub-flow is an exact Hamiltonian flow: the method is symplectic,
the energy error stays bounded with no secular drift. The stability limit comes from the kicks
alone: h·sqrt(k/m) < 2 for a spring, as for Störmer-Verlet. splitting4 and splitting6 have
negative γ, so they run damped kicks backward: keep h × (damping rate) well below 1 with them (a
backward implicit-midpoint step has a pole at |τ| × rate = 2; status 1 if it is hit); Strang's
damped kicks never amplify, however strong the damping.

Dense output: a partial step of length t_out - t_a from the step start t_a with the same scheme
(full order, exact for a free body, quaternion unit by construction), not a cubic Hermite: at
|ω| h ~ 1 rad per step, the regime these methods are for, a cubic through the step ends of q
is off by about (|ω| h)^4 / 6000 (2e-4 at 1 rad per step), far above the steps' own accuracy.
Costs one step per output time.
Error estimate: the last step is redone as two half steps; their difference d gives that step's
local error 2^p/(2^p - 1)·|d| (Richardson, order p), and the segment's estimate is that × the
number of steps (two extra steps per segment), as rk4 does.
``nfev`` counts ``force_torque`` evaluations (the drifts are not counted).
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.compiled.jit import inlined, jit, kernel
from massprops.dynamics.integrators._shared import (
    all_finite,
    copy_into,
    emit_start,
    fill_nan,
    project_quaternion,
    quat_offset,
    step_count,
)
from massprops.dynamics.integrators._subflows import (
    drift,
    drift_work,
    kick,
    kick_program,
    kick_work,
)
from massprops.dynamics.integrators.base import (
    NFEV,
    STATUS,
    STATUS_NONFINITE,
    STEPS,
    IntegratorSpec,
    segment_runner,
)
from massprops.errors import UsageError

# --- composition coefficients γ (palindromic, Σγ = 1) of the symmetric Strang step -------------
STRANG = (1.0,)
"""Order 2: the Strang step itself."""

_M4 = (0.28, 0.62546642846767004501)
MCLACHLAN_S5_ORDER4 = (*_M4, 1.0 - 2.0 * sum(_M4), *_M4[::-1])
"""Order 4, 5 stages: McLachlan (1995), "On the numerical integration of ordinary differential
equations by symmetric composition methods", SIAM J. Sci. Comput. 16(1); the member of the
one-parameter family Σγ = 1, Σγ³ = 0 with γ1 = 0.28 chosen there to minimise the error
constants (also Hairer, Lubich & Wanner, GNI, §V.3.2)."""

_KL6 = (0.39216144400731413928, 0.33259913678935943860, -0.70624617255763935981,
        0.082213596293550800230)
KAHAN_LI_S9_ORDER6 = (*_KL6, 1.0 - 2.0 * sum(_KL6), *_KL6[::-1])
"""Order 6, 9 stages: Kahan & Li (1997), "Composition constants for raising the orders of
unconventional schemes for ordinary differential equations", Math. Comp. 66(219), scheme
s9odr6a (γ5 = 0.79854399093482996340 there; here 1 - 2 Σ of the others, equal to round-off)."""


# --- one composed step -------------------------------------------------------------------------
@jit
def composed_step(y, h, gam, kp, wk, dw):
    """y := Ψ_h(y) in place (h may be any sign); returns the force evaluations used.

    gam (s,) float64 composition coefficients; kp from `_subflows.kick_program`; wk, dw scratch
    from `kick_work`, `drift_work`. The quaternion is projected at the end.
    """
    inertia = kp[6]
    n = y.shape[0]
    if not kp[10]:  # no active force term: the exact flow itself
        drift(y, h, inertia, dw)
        project_quaternion(y, quat_offset(n))
        return 0
    s = gam.shape[0]
    nfev = kick(y, 0.0, 0.5 * gam[0] * h, kp, wk)
    for i in range(s):
        drift(y, gam[i] * h, inertia, dw)
        after = 0.5 * gam[i + 1] * h if i + 1 < s else 0.0
        nfev += kick(y, 0.5 * gam[i] * h, after, kp, wk)
    project_quaternion(y, quat_offset(n))
    return nfev


@inlined
def _emit_partial(y_a, y_b, t_a, t_b, gam, kp, wk, dw, part, t_out, y_out, k):
    """Fill y_out rows from k on whose times are <= t_b (the step t_a -> t_b from y_a to y_b):
    a partial step of length t_out[k] - t_a from y_a, or y_b itself at t_b. Returns (next k,
    evaluations used)."""
    nfev = 0
    while k < t_out.shape[0] and t_out[k] <= t_b:
        if t_out[k] >= t_b:
            copy_into(y_b, y_out[k])
        else:
            copy_into(y_a, part)
            nfev += composed_step(part, t_out[k] - t_a, gam, kp, wk, dw)
            copy_into(part, y_out[k])
        k += 1
    return k, nfev


@inlined
def _richardson(y_a, y_b, h, gam, order, kp, wk, dw, part):
    """Local error (max-norm, absolute) of the step y_a -> y_b of length h: 2^p/(2^p - 1) of its
    difference from two half steps. Returns (error, evaluations used)."""
    copy_into(y_a, part)
    nfev = composed_step(part, 0.5 * h, gam, kp, wk, dw)
    nfev += composed_step(part, 0.5 * h, gam, kp, wk, dw)
    d = 0.0
    for i in range(y_a.shape[0]):
        d = max(d, abs(y_b[i] - part[i]))
    gain = 2.0 ** order
    return gain / (gain - 1.0) * d, nfev


@kernel
def _kernel(y, t0, t1, h_req, active, codes, params, mass, inertia, rot_only, t_out, y_out,
            stats, gam, order):
    n = y.shape[0]
    k = emit_start(y, t0, t_out, y_out)
    if t1 <= t0:
        return 0.0, t0
    if not all_finite(y):
        stats[STATUS] = STATUS_NONFINITE
        fill_nan(y_out, k)
        return 0.0, t0
    m = step_count(t0, t1, h_req)
    h = (t1 - t0) / m
    kp = kick_program(active, codes, params, mass, inertia, quat_offset(n))
    wk, dw = kick_work(n), drift_work()
    y_a, part = np.empty(n), np.empty(n)
    nfev = 0
    t_a = t0
    ok = True
    i = 0
    while i < m:
        t_b = t1 if i == m - 1 else t0 + (i + 1) * h
        copy_into(y, y_a)
        nfev += composed_step(y, h, gam, kp, wk, dw)
        if not all_finite(y):
            copy_into(y_a, y)  # the last finite state
            ok = False
            break
        if k < t_out.shape[0] and t_out[k] <= t_b:
            k, used = _emit_partial(y_a, y, t_a, t_b, gam, kp, wk, dw, part, t_out, y_out, k)
            nfev += used
        t_a = t_b
        i += 1
    stats[STEPS] += i
    if not ok:
        stats[NFEV] += nfev
        stats[STATUS] = STATUS_NONFINITE
        fill_nan(y_out, k)
        return 0.0, t_a
    local, used = _richardson(y_a, y, h, gam, order, kp, wk, dw, part)
    stats[NFEV] += nfev + used
    return (local * m if math.isfinite(local) else 0.0), t1


# --- the registry entries ----------------------------------------------------------------------
def _moments_checked(name: str, inertia) -> None:
    """The closed-form drift needs the principal moments positive and ascending (once per
    segment; a `ForceProgram` always has them so)."""
    i = np.asarray(inertia)
    if not (i.shape == (3,) and np.all(np.isfinite(i)) and 0 < i[0] <= i[1] <= i[2]):
        raise UsageError(f"integrator {name}: expected the principal moments as (3,) positive "
                         f"and ascending (kg·m²), got {i.tolist()}; pass "
                         "ForceProgram.inertia (RigidBody.principal_moments)")


def _entry(name: str, gammas: tuple[float, ...], order: int):
    """The kernel for `segment_runner`: checks the moments, then runs the compiled loop with this
    method's coefficients (one compiled kernel serves all three methods)."""
    gam = np.array(gammas, dtype=np.float64)

    def kernel(y, t0, t1, h, active, codes, params, mass, inertia, rot_only, t_out, y_out,
               stats):
        _moments_checked(name, inertia)
        return _kernel(y, t0, t1, h, active, codes, params, mass, inertia, rot_only, t_out,
                       y_out, stats, gam, order)

    return kernel


def _spec(name: str, gammas: tuple[float, ...], order: int, what: str) -> IntegratorSpec:
    return IntegratorSpec(
        name=name, kind="fixed", order=order, kernel="splitting",
        description=f"{what}: exact free-rotation drift + force kicks, fixed step (time.step)",
        run_segment=segment_runner(name, "fixed", _entry(name, gammas, order)))


SPECS: tuple[IntegratorSpec, ...] = (
    _spec("splitting", STRANG, 2, "Strang, order 2"),
    _spec("splitting4", MCLACHLAN_S5_ORDER4, 4, "McLachlan composition, order 4"),
    _spec("splitting6", KAHAN_LI_S9_ORDER6, 6, "Kahan-Li composition, order 6"),
)
"""The three splitting methods, registered in `INTEGRATORS` by the package."""
