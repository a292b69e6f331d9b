"""Work-precision of massprops' integrators against scipy's solve_ivp, side by side in one run.

Three scenes (written as YAML in a temporary folder and read by massprops' own scene parser):
a torqued asymmetric body over 30 s, a torque-free spinning body under gravity (20 s; massprops
has its closed form), and a stiff overdamped spring-damper holding a spinning body (2 s).

- massprops: ``massprops.dynamics.precision.precision(scene, integrators=[name])``, one call per
  integrator (so that one failing ladder cannot hide the others), exactly what
  ``massprops precision`` reports: wall time = best of repeats of the compiled run, warm-up apart.
- scipy: ``solve_ivp`` with RK45, DOP853, Radau and LSODA over rtol 1e-3 ... 1e-12, on the same
  equations written in numpy (``_scipy_model``, checked against the compiled right-hand side),
  state [r, v, q, omega'] in the principal frame like massprops, atol = rtol × each block's
  largest magnitude along the reference (massprops' own per-block rule, taken a priori), Jacobians
  by scipy's finite differences. Nothing renormalises the quaternion inside scipy. Wall time =
  the solve_ivp calls only, best of repeats by massprops' rule (repeat until MIN_TIMED_S used,
  at most 5 runs). A ladder stops at the reference's accuracy, after a run longer than
  --max-run-s, or at the evaluation budget --max-nfev.

Both are measured with ``massprops.dynamics.accuracy.state_error`` (the contract's one-number
error over 11 sample times) against the SAME reference ``precision.reference_run`` returns.
Per scene, a table: for each integrator, the error reached within 1 ms and 10 ms and the time to
reach 1e-8, read off its work-precision curve (its Pareto front: the best error within a given
time), interpolated log-log between measured runs, never extrapolated ("—": out of reach).

    python benchmarks/bench_precision.py [--plot DIR] [--docs] [--scenes torqued,free,stiff]
        [--scene-file sample_scenes/X.yaml [--ours dop853,implicit]]
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import _scipy_model as peer  # the script's folder is on sys.path: these are its neighbours
import numpy as np
from _scenes import SCENES, SceneCase
from _workprecision_plot import plot_scene

from massprops.dynamics.accuracy import Scales, state_error
from massprops.dynamics.frames import to_world
from massprops.dynamics.integrators import INTEGRATORS
from massprops.dynamics.precision import (
    AT_REFERENCE,
    MIN_TIMED_S,
    SAMPLES,
    applicable,
    precision,
    reference_run,
)
from massprops.dynamics.program import compile_forces
from massprops.dynamics.scene import load_scene

SCIPY_METHODS = ("RK45", "DOP853", "Radau", "LSODA")
SCIPY_RTOLS = tuple(10.0**-k for k in range(3, 13))
BUDGETS_S = (1e-3, 1e-2)
TARGET = 1e-8
REPO = Path(__file__).resolve().parent.parent


@dataclass
class Curve:
    """One integrator's runs: points (wall s, error) of the runs that did not diverge; note says
    what else happened (diverged rungs, budget, failure)."""

    label: str
    family: str  # "massprops" | "scipy"
    method: str
    points: list[tuple[float, float]] = field(default_factory=list)
    note: str = ""


# --- reading a curve ------------------------------------------------------------------------------
def pareto(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """The best error reachable within each time: points sorted by time, each kept only if its
    error beats every faster one."""
    front: list[tuple[float, float]] = []
    for wall, err in sorted(points):
        if not front or err < front[-1][1]:
            front.append((wall, err))
    return front


def _log_interp(x, x0, x1, y0, y1) -> float:
    """y at x on the straight line through (x0, y0), (x1, y1) in log-log axes."""
    if x1 == x0:
        return min(y0, y1)
    s = (math.log(x) - math.log(x0)) / (math.log(x1) - math.log(x0))
    return math.exp(math.log(y0) + s * (math.log(y1) - math.log(y0)))


def error_within(points, budget_s: float) -> float | None:
    """Error reached within ``budget_s`` (None if even the fastest run takes longer)."""
    front = pareto(points)
    if not front or front[0][0] > budget_s:
        return None
    for (t0, e0), (t1, e1) in zip(front, front[1:]):
        if t0 <= budget_s < t1:
            return _log_interp(budget_s, t0, t1, max(e0, 1e-300), max(e1, 1e-300))
    return front[-1][1]  # the budget covers every run: the curve's best


def time_to(points, target: float) -> float | None:
    """Wall time to reach error ``target`` (None if no run reached it)."""
    front = pareto(points)
    for i, (wall, err) in enumerate(front):
        if err <= target:
            if i == 0:
                return wall
            (t0, e0) = front[i - 1]
            return _log_interp(target, e0, max(err, 1e-300), t0, wall)
    return None


# --- running both families ------------------------------------------------------------------------
def our_curves(scene, case: SceneCase) -> tuple[list[Curve], dict | None]:
    """massprops' ladders, one precision() call per integrator; (curves, reference)."""
    names = case.ours or tuple(applicable(scene, compile_forces(scene), INTEGRATORS))
    curves, reference = [], None
    for name in names:
        curve = Curve(f"massprops {name}", "massprops", name)
        try:
            report = precision(scene, integrators=[name])
        except Exception as exc:  # a benchmark reports a failing ladder and goes on
            curve.note = f"ladder failed: {type(exc).__name__}: {exc}"
            curves.append(curve)
            continue
        reference = report.reference
        diverged = 0
        for run in report.runs:
            if run.error is None:
                diverged += 1
            else:
                curve.points.append((run.wall_time_s, max(run.error, 1e-17)))
        if diverged:
            curve.note = f"{diverged} rung(s) diverged"
        curves.append(curve)
    return curves, reference


