"""Start-up of two checkouts side by side: `import massprops` and `inspect --json` on a small file,
alternating whole processes, the least of N runs each (the least is the least disturbed by other
load). Usage: python benchmarks/startup_compare.py TREE_BEFORE TREE_AFTER [N]
(make TREE_BEFORE with `git worktree add --detach /tmp/before REV`)."""

import os
import subprocess
import sys
import tempfile
import time

CASES = {"import massprops": ["-c", "import massprops"],
         "inspect cuboid.obj --json": ["-m", "massprops", "inspect",
                                       "{tree}/sample_meshes/cuboid.obj", "--json"]}


def main(before: str, after: str, n: int) -> None:
    scratch = tempfile.mkdtemp()
    for label, args in CASES.items():
        times: dict[str, list[float]] = {before: [], after: []}
        for _ in range(n):
            for tree in (before, after):
                cmd = [sys.executable] + [x.format(tree=tree) for x in args]
                start = time.perf_counter()
                subprocess.run(cmd, env=dict(os.environ, PYTHONPATH=tree), cwd=scratch,
                               check=True, capture_output=True)
                times[tree].append(time.perf_counter() - start)
        tb, ta = min(times[before]), min(times[after])
        print(f"{label:28s} before {tb * 1000:7.1f} ms   after {ta * 1000:7.1f} ms   "
              f"ratio {ta / tb:.3f}  (least of {n})")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 15)
