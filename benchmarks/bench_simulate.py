"""Speed of `massprops simulate` against scipy's solve_ivp(method="DOP853") at equal final error.

(a) In process: the torqued asymmetric body of bench_precision.py over 100 s. Our dop853 (the
    engine `simulate` runs it on, the system of one body: ``systems.run.simulate_system``, its
    main run alone, warm-up apart) against solve_ivp DOP853 on the same
    equations (``_scipy_model``, checked against our compiled right-hand side), each at the rtol
    that brings its final error just under 1e-6 and 1e-10 (rtol is tuned by tolerance
    proportionality, a few runs each). Best of --repeat. Target: scipy / massprops >= 20.
    Compile time apart: the first call in this process (compile or cache load), and a cold
    compile in a fresh process with an empty numba cache.
(b) Whole processes: a fast-spinning torqued body with drag over 1000 s, where scipy's DOP853
    needs ~4e5 evaluations. ``python -m massprops simulate scene.yaml --json --quiet`` (its
    scene rtol; the process also runs its error-estimate companion at rtol/20 on the second
    core, as every simulate does) against ``python _scipy_process.py`` (numpy + scipy only)
    running solve_ivp DOP853 at the rtol whose final error matches ours (tuned in process first;
    the errors of both processes are then checked). Best of --repeat-process.
    Target: scipy / massprops >= 10.

Error: ``massprops.dynamics.accuracy.state_error`` (the contract's metric) at the final time,
against ``precision.reference_run`` (dop853 at rtol 1e-13, checked against 1e-12). scipy's atol is
rtol × each state block's largest magnitude along the reference (massprops' per-block rule).

    python benchmarks/bench_simulate.py [--part a|b|ab] [--repeat 5] [--repeat-process 3]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

import _scipy_model as peer  # the script's folder is on sys.path: these are its neighbours
import numpy as np
from _scenes import LONG_DRAG, SCENES

from massprops.dynamics.accuracy import ADAPTIVE_TIGHTENING, Scales, state_error
from massprops.dynamics.compiled.compiling import SYSTEM_ENTRIES, prepare
from massprops.dynamics.frames import to_world
from massprops.dynamics.integrators import INTEGRATORS
from massprops.dynamics.precision import reference_run
from massprops.dynamics.program import compile_forces, initial_principal_state
from massprops.dynamics.scene import load_scene
from massprops.dynamics.systems.one_body import as_system
from massprops.dynamics.systems.run import simulate_system

HERE = Path(__file__).resolve().parent
TARGETS = (1e-6, 1e-10)
SAMPLES = 10


def final_row(traj):
    """The last sample of a trajectory, as the fields state_error reads."""
    return SimpleNamespace(t=traj.t[-1:], position=traj.position[-1:],
                           orientation=traj.orientation[-1:], velocity=traj.velocity[-1:],
                           angular_velocity=traj.angular_velocity[-1:])


class Problem:
    """A scene with its reference: final errors of principal-frame end states, both solvers."""

    def __init__(self, path: Path):
        self.scene = load_scene(path)
        self.system = as_system(self.scene)
        peer.check_same_equations(self.scene)
        self.program = compile_forces(self.scene)
        self.t_out = np.linspace(0.0, self.scene.time.duration, SAMPLES + 1)
        self.truth, self.reference = reference_run(self.scene, self.program, INTEGRATORS,
                                                   self.scene.time.duration / SAMPLES)
        self.scales = Scales.of(self.scene.body.size, self.truth, self.scene.time.duration)
        self.blocks = peer.block_scales(self.scene, self.truth)

    def error_of(self, t: np.ndarray, y: np.ndarray) -> float:
        """Contract-metric error at the final time of principal-frame samples y (n, 13)."""
        traj = to_world(self.scene, t, y, self.program, with_energy=False)
        return state_error(final_row(traj), final_row(self.truth), self.scales)

    def ours(self, rtol: float) -> tuple[float, int, int, float]:
        """(error, steps, nfev, wall s) of our dop853 at ``rtol``: the body as the system of
        one body, as `simulate` runs it, without its estimate's companions."""
        run = simulate_system(self.system, integrator="dop853", rtol=rtol, estimate=False,
                              every=self.scene.time.duration / SAMPLES)
        body = run.samples
        last = SimpleNamespace(t=body.t[-1:], position=body.position[-1:, 0],
                               orientation=body.orientation[-1:, 0],
                               velocity=body.velocity[-1:, 0],
                               angular_velocity=body.angular_velocity[-1:, 0])
        return (state_error(last, final_row(self.truth), self.scales), run.steps,
                run.evaluations, run.wall_time_s)

    def scipy(self, rtol: float) -> tuple[float, int, int, float]:
        """(error, steps (unknown: 0), nfev, wall s) of solve_ivp DOP853 at ``rtol``."""
        run = peer.solve(self.scene, "DOP853", rtol, self.t_out, self.blocks)
        return self.error_of(run.t, run.y), 0, run.nfev, run.wall


