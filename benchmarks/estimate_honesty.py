"""Honesty of `simulate`'s error estimate over the sample scenes: true error / estimate.

For every scene in sample_scenes/ (or those named), `massprops.dynamics.precision.precision`
runs every applicable integrator over its full ladder of settings; each rung reports its true
error (against the exact solution or a checked reference run) and its own `error_estimate`.
This prints, per integrator and overall, the distribution of true / estimate: quantiles, the
fraction of runs with true <= 10 × estimate (the requirement: >= 95 %) and with true <= estimate
(the estimate is an upper bound), and the median estimate / true (usefulness: within 0.1 ... 10).

Only rungs whose true error is above FLOOR × the reference's own accuracy count: below that the
"truth" is the reference's own round-off and the ratio says nothing about the estimate. Rungs that
diverged (no error) or had no estimate are counted apart.

    python benchmarks/estimate_honesty.py [SCENE.yaml ...] [--skip long_run unstable]

The full ladders take minutes (long_run.yaml alone integrates 1000 s per rung); progress goes to
stderr.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from massprops.dynamics.precision import precision
from massprops.dynamics.scene import load_scene
from massprops.errors import MassPropsError

SCENES = Path(__file__).resolve().parent.parent / "sample_scenes"
FLOOR = 1e3
"""Rungs count only if their true error exceeds FLOOR × the reference's accuracy."""
QUANTILES = (0.0, 0.05, 0.25, 0.5, 0.75, 0.95, 1.0)


WORST = 12
"""How many of the largest true / estimate rungs (the dishonest ones) are listed."""


def ratios_of(path: Path) -> tuple[list[tuple[str, float, object]], dict]:
    """[(integrator, true / estimate, rung)] of the counted rungs of one scene, and tallies of
    the rungs left out (diverged, no estimate, at the reference's floor)."""
    from massprops.dynamics.systems.scene import is_system_text  # systems: their own ladder

    if is_system_text(path.read_text(encoding="utf-8")):
        from massprops.dynamics.systems.precision import precision_system
        from massprops.dynamics.systems.scene import load_system

        report = precision_system(load_system(path))
    else:
        report = precision(load_scene(path))
    floor = FLOOR * report.reference["accuracy"]
    counted, left_out = [], defaultdict(int)
    for run in report.runs:
        if run.error is None:
            left_out["diverged"] += 1
        elif run.estimate is None:
            left_out["no estimate"] += 1
        elif run.error <= floor:
            left_out["at the reference floor"] += 1
        else:
            counted.append((run.integrator, true_over_estimate(run), run))
    return counted, {"reference": report.reference, **left_out}


def true_over_estimate(run) -> float:
    """error / estimate; an estimate of 0 under a non-zero error is infinitely dishonest."""
    return run.error / run.estimate if run.estimate > 0 else np.inf


def summary(label: str, ratios: list[float]) -> str:
    r = np.asarray(ratios, dtype=float)
    q = np.quantile(r, QUANTILES)
    within10, within1 = np.mean(r <= 10.0), np.mean(r <= 1.0)
    usefulness = 1.0 / float(np.median(r))  # median of est/true = 1 / median of true/est
    return (f"{label:<12} n={r.size:4d}  true/est quantiles "
            + " ".join(f"{x:9.3g}" for x in q)
            + f"  <=10: {within10:6.1%}  <=1: {within1:6.1%}  median est/true {usefulness:8.3g}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", type=Path, help="default: every sample scene")
    parser.add_argument("--skip", nargs="*", default=[], help="scene names to leave out")
    args = parser.parse_args(argv)
    paths = args.scenes or sorted(SCENES.glob("*.yaml"))
    paths = [p for p in paths if p.stem not in args.skip]
    per_integrator: dict[str, list[float]] = defaultdict(list)
    per_scene: dict[str, list[float]] = {}
    worst: list[tuple[float, str, object]] = []
    per_cell: dict[str, dict[str, list[float]]] = defaultdict(dict)
    for path in paths:
        start = time.perf_counter()
        try:
            counted, info = ratios_of(path)
        except MassPropsError as exc:
            print(f"{path.name}: precision failed: {exc}", file=sys.stderr)
            continue
        for name, ratio, run in counted:
            per_integrator[name].append(ratio)
            worst.append((ratio, path.stem, run))
        per_scene[path.stem] = [ratio for _, ratio, _ in counted]
        for name, ratio, _ in counted:
            per_cell[path.stem].setdefault(name, []).append(ratio)
        ref = info.pop("reference")
        print(f"{path.name}: {len(counted)} rungs counted, left out {dict(info)}; reference "
              f"{ref['integrator']} accuracy {ref['accuracy']:.2g}; "
              f"{time.perf_counter() - start:.1f} s", file=sys.stderr)
    print(f"true error / error_estimate (rungs with error > {FLOOR:g} x reference accuracy); "
          "quantiles " + " ".join(f"{q:g}" for q in QUANTILES))
    for name, ratios in sorted(per_integrator.items()):
        print(summary(name, ratios))
    everything = [r for ratios in per_integrator.values() for r in ratios]
    if everything:
        print(summary("ALL", everything))
    print("per scene:")
    for name, ratios in per_scene.items():
        if ratios:
            print(summary(name, ratios))
    print("fraction of rungs with true <= 10 x estimate (count), scene x integrator:")
    names = sorted(per_integrator)
    print(f"{'':<17}" + "".join(f"{n:>12}" for n in names))
    for scene_name, ratios in per_cell.items():
        cells = []
        for n in names:
            r = np.asarray(ratios.get(n, []))
            cells.append(f"{np.mean(r <= 10):6.0%} ({r.size:2d})" if r.size else f"{'-':>12}")
        print(f"{scene_name:<17}" + "".join(f"{c:>12}" for c in cells))
    print(f"the {WORST} largest true / estimate:")
    for ratio, scene, run in sorted(worst, key=lambda w: -w[0])[:WORST]:
        print(f"  {ratio:9.3g}  {scene:<16} {run.integrator:<11} {run.setting_name} "
              f"{run.setting:<10.3g} error {run.error:.3g}  estimate {run.estimate:.3g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
