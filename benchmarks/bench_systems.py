"""Systems of bodies (issue 17 §5): massprops' compiled step loop on the targets' problems.

Prints, in one process, after one warm-up run (compiling or loading the kernel is not timed):
- the four-bar (sample_scenes/four_bar.yaml, 5 s): the loosest rtol of a ladder whose final
  joint coordinates are within 1e-10 rad of a reference run (rtol 1e-13), and its wall time
  (target ≤ 5 ms);
- the double pendulum (sample_scenes/double_pendulum.yaml, 10 s): the error of its angles at 10 s
  against a reference at rtol 1e-14 over a ladder down to rtol 1e-13, its floor (the smallest
  error reached) and the wall time of the loosest rtol within 2× of it (target ≤ 20 ms);
- per right-hand-side evaluation and per step, chains of 2, 10 and 30 links (the chain10 sample's
  links: 0.2 m, 0.1 kg, hinges about y, top hinge at 0.5 rad, 2 s at rtol 1e-9), and the 30/10
  ratio (target ≤ 3.3; linear cost gives ≤ 3).
Wall times are the best of --repeat runs of the integration alone (`systems.integrate`, the call
`simulate` times as wall_time_s), outputs at the start and end only; "simulate" adds the set-up
and the outputs of one `simulate_system` call without the error estimate. The peer comparison
(MuJoCo, Pinocchio, exudyn) is another script's.

    PYTHONPATH=. python benchmarks/bench_systems.py [--repeat 7]
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from massprops.dynamics.systems.integrate import integrate  # noqa: E402
from massprops.dynamics.systems.run import (  # noqa: E402
    error_floors,
    load_windows,
    prepare,
    simulate_system,
)
from massprops.dynamics.systems.scene import load_system, parse_system  # noqa: E402

LADDER = tuple(10.0 ** (-k / 2) for k in range(16, 27))  # 1e-8 ... 1e-13 in half decades


def _run(scene, rtol: float, repeat: int):
    """(best wall s, run) of the integration alone, outputs at 0 and the end."""
    system, y0, _ = prepare(scene)
    t_out = np.array([0.0, scene.time.duration])
    floors, windows = error_floors(system, scene.time.duration), load_windows(scene)
    integrate(system, y0, t_out, rtol, floors, windows)  # warm: kernel loaded
    best, run = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        run = integrate(system, y0, t_out, rtol, floors, windows)
        best = min(best, time.perf_counter() - start)
    if run.failure is not None:
        raise SystemExit(f"{scene.source}: {run.failure}")
    return best, run, system


def _coordinates(run, system) -> np.ndarray:
    return run.y_out[-1, :system.nq]


def four_bar(repeat: int) -> None:
    scene = load_system(ROOT / "sample_scenes" / "four_bar.yaml")
    _, ref, system = _run(scene, 1e-13, 1)
    truth = _coordinates(ref, system)
    for rtol in LADDER:
        wall, run, system = _run(scene, rtol, repeat)
        error = float(np.abs(_coordinates(run, system) - truth).max())
        if error <= 1e-10:
            whole = _simulate(scene, rtol)
            print(f"four-bar to 1e-10: rtol {rtol:.1e}, error {error:.2e} rad, {run.steps} steps, "
                  f"{run.nfev} evaluations, {wall * 1e3:.2f} ms (simulate {whole * 1e3:.1f} ms; "
                  "target 5 ms; Pinocchio + scipy DOP853 ~18 ms)")
            return
    print("four-bar: 1e-10 not reached on the ladder")


def double_pendulum(repeat: int) -> None:
    scene = load_system(ROOT / "sample_scenes" / "double_pendulum.yaml")
    _, ref, system = _run(scene, 1e-14, 1)
    truth = _coordinates(ref, system)
    rows = []
    for rtol in LADDER:
        wall, run, system = _run(scene, rtol, repeat)
        rows.append((rtol, float(np.abs(_coordinates(run, system) - truth).max()), wall, run))
    floor = min(r[1] for r in rows)
    rtol, error, wall, run = next(r for r in rows if r[1] <= 2 * floor)
    whole = _simulate(scene, rtol)
    print(f"double pendulum, angles at 10 s: floor {floor:.2e} rad; within 2x of it at rtol "
          f"{rtol:.1e} (error {error:.2e}), {run.steps} steps, {run.nfev} evaluations, "
          f"{wall * 1e3:.2f} ms (simulate {whole * 1e3:.1f} ms; target 20 ms)")


def _simulate(scene, rtol: float) -> float:
    simulate_system(scene, rtol=rtol, every=scene.time.duration, estimate=False)  # warm
    start = time.perf_counter()
    simulate_system(scene, rtol=rtol, every=scene.time.duration, estimate=False)
    return time.perf_counter() - start


def chain_text(n: int) -> str:
    """n uniform links of 0.2 m and 0.1 kg hanging from the origin, hinges about y."""
    length, mass = 0.2, 0.1
    side = mass * (length * length + 0.01 * 0.01) / 12
    inertia = f"[[{side!r}, 0, 0], [0, {side!r}, 0], [0, 0, {mass * 0.01 * 0.01 / 12!r}]]"
    bodies = "\n".join(f"  link{i}: {{mass: {mass}, inertia: {inertia}, "
                       f"position: [0, 0, {-(i + 0.5) * length!r}]}}" for i in range(n))
    joints = "\n".join(f"  - {{name: j{i}, type: revolute, bodies: "
                       f"[{'world' if i == 0 else f'link{i - 1}'}, link{i}], "
                       f"point: [0, 0, {-i * length!r}], axis: [0, 1, 0]}}" for i in range(n))
    return (f"bodies:\n{bodies}\njoints:\n{joints}\ninitial:\n  positions: {{j0: 0.5}}\n"
            "forces:\n  - {type: gravity, g: [0, 0, -9.81]}\ntime: {duration: 2.0}\n")


def chains(repeat: int) -> None:
    per_eval = {}
    for n in (2, 10, 30):
        scene = parse_system(chain_text(n), source=f"chain{n}", base_dir=ROOT)
        wall, run, _ = _run(scene, 1e-9, repeat)
        per_eval[n] = wall / run.nfev
        print(f"chain of {n:2d} links: {run.steps} steps, {run.nfev} evaluations, "
              f"{wall / run.steps * 1e6:.1f} µs per step, {per_eval[n] * 1e6:.2f} µs per "
              "right-hand side")
    print(f"30/10 cost per right-hand side: {per_eval[30] / per_eval[10]:.2f} (target 3.3; "
          "numpy before: 3.65)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    print(f"massprops systems, {platform.processor() or platform.machine()}, "
          f"{time.strftime('%Y-%m-%d')}")
    four_bar(args.repeat)
    double_pendulum(args.repeat)
    chains(args.repeat)


if __name__ == "__main__":
    main()
