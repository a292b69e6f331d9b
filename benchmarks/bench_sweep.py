"""Speed of `massprops sweep` (issue 33 §5): a sweep's cost against the sum of its runs, and its
scaling over local workers and a Dask cluster, beside a plain Python loop over
`massprops.simulate`, side by side in one run.

For each scene (a one-body sample and a system sample), N samples varying one body's mass by
1 % (so every sample is a real draw, its inertia scaled with it), without the error estimate
(its companions would take the second core and blur the scaling):

- the plain loop: ``massprops.simulate(scene)`` N times in this process on the scene as read,
  its wall time and the sum of the runs' own ``wall_time_s`` (the sum of runs);
- ``run_sweep`` in this process (``jobs=1``): wall time over the sum of runs (target <= 1.2);
- ``run_sweep`` on a local pool of 2 workers: the speed-up over ``jobs=1`` (target >= 1.8 on
  2 cores), including the pool's start;
- the same on a local Dask cluster of 2 one-thread worker processes, warm (its second sweep;
  the first, which pays the workers' imports and kernel loads, is printed too; ``--no-dask``
  skips it).

Every variant's rows are checked equal (the draws depend on the seed and the index alone).

    python benchmarks/bench_sweep.py [--samples 1000] [--no-dask]
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

SCENES = (("sample_scenes/compound_pendulum.yaml", "body.mass"),
          ("sample_scenes/double_pendulum.yaml", "bodies.lower.mass"))


def _rows(prepared, **kw):
    from massprops.sweep import run_sweep

    start = time.perf_counter()
    rows = [r.as_dict() for r in run_sweep(prepared, **kw)]
    wall = time.perf_counter() - start
    for r in rows:
        r.pop("wall_time_s")
    return rows, wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--no-dask", action="store_true")
    args = parser.parse_args()
    import massprops
    from massprops.sweep import prepare

    print(f"# {platform.node()} {platform.processor() or platform.machine()}, "
          f"{time.strftime('%Y-%m-%d')}, {args.samples} samples, no error estimate")
    print(f"{'scene':40s} {'loop':>8s} {'runs':>8s} {'sweep':>8s} {'/runs':>6s} "
          f"{'jobs 2':>8s} {'x':>5s} {'dask 2':>8s} {'x':>5s}")
    for path, key in SCENES:
        scene = massprops.load_scene(str(ROOT / path))
        massprops.simulate(scene, estimate=False)  # kernels compiled or loaded
        start = time.perf_counter()
        runs = sum(massprops.simulate(scene, estimate=False).wall_time_s
                   for _ in range(args.samples))
        loop = time.perf_counter() - start
        prepared = prepare(ROOT / path, [f"{key}=relative:1%"], samples=args.samples, seed=0,
                           options={"estimate": False})
        here, t_here = _rows(prepared)
        pooled, t_pool = _rows(prepared, jobs=2)
        assert pooled == here, "the pool's rows differ from one process's"
        t_dask = t_cold = float("nan")
        if not args.no_dask:
            import distributed

            with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                          dashboard_address=":0") as cluster, \
                    distributed.Client(cluster) as client:
                # the first sweep on fresh workers pays their imports and kernel loads; a
                # cluster in use is warm: both are printed
                clustered, t_cold = _rows(prepared, executor=client.get_executor(), workers=2)
                assert clustered == here, "the cluster's rows differ from one process's"
                clustered, t_dask = _rows(prepared, executor=client.get_executor(), workers=2)
            assert clustered == here, "the cluster's rows differ from one process's"
            print(f"  dask: first sweep on fresh workers {t_cold:.2f} s, warm {t_dask:.2f} s")
        print(f"{path:40s} {loop:8.2f} {runs:8.2f} {t_here:8.2f} {t_here / runs:6.2f} "
              f"{t_pool:8.2f} {t_here / t_pool:5.2f} {t_dask:8.2f} {t_here / t_dask:5.2f}")
    print("columns: s of wall; /runs = sweep (jobs 1) over the sum of the runs' own wall times "
          "(target <= 1.2); x = speed-up over jobs 1 (target >= 1.8)")


if __name__ == "__main__":
    main()
