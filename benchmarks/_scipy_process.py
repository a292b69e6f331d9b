"""A whole scipy process, the peer of `massprops simulate`: read a problem (JSON), integrate it
with solve_ivp, print the final state as one JSON line. Loads numpy, scipy and the numpy
right-hand side (``_scipy_rhs``) only, never massprops or numba.

    python benchmarks/_scipy_process.py problem.json

problem: {"rhs": NumpyRhs.as_dict(), "y0": (13,) principal-frame state, "duration": s,
          "method": "DOP853", "rtol": float, "atol": (13,)}  (one segment: no force windows)
prints:  {"y": (13,) state at t = duration, principal frame, "nfev": int, "solve_s": float}
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
from _scipy_rhs import NumpyRhs
from scipy.integrate import solve_ivp


def main() -> None:
    with open(sys.argv[1], encoding="utf-8") as f:
        problem = json.load(f)
    rhs = NumpyRhs(**problem["rhs"])
    start = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, problem["duration"]), np.array(problem["y0"]),
                    method=problem["method"], rtol=problem["rtol"],
                    atol=np.array(problem["atol"]))
    solve_s = time.perf_counter() - start
    if sol.status != 0:
        sys.exit(f"solve_ivp failed: {sol.message}")
    print(json.dumps({"y": sol.y[:, -1].tolist(), "nfev": int(sol.nfev), "solve_s": solve_s}))


if __name__ == "__main__":
    main()
