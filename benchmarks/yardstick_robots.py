"""Yardstick: how many links of public robot descriptions ``massprops model`` computes.

Point it at folders holding descriptions as shipped in public Python packages (none written for
massprops), e.g. installed with ``pip install --no-deps --target DIR dm_control gymnasium
example-robot-data`` and pybullet's ``pybullet_data`` folder. Every ``*.urdf``, ``*.xacro``,
``*.sdf`` and MJCF ``*.xml`` (root ``<mujoco>`` with a ``<worldbody>``: whole models, not include
fragments) is run through `analyze_model` with the repair options a user would add
(``--fill-holes --max-hole 0.5``) in a worker process (a time limit per file).

The measure: among the links that have geometry and a positive stated mass (MJCF: bodies with
geometry, whose mass MuJoCo takes from the inertial or the geoms), the share computed. Every
other such link is a refusal, printed on one line: the link, the file, the reason and the option
that would help (or "none" where no option would). A file refused as a whole counts all its
candidate links as refused. Two kinds of refusal are no fault of the reader and are counted
apart as well as in the total: an MJCF model that MuJoCo itself refuses to load (with the
``mujoco`` package installed; such files are build intermediates or use removed features), and a
link whose mesh file the package does not ship ("no such file"). Procedurally generated sets
(pybullet's ``random_urdfs``: a thousand outputs of one generator) are reported apart and left
out of the total, so they do not drown the hand-made models.

    python benchmarks/yardstick_robots.py DIR... [--timeout 120] [--jobs 2] [--quiet]
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import os
import re
import sys
import tempfile
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

GENERATED = ("random_urdfs",)


def find_descriptions(roots: list[Path]) -> list[Path]:
    out = []
    for root in roots:
        for p in sorted(root.rglob("*")):
            if not p.is_file():
                continue
            name = p.name.lower()
            if name.endswith((".urdf", ".xacro", ".sdf")):
                out.append(p)
            elif name.endswith(".xml") and _is_mjcf_model(p):
                out.append(p)
    return out


def _is_mjcf_model(p: Path) -> bool:
    try:
        head = p.read_bytes()[:200_000]
    except OSError:
        return False
    return b"<mujoco" in head and b"<worldbody" in head


def _candidates_of_failed(path: Path) -> int:
    """Links with geometry and a stated mass > 0, counted from the raw XML (a refused file)."""
    try:
        root = ET.parse(path).getroot()
    except Exception:
        return 0
    n = 0
    if root.tag == "robot":
        for link in root.iter("link"):
            mass = link.find("inertial/mass")
            geo = link.find("collision") is not None or link.find("visual") is not None
            try:
                ok = mass is not None and float(mass.get("value", "0")) > 0
            except ValueError:
                ok = False
            n += geo and ok
    elif root.tag == "mujoco":
        n = sum(1 for b in root.iter("body") if b.find("geom") is not None)
    elif root.tag == "sdf":
        for link in root.iter("link"):
            mass = link.find("inertial/mass")
            geo = link.find("collision") is not None or link.find("visual") is not None
            try:
                ok = mass is not None and float((mass.text or "0").strip()) > 0
            except ValueError:
                ok = False
            n += geo and ok
    return n


def mujoco_refuses(path: Path) -> str | None:
    """MuJoCo's own error for an MJCF file it cannot load, None if it loads (or no mujoco)."""
    try:
        import mujoco  # optional: only to set apart the models MuJoCo itself refuses
    except ImportError:
        return None
    try:
        mujoco.MjModel.from_xml_path(str(path))
    except Exception as exc:
        return " ".join(str(exc).split())[:160]
    return None


