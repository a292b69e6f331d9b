"""The one compiled entry of a system's run: `run_segment`, one call per segment, with any of
the systems' methods (DOP853, `systems_dop853`; rk4, midpoint, implicit, `systems_fixed`), and
one call for all the samples' outputs (`systems_outputs`).

One kernel, not one per method: every method calls the same right-hand side and projection,
which numba compiles (~1 min) into each kernel that calls them; a single entry compiles them
once, for the wheel's prebuilt kernels and for a machine without them alike. The outputs use the
same accelerations, kinematics and loads: as a method code of this entry they cost only their
own code to compile.
"""

from __future__ import annotations

import numpy as np

from massprops.dynamics.compiled import systems_dop853, systems_fixed, systems_outputs
from massprops.dynamics.compiled.jit import array_kernel
from massprops.dynamics.compiled.systems_step import OK, rhs, workspace
from massprops.dynamics.compiled.unowned import unowned

DOP853 = 3
"""The method code of DOP853 (the fixed-step ones: `systems_fixed.METHODS`)."""

METHODS = {"dop853": DOP853, **systems_fixed.METHODS}
"""Registry names -> method codes of `run_segment`."""


@array_kernel
def run_segment(prog, y, t0, t1, setting, method, scales, t_out, y_out, istats, fstats, acc_b,
                acc_u, max_steps, yfail, out):
    """Integrate y (in place) from t0 to t1 with ``method`` (a METHODS code) at ``setting``
    (DOP853: rtol; the others: the step h, s); samples at t_out[istats[4]:] into y_out.
    With a `systems_outputs` code (STATES, ENERGIES, OUTPUTS) instead: no step, each sample
    y_out[s] at t_out[s] evaluated into out[s] (its layout there; a failure in istats); the
    other arguments are unread.

    prog: the system program (`dynamics.systems.program`); scales (n,): each component's error
    scale floor, grown to its running max |y_i| here; istats, fstats, acc_b, acc_u, yfail: see
    `systems_dop853` (the layout every method keeps); max_steps: the run bound. The loops
    take views numba does not reference-count (`unowned`) and, last, the owned arrays: an
    argument stays alive until the call returns."""
    ws = workspace(prog)
    if method >= systems_outputs.STATES:
        systems_outputs.evaluate(prog, ws, systems_outputs.scratch(prog), t_out, y_out, out,
                                 istats, method)
        return
    arrays = (y, scales, t_out, y_out, istats, fstats, acc_b, acc_u, yfail)
    if method == DOP853:
        own = systems_dop853.scratch(y.size)
        systems_dop853.segment(unowned(prog), unowned(ws), unowned(own), unowned(arrays), t0, t1,
                               setting, max_steps, (prog, ws, own, arrays))
    else:
        fixed = systems_fixed.scratch(y.size, method)
        systems_fixed.segment(unowned(prog), unowned(ws), unowned(fixed), unowned(arrays), t0,
                              t1, setting, method, max_steps, (prog, ws, fixed, arrays))


def stand_in() -> tuple:
    """The program of a stand-in system (a rod on a hinge, no loops) whose arrays have the types
    of every real program (`dynamics.systems.program`): warming the kernel up on it loads or
    compiles the very kernel real runs use."""
    ints = np.int64
    return (np.array([1, 1, 0, 1, 1], ints), np.array([[1, -1, 0, 0, 0, 1, 1, 0]], ints),
            np.array([[[0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]]), np.zeros((1, 3)),
            np.array([[0.0, 0.0, 0.5]]), np.eye(3).reshape(1, 3, 3), np.zeros(1, ints),
            np.ones(1), np.eye(3).reshape(1, 3, 3), np.eye(3).reshape(1, 3, 3),
            np.array([[0.0, 0.0, -0.5]]), np.array([[0.0, 0.0, -9.81]]), np.zeros((0, 5), ints),
            np.zeros((0, 13)), np.zeros((0, 4), ints), np.zeros((0, 8)), np.zeros((0, 2), ints),
            np.zeros((0, 9)), np.zeros(0, ints), np.zeros((0, 6)),
            np.array([1.0, 1e-8, 1e-14, 1e-6]), np.zeros((0, 3), ints), np.zeros((0, 21)),
            np.zeros((0, 3), ints), np.zeros((0, 2)),
            np.array([[[0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]]), np.eye(3).reshape(1, 3, 3),
            np.zeros((1, 2), ints), np.array([[0.0, 0.0, 0.5]]))


def warm_up() -> None:
    """Run one short segment of the `stand_in` system and one right-hand side from Python
    (`systems_step.rhs`, the stiffness probe's): loads or compiles both."""
    y, prog = np.array([0.1, 0.0]), stand_in()
    rhs(prog, workspace(prog), 0.0, y, np.zeros(2), -1)
    run_segment(prog, y, 0.0, 1e-3, 1e-6, DOP853, np.ones(2), np.array([0.0, 1e-3]),
                np.zeros((2, 2)), np.array([0, 0, 0, OK, 1, -1, -1], np.int64),
                np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]), np.zeros((0, 1)),
                np.zeros((0, 1)), 1000, np.zeros(2), np.zeros((0, 0)))
