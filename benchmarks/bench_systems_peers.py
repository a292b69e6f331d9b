"""Systems against their peers (issue 17 §5): the double pendulum and the four-bar of
sample_scenes/ in massprops (the public API: massprops.load_scene, massprops.simulate), MuJoCo,
Pinocchio + scipy and exudyn, each against a 30-digit reference that shares nothing with
massprops (tests/system_truth.py: the equations derived by hand, integrated in mpmath).

Errors: the double pendulum's joint angles (shoulder, elbow) at t = 10 s, the larger of the two;
the four-bar's crank angle (joint A) at t = 5 s; in rad. Times: wall time in process, warm, best
of repeats (until 0.2 s is used, at most 5); the first call apart, as "set-up" (MuJoCo's
compile, Pinocchio's model, exudyn's assembly; massprops' import, scene and what its first call
costs beyond a warm one). Per tool and method, the time to reach 1e-6 and 1e-10 is read off its
time-accuracy front, interpolated log-log between the settings around the target ("≤" when its
fastest setting already does better; "not reached" when none does); "/ massprops" is that time
over massprops' main run's (below 1: the peer is faster). A peer's ladder stops after a run
longer than --max-run-s; massprops' runs to rtol 1e-12 unless a call takes 15 times that.

- massprops: simulate(scene, rtol=...) at rtol 1e-3 ... 1e-12 (its own DOP853 with projection
  onto the loop); "call" is the whole simulate() call, which also runs the error estimate's
  companion at rtol/20, "run" its main integration (result.wall_time_s).
- MuJoCo: RK4, Euler (its default) and implicitfast at fixed steps; the four-bar's loop an
  equality connect as stiff as MuJoCo allows (solref timeconst = 2 × timestep, the refsafe
  floor; solimp 0.9999): soft, so its error has a floor; the loop residual is printed.
- Pinocchio: ABA (double pendulum) or the four-bar in its crank angle (the other joints closed
  by Newton, accelerations from the KKT system of CRBA, the non-linear effects and the loop
  point's Jacobian), scipy solve_ivp DOP853 at rtol = atol 1e-3 ... 1e-13.
- exudyn: a kinematic tree in joint coordinates; explicit RK44, RK67 and DOPRI5 on the
  double pendulum; the four-bar's loop a spherical joint (x, z) that only its implicit solvers
  take (generalized-α with ρ∞ = 1, and its index-2 trapezoidal rule) at fixed steps.

The reference: benchmarks/_systems_reference.json (made by --recompute-reference, ~80 s: GBS
extrapolation at 30 digits, and a second run at another step/order whose difference is its
error bar; the GBS code was checked against mpmath.odefun's Taylor method at t = 1 s: 1e-26 on
the double pendulum, 2e-20 on the four-bar, at these settings).

    python benchmarks/bench_systems_peers.py [--tools massprops,mujoco,pinocchio,exudyn]
        [--problems double_pendulum,four_bar] [--max-run-s 4] [--recompute-reference]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))  # the independent truth lives with the tests
import _peer_models as peers  # noqa: E402  (the script's folder is on sys.path)
import system_truth as truth  # noqa: E402

REFERENCE = Path(__file__).resolve().parent / "_systems_reference.json"
PROBLEMS = ("double_pendulum", "four_bar")
TARGETS = (1e-6, 1e-10)
INSTALL = {"mujoco": "pip install mujoco", "pinocchio": "pip install pin",
           "exudyn": "pip install exudyn"}


def reference(recompute: bool) -> dict:
    """{problem: {"angles": [...], "bar": error bar}} from the cache, or made (and cached)."""
    if REFERENCE.exists() and not recompute:
        data = json.loads(REFERENCE.read_text())
    else:
        import mpmath as mp  # only to write the numbers out at 30 digits

        start = time.perf_counter()
        dp = truth.double_pendulum_reference(10.0, steps_per_s=40, levels=12)
        dp2 = truth.double_pendulum_reference(10.0, steps_per_s=20, levels=14)
        fb = truth.four_bar_reference(5.0, steps_per_s=20, levels=14)
        fb2 = truth.four_bar_reference(5.0, steps_per_s=20, levels=12)
        with mp.workdps(30):
            data = {
                "made_by": "python benchmarks/bench_systems_peers.py --recompute-reference "
                           f"({time.perf_counter() - start:.0f} s): tests/system_truth.py at "
                           "30 digits, GBS 40 steps/s order 24 (double pendulum) and 20 "
                           "steps/s order 28 (four-bar); the bar is the distance to a run at "
                           "20 steps/s order 28 and 24 respectively",
                "double_pendulum": {"t": 10.0, "joints": ["shoulder", "elbow"],
                                    "angles": [mp.nstr(v, 30) for v in dp],
                                    "bar": float(max(abs(a - b) for a, b in zip(dp, dp2)))},
                "four_bar": {"t": 5.0, "joints": ["A"], "angles": [mp.nstr(fb, 30)],
                             "bar": float(abs(fb - fb2))}}
        REFERENCE.write_text(json.dumps(data, indent=1) + "\n")
    return {p: {"angles": np.array([float(v) for v in data[p]["angles"]]),
                "bar": data[p]["bar"], "joints": data[p]["joints"]} for p in PROBLEMS}


def best_of(run) -> tuple[float, object]:
    """(best wall s, last output): repeats until 0.2 s is used, at most 5."""
    times, used, out = [], 0.0, None
    while len(times) < 5 and (not times or used < 0.2):
        start = time.perf_counter()
        out = run()
        times.append(time.perf_counter() - start)
        used += times[-1]
    return min(times), out


class Ladder:
    """One tool's method over its settings: rows of (setting, time s, error, note)."""

    def __init__(self, tool: str, method: str) -> None:
        self.tool, self.method, self.rows, self.first = tool, method, [], None

    def add(self, setting: str, seconds: float, error: float, note: str = "") -> None:
        self.rows.append((setting, seconds, error, note))
        print(f"  {self.tool} {self.method} {setting}: {seconds * 1e3:.3g} ms, error "
              f"{error:.2g} {note}", flush=True)

    def time_to(self, target: float) -> str:
        front, best = [], math.inf
        for _, seconds, error, _ in sorted(self.rows, key=lambda r: r[1]):
            if error < best:
                best = error
                front.append((seconds, error))
        for k, (seconds, error) in enumerate(front):
            if error <= target:
                if k == 0:
                    return f"≤ {_ms(seconds)}"
                (t0, e0), (t1, e1) = front[k - 1], (seconds, error)
                x = math.log(target / e0) / math.log(e1 / e0)
                return _ms(t0 * (t1 / t0) ** x)
        return "not reached"


