"""The implicit method (Radau IIA) on a stiff scene: steps, evaluations, rejected pieces, Jacobians,
wall time and the TRUE error at a ladder of steps, this tree against another (``--tree``), run
interleaved on the same machine.

The truth is dop853 at rtol 1e-13 (checked against rtol 1e-12: their distance bounds the tighter
one's error, as in `precision.reference_run`), not the implicit method itself, so an error that
the method's own Newton iteration leaves shows. It is stability-limited on a stiff scene (~2.5e7
steps, ~1 min per rtol for heavy_top_damped) and cached in ``--reference`` (an .npz keyed by the
scene's text, so an edited scene recomputes).

    python benchmarks/bench_implicit.py [--scene sample_scenes/heavy_top_damped.yaml]
        [--factors 4,2,1,0.5] [--repeat 3] [--tree /tmp/before] [--reference FILE.npz]

Steps are multiples of the scene's default step (simulate.default_step). Wall: the main run only
(`_one_run.run_any`: simulate without its estimate, kernel compiled and warm), best of
--repeat, each tree in its own process, the processes interleaved repeat by repeat. Timings on
a shared machine only ever grow.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
REF_RTOLS = (1e-13, 1e-12)
REF_MAX_STEPS = 60_000_000


def _stack(traj) -> np.ndarray:
    return np.hstack([traj.t[:, None], traj.position, traj.orientation, traj.velocity,
                      traj.angular_velocity])


def _unstack(a: np.ndarray):
    from types import SimpleNamespace

    return SimpleNamespace(t=a[:, 0], position=a[:, 1:4], orientation=a[:, 4:8],
                           velocity=a[:, 8:11], angular_velocity=a[:, 11:14])


def reference(scene_path: str, cache: Path | None, samples: int):
    """(truth, its own accuracy) in the contract's metric, from the cache when it matches."""
    from _one_run import run_any

    from massprops.dynamics.accuracy import Scales, state_error
    from massprops.dynamics.program import compile_forces
    from massprops.dynamics.scene import load_scene

    key = hashlib.sha256(Path(scene_path).read_bytes()).hexdigest()[:16] + f"-{samples}"
    if cache is not None and cache.exists():
        stored = np.load(cache)
        if str(stored["key"]) == key:
            return _unstack(stored["truth"]), float(stored["accuracy"])
    scene = load_scene(scene_path)
    program = compile_forces(scene)
    runs = []
    for rtol in REF_RTOLS:
        run = run_any(scene, program, "dop853", rtol, samples, max_steps=REF_MAX_STEPS)
        if run.failure is not None:
            raise SystemExit(f"reference run at rtol {rtol} failed: {run.failure}")
        runs.append(run.trajectory)
    scales = Scales.of(scene.body.size, runs[0], scene.time.duration)
    accuracy = state_error(runs[0], runs[1], scales) / 9
    if cache is not None:
        np.savez(cache, key=key, truth=_stack(runs[0]), accuracy=accuracy)
    return runs[0], accuracy


def measure(scene_path: str, factors: list[float], samples: int, reference_file: str) -> list:
    """One process: every factor once (compiled warm first), error against the cached truth."""
    from _one_run import run_any

    from massprops.dynamics.accuracy import Scales, state_error
    from massprops.dynamics.compiled.compiling import prepare
    from massprops.dynamics.program import compile_forces
    from massprops.dynamics.scene import load_scene
    from massprops.dynamics.simulate import default_step

    scene = load_scene(scene_path)
    program = compile_forces(scene)
    stored = np.load(reference_file)
    truth = _unstack(stored["truth"])
    scales = Scales.of(scene.body.size, truth, scene.time.duration)
    prepare(["implicit"])
    h0 = default_step(scene, program, stiff=True)
    rows = []
    for factor in factors:
        run = run_any(scene, program, "implicit", factor * h0, samples)
        error = state_error(run.trajectory, truth, scales) if run.failure is None else None
        rows.append({"factor": factor, "h": factor * h0, "steps": run.steps,
                     "nfev": run.evaluations, "wall": run.wall, "error": error})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default=str(ROOT / "sample_scenes" / "heavy_top_damped.yaml"))
    ap.add_argument("--factors", default="4,2,1,0.5", help="steps as multiples of the default")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--samples", type=int, default=500)
    ap.add_argument("--tree", default=None, help="another checkout, measured interleaved")
    ap.add_argument("--reference", default=None, help="cache file of the dop853 truth (.npz)")
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    factors = [float(x) for x in args.factors.split(",")]
    scene = str(Path(args.scene).resolve())
    if args.child:  # one measurement in this process (the tree is on PYTHONPATH)
        print(json.dumps(measure(scene, factors, args.samples, args.child)))
        return
    cache = Path(args.reference or Path(os.environ.get("TMPDIR", "/tmp"))
                 / f"bench_implicit_ref_{Path(scene).stem}.npz")
    _, accuracy = reference(scene, cache, args.samples)
    print(f"truth: dop853 rtol {REF_RTOLS[0]:g}, accuracy {accuracy:.2g} (against rtol "
          f"{REF_RTOLS[1]:g} / 9), {args.samples} samples; cached in {cache}")
    trees = {"this": ROOT} | ({"other": Path(args.tree).resolve()} if args.tree else {})
    best: dict[str, list] = {}
    for _ in range(args.repeat):
        for label, tree in trees.items():
            env = dict(os.environ, PYTHONPATH=str(tree))
            out = subprocess.run([sys.executable, __file__, "--scene", scene, "--factors",
                                  args.factors, "--samples", str(args.samples), "--child",
                                  str(cache)], env=env, capture_output=True, text=True,
                                 check=True, cwd=tree)
            rows = json.loads(out.stdout.strip().splitlines()[-1])
            if label not in best:
                best[label] = rows
            else:
                for kept, row in zip(best[label], rows):
                    kept["wall"] = min(kept["wall"], row["wall"])
    print(f"{'tree':>6s} {'h/h0':>5s} {'h (s)':>9s} {'steps':>8s} {'nfev':>9s} {'nfev/st':>7s} "
          f"{'wall (s)':>8s} {'error':>9s}")
    for i, factor in enumerate(factors):
        for label in trees:
            r = best[label][i]
            err = "failed" if r["error"] is None else f"{r['error']:.2e}"
            print(f"{label:>6s} {factor:5g} {r['h']:9.3g} {r['steps']:8d} {r['nfev']:9d} "
                  f"{r['nfev'] / max(r['steps'], 1):7.1f} {r['wall']:8.3f} {err:>9s}")


if __name__ == "__main__":
    main()
