"""The time-stepping methods: the registry's records of the methods the systems engine steps
(`dynamics.compiled.systems_dop853`, `dynamics.compiled.systems_fixed`), one body and many alike
(a ``body:`` scene runs as the system of one body, `systems.one_body`).

Each record carries what the rest of the package reads of a method: its kind (which setting it
takes), its order, whether it is stable far beyond the explicit step limit, the order its error
estimate may assume, and its Butcher tableau (`accuracy.rotation_floor` reads what one step does
to a rotation from it). The step loops themselves are the engine's; a record has no
``run_segment``.
"""

from __future__ import annotations

import math

from massprops.dynamics.integrators._dop853_tableau import A as DOP853_A
from massprops.dynamics.integrators._dop853_tableau import B as DOP853_B
from massprops.dynamics.integrators.base import IntegratorSpec

_S6 = math.sqrt(6.0)
RADAU_A = (
    ((88.0 - 7.0 * _S6) / 360.0, (296.0 - 169.0 * _S6) / 1800.0, (-2.0 + 3.0 * _S6) / 225.0),
    ((296.0 + 169.0 * _S6) / 1800.0, (88.0 + 7.0 * _S6) / 360.0, (-2.0 - 3.0 * _S6) / 225.0),
    ((16.0 - _S6) / 36.0, (16.0 + _S6) / 36.0, 1.0 / 9.0))
"""(3, 3) the 3-stage Radau IIA matrix (Hairer & Wanner, Solving ODEs II, Table IV.5.6); its
last row is the weights b (stiffly accurate), its row sums the nodes (4 ∓ √6)/10 and 1."""

RK4_TABLEAU = (((0.0, 0.0, 0.0, 0.0), (0.5, 0.0, 0.0, 0.0), (0.0, 0.5, 0.0, 0.0),
                (0.0, 0.0, 1.0, 0.0)), (1 / 6, 1 / 3, 1 / 3, 1 / 6))
"""(A, b) of the classical Runge-Kutta method."""

SPECS = (
    IntegratorSpec(
        name="dop853", kind="adaptive", order=8, kernel="dop853",
        description="Dormand-Prince 8(5,3), adaptive step (time.rtol), 7th-order dense output",
        tableau=(tuple(map(tuple, DOP853_A[:12, :12].tolist())), tuple(DOP853_B.tolist()))),
    IntegratorSpec(
        name="rk4", kind="fixed", order=4, kernel="fixed",
        description="classical Runge-Kutta 4, fixed step (time.step)", tableau=RK4_TABLEAU),
    IntegratorSpec(
        name="midpoint", kind="fixed", order=2, stiff=True, kernel="fixed",
        description="implicit midpoint, fixed step (time.step): symplectic, keeps quadratic "
                    "invariants",
        tableau=(((0.5,),), (1.0,))),
    IntegratorSpec(
        name="implicit", kind="fixed", order=5, stiff=True, kernel="fixed",
        description="Radau IIA order 5, fixed step (time.step), L-stable: for stiff "
                    "springs/dampers",
        tableau=(RADAU_A, RADAU_A[2]),
        # On a stiff problem the global error can fall from order 5 to the stage order 3 (order
        # reduction, Hairer & Wanner IV.15). Measured on heavy_top_damped: error ratios 20
        # between 4h and 2h, 13 between 2h and h, so a rule that trusted the coarser ratio up
        # to 2^5 reported 7.7e-11 for a true 1.3e-10-2.0e-10; up to 2^3 it reports 2.2e-10.
        estimate_order=3),
)
"""dop853, rk4, midpoint, implicit: the registry's stepped entries, in this order."""