def _ms(seconds: float) -> str:
    return f"{seconds * 1e3:.3g} ms" if seconds < 1 else f"{seconds:.3g} s"


def _error(problem: str, angles, ref) -> float:
    angles = np.asarray(angles, float)
    if not np.all(np.isfinite(angles)):
        return math.inf
    return float(np.abs(angles - ref["angles"]).max())


def _sample(problem: str) -> dict:
    return yaml.safe_load((ROOT / "sample_scenes" / f"{problem}.yaml").read_text())


def _start(problem: str, sample: dict):
    """Tree coordinates and rates at t = 0 (the four-bar's others follow from the loop)."""
    if problem == "double_pendulum":
        return [float(v) for v in sample["initial"]["positions"].values()], [0.0, 0.0]
    rate = float(sample["initial"]["rates"]["A"])
    return [0.0, 0.0, 0.0], list(peers.four_bar_rates(sample, rate))


def run_massprops(problem, ref, budget):
    import massprops  # the library under test, through its public API

    path = ROOT / "sample_scenes" / f"{problem}.yaml"
    start = time.perf_counter()
    scene = massprops.load_scene(path)
    duration = scene.time.duration
    massprops.simulate(scene, rtol=1e-3, every=duration)
    call, run = Ladder("massprops", "dop853 (call)"), Ladder("massprops", "dop853 (run)")
    first = time.perf_counter() - start  # import, scene, first call at rtol 1e-3
    for k in range(3, 13):
        seconds, result = best_of(lambda k=k: massprops.simulate(scene, rtol=10.0 ** -k,
                                                                 every=duration))
        joints = result.as_dict()["final"]["joints"]
        error = _error(problem, [joints[j]["coordinates"][0] for j in ref["joints"]], ref)
        estimate = result.as_dict()["diagnostics"]["error_estimate"]
        call.add(f"rtol 1e-{k}", seconds, error, f"its estimate {estimate:.2g}")
        run.add(f"rtol 1e-{k}", result.wall_time_s, error)
        if seconds > 15 * budget:  # the tool under test: its whole ladder unless very slow
            break
    call.first = max(first - call.rows[0][1], 0.0)  # what the first call costs beyond a warm one
    return [call, run]


