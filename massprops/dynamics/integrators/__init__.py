"""The integrator family: one registry of every method a run may name, and the one-body kernels
of the methods only a single body has.

``INTEGRATORS`` maps a name to an `IntegratorSpec` (name, kind, order, description, stiff,
estimate_order, tableau, run_segment). `--integrator`'s choices, ``time.integrator``, `auto`'s
rule, `precision`'s ladders and the help text all read it. Two kinds of entry:

- The time-stepping methods (``stepped``: ``dop853``, adaptive, order 8; ``rk4``, fixed, order
  4; ``midpoint``, implicit midpoint, fixed, order 2, symplectic; ``implicit``, Radau IIA,
  fixed, order 5, L-stable). The systems engine steps them (`dynamics.compiled`), for a system
  and for one body alike (a ``body:`` scene runs as the system of one body); their records have
  no ``run_segment``. `SYSTEM_METHODS` lists them.
- The methods of one free body's own structure, with one-body kernels (``run_segment``):
  ``splitting``, ``splitting4``, ``splitting6`` (exact free rotations and force kicks, Strang
  and its McLachlan / Kahan-Li compositions, fixed, orders 2, 4, 6: for fast spin and long
  conservative runs), and ``exact`` (kind "exact"), the closed-form torque-free body and heavy
  symmetric top, which takes no step and whose cost does not depend on t.

A one-body kernel's ``run_segment`` (dynamics.runner calls it once per segment between force
windows' edges, ``ForceProgram.breakpoints``)::

    err, t_reached = spec.run_segment(y, t0, t1, setting, program_arrays, rot_only,
                                      t_out, y_out, stats)

1. ``y`` : (ny,) float64, the state at ``t0``: ny = 13 [r world m, v world m/s, q principal->world
   (w, x, y, z), omega principal rad/s] or, with ``rot_only``, ny = 7 [q, omega] (translation is
   then closed form and handled by the caller). It is overwritten in place with the state at
   ``t_reached``; the quaternion is re-normalised after every step (projection).
2. ``t_reached`` == ``t1`` unless the method failed; the state is then the last finite one.
3. ``setting`` : the step h > 0 (s) of a fixed-step method; the segment is done in
   n = ceil((t1 - t0) / h) equal steps (ratios within 1e-12 of an integer round down), so it
   lands exactly on t1 and a window shorter than h is still resolved. Ignored by ``exact``.
4. ``program_arrays`` : (active (k,) bool, codes (k,) int64, params (k, NPAR) float64, mass kg,
   inertia (3,) kg·m²), from ``ForceProgram`` and ``ForceProgram.active``.
5. ``t_out`` : (n_out,) float64 sorted times within [t0, t1]; ``y_out`` : (n_out, ny) float64,
   filled with the state at those times; rows after ``t_reached`` are NaN.
6. ``stats`` : (5,) int64 [steps, nfev, rejected, njev, status], accumulated (+=); status is set
   to 1 if a NaN/inf appeared (the step is abandoned, the state is the last finite one).
7. ``err`` : float, the segment's accumulated local error estimate (max-norm, absolute units).
8. All stepping happens inside one numba-compiled function (``compiled.jit.kernel``): one Python
   call per segment, never per step.
9. ``run_segment`` checks its arguments once per segment and raises
   `massprops.errors.UsageError` naming the integrator, what was expected and what came.

Caching: numba's on-disk cache is keyed on each kernel's own source file only; importing
``massprops.dynamics`` therefore points it at a folder named by a hash of all the dynamics
sources, so an edit or upgrade of a file a kernel calls into recompiles instead of running stale
code (``dynamics.compiled``: prebuilt at install, else compiled once on first use).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from importlib import import_module

from massprops.dynamics.integrators.base import IntegratorSpec

_BUILT_IN: dict[str, tuple[str, int | None]] = {
    "exact": ("closed_form", None), "dop853": ("stepped", 0), "rk4": ("stepped", 1),
    "midpoint": ("stepped", 2), "implicit": ("stepped", 3),
    "splitting": ("splitting", 0), "splitting4": ("splitting", 1), "splitting6": ("splitting", 2),
}
"""name -> (module in this package, index into its ``SPECS``, or None for its one ``SPEC``).
Written out so that a run imports only the module of the method it uses (the splitting module
makes its numba dispatchers on import)."""

SYSTEM_METHODS: tuple[str, ...] = tuple(name for name, (module, _) in _BUILT_IN.items()
                                        if module == "stepped")
"""The methods the systems engine steps: every time-stepping method a scene may name, for one
body (as the system of one body) and many."""


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


__all__ = ["INTEGRATORS", "SYSTEM_METHODS", "IntegratorSpec", "integrator_names", "register"]