def scipy_run(scene, program, method, rtol, t_out, blocks, truth, scales, max_nfev):
    """(best wall s, error or None, nfev, status) of one rung, timed by massprops' rule."""
    first = peer.solve(scene, method, rtol, t_out, blocks, max_nfev)
    if first.status != "ok":
        return first.wall, None, first.nfev, first.status
    traj = to_world(scene, first.t, first.y, program, with_energy=False)
    error = state_error(traj, truth, scales)
    wall, spent, tries = first.wall, first.wall, 1
    while spent < MIN_TIMED_S and tries < 5:
        again = peer.solve(scene, method, rtol, t_out, blocks, max_nfev)
        wall, spent, tries = min(wall, again.wall), spent + again.wall, tries + 1
    return wall, (error if math.isfinite(error) else None), first.nfev, "ok"


def scipy_curves(scene, program, truth, floor, max_nfev, max_run_s) -> list[Curve]:
    """solve_ivp ladders of every method in SCIPY_METHODS."""
    t_out = np.linspace(0.0, scene.time.duration, SAMPLES + 1)
    scales = Scales.of(scene.body.size, truth, scene.time.duration)
    blocks = peer.block_scales(scene, truth)
    curves = []
    for method in SCIPY_METHODS:
        curve = Curve(f"scipy {method}", "scipy", method)
        for rtol in SCIPY_RTOLS:
            if rtol < peer.SCIPY_MIN_RTOL:
                break
            wall, error, nfev, status = scipy_run(scene, program, method, rtol, t_out, blocks,
                                                  truth, scales, max_nfev)
            if status == "budget":
                curve.note = f"rtol {rtol:.0e} and tighter: over {max_nfev:.0e} evaluations"
                break
            if error is None:
                curve.note = f"rtol {rtol:.0e} failed: {status}"
                break
            curve.points.append((wall, max(error, 1e-17)))
            if error <= floor:
                break
            if wall > max_run_s and rtol != SCIPY_RTOLS[-1]:
                curve.note = f"stopped after rtol {rtol:.0e} ({wall:.1f} s > {max_run_s:g} s)"
                break
        curves.append(curve)
    return curves


# --- reporting ------------------------------------------------------------------------------------
def _fmt(x: float | None, unit: str = "") -> str:
    if x is None:
        return "—"
    if unit == "s":
        return f"{x * 1e3:.3g} ms" if x < 1 else f"{x:.3g} s"
    return f"{x:.1e}"


def print_table(name: str, case: SceneCase, reference: dict, curves: list[Curve]) -> None:
    print(f"\n== {name}: {case.title}")
    setting = "" if reference["setting"] is None else f" {reference['setting']:g}"
    print(f"   reference: {reference['integrator']}{setting}, accuracy "
          f"{reference['accuracy']:.1e} ({reference['checked']})")
    if case.left_out:
        print(f"   {case.left_out}")
    head = "".join(f"{'err in ' + _fmt(b, 's'):>14}" for b in BUDGETS_S)
    print(f"   {'integrator':<20}{head}{'time to ' + format(TARGET, '.0e'):>16}"
          f"{'best error':>12}{'runs':>6}  notes")
    for c in curves:
        cells = "".join(f"{_fmt(error_within(c.points, b)):>14}" for b in BUDGETS_S)
        best = min((e for _, e in c.points), default=None)
        print(f"   {c.label:<20}{cells}{_fmt(time_to(c.points, TARGET), 's'):>16}"
              f"{_fmt(best):>12}{len(c.points):>6}  {c.note}")
    _print_ratio(curves)


