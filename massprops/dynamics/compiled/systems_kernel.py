"""The compiled entries of a system's run, each compiled and cached on its own so that a run
compiles (or loads) only what it uses: `step_dop853` (one segment of DOP853, `systems_dop853`),
`step_fixed` (one segment of rk4, midpoint or Radau IIA, `systems_fixed`), `evaluate_samples`
(every sample's outputs, and the right-hand sides of the stiffness probe's states,
`systems_outputs`), and `systems_step.rhs` (one right-hand side from Python, for the tests).
`WARM_UPS` names them for `compiled.compiling`.

They share the right-hand side, kinematics and loads (`systems_step`, `systems_loops`, ...):
numba compiles those once per process and links a copy into each entry, so the second entry a
process compiles costs its own code and the link, not the shared code again; a fresh process
(the first run's helper on the second core, `compiling`) compiles the shared code anew.
"""

from __future__ import annotations

import numpy as np

from massprops.dynamics.compiled import systems_dop853, systems_fixed, systems_outputs
from massprops.dynamics.compiled import systems_layout as L
from massprops.dynamics.compiled.jit import array_kernel
from massprops.dynamics.compiled.systems_step import OK, rhs, workspace
from massprops.dynamics.compiled.unowned import unowned

METHODS = {"dop853": -1, **systems_fixed.METHODS}
"""Registry names -> the method codes the step entries take (dop853's is unread)."""


@array_kernel
def step_dop853(prog, y, t0, t1, rtol, method, scales, t_out, y_out, istats, fstats, acc_b,
                acc_u, max_steps, yfail):
    """Integrate y (in place) from t0 to t1 with DOP853 at ``rtol``; samples at
    t_out[istats[4]:] into y_out (``method`` is unread: the step entries take one signature).

    prog: the system program (`dynamics.systems.program`); scales (n,): each component's error
    scale floor, grown to its running max |y_i| here; istats, fstats, acc_b, acc_u, yfail: see
    `systems_dop853` (the layout every method keeps); max_steps: the run bound. The loops
    take views numba does not reference-count (`unowned`) and, last, the owned arrays: an
    argument stays alive until the call returns."""
    ws = workspace(prog)
    arrays = (y, scales, t_out, y_out, istats, fstats, acc_b, acc_u, yfail)
    own = systems_dop853.scratch(y.size)
    systems_dop853.segment(unowned(prog), unowned(ws), unowned(own), unowned(arrays), t0, t1,
                           rtol, max_steps, (prog, ws, own, arrays))


@array_kernel
def step_fixed(prog, y, t0, t1, h, method, scales, t_out, y_out, istats, fstats, acc_b, acc_u,
               max_steps, yfail):
    """`step_dop853` with the fixed-step ``method`` (a `systems_fixed.METHODS` code) in equal
    steps of at most ``h`` (s); scales (n,) are its Newton norm's."""
    ws = workspace(prog)
    arrays = (y, scales, t_out, y_out, istats, fstats, acc_b, acc_u, yfail)
    fixed = systems_fixed.scratch(y.size, method)
    systems_fixed.segment(unowned(prog), unowned(ws), unowned(fixed), unowned(arrays), t0, t1,
                          h, method, max_steps, (prog, ws, fixed, arrays))


@array_kernel
def evaluate_samples(prog, t_out, y_out, out, istats, mode):
    """Each sample y_out[s] at t_out[s] evaluated into out[s] by ``mode`` (`systems_outputs`'s
    STATES, ENERGIES, OUTPUTS: its layout there); a failure in istats[3:5]."""
    ws = workspace(prog)
    systems_outputs.evaluate(prog, ws, systems_outputs.scratch(prog), t_out, y_out, out, istats,
                             mode)


STEPS = {"dop853": step_dop853, "rk4": step_fixed, "midpoint": step_fixed,
         "implicit": step_fixed}
"""Registry names -> the entry that steps them."""


def stand_in() -> tuple:
    """The program of a stand-in system (a rod on a hinge, no loops) whose arrays have the types
    of every real program (`dynamics.systems.program`): warming an entry up on it loads or
    compiles the very code real runs use."""
    ints, hinge, eye = np.int64, np.array([[[0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]]), np.eye(3)[None]
    slots = {
        L.P_DIMS: np.array([1, 1, 0, 1, 1], ints),  # nq, nv, m, bodies, joints (`L.D_*`)
        L.P_JOINTS: np.array([[1, -1, 0, 0, 0, 1, 1, 0]], ints), L.P_AXES: hinge,
        L.P_S_PARENT: np.zeros((1, 3)), L.P_S_CHILD: np.array([[0.0, 0.0, 0.5]]),
        L.P_ROT_PARENT0: eye, L.P_PARENT_JOINT: np.zeros(1, ints), L.P_MASS: np.ones(1),
        L.P_INERTIA: eye, L.P_ROTATION0: eye, L.P_COM0: np.array([[0.0, 0.0, -0.5]]),
        L.P_WEIGHT: np.array([[0.0, 0.0, -9.81]]), L.P_PRIMS: np.zeros((0, 5), ints),
        L.P_PRIM_VALUES: np.zeros((0, 13)), L.P_FORCES: np.zeros((0, 4), ints),
        L.P_FORCE_VALUES: np.zeros((0, 8)), L.P_SPRINGS: np.zeros((0, 2), ints),
        L.P_SPRING_VALUES: np.zeros((0, 9)), L.P_LOADED: np.zeros(0, ints),
        L.P_LOADED_VALUES: np.zeros((0, 6)), L.P_TOLERANCES: np.array([1.0, 1e-8, 1e-14, 1e-6]),
        L.P_CUT_LOADS: np.zeros((0, 3), ints), L.P_CUT_LOAD_VALUES: np.zeros((0, 21)),
        L.P_COUPLINGS: np.zeros((0, 3), ints), L.P_COUPLING_VALUES: np.zeros((0, 2)),
        L.P_AXES_PARENT: hinge, L.P_TURN0: eye, L.P_SCENE_JOINTS: np.zeros((1, 2), ints),
        L.P_SCENE_POINTS: np.array([[0.0, 0.0, 0.5]]),
    }
    return tuple(np.ascontiguousarray(slots[k]) for k in range(L.PROGRAM_SLOTS))


def _warm_step(entry, method: int) -> None:
    y, prog = np.array([0.1, 0.0]), stand_in()
    entry(prog, y, 0.0, 1e-3, 1e-3 if entry is step_fixed else 1e-6, method, np.ones(2),
          np.array([0.0, 1e-3]), np.zeros((2, 2)), np.array([0, 0, 0, OK, 1, -1, -1], np.int64),
          np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]), np.zeros((0, 1)), np.zeros((0, 1)),
          1000, np.zeros(2))


def _warm_outputs() -> None:
    prog = stand_in()
    evaluate_samples(prog, np.zeros(1), np.array([[0.1, 0.0]]), np.zeros((1, 1)),
                     np.array([0, 0, 0, OK, 0, -1, -1], np.int64), systems_outputs.ENERGIES)


def _warm_rhs() -> None:
    prog = stand_in()
    rhs(prog, workspace(prog), 0.0, np.array([0.1, 0.0]), np.zeros(2), -1)


WARM_UPS = {"dop853": lambda: _warm_step(step_dop853, METHODS["dop853"]),
            "fixed": lambda: _warm_step(step_fixed, METHODS["rk4"]),
            "outputs": _warm_outputs, "rhs": _warm_rhs}
"""The systems' compiled entries by name (`compiling`'s kernel names): each runs its entry once
on the `stand_in` system, which loads or compiles it (and what it calls)."""
