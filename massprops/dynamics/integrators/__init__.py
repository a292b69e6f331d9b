"""The integrator family: a plain registry of methods that step the Newton-Euler state.

``INTEGRATORS`` maps a name to an `IntegratorSpec` (name, kind, order, description, run_segment,
stiff). The simulate module splits [0, duration] at the force windows' edges
(``ForceProgram.breakpoints``) and calls, for each segment with no discontinuity inside::

    err, t_reached = spec.run_segment(y, t0, t1, setting, program_arrays, rot_only,
                                      t_out, y_out, stats)

The contract every implementation keeps (a new method, e.g. a splitting scheme, adds one module
with one ``SPEC`` and one entry in ``_BUILT_IN`` below, or calls `register`):

1. ``y`` : (ny,) float64, the state at ``t0``: ny = 13 [r world m, v world m/s, q principal->world
   (w, x, y, z), omega principal rad/s] or, with ``rot_only``, ny = 7 [q, omega] (translation is
   then closed form and handled by the caller). It is overwritten in place with the state at
   ``t_reached``. The quaternion is re-normalised after every step (projection).
2. ``t_reached`` == ``t1`` unless the method failed; the state is then the last finite one.
3. ``setting`` : for ``kind == "fixed"`` the step h > 0 (s); the segment is done in
   n = ceil((t1 - t0) / h) equal steps (ratios within 1e-12 of an integer round down), so it
   lands exactly on t1 and a window shorter than h is still resolved (an implicit method may
   cut a step into pieces where its Newton iteration fails; step ends stay on that grid).
   For ``kind == "adaptive"`` the relative tolerance rtol; the absolute tolerance of
   component i is rtol × S_b, S_b the largest |component| block b (r, v, q or omega) has had
   in this segment so far (its start, the accepted steps and the trial step's end), and 1 for
   the quaternion: each block's error is relative to that block's own size, so a component
   passing through zero needs no extra care.
4. ``program_arrays`` : (active (k,) bool, codes (k,) int64, params (k, NPAR) float64, mass kg,
   inertia (3,) kg·m²[, floors (4,), max_steps int]), from ``ForceProgram`` and
   ``ForceProgram.active``; the kernels call ``forces.rhs`` with them and never look inside.
   The optional sixth and seventh entries are for error-scaled kernels (``segment_runner(...,
   scaled=True)``): the error-scale floors, and the step limit (the run bound,
   massprops.dynamics.budget): such a kernel stops with status 3 once stats[STEPS] reaches it.
5. ``t_out`` : (n_out,) float64 sorted times within [t0, t1]; ``y_out`` : (n_out, ny) float64,
   filled with the state at those times by dense output, not the nearest step: DOP853's own 7th
   order interpolant, Radau's collocation polynomial, a cubic Hermite interpolant from the step
   end values and derivatives for the other fixed-step methods. The interpolated quaternion is
   re-normalised. Rows after ``t_reached`` are NaN.
6. ``stats`` : (5,) int64 [steps, nfev, rejected, njev, status], accumulated (+=); status is set
   to 1 if a NaN/inf appeared (the step is abandoned, the state is the last finite one), 2 if the
   step fell below 1e-14 × max(|t|, t1 - t0) (stiffness or a singularity), 3 if the step limit
   of item 4 was reached (the state is valid at ``t_reached``). A quaternion whose norm is zero
   or not finite counts as NaN (``_shared.project_quaternion``). Callers check status (and
   ``t_reached < t1``) after every call.
7. ``err`` : float, the segment's accumulated local error estimate: max-norm in absolute units of
   the state, summed over the steps. Each module's docstring says how it is estimated. The
   global error estimate is the caller's job. On failure it covers the steps taken (possibly 0).
8. All stepping happens inside one numba-compiled function per method (``compiled.jit.kernel``): one
   Python call per segment, never per step; work arrays are allocated once per segment. No
   array-to-slice assignment in compiled code (``_shared.copy_into``): it compiles numba's
   shape-error message machinery, seconds of every first compile.
9. ``run_segment`` checks its arguments (once per segment) and raises
   `massprops.errors.UsageError` naming the integrator, what was expected and what came.

The methods: ``rk4`` (fixed, order 4), ``dop853`` (adaptive, order 8), ``implicit`` (Radau IIA,
fixed, order 5, L-stable: damps a stiff mode out), ``midpoint`` (implicit midpoint, fixed,
order 2, symplectic: keeps a stiff linear mode's energy, aliases its phase), ``splitting``,
``splitting4``, ``splitting6`` (exact free rotations and force kicks, Strang and its McLachlan /
Kahan-Li compositions, fixed, orders 2, 4, 6: for fast spin and long conservative runs).
``spec.stiff`` marks the ones stable far beyond the explicit step limit.

``exact`` (kind "exact") is the closed-form torque-free body: it takes no step and its cost does
not depend on t; simulate offers it only for torque-free scenes with constant forces.

Caching: numba's on-disk cache is keyed on each kernel's own source file only; importing
``massprops.dynamics`` therefore points it at a folder named by a hash of all the dynamics
sources, so an edit or upgrade of a file a kernel calls into recompiles instead of running stale
code. The kernels are compiled when the package is built (``dynamics.compiled.prebuilt``);
where none fits, a method's kernel is compiled once, on first use (2-10 s of one core;
``dynamics.compiled.compiling`` gets them ready before a run and says so); later runs load
them in well under a second.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from importlib import import_module

from massprops.dynamics.integrators.base import IntegratorSpec

_BUILT_IN: dict[str, tuple[str, int | None]] = {
    "exact": ("closed_form", None), "rk4": ("rk4", None), "dop853": ("dop853", None),
    "implicit": ("radau", None), "midpoint": ("midpoint", None),
    "splitting": ("splitting", 0), "splitting4": ("splitting", 1), "splitting6": ("splitting", 2),
}
"""name -> (module in this package, index into its ``SPECS``, or None for its one ``SPEC``).
Written out so that a run imports only the module of the method it uses (each module makes its
numba dispatchers on import: all eight cost ~20 ms of a ~0.7 s ``massprops simulate``)."""


class _Registry(Mapping[str, IntegratorSpec]):
    """The registry: a read-only mapping name -> IntegratorSpec whose built-in entries are
    imported on first access (`register` adds more). Iterating lists every name; looking at
    the values imports every module."""

    def __init__(self, built_in: dict[str, tuple[str, int | None]]) -> None:
        self._where = dict(built_in)
        self._specs: dict[str, IntegratorSpec] = {}

    def __getitem__(self, name: str) -> IntegratorSpec:
        if name not in self._specs:
            module, index = self._where[name]  # KeyError for an unknown name, as a dict
            found = import_module(f"{__name__}.{module}")
            self._specs[name] = found.SPEC if index is None else found.SPECS[index]
        return self._specs[name]

    def __contains__(self, name: object) -> bool:  # Mapping's own would import the module
        return name in self._where

    def __iter__(self) -> Iterator[str]:
        return iter(self._where)

    def __len__(self) -> int:
        return len(self._where)

    def add(self, spec: IntegratorSpec) -> None:
        """Enter a spec built elsewhere (`register` checks the name first)."""
        self._where[spec.name] = ("", None)  # never looked up: the spec is already here
        self._specs[spec.name] = spec


INTEGRATORS: _Registry = _Registry(_BUILT_IN)
"""name -> IntegratorSpec; the CLI's choices and the scene's ``time.integrator`` come from here."""


def integrator_names() -> tuple[str, ...]:
    """What ``time.integrator`` and ``--integrator`` accept: "auto" and every registered name."""
    return ("auto", *sorted(INTEGRATORS))


def register(spec: IntegratorSpec) -> None:
    """Add ``spec`` to `INTEGRATORS`; a name can be registered once."""
    if spec.name in INTEGRATORS:
        raise ValueError(f"integrator {spec.name!r} is already registered")
    INTEGRATORS.add(spec)


__all__ = ["INTEGRATORS", "IntegratorSpec", "integrator_names", "register"]