def _print_ratio(curves: list[Curve]) -> None:
    """Time to TARGET: fastest massprops vs fastest scipy integrator, then the same method."""
    reach = {c.label: time_to(c.points, TARGET) for c in curves}
    best = {}
    for family in ("massprops", "scipy"):
        times = [(reach[c.label], c.label) for c in curves
                 if c.family == family and reach[c.label] is not None]
        best[family] = min(times) if times else None
    ours, theirs = best["massprops"], best["scipy"]
    if ours and theirs:
        print(f"   to {TARGET:.0e}: fastest {ours[1]} {_fmt(ours[0], 's')} vs fastest "
              f"{theirs[1]} {_fmt(theirs[0], 's')}: {theirs[0] / ours[0]:.0f}x")
    else:
        print(f"   to {TARGET:.0e}: not reached by "
              + " and ".join(f for f in best if best[f] is None))
    a, b = reach.get("massprops dop853"), reach.get("scipy DOP853")
    if a and b:
        print(f"   to {TARGET:.0e}, same method: massprops dop853 {_fmt(a, 's')} vs scipy "
              f"DOP853 {_fmt(b, 's')}: {b / a:.0f}x")


def run_scene(name: str, case: SceneCase, path: Path, args) -> tuple[dict, list[Curve]]:
    """Both families on the scene file at ``path``; prints its table."""
    scene = load_scene(path)
    peer.check_same_equations(scene)
    program = compile_forces(scene)
    start = time.perf_counter()
    ours, reported = our_curves(scene, case)
    t_ours = time.perf_counter() - start
    truth, reference = reference_run(scene, program, INTEGRATORS, scene.time.duration / SAMPLES)
    if reported is not None and reported["accuracy"] != reference["accuracy"]:
        raise SystemExit(f"{name}: the reference differs from the one precision() used")
    start = time.perf_counter()
    theirs = scipy_curves(scene, program, truth, AT_REFERENCE * reference["accuracy"],
                          args.max_nfev, args.max_run_s)
    t_theirs = time.perf_counter() - start
    print_table(name, case, reference, ours + theirs)
    print(f"   (benchmark time: massprops ladders {t_ours:.0f} s, scipy ladders {t_theirs:.0f} s)")
    return reference, ours + theirs


def _cases(args, folder: Path, parser) -> list[tuple[str, SceneCase, Path]]:
    """(name, case, scene file) of the built-in scenes asked for, then of --scene-file ones."""
    names = [s.strip() for s in args.scenes.split(",") if s.strip()]
    unknown = sorted(set(names) - set(SCENES))
    if unknown:
        parser.error(f"unknown scene(s) {', '.join(unknown)}; choose from {', '.join(SCENES)}")
    out = []
    for name in names:
        path = folder / f"{name}.yaml"
        path.write_text(SCENES[name].text(), encoding="utf-8")
        out.append((name, SCENES[name], path))
    ours = tuple(args.ours.split(",")) if args.ours else None
    for path in args.scene_file:
        if not path.is_file():
            parser.error(f"--scene-file {path}: no such file")
        out.append((path.stem, SceneCase(str(path), "", 0.0, ours=ours), path))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plot", type=Path, help="write one work-precision PNG per scene here")
    parser.add_argument("--docs", action="store_true",
                        help="write docs/work_precision.png (the torqued scene)")
    parser.add_argument("--scenes", default=",".join(SCENES),
                        help=f"comma-separated subset of {', '.join(SCENES)} ('' for none)")
    parser.add_argument("--scene-file", type=Path, action="append", default=[],
                        help="also run this scene file (e.g. sample_scenes/*.yaml); repeatable")
    parser.add_argument("--ours", default="",
                        help="massprops integrators for --scene-file scenes, comma-separated "
                             "(default: all applicable)")
    parser.add_argument("--max-nfev", type=int, default=300_000,
                        help="evaluation budget of one scipy run")
    parser.add_argument("--max-run-s", type=float, default=5.0,
                        help="a scipy ladder stops after a run longer than this")
    args = parser.parse_args()
    if args.plot:
        args.plot.mkdir(parents=True, exist_ok=True)
    print(f"error metric: massprops.dynamics.accuracy.state_error over {SAMPLES + 1} samples; "
          "times: best of repeats, compiled warm-up excluded")
    with tempfile.TemporaryDirectory() as tmp:
        for name, case, path in _cases(args, Path(tmp), parser):
            reference, curves = run_scene(name, case, path, args)
            title = f"{name}: {case.title}"
            if args.plot:
                plot_scene(curves, reference, title, args.plot / f"work_precision_{name}.png",
                           BUDGETS_S, TARGET)
            if args.docs and name == "torqued" and case is SCENES["torqued"]:
                (REPO / "docs").mkdir(exist_ok=True)
                plot_scene(curves, reference, title, REPO / "docs" / "work_precision.png",
                           BUDGETS_S, TARGET)


if __name__ == "__main__":
    main()
