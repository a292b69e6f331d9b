"""Fuzz `massprops simulate` and `massprops precision` over random systems of bodies, as whole
processes (the systems sibling of fuzz_dynamics.py).

Random systems (`_fuzz_system_scenes.py`): chains of 2-12 links and trees (branches), some
closed back to the world; planar four-bars (Grashof or not, parallelograms, near-flat poses)
and slider-cranks; free bodies; every joint type (revolute, prismatic, cylindrical, universal,
spherical, fixed, distance, free); masses 1e-6 ... 1e6 kg with ratios up to 1e6, sizes
1e-4 ... 1e3 m, the whole scene up to 1e8 m from the origin; joint springs (up to 1e12),
dampers and drives with windows (on loop-closing joints too), body forces and torques with
windows, springs between bodies, initial rates up to 1e4 rad/s, durations 1e-3 ... 1e3 s, every
method a system accepts (auto, dop853, rk4, midpoint, implicit) with random steps and
tolerances, in the scene or on the command line. Each case runs in its own process with a time
limit; the outcome must be one of:

- exit 0 with a strict JSON document on stdout (no NaN or inf: parsed with a hook that
  rejects them) and nothing on stderr but notes and warnings;
- exit 3 (the computation failed, or the run bound refused or stopped it) or exit 2 (an option
  that does not apply) with exactly one error line on stderr;
- a method systems refuse (splitting, splitting4, splitting6, exact; ~6 % of cases): exit 2
  with one line; a deliberately broken scene (~8 %: a zero axis, a bad inertia, an unknown
  body or key, wrong rate counts, a rate on a fixed joint, ...): exit 1 with one line;
- never a traceback, a hang (the time limit) or another exit code. A valid scene refused with
  exit 1 (one line) is listed for review, not counted as a failure: the generator cannot tell
  every mechanism it builds is well-posed.

    python benchmarks/fuzz_systems.py [--cases 200] [--seed 1] [--precision-every 5]
        [--timeout 120] [--max-steps 200000] [--jobs 1] [--budget S] [--keep DIR]

--max-steps is passed to simulate so that runs that need more stop quickly; precision runs with
its defaults. --budget stops starting runs after S seconds (the cases run so far are reported).
Every case's scene is kept in --keep (default: a temporary folder, printed), a failing case's
stderr and stdout next to it, and one line per run (time, verdict, last stderr line) in
runs.log there.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _fuzz_system_scenes import random_case  # noqa: E402  (a sibling script, not a package)

PREFIXES = ("massprops: error:", "massprops: warning:", "massprops: note:",
            "massprops: compiling")
REASONS = (("would take", "bound: refused"), ("output samples", "bound: samples"),
           ("stopped at", "bound: stopped"), ("max-steps", "bound"),
           ("reference run failed", "reference failed"), ("diverged", "diverged"),
           ("singular", "singular pose"), ("stability", "explicit step unstable"),
           ("cannot be closed", "loop not closed"), ("Newton", "Newton failed"),
           ("does not apply", "method refused"),
           ("below round-off", "rtol below round-off"))


def _reject(name: str):
    raise ValueError(f"non-finite number {name} in the JSON output")


def reason_of(line: str) -> str:
    """A short name for the one error line of a refused case."""
    for key, name in REASONS:
        if key in line:
            return name
    return "other"


def judge(proc: subprocess.CompletedProcess, expect: str, scene: str = "") -> str:
    """'ok', 'refused (...)', 'review (...)' (a valid scene refused in one line, or a result
    whose own error estimate is >= 1) or what is wrong (upper case). ``scene``: the scene's
    path, which a refusal's line should name (noted when it does not)."""
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    if any("Traceback" in line for line in lines):
        return "TRACEBACK"
    errors = [line for line in lines if line.startswith("massprops: error:")]
    if any(not line.startswith(PREFIXES) for line in lines):
        return "STRAY STDERR"
    code = proc.returncode
    if code == 0:
        if errors:
            return "ERROR LINE ON SUCCESS"
        try:
            doc = json.loads(proc.stdout, parse_constant=_reject)
        except ValueError as exc:
            return f"BAD JSON ({str(exc)[:60]})"
        if expect != "run":
            return {"usage": "RAN A REFUSED METHOD", "invalid": "ACCEPTED AN INVALID SCENE"}[expect]
        return "review (0: error estimate >= 1)" if _blown_up(doc) else "ok"
    if code not in (1, 2, 3):
        return f"EXIT {code}"
    if len(errors) != 1:
        return f"NOT ONE ERROR LINE (exit {code}, {len(errors)} lines)"
    if expect == "invalid":
        return "refused (1: invalid scene)" if code == 1 else f"EXIT {code} ON AN INVALID SCENE"
    if expect == "usage":  # named on the command line: exit 2; in the scene: its line, exit 1
        if code == 2 or (code == 1 and "time.integrator" in errors[0]):
            return f"refused ({code}: method)"
        return f"EXIT {code} FOR A REFUSED METHOD"
    if code == 1:
        return "review (1: valid scene refused)"
    unnamed = "" if scene in errors[0] else "; no file named"
    return f"refused ({code}: {reason_of(errors[0])}{unnamed})"


