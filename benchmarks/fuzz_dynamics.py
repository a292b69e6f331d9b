"""Fuzz `massprops simulate` and `massprops precision` over extreme scenes, as whole processes.

Random explicit bodies (box-like principal moments with ratios down to ~1e-9, random principal
axes, mass 1e-6 ... 1e6 kg), spins up to 1e5 rad/s in body or world frame, random subsets of
gravity, body/world torques, off-centre forces, springs with stiffness up to 1e12 N/m (damped or
not), drag, durations 1e-3 ... 1e6 s, every integrator (and auto), default or random steps and
tolerances. Each case runs in its own process with a time limit; the outcome must be one of:

- exit 0 with a strict JSON document on stdout (no NaN or inf: parsed with a hook that
  rejects them) and nothing on stderr but notes and warnings;
- exit 3 (the computation failed or the run bound refused or stopped it) or exit 2 (an option
  that does not apply, e.g. exact on a torqued scene) with exactly one error line on stderr;
- never a traceback, a hang (the time limit) or another exit code.

    python benchmarks/fuzz_dynamics.py [--cases 200] [--seed 1] [--precision-every 5]
        [--timeout 300] [--max-steps 200000] [--keep DIR]

--max-steps is passed to simulate so that runs that need more stop quickly (the mechanism is
the same at any bound); precision runs with its defaults. A failing case's scene is kept in
--keep (default: a temporary folder, printed).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np
import yaml

INTEGRATORS = ("auto", "exact", "rk4", "dop853", "implicit", "midpoint", "splitting",
               "splitting4", "splitting6")


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def random_scene(rng: np.random.Generator) -> dict:
    """One random scene (a dict in the scene format) with an explicit body."""
    mass = float(10 ** rng.uniform(-6, 6))
    dims = 10 ** rng.uniform(-4.5, 0, 3)  # box semi-axes: moment ratios down to ~1e-9
    a2 = dims ** 2
    moments = mass / 5 * np.array([a2[1] + a2[2], a2[0] + a2[2], a2[0] + a2[1]])
    r = random_rotation(rng) if rng.random() < 0.5 else np.eye(3)
    inertia = r @ np.diag(moments) @ r.T
    inertia = 0.5 * (inertia + inertia.T)
    size = float(np.max(dims))
    spin = float(10 ** rng.uniform(-3, 5))
    axis = rng.normal(size=3)
    omega = spin * axis / np.linalg.norm(axis)
    if rng.random() < 0.3:  # near a principal axis: the fast-spinning needle or disk
        omega = r @ (np.array([spin, 0, 0]) if rng.random() < 0.5 else np.array([0, 0, spin]))
        omega = omega + 1e-3 * spin * rng.normal(size=3)
    scene = {
        "body": {"mass": mass, "inertia": inertia.tolist()},
        "initial": {"position": (size * rng.normal(size=3)).tolist(),
                    "velocity": (size * rng.normal(size=3)).tolist(),
                    "angular_velocity": omega.tolist(),
                    "angular_velocity_frame": str(rng.choice(["body", "world"]))},
        "forces": [],
        "time": {"duration": float(10 ** rng.uniform(-3, 6)),
                 "integrator": str(rng.choice(INTEGRATORS))},
    }
    forces = scene["forces"]
    if rng.random() < 0.4:
        forces.append({"type": "gravity", "g": [0.0, 0.0, -9.81]})
    if rng.random() < 0.3:
        scale = float(moments.max() * spin ** 2 * 10 ** rng.uniform(-6, 0))
        forces.append({"type": "torque", "vector": (scale * rng.normal(size=3)).tolist(),
                       "frame": str(rng.choice(["body", "world"]))})
    if rng.random() < 0.2:
        forces.append({"type": "force", "vector": (mass * rng.normal(size=3)).tolist(),
                       "frame": str(rng.choice(["body", "world"])),
                       "point": (size * rng.normal(size=3)).tolist(),
                       "start": 0.0, "end": float(scene["time"]["duration"] * rng.random())})
    if rng.random() < 0.35:
        k = float(10 ** rng.uniform(-2, 12))
        spring = {"type": "spring", "anchor": [0.0, 0.0, 0.0], "stiffness": k,
                  "point": (size * rng.normal(size=3) * (rng.random() < 0.5)).tolist()}
        if rng.random() < 0.5:
            spring["damping"] = float(10 ** rng.uniform(-3, 1) * math.sqrt(k * mass))
        if rng.random() < 0.3:
            spring["rest_length"] = size
        forces.append(spring)
    if rng.random() < 0.2:
        forces.append({"type": "drag", "linear": float(mass * 10 ** rng.uniform(-3, 2)),
                       "angular": float(moments.min() * 10 ** rng.uniform(-3, 2))})
    if not forces:
        del scene["forces"]
    if rng.random() < 0.3:
        scene["time"]["step"] = float(scene["time"]["duration"] * 10 ** rng.uniform(-7, -1))
    if rng.random() < 0.3:
        scene["time"]["rtol"] = float(10 ** rng.uniform(-13, -3))
    return scene


def _reject(name: str):
    raise ValueError(f"non-finite number {name} in the JSON output")


REASONS = (("would take", "bound: fixed steps refused"), ("output samples", "bound: samples"),
           ("stopped at", "bound: stopped"), ("reference run failed", "reference failed"),
           ("diverged", "diverged"), ("exact solves only", "exact does not apply"),
           ("below round-off", "rtol below round-off"))


def reason_of(stderr: str) -> str:
    """A short name for the one error line of a refused case."""
    for key, name in REASONS:
        if key in stderr:
            return name
    return "other"


def judge(proc: subprocess.CompletedProcess) -> str:
    """'ok', 'refused' (one clean error line) or what is wrong."""
    err_lines = [line for line in proc.stderr.splitlines() if line.strip()]
    if any("Traceback" in line for line in err_lines):
        return "TRACEBACK"
    errors = [line for line in err_lines if line.startswith("massprops: error:")]
    other = [line for line in err_lines
             if not line.startswith(("massprops: error:", "massprops: warning:",
                                     "massprops: compiling"))]
    if other:
        return "STRAY STDERR"
    if proc.returncode == 0:
        try:
            json.loads(proc.stdout, parse_constant=_reject)
        except ValueError as exc:
            return f"BAD JSON ({exc})"
        return "ok" if not errors else "ERROR LINE ON SUCCESS"
    if proc.returncode in (2, 3):
        if len(errors) != 1:
            return "NOT ONE ERROR LINE"
        return f"refused ({proc.returncode}: {reason_of(errors[0])})"
    return f"EXIT {proc.returncode}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--precision-every", type=int, default=5,
                    help="every Nth case also runs precision")
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--max-steps", type=int, default=200_000)
    ap.add_argument("--keep", default=None)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    keep = Path(args.keep or tempfile.mkdtemp(prefix="massprops-fuzz-"))
    keep.mkdir(parents=True, exist_ok=True)
    tally: Counter = Counter()
    bad: list[tuple[str, str]] = []
    slowest = (0.0, "")
    start = time.perf_counter()
    for case in range(args.cases):
        scene = random_scene(rng)
        path = keep / f"case{case:04d}.yaml"
        path.write_text(yaml.safe_dump(scene), encoding="utf-8")
        commands = [("simulate", ["simulate", str(path), "--json", "-q",
                                  "--max-steps", str(args.max_steps)])]
        if case % args.precision_every == 0:
            commands.append(("precision", ["precision", str(path), "--json", "-q"]))
        for what, argv in commands:
            t0 = time.perf_counter()
            try:
                proc = subprocess.run([sys.executable, "-m", "massprops", *argv],
                                      capture_output=True, text=True, timeout=args.timeout)
                verdict = judge(proc)
            except subprocess.TimeoutExpired:
                verdict, proc = "HANG", None
            spent = time.perf_counter() - t0
            slowest = max(slowest, (spent, f"{what} {path.name}"))
            tally[(what, verdict)] += 1
            if not (verdict == "ok" or verdict.startswith("refused")):
                bad.append((f"{what} {path}", verdict))
                if proc is not None:
                    (keep / f"case{case:04d}.{what}.stderr").write_text(proc.stderr)
        print(f"\r{case + 1}/{args.cases} cases, {len(bad)} bad", end="", flush=True)
    print()
    print(f"{args.cases} cases in {time.perf_counter() - start:.0f} s (seed {args.seed}); "
          f"slowest: {slowest[1]} {slowest[0]:.1f} s")
    for (what, verdict), n in sorted(tally.items()):
        print(f"  {what:10s} {verdict:44s} {n}")
    for where, verdict in bad:
        print(f"BAD: {where}: {verdict}")
    print(f"scenes kept in {keep}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
