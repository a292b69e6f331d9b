"""What each compiled entry of the systems engine costs to compile and to load (issue 31, item 5;
docs/performance.md, "Compiling and loading").

    PYTHONPATH=. python benchmarks/bench_compile.py [--entries dop853,fixed,outputs,rhs]

Per entry (`compiling.SYSTEM_ENTRIES`), each in a new process with its own empty kernel cache
(NUMBA_CACHE_DIR): compiling it alone (fresh); compiling it after DOP853's entry in the same
process (second: the shared right-hand side is compiled already); and loading it from that warm
cache after numba's start (load). Wall seconds; run it on an idle machine.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

TIMED = """
import sys, time
from massprops.dynamics.compiled.jit import start_numba_lean
start_numba_lean()
from massprops.dynamics.compiled.systems_kernel import WARM_UPS
for name in sys.argv[1:]:
    start = time.perf_counter()
    WARM_UPS[name]()
    print(time.perf_counter() - start)
"""


def timed(cache: str, names: list[str]) -> list[float]:
    """Seconds of each warm-up of ``names``, in order, in one new process on ``cache``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", TIMED, *names], env=env, cwd=ROOT, check=True,
                         capture_output=True, text=True)
    return [float(line) for line in out.stdout.split()]


def main() -> None:
    from massprops.dynamics.compiled.compiling import SYSTEM_ENTRIES

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--entries", default=",".join(SYSTEM_ENTRIES))
    names = parser.parse_args().entries.split(",")
    print(f"{'entry':10s} {'fresh':>9s} {'second':>9s} {'load':>9s}")
    for name in names:
        with tempfile.TemporaryDirectory() as fresh, tempfile.TemporaryDirectory() as warm:
            alone = timed(fresh, [name])[0]
            second = timed(warm, ["dop853", name])[1] if name != "dop853" else float("nan")
            load = timed(warm if name != "dop853" else fresh, [name])[0]
        print(f"{name:10s} {alone:8.2f}s {second:8.2f}s {load * 1e3:7.1f}ms", flush=True)


if __name__ == "__main__":
    main()