def _blown_up(doc: dict) -> bool:
    """True when a simulate result's own error estimate says it is meaningless (>= 1: the
    contract's metric is relative, so 1 is an error as large as the motion)."""
    estimate = doc.get("diagnostics", {}).get("error_estimate") if isinstance(doc, dict) else None
    return isinstance(estimate, (int, float)) and estimate >= 1


def commands(rng: np.random.Generator, case: int, path: Path, args) -> list[tuple[str, list]]:
    """simulate (random --step / --rtol on the command line at times); precision every Nth."""
    sim = ["simulate", str(path), "--json", "-q", "--max-steps", str(args.max_steps)]
    if rng.random() < 0.15:
        sim += ["--rtol", f"{10 ** rng.uniform(-13, -3):.3g}"]
    if rng.random() < 0.15:
        sim += ["--step", f"{10 ** rng.uniform(-6, -1):.3g}"]
    out = [("simulate", sim)]
    if case % args.precision_every == 0:
        out.append(("precision", ["precision", str(path), "--json", "-q"]))
    return out


def run_one(argv: list, timeout: float) -> tuple[subprocess.CompletedProcess | None, float]:
    t0 = time.perf_counter()
    try:
        proc = subprocess.run([sys.executable, "-m", "massprops", *argv], capture_output=True,
                              text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        proc = None
    return proc, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--precision-every", type=int, default=5,
                    help="every Nth case also runs precision")
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--max-steps", type=int, default=200_000)
    ap.add_argument("--jobs", type=int, default=1, help="cases run side by side")
    ap.add_argument("--budget", type=float, default=0.0,
                    help="seconds after which no new run starts (0: no limit)")
    ap.add_argument("--keep", default=None)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    keep = Path(args.keep or tempfile.mkdtemp(prefix="massprops-fuzz-systems-"))
    keep.mkdir(parents=True, exist_ok=True)
    jobs = []  # (case, what, argv, expect, label, path)
    for case in range(args.cases):
        scene, expect, label = random_case(rng)
        path = keep / f"case{case:04d}.yaml"
        text = yaml.safe_dump(scene, default_flow_style=None, width=1000)
        path.write_text(f"# {label}, expect {expect}\n{text}", encoding="utf-8")
        jobs += [(case, what, argv, expect, label, path)
                 for what, argv in commands(rng, case, path, args)]
    tally: Counter = Counter()
    bad, review, done_runs, slowest = [], [], [], (0.0, "")
    start = time.perf_counter()

    log = (keep / "runs.log").open("w", encoding="utf-8")

    def work(job):
        if args.budget and time.perf_counter() - start > args.budget:
            return job, "skipped", 0.0
        return job, *run_one(job[2], args.timeout)

    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for done, ((_case, what, argv, expect, label, path), proc, spent) in enumerate(
                pool.map(work, jobs), 1):
            if proc == "skipped":
                continue
            verdict = "HANG" if proc is None else judge(proc, expect, str(path))
            said = "" if proc is None else (proc.stderr.strip().splitlines() or [""])[-1]
            log.write(f"{path.name} {what} [{label}] {spent:.1f} s {verdict} | {said[:200]}\n")
            log.flush()
            slowest = max(slowest, (spent, f"{what} {path.name}"))
            tally[(what, verdict)] += 1
            done_runs.append(f"{what} {path}")
            where = f"{what} {path} [{label}] {' '.join(argv[2:])}"
            if verdict.startswith("review"):
                review.append((where, proc.stderr.strip()[:300] or verdict))
                path.with_suffix(f".{what}.stdout").write_text(proc.stdout[:100_000])
            elif not (verdict == "ok" or verdict.startswith("refused")):
                bad.append((where, verdict))
                if proc is not None:
                    path.with_suffix(f".{what}.stderr").write_text(proc.stderr)
                    path.with_suffix(f".{what}.stdout").write_text(proc.stdout[:100_000])
            print(f"\r{done}/{len(jobs)} runs, {len(bad)} bad", end="", flush=True)
    print()
    ran = len({where.split()[1] for where in done_runs})
    print(f"{ran} of {args.cases} cases ({sum(tally.values())} runs) in "
          f"{time.perf_counter() - start:.0f} s "
          f"(seed {args.seed}, {args.jobs} side by side); slowest: {slowest[1]} "
          f"{slowest[0]:.1f} s")
    for (what, verdict), n in sorted(tally.items()):
        print(f"  {what:10s} {verdict:48s} {n}")
    for where, said in review:
        print(f"REVIEW: {where}\n    {said}")
    for where, verdict in bad:
        print(f"BAD: {where}: {verdict}")
    print(f"scenes kept in {keep}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