def run_mujoco(problem, ref, budget):
    sample = _sample(problem)
    q0, v0 = _start(problem, sample)
    ladders = []
    for method, counts in (("RK4", (1e3, 2e3, 5e3, 1e4, 2e4, 5e4, 1e5, 2e5, 5e5, 1e6, 2e6)),
                           ("Euler", (1e3, 1e4, 1e5, 1e6)),
                           ("implicitfast", (1e3, 1e4, 1e5, 1e6))):
        ladder = Ladder("MuJoCo", method)
        for steps in map(int, counts):
            compile_s, run = peers.mujoco_runner(sample, q0, v0, method, steps)
            ladder.first = ladder.first or compile_s
            seconds, (q, residual) = best_of(run)
            note = f"loop residual {residual:.2g} m" if problem == "four_bar" else ""
            ladder.add(f"{steps} steps", seconds, _error(problem, q[:len(ref['angles'])], ref),
                       note)
            if seconds > budget:
                break
        ladders.append(ladder)
    return ladders


def run_pinocchio(problem, ref, budget):
    from scipy.integrate import solve_ivp

    sample = _sample(problem)
    q0, v0 = _start(problem, sample)
    duration = float(sample["time"]["duration"])
    start = time.perf_counter()
    model, frame, _, target = peers.pinocchio_model(sample)
    loop = None
    if problem == "four_bar":
        loop = peers.PinocchioLoop(model, frame, target)
        f, y0 = loop.rhs(), np.array([q0[0], v0[0]])
    else:
        f, y0 = peers.pinocchio_chain_rhs(model), np.array([*q0, *v0])
    f(0.0, y0)
    ladder = Ladder("Pinocchio", "ABA + scipy DOP853" if loop is None
                    else "crank angle (Newton, KKT) + scipy DOP853")
    ladder.first = time.perf_counter() - start

    def run(rtol):
        if loop is not None:  # Newton starts from the assembly pose again, not the last run's end
            loop.reset()
        return solve_ivp(f, (0.0, duration), y0, method="DOP853", rtol=rtol, atol=rtol)

    for k in range(3, 14):
        seconds, sol = best_of(lambda k=k: run(10.0 ** -k))
        ladder.add(f"rtol 1e-{k}", seconds, _error(problem, sol.y[:len(ref["angles"]), -1], ref),
                   f"{sol.nfev} evaluations")
        if seconds > budget:
            break
    return [ladder]