def tune_rtol(run, target: float, rtol: float, tries: int = 8) -> tuple[float, tuple]:
    """The loosest rtol tried whose error is <= target, steered into (0.7, 1] × target by a
    secant on log error against log rtol (slope 1, tolerance proportionality, until two runs
    give their own); (rtol, run(rtol))."""
    best, seen = None, []
    for _ in range(tries):
        rtol = max(rtol, peer.SCIPY_MIN_RTOL)
        out = run(rtol)
        error = max(out[0], 1e-300)
        if error <= target and (best is None or rtol > best[0]):
            best = (rtol, out)
        if 0.7 * target < error <= target or (error <= target and rtol == peer.SCIPY_MIN_RTOL):
            break
        seen.append((np.log(rtol), np.log(error)))
        slope = 1.0
        if len(seen) >= 2 and seen[-1][0] != seen[-2][0]:
            slope = (seen[-1][1] - seen[-2][1]) / (seen[-1][0] - seen[-2][0])
            slope = min(2.0, max(0.5, slope))
        rtol *= np.exp(min(4.6, max(-4.6, (np.log(0.85 * target) - np.log(error)) / slope)))
    if best is None:
        raise SystemExit(f"target {target:g} not reached (last rtol {rtol:g}, error {error:g})")
    return best


def best_wall(run, rtol: float, repeat: int) -> float:
    return min(run(rtol)[3] for _ in range(repeat))


def cold_compile_seconds() -> float:
    """Warm-up of every systems entry (both step loops, the outputs, the right-hand side) in a
    fresh process with an empty numba cache: a real compile (about a minute)."""
    code = ("from massprops.dynamics.compiled.compiling import SYSTEM_ENTRIES, prepare; "
            "print(prepare(SYSTEM_ENTRIES))")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        out = subprocess.run([sys.executable, "-c", code], env=env,
                             cwd=HERE.parent, check=True, capture_output=True, text=True)
    return float(out.stdout.strip().splitlines()[-1])


def part_a(folder: Path, args) -> None:
    path = folder / "torqued100.yaml"
    path.write_text(SCENES["torqued"].text(duration=100.0), encoding="utf-8")
    first = prepare(SYSTEM_ENTRIES)
    problem = Problem(path)
    ref = problem.reference
    print(f"(a) in process: {SCENES['torqued'].title.replace('30 s', '100 s')}")
    print(f"    reference: {ref['integrator']} rtol {ref['setting']:g}, accuracy "
          f"{ref['accuracy']:.1e}; error = contract metric at t = 100 s")
    print(f"    our dop853, first call in this process (compile or cache load): "
          f"{first:.2f} s")
    if not args.no_cold:
        print(f"    our dop853, cold compile (fresh process, empty numba cache): "
              f"{cold_compile_seconds():.2f} s")
    print(f"    {'target':>7} {'solver':>10} {'rtol':>9} {'error':>9} {'steps':>7} {'nfev':>8} "
          f"{'wall s':>9}")
    for target in TARGETS:
        rows = {}
        for label, run in (("massprops", problem.ours), ("scipy", problem.scipy)):
            rtol, (error, steps, nfev, _) = tune_rtol(run, target, target / 10)
            rows[label] = best_wall(run, rtol, args.repeat)
            shown = f"{steps:7d}" if steps else f"{'—':>7}"
            print(f"    {target:7.0e} {label:>10} {rtol:9.2e} {error:9.2e} {shown} {nfev:8d} "
                  f"{rows[label]:9.5f}")
        print(f"    {target:7.0e}   ratio scipy / massprops: "
              f"{rows['scipy'] / rows['massprops']:.0f}x (target >= 20x)")