def run_one(path: str, package_paths: list[str]) -> dict:
    # imported in the worker: each file's process loads massprops once per worker
    from massprops.errors import error_message
    from massprops.repair import RepairOptions
    from massprops.robot.analyze import analyze_model

    if path.endswith(".xml"):
        refused = mujoco_refuses(Path(path))
        if refused:
            return {"file": path, "error": None, "links": [], "mujoco": refused}
    repairs = RepairOptions(fill_holes=True, max_hole=0.5)
    try:
        report = analyze_model(path, repairs=repairs, package_paths=package_paths)
    except Exception as exc:
        return {"file": path, "error": error_message(exc), "links": []}
    links = []
    for r in report.links:
        s = r.link.stated
        if not r.link.geometries:
            continue
        if report.model.format == "mjcf":
            candidate = s is None or s.mass > 0
        else:
            candidate = s is not None and s.mass > 0
        if candidate:
            links.append({"link": r.name, "status": r.status, "reason": r.reason,
                          "source": r.link.source})
    return {"file": path, "error": None, "links": links}


def helpful_option(reason: str) -> str:
    text = reason.lower()
    if "package" in text and "cannot find" in text or "model '" in text:
        return "--package-path DIR"
    if "open" in text or "boundary" in text or "hole" in text:
        return "--allow-open or --shell T (holes larger than --max-hole 0.5)"
    if "xacro" in text:
        return "--xacro-arg NAME:=VALUE"
    if "overlap" in text or "intersect" in text:
        return "--union"
    return "none"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("roots", nargs="+", type=Path)
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--quiet", action="store_true", help="Totals only, no refusal lines.")
    args = ap.parse_args(argv)
    args.roots = [r.resolve() for r in args.roots]
    # MuJoCo writes MUJOCO_LOG.TXT into the working folder for every model it refuses
    os.chdir(tempfile.mkdtemp(prefix="yardstick-"))
    files = find_descriptions(args.roots)
    package_paths = [str(r) for r in args.roots]
    totals = {"main": Counter(), "generated": Counter()}
    refusals = []
    by_source = Counter()
    with cf.ProcessPoolExecutor(args.jobs) as pool:
        futures = {pool.submit(run_one, str(p), package_paths): p for p in files}
        for fut, p in futures.items():
            group = "generated" if any(g in p.parts for g in GENERATED) else "main"
            t = totals[group]
            t["files"] += 1
            try:
                res = fut.result(timeout=args.timeout)
            except Exception as exc:  # a timeout or a crashed worker: the file is refused
                res = {"file": str(p), "error": f"{type(exc).__name__}: {exc}", "links": []}
            if res.get("mujoco"):
                t["mujoco_refuses"] += 1
                if group == "main":
                    refusals.append(f"{p}: set apart, MuJoCo refuses it: {res['mujoco']}")
                continue
            if res["error"]:
                n = _candidates_of_failed(p)
                t["candidates"] += n
                t["files_refused"] += 1
                if group == "main":
                    refusals.append(f"{p}: whole file ({n} links): {_short(res['error'])} "
                                    f"[helps: {helpful_option(res['error'])}]")
                continue
            for link in res["links"]:
                t["candidates"] += 1
                if link["status"] == "computed":
                    t["computed"] += 1
                    by_source[link["source"]] += group == "main"
                else:
                    t["not_shipped"] += "no such file" in (link["reason"] or "")
                if link["status"] != "computed" and group == "main":
                    refusals.append(f"{link['link']}: {p}: {_short(link['reason'])} "
                                    f"[helps: {helpful_option(link['reason'] or '')}]")
    if not args.quiet:
        for line in refusals:
            print(line)
    for group, t in totals.items():
        if not t["files"]:
            continue
        share = t["computed"] / t["candidates"] if t["candidates"] else float("nan")
        shipped = t["candidates"] - t["not_shipped"]
        print(f"{group}: {t['files']} files ({t['files_refused']} refused whole, "
              f"{t['mujoco_refuses']} MJCF set apart: MuJoCo refuses them), "
              f"{t['computed']} of {t['candidates']} links computed = {100 * share:.1f} %; "
              f"{t['not_shipped']} links name a mesh file the package does not ship: "
              f"{t['computed']} of {shipped} = {100 * t['computed'] / max(shipped, 1):.1f} % "
              "of the rest")
    print(f"computed from visual geometry (no collision element): {by_source['visual']}")
    return 0


def _short(text: str | None) -> str:
    return re.sub(r"\s+", " ", text or "")[:220]


if __name__ == "__main__":
    sys.exit(main())
