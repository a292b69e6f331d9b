"""Speed of our compiled DOP853 against scipy's solve_ivp(method="DOP853") at equal final error.

The problem: an asymmetric 2 kg body (principal moments 1, 2, 3 kg·m²) spinning about its major
axis, under gravity, a constant body-frame torque, a world force off the centre of mass and a
spring at the centre of mass, over 100 s (well conditioned: the error grows about linearly).
scipy integrates the same equations written as plain numpy (checked against our compiled
right-hand side before timing). The reference is our DOP853 at rtol 1e-14 (its distance to
scipy's tightest run is printed too).

For each target final error (max-norm over the 13 state components) each solver is run on an
rtol ladder; the loosest rtol that meets the target is timed (best of --repeat). Prints wall
times, steps, evaluations and the ratio scipy / ours (target >= 20). Compile time is reported
apart: the first call in this process (compile or cache load), and a cold compile in a fresh
process with an empty numba cache.

    python benchmarks/bench_integrators.py [--repeat 3] [--duration 100]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from _scipy_model import check_same_equations
from _scipy_model import numpy_rhs as numpy_rhs_of
from scipy.integrate import solve_ivp

from massprops.dynamics.model import (
    Gravity,
    InitialState,
    OutputSettings,
    PointForce,
    RigidBody,
    Scene,
    Spring,
    TimeSettings,
    Torque,
)
from massprops.dynamics.program import compile_forces
from massprops.dynamics.simulate import simulate

MASS, MOMENTS = 2.0, np.array([1.0, 2.0, 3.0])
G = np.array([0.0, 0.0, -9.81])
TORQUE_BODY = np.array([0.01, 0.005, 0.02])
FORCE, FORCE_ARM = np.array([0.05, 0.0, 0.02]), np.array([0.0, 0.05, 0.0])
ANCHOR, K, SPRING_ARM = np.array([0.0, 0.0, 1.0]), 6.0, np.zeros(3)
Y0 = np.array([0.1, 0.0, 0.2, 0.0, 0.3, 0.0, 0.98006658, 0.0, 0.11920292, 0.15893723,
               0.05, -0.03, 2.0])
Y0[6:10] /= np.linalg.norm(Y0[6:10])
TARGETS = (1e-6, 1e-10)
LADDER = 10.0 ** -np.arange(3.0, 14.01, 0.5)


def scene() -> Scene:
    body = RigidBody(MASS, MOMENTS, np.eye(3), np.zeros(3), 1.0)
    forces = (Gravity(G), Torque(TORQUE_BODY, "body"), PointForce(FORCE, point=FORCE_ARM),
              Spring(ANCHOR, K, point=SPRING_ARM))
    return Scene(body, InitialState(), forces, TimeSettings(1.0), OutputSettings())


def program():
    return compile_forces(scene())


numpy_rhs = numpy_rhs_of(scene())
"""The same Newton-Euler equations in plain numpy (benchmarks/_scipy_rhs.py, shared with
bench_precision.py and bench_simulate.py); checked against the compiled one before timing."""


def ours(p, rtol: float, duration: float):
    """(final state, steps, evaluations, wall s) of our dop853 (on the systems engine, as
    `simulate` runs it: the main run's wall time, no error estimate), the state in Y0's layout
    [r, v, q, ω body] (the body's principal axes are its body axes)."""
    start = InitialState(Y0[0:3], Y0[6:10], Y0[3:6], Y0[10:13], "body")
    sc = dataclasses.replace(scene(), initial=start, time=TimeSettings(duration))
    res = simulate(sc, integrator="dop853", rtol=rtol, estimate=False)
    tr = res.trajectory
    y = np.concatenate([tr.position[-1], tr.velocity[-1], tr.orientation[-1],
                        tr.angular_velocity_body[-1]])
    return canonical(y), res.steps, res.evaluations, res.wall_time_s


def scipy_dop853(rtol: float, duration: float):
    scale = np.concatenate([[np.abs(Y0[0:3]).max()] * 3, [np.abs(Y0[3:6]).max()] * 3, [1.0] * 4,
                            [np.abs(Y0[10:13]).max()] * 3])
    start = time.perf_counter()
    sol = solve_ivp(numpy_rhs, (0.0, duration), Y0, method="DOP853", rtol=rtol,
                    atol=rtol * scale)
    wall = time.perf_counter() - start
    y = sol.y[:, -1].copy()
    y[6:10] /= np.linalg.norm(y[6:10])
    return canonical(y), sol.t.size - 1, sol.nfev, wall


def canonical(y: np.ndarray) -> np.ndarray:
    """``y`` with its quaternion's scalar part >= 0: q and -q are one rotation, and the two
    solvers' final states are compared component by component."""
    if y[6] < 0:
        y[6:10] *= -1
    return y


def at_target(run, reference, target, repeat):
    """Loosest rtol of the ladder meeting the target; (rtol, error, steps, nfev, best wall)."""
    for rtol in LADDER:
        if rtol < 2.3e-14:  # scipy refuses rtol below 100 eps
            break
        y, steps, nfev, _ = run(rtol)
        error = np.abs(y - reference).max()
        if error <= target:
            wall = min(run(rtol)[3] for _ in range(repeat))
            return rtol, error, steps, nfev, wall
    return None


def cold_compile_seconds() -> float:
    """First call in a fresh process with an empty numba cache (so: a real compile)."""
    code = ("import sys, time; sys.path.insert(0, 'benchmarks'); s = time.perf_counter(); "
            "import bench_integrators as b; b.ours(b.program(), 1e-6, 1.0); "
            "print(time.perf_counter() - s)")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        out = subprocess.run([sys.executable, "-c", code], env=env, cwd=root, check=True,
                             capture_output=True, text=True)
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--duration", type=float, default=100.0)
    parser.add_argument("--no-cold", action="store_true", help="skip the cold-compile timing")
    args = parser.parse_args()
    p = program()
    check_same_equations(scene())
    start = time.perf_counter()
    ours(p, 1e-6, 1e-3)
    first_call = time.perf_counter() - start
    reference = ours(p, 1e-14, args.duration)[0]
    scipy_tight = scipy_dop853(2.3e-14, args.duration)[0]
    print(f"problem: torqued body, {args.duration:g} s; reference = our dop853 at rtol 1e-14 "
          f"(scipy at 2.3e-14 differs by {np.abs(scipy_tight - reference).max():.2e})")
    print(f"first call in this process (compile or cache load): {first_call:.2f} s")
    if not args.no_cold:
        print(f"cold compile (fresh process, empty numba cache):    {cold_compile_seconds():.2f} s")
    print(f"{'target':>8} {'solver':>8} {'rtol':>9} {'error':>9} {'steps':>7} {'nfev':>8} "
          f"{'wall s':>9}")
    for target in TARGETS:
        a = at_target(lambda rtol: ours(p, rtol, args.duration), reference, target, args.repeat)
        b = at_target(lambda rtol: scipy_dop853(rtol, args.duration), reference, target,
                      args.repeat)
        for label, row in (("massprops", a), ("scipy", b)):
            if row is None:
                print(f"{target:8.0e} {label:>8}  target not reached on the rtol ladder")
                continue
            rtol, error, steps, nfev, wall = row
            print(f"{target:8.0e} {label:>8} {rtol:9.2e} {error:9.2e} {steps:7d} {nfev:8d} "
                  f"{wall:9.4f}")
        if a and b:
            print(f"{target:8.0e}    ratio scipy / massprops: {b[4] / a[4]:.0f}x (target >= 20x)")


if __name__ == "__main__":
    main()
