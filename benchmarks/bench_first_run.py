"""First run on a fresh machine: `massprops simulate` of every sample scene as a whole process with
an EMPTY numba cache (a new temporary NUMBA_CACHE_DIR per measurement), then warm (the same
cache, best of --warm), and the first `precision` (which compiles every integrator).

Targets (issue 8): the first simulate of any sample scene <= 3 s, the first exact run <= 1 s,
warm runs no slower than before. `--tree DIR` runs another checkout (e.g. the commit before this
work, exported with `git archive`) the same way, side by side, so the numbers compare on the same
machine at the same load. A source tree has no prebuilt kernels, so its cold runs compile; a
fresh machine's first run is measured with `--python`, the interpreter of an environment where
massprops was installed with `pip install .` (the kernels compiled into the wheel): its cold
runs start from an empty home cache (XDG_CACHE_HOME), NUMBA_CACHE_DIR unset, as a new user's:

    python benchmarks/bench_first_run.py [--scenes dzhanibekov,needle] [--warm 3]
        [--tree /tmp/before] [--python /tmp/venv/bin/python ...] [--installed-only]
        [--precision needle] [--no-precision]

Printed per scene: the integrator auto (or the scene) picks, cold and warm wall seconds of each
tree, and whether the notice line appeared on stderr (it must on a cold run that compiles, never
on a warm one, never on stdout). Timings on a shared machine only ever grow: run it idle, and
repeat before trusting a difference under ~20 %.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "sample_scenes"
FIRST_TARGET_S, EXACT_TARGET_S = 3.0, 1.0


def run_process(tree: Path, args: list[str], cache: Path
                ) -> tuple[float, float, subprocess.CompletedProcess]:
    """Wall and CPU (user + system, the process and the helpers it waited for) seconds and the
    result of ``python -m massprops ARGS``: importing massprops from ``tree`` with numba's cache
    in ``cache``, or, for ``tree`` a Python executable, its installed massprops with ``cache`` as
    the home cache. CPU seconds are less sensitive than wall seconds to other jobs."""
    if tree.is_file():
        python, cwd = str(tree), cache
        env = dict(os.environ, XDG_CACHE_HOME=str(cache))
        env.pop("NUMBA_CACHE_DIR", None)
        env.pop("PYTHONPATH", None)
    else:
        python, cwd = sys.executable, tree
        env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), PYTHONPATH=str(tree))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run([python, "-m", "massprops", *args], cwd=cwd, env=env,
                          capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, proc


def measure(tree: Path, args: list[str], warm: int) -> dict:
    """Cold (empty cache) and best-of-``warm`` warm wall times of one command."""
    cache = Path(tempfile.mkdtemp(prefix="massprops-numba-"))
    try:
        cold, cold_cpu, proc = run_process(tree, args, cache)
        notice_cold = "compiling" in proc.stderr
        stdout_clean = "compiling" not in proc.stdout
        warm_times, notice_warm = [], False
        for _ in range(warm):
            t, _, again = run_process(tree, args, cache)
            warm_times.append(t)
            notice_warm |= "compiling" in again.stderr
        return {"cold": cold, "cold_cpu": cold_cpu, "warm": min(warm_times),
                "exit": proc.returncode,
                "notice_cold": notice_cold, "notice_warm": notice_warm,
                "stdout_clean": stdout_clean, "integrator": _integrator(proc.stdout)}
    finally:
        shutil.rmtree(cache, ignore_errors=True)


def _integrator(stdout: str) -> str:
    try:
        return json.loads(stdout)["integrator"]
    except (ValueError, KeyError):
        return "-"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default="", help="comma-separated names (default: all)")
    ap.add_argument("--warm", type=int, default=3)
    ap.add_argument("--tree", default=None, help="another checkout to measure side by side")
    ap.add_argument("--python", action="append", default=[],
                    help="the interpreter of an environment with massprops installed "
                         "(repeatable: several installs side by side)")
    ap.add_argument("--installed-only", action="store_true",
                    help="measure only the --python environments, not this source tree")
    ap.add_argument("--precision", default="needle", help="scene of the first-precision run")
    ap.add_argument("--no-precision", action="store_true")
    args = ap.parse_args()
    names = [n for n in args.scenes.split(",") if n] or sorted(
        p.stem for p in SCENES.glob("*.yaml"))
    trees = {} if args.installed_only else {"this": ROOT}
    trees |= {"other": Path(args.tree).resolve()} if args.tree else {}
    # the installed package is the one a user meets: it leads
    installed = {(f"installed{k + 1}" if len(args.python) > 1 else "installed"):
                 Path(py).absolute() for k, py in enumerate(args.python)}
    trees = installed | trees
    print(f"{'scene':18s} {'integrator':11s} " + " ".join(
        f"{label + ' cold (cpu)':>17s} {label + ' warm':>10s}" for label in trees) + "  notes")
    worst_first, worst_exact = 0.0, 0.0
    for name in names:
        scene = str(SCENES / f"{name}.yaml")
        cells, notes, integrator = [], [], "-"
        for label, tree in trees.items():
            m = measure(tree, ["simulate", scene, "--json", "--quiet"], args.warm)
            cells.append(f"{m['cold']:8.2f} ({m['cold_cpu']:5.2f}) {m['warm']:10.2f}")
            if label == next(iter(trees)):
                integrator = m["integrator"]
                worst_first = max(worst_first, m["cold"])
                if integrator == "exact":
                    worst_exact = max(worst_exact, m["cold"])
                if m["notice_warm"] or not m["stdout_clean"]:
                    notes.append("NOTICE MISPLACED")
                if m["exit"] not in (0, 3):
                    notes.append(f"exit {m['exit']}")
                notes.append("notice" if m["notice_cold"] else "no notice")
        print(f"{name:18s} {integrator:11s} " + " ".join(cells) + "  " + ", ".join(notes))
    if not args.no_precision:
        scene = str(SCENES / f"{args.precision}.yaml")
        cells = []
        for tree in trees.values():
            m = measure(tree, ["precision", scene, "--json", "--quiet"], 1)
            cells.append(f"{m['cold']:8.2f} ({m['cold_cpu']:5.2f}) {m['warm']:10.2f}")
        print(f"{'precision ' + args.precision:30s} " + " ".join(cells))
    print(f"first simulate, worst scene: {worst_first:.2f} s (target {FIRST_TARGET_S} s); "
          f"first exact run, worst: {worst_exact:.2f} s (target {EXACT_TARGET_S} s)")


if __name__ == "__main__":
    main()