def run_exudyn(problem, ref, budget):
    from _peer_exudyn import exudyn_runner

    sample = _sample(problem)
    q0, v0 = _start(problem, sample)
    if problem == "double_pendulum":
        plan = [("RK44", [(n, None) for n in (1e3, 3e3, 1e4, 3e4, 1e5, 3e5)]),
                ("RK67", [(n, None) for n in (1e2, 3e2, 1e3, 3e3, 1e4, 3e4)]),
                ("DOPRI5", [(100, 10.0 ** -k) for k in range(4, 14)]),
                ("GeneralizedAlpha", [(n, None) for n in (1e3, 1e4, 1e5)])]
    else:
        plan = [(s, [(n, None) for n in (1e3, 3e3, 1e4, 3e4, 1e5)])
                for s in ("GeneralizedAlpha", "TrapezoidalIndex2")]
    ladders = []
    for solver, settings in plan:
        ladder = Ladder("exudyn", solver + (" (ρ∞ = 1)" if solver == "GeneralizedAlpha" else ""))
        for steps, rtol in settings:
            build, run = exudyn_runner(sample, q0, v0, solver, int(steps), rtol)
            ladder.first = ladder.first or build
            seconds, (q, _) = best_of(run)
            ladder.add(f"rtol {rtol:.0e}" if rtol else f"{int(steps)} steps", seconds,
                       _error(problem, q[:len(ref["angles"])], ref))
            if seconds > budget:
                break
        ladders.append(ladder)
    return ladders


RUNNERS = {"massprops": run_massprops, "mujoco": run_mujoco, "pinocchio": run_pinocchio,
           "exudyn": run_exudyn}


def summary(problem: str, ladders: list[Ladder], ref: dict) -> None:
    base = {t: next((lad.time_to(t) for lad in ladders if lad.method == "dop853 (run)"), None)
            for t in TARGETS}
    print(f"\n### {problem} (reference error bar {ref['bar']:.1g} rad)\n")
    print("| tool | method | set-up | best error (its time) | time to 1e-6 | / massprops | "
          "time to 1e-10 | / massprops |\n|---|---|---|---|---|---|---|---|")
    for lad in ladders:
        best = min(lad.rows, key=lambda r: (r[2], r[1]))
        cells = []
        for t in TARGETS:
            reach = lad.time_to(t)
            cells += [reach, _ratio(reach, base[t])]
        setup = "—" if lad.first is None else _ms(lad.first)
        print(f"| {lad.tool} | {lad.method} | {setup} | {best[2]:.2g} "
              f"({_ms(best[1])}) | " + " | ".join(cells) + " |")


def _ratio(reach: str, base: str | None) -> str:
    seconds = _seconds(reach)
    ours = _seconds(base) if base else None
    return f"{seconds / ours:.2g}" if seconds and ours else "—"


def _seconds(text: str) -> float | None:
    if not text or text == "not reached":
        return None
    value, unit = text.replace("≤ ", "").split()
    return float(value) * (1e-3 if unit == "ms" else 1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tools", default="massprops,mujoco,pinocchio,exudyn")
    parser.add_argument("--problems", default=",".join(PROBLEMS))
    parser.add_argument("--max-run-s", type=float, default=4.0)
    parser.add_argument("--recompute-reference", action="store_true")
    args = parser.parse_args()
    refs = reference(args.recompute_reference)
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo")
                if line.startswith("model name")), platform.processor()) \
        if os.path.exists("/proc/cpuinfo") else platform.processor()
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; {cpu}, {os.cpu_count()} "
          f"cores, load {os.getloadavg()[0]:.1f}; Python {platform.python_version()}")
    results = {p: [] for p in args.problems.split(",")}
    for tool in args.tools.split(","):
        module = "pinocchio" if tool == "pinocchio" else tool
        try:
            __import__(module)
        except ImportError:
            print(f"{tool}: not installed, skipped ({INSTALL.get(tool, 'pip install ' + tool)})")
            continue
        for problem in results:
            print(f"{tool} on {problem}:", flush=True)
            results[problem] += RUNNERS[tool](problem, refs[problem], args.max_run_s)
    for problem, ladders in results.items():
        summary(problem, ladders, refs[problem])


if __name__ == "__main__":
    main()
