"""What every integrator is: the `IntegratorSpec` record, the stats layout, and the checked Python
entry point `segment_runner` that wraps a method's compiled kernel (see the package docstring for
the contract)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from massprops.errors import UsageError, setting_ref
from massprops.tolerances import EPS, RTOL_FLOOR

# --- stats : (5,) int64, accumulated (+=) by every kernel -----------------------------------------
STEPS, NFEV, REJECTED, NJEV, STATUS = range(5)
"""Indices into ``stats``: accepted steps, right-hand-side evaluations, rejected steps (adaptive
error test or failed Newton iterations), Jacobian evaluations, status."""

STATUS_OK, STATUS_NONFINITE = 0, 1
"""``stats[STATUS]``: 0 fine; 1 a NaN/inf appeared (the state is the last finite one)."""

KINDS = ("fixed", "adaptive", "exact")

RunSegment = Callable[..., tuple[float, float]]
"""run_segment(y, t0, t1, setting, program_arrays, rot_only, t_out, y_out, stats) -> (err, t)."""


@dataclass(frozen=True)
class IntegratorSpec:
    """One entry of the `INTEGRATORS` registry.

    name : registry key, what ``time.integrator`` and ``--integrator`` accept.
    kind : "fixed" (``setting`` is the step h, s), "adaptive" (``setting`` is rtol) or "exact"
        (closed form, no steps, ``setting`` ignored).
    order : classical order of the step-point values (0 for kind "exact": no truncation).
    description : one line, shown in ``--help``.
    run_segment : the checked entry point of a one-body kernel (`segment_runner`), see the
        package docstring; None for a method the systems engine steps (`stepped`).
    stiff : stable far beyond the explicit step limit (~2.8 / ForceProgram.stiffest_rate).
    estimate_order : the highest order the error estimate's Richardson rule may assume (None:
        ``order``); lower where the order can fall on stiff problems (order reduction).
    kernel : the name of its compiled kernel (`compiled.compiling`; methods that share one name
        it alike and compile it once); None for a closed form, which compiles nothing.
    tableau : (A, b), the Butcher tableau of one step as nested tuples (A (s, s), b (s,)), whose
        stability function R(z) = 1 + z bᵀ (I − z A)⁻¹ 1 tells what a step does to a rotation
        (`accuracy.rotation_floor`); None for a method that is no single Runge-Kutta step (the
        splitting methods turn exactly; the closed form takes no step).
    """

    name: str
    kind: str
    order: int
    description: str
    run_segment: RunSegment | None = None
    stiff: bool = False
    estimate_order: int | None = None
    tableau: tuple | None = None
    kernel: str | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"integrator {self.name!r}: kind must be one of {KINDS}, "
                             f"got {self.kind!r}")
        if "\n" in self.description:
            raise ValueError(f"integrator {self.name!r}: the description must be one line")


def segment_runner(name: str, kind: str, kernel) -> RunSegment:
    """The contract's ``run_segment`` for ``kernel``: checks the arguments once per segment (not
    per step), then hands everything to the compiled kernel.

    kernel(y, t0, t1, setting, active, codes, params, mass, inertia, rot_only, t_out, y_out,
    stats) -> (err, t_reached), compiled with numba.
    """
    what = "step" if kind == "fixed" else "rtol"
    fix = setting_ref("time.step") if kind == "fixed" else setting_ref("time.rtol")

    def run_segment(y, t0, t1, setting, program_arrays, rot_only, t_out, y_out, stats):
        t0, t1, setting, rot_only = float(t0), float(t1), float(setting), bool(rot_only)
        if not (math.isfinite(setting) and setting > 0):
            raise UsageError(f"integrator {name}: expected a {what} > 0, got {setting!r}; "
                             f"set {fix} to a positive number")
        if kind == "adaptive":
            check_rtol(setting, f"integrator {name}")
        check_arrays(name, y, t0, t1, rot_only, t_out, y_out, stats)
        active, codes, params, mass, inertia = program_arrays[:5]
        return kernel(y, t0, t1, setting, active, codes, params, float(mass), inertia,
                      rot_only, t_out, y_out, stats)

    run_segment.__name__ = f"run_segment_{name}"
    run_segment.__doc__ = (f"Advance y in place from t0 to t1 with {name} ({kind}; setting = "
                           f"{what}); see massprops.dynamics.integrators for the contract.")
    return run_segment


def check_rtol(rtol: float, who: str) -> None:
    """UsageError (said as ``who: ...``) for an ``rtol`` below `tolerances.RTOL_FLOOR`, the
    smallest relative tolerance float64 can deliver (one scene's key is refused the same way,
    at its line: `dynamics.scene`)."""
    if rtol < RTOL_FLOOR:
        raise UsageError(f"{who}: {setting_ref('rtol')} {rtol!r} asks for more digits than "
                         f"float64 has (a step is rounded to {EPS / 2:.2g} relative); the "
                         f"smallest accepted is {RTOL_FLOOR:g}")


def ignored_settings(spec: IntegratorSpec, rtol: float | None, step: float | None) -> str | None:
    """What a run of ``spec`` does not read among the settings its caller gave (``rtol``,
    ``step``; None: not given), said so that a setting that changes nothing is not taken for
    one that did, or None: an adaptive method takes rtol, a fixed-step one its step, a closed
    form neither."""
    unread = [(name, value) for name, value, takes in (
        ("rtol", rtol, spec.kind == "adaptive"), ("step", step, spec.kind == "fixed"))
        if value is not None and not takes]
    if not unread:
        return None
    said = " and ".join(f"{setting_ref(name)} {value:g}" for name, value in unread)
    takes = {"adaptive": f"an adaptive method: its steps follow {setting_ref('rtol')}",
             "fixed": f"a fixed-step method: it takes {setting_ref('step')}",
             "exact": "a closed form: it takes no steps"}[spec.kind]
    return f"{said} ignored: {spec.name} is {takes}"


def check_arrays(name, y, t0, t1, rot_only, t_out, y_out, stats) -> None:
    """Shapes and dtypes of the contract, each failure one line naming what was expected."""
    ny = 7 if rot_only else 13
    if not (isinstance(y, np.ndarray) and y.dtype == np.float64 and y.shape == (ny,)):
        raise UsageError(f"integrator {name}: expected y as a ({ny},) float64 array "
                         f"(rot_only={rot_only}), got {_describe(y)}")
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 >= t0):
        raise UsageError(f"integrator {name}: expected finite t0 <= t1, got [{t0!r}, {t1!r}]")
    if not (isinstance(t_out, np.ndarray) and t_out.ndim == 1 and t_out.dtype == np.float64):
        raise UsageError(f"integrator {name}: expected t_out as an (n,) float64 array, "
                         f"got {_describe(t_out)}")
    if t_out.size and (t_out[0] < t0 or t_out[-1] > t1 or np.any(np.diff(t_out) < 0)):
        raise UsageError(f"integrator {name}: expected t_out sorted within [{t0!r}, {t1!r}], "
                         f"got values from {t_out.min()!r} to {t_out.max()!r}")
    if not (isinstance(y_out, np.ndarray) and y_out.dtype == np.float64
            and y_out.shape == (t_out.size, ny)):
        raise UsageError(f"integrator {name}: expected y_out as a ({t_out.size}, {ny}) float64 "
                         f"array, got {_describe(y_out)}")
    if not (isinstance(stats, np.ndarray) and stats.dtype == np.int64 and stats.shape == (5,)):
        raise UsageError(f"integrator {name}: expected stats as a (5,) int64 array, "
                         f"got {_describe(stats)}")


def _describe(a) -> str:
    if isinstance(a, np.ndarray):
        return f"shape {a.shape} dtype {a.dtype}"
    return type(a).__name__
