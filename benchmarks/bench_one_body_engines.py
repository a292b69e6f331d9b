"""One body on its two engines: the systems engine `simulate` runs it on (decision 0024) against
the one-body kernels, side by side in this process, on the one-body sample scenes.

For each scene and engine: dop853 at the scene's rtol, steps, evaluations, the main run's wall
time (best of --repeat), µs per evaluation, the whole `simulate` call's wall time and the run's
error estimate. The one-body engine is reached by routing no method to the systems engine
(`simulate.SYSTEM_METHODS` emptied for the call), which is how `simulate` ran before 0024.

    python benchmarks/bench_one_body_engines.py [--repeat 3] [SCENE ...]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import massprops.dynamics.simulate as sim
from massprops.dynamics.scene import load_scene

SCENES = Path(__file__).resolve().parent.parent / "sample_scenes"
DEFAULT = ("dzhanibekov", "tiny", "heavy_top", "needle", "compound_pendulum")


def measure(scene, repeat: int) -> tuple:
    """(steps, evaluations, best run s, best call s, estimate) of dop853 on ``scene``."""
    sim.simulate(scene, integrator="dop853")  # kernels loaded, caches warm
    run_s, call_s, result = [], [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = sim.simulate(scene, integrator="dop853")
        call_s.append(time.perf_counter() - start)
        run_s.append(result.wall_time_s)
    return (result.steps, result.evaluations, min(run_s), min(call_s),
            result.diagnostics["error_estimate"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=DEFAULT)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(f"{'scene':18} {'engine':8} {'steps':>7} {'evals':>8} {'run ms':>8} {'µs/eval':>8} "
          f"{'call ms':>8} {'estimate':>9}")
    routed = sim.SYSTEM_METHODS
    for name in args.scenes:
        scene = load_scene(SCENES / f"{name}.yaml")
        for engine, methods in (("systems", routed), ("one-body", ())):
            sim.SYSTEM_METHODS = methods
            try:
                steps, evals, run, call, estimate = measure(scene, args.repeat)
            finally:
                sim.SYSTEM_METHODS = routed
            print(f"{name:18} {engine:8} {steps:7d} {evals:8d} {run * 1e3:8.2f} "
                  f"{run / evals * 1e6:8.2f} {call * 1e3:8.2f} {estimate:9.1e}")


if __name__ == "__main__":
    main()