def run_process(cmd: list[str], repeat: int) -> tuple[float, str]:
    """(best wall s over ``repeat`` runs, stdout of that run) of a whole process."""
    best = (float("inf"), "")
    for _ in range(repeat):
        start = time.perf_counter()
        out = subprocess.run(cmd, cwd=HERE.parent, check=True, capture_output=True, text=True)
        best = min(best, (time.perf_counter() - start, out.stdout))
    return best


def part_b(folder: Path, args) -> None:
    path = folder / "long_drag.yaml"
    path.write_text(LONG_DRAG.text(), encoding="utf-8")
    problem = Problem(path)
    scene = problem.scene
    if problem.program.breakpoints(0.0, scene.time.duration).size:
        raise SystemExit("part (b) needs a scene without force windows (one solve_ivp call)")
    duration = scene.time.duration
    print(f"\n(b) whole processes: {LONG_DRAG.title}; massprops at the scene's rtol "
          f"{scene.time.rtol:g}")
    ours_s, stdout = run_process([sys.executable, "-m", "massprops", "simulate", str(path),
                                  "--json", "--quiet"], args.repeat_process)
    result = json.loads(stdout)
    final = result["final"]
    ours_traj = SimpleNamespace(t=np.array([duration]), position=np.array([final["position"]]),
                                orientation=np.array([final["orientation"]]),
                                velocity=np.array([final["velocity"]]),
                                angular_velocity=np.array([final["angular_velocity"]]))
    ours_error = state_error(ours_traj, final_row(problem.truth), problem.scales)
    print(f"    massprops: error {ours_error:.2e} (its own estimate "
          f"{result['diagnostics']['error_estimate']:.2e}), {result['evaluations']} "
          f"evaluations; run {result['wall_time_s']:.3f} s + numba cache load "
          f"{result['warmup_time_s']:.3f} s + error-estimate run, imports, I/O")
    main_s = min(problem.ours(scene.time.rtol)[3] for _ in range(3))
    companion_s = min(problem.ours(scene.time.rtol / ADAPTIVE_TIGHTENING)[3] for _ in range(3))
    print(f"    (in this process: its run {main_s:.3f} s, its companion at rtol / "
          f"{ADAPTIVE_TIGHTENING:g} {companion_s:.3f} s)")
    rtol, (error_in, _, nfev_in, _) = tune_rtol(problem.scipy, ours_error, 1e-10)
    print(f"    scipy DOP853 rtol tuned in process to {rtol:.3g}: error {error_in:.2e}, "
          f"{nfev_in} evaluations")
    task = {"rhs": peer.numpy_rhs(scene, 0.5 * duration).as_dict(),
            "y0": initial_principal_state(scene).tolist(), "duration": duration,
            "method": "DOP853", "rtol": rtol,
            "atol": peer.block_atol(rtol, problem.blocks).tolist()}
    task_path = folder / "problem.json"
    task_path.write_text(json.dumps(task), encoding="utf-8")
    theirs_s, stdout = run_process([sys.executable, str(HERE / "_scipy_process.py"),
                                    str(task_path)], args.repeat_process)
    out = json.loads(stdout)
    theirs_error = problem.error_of(np.array([0.0, duration]),
                                    np.array([task["y0"], out["y"]]))
    print(f"    scipy process: error {theirs_error:.2e}, {out['nfev']} evaluations, "
          f"solve_ivp {out['solve_s']:.2f} s (in the fastest process)")
    print(f"    errors scipy / massprops: {theirs_error / ours_error:.2f} (<= 1: scipy is at "
          f"least as accurate)")
    print(f"    best of {args.repeat_process}: massprops {ours_s:.2f} s, scipy {theirs_s:.2f} s: "
          f"ratio {theirs_s / ours_s:.1f}x (target >= 10x)")
    imports = run_process([sys.executable, "-c", "import massprops.cli, "
                           "massprops.dynamics.simulate"], args.repeat_process)[0]
    print(f"    for scale: python + importing massprops' CLI and dynamics alone: {imports:.2f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", default="ab", choices=["a", "b", "ab"])
    parser.add_argument("--repeat", type=int, default=5, help="in-process repeats (a)")
    parser.add_argument("--repeat-process", type=int, default=3, help="process repeats (b)")
    parser.add_argument("--no-cold", action="store_true", help="skip the cold-compile timing")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        if "a" in args.part:
            part_a(Path(tmp), args)
        if "b" in args.part:
            part_b(Path(tmp), args)


if __name__ == "__main__":
    main()
