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

With ``--packages NAME...`` (installed distributions, e.g. ``example-robot-data
gymnasium-robotics robosuite``) the folders come from the installed packages themselves: a
module's own folder (``importlib.util.find_spec``), or, for a distribution with no module of
that name (example-robot-data installs through cmeel), the folder holding the description files
its installed record lists (``importlib.metadata``); no site-packages path is written anywhere.

Every file runs with ``--check RTOL`` (default 0.1): the inertia doctor's table, one column per
package (a folder given on the command line is its own column): links with a stated inertial,
each validity test failed by the stated and by the computed inertial, agreement within RTOL,
the links diagnosed by each cause and those left unexplained, with the files refused and the run
time. Refused files are grouped by their error message (paths and numbers blanked), so each
distinct parse failure shows once with its count and one file.

    python benchmarks/yardstick_robots.py DIR... [--packages NAME...] [--check 0.1]
        [--timeout 120] [--jobs 2] [--quiet]
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import importlib.metadata
import importlib.util
import os
import re
import sys
import tempfile
import time
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


DESCRIPTION_ENDINGS = (".urdf", ".xacro", ".sdf", ".xml")
TESTS = ("positive_definite", "triangle", "com_inside", "realizable")


def package_roots(name: str) -> list[Path]:
    """The folders an installed package ships its files in, from the package itself: its
    module's folder, else the folder holding the description files its installed record lists
    (a distribution such as example-robot-data that installs data only, through cmeel)."""
    module = name.replace("-", "_")
    try:
        spec = importlib.util.find_spec(module)
    except (ImportError, ValueError):
        spec = None
    if spec is not None and spec.submodule_search_locations:
        return [Path(d).resolve() for d in spec.submodule_search_locations]
    try:
        dist = importlib.metadata.distribution(name)
    except importlib.metadata.PackageNotFoundError:
        raise SystemExit(f"yardstick: {name}: not installed (pip install {name})") from None
    files = [Path(str(dist.locate_file(f))).resolve() for f in dist.files or ()
             if str(f).lower().endswith(DESCRIPTION_ENDINGS) and "/include/" not in f"/{f}"]
    if not files:
        return []
    return [Path(os.path.commonpath([f.parent for f in files]))]


def run_one(path: str, package_paths: list[str], check: float) -> dict:
    # imported in the worker: each file's process loads massprops once per worker
    from massprops.errors import error_message
    from massprops.repair import RepairOptions
    from massprops.robot.analyze import analyze_model

    start = time.perf_counter()
    if path.endswith(".xml"):
        refused = mujoco_refuses(Path(path))
        if refused:
            return {"file": path, "error": None, "links": [], "mujoco": refused,
                    "seconds": time.perf_counter() - start}
    repairs = RepairOptions(fill_holes=True, max_hole=0.5)
    try:
        report = analyze_model(path, repairs=repairs, package_paths=package_paths, check=check)
    except Exception as exc:
        return {"file": path, "error": error_message(exc), "links": [],
                "seconds": time.perf_counter() - start}
    links = []
    for r in report.links:
        s = r.link.stated
        if not r.link.geometries:
            continue
        if report.model.format == "mjcf":
            candidate = s is None or s.mass > 0
        else:
            candidate = s is not None and s.mass > 0
        if not candidate:
            continue
        row = {"link": r.name, "status": r.status, "reason": r.reason, "source": r.link.source,
               "stated": s is not None and r.computed is not None}
        if r.computed is not None:
            row["computed_valid"] = r.computed_validity().as_dict()
            if s is not None:
                row["stated_valid"] = r.stated_validity().as_dict()
                row["worst"] = r.comparison.worst if r.comparison is not None else None
                row["com_rel"] = r.comparison.com_rel if r.comparison is not None else None
                d = r.diagnosis
                row["causes"] = None if d is None else [c for c, _p, _t in d.causes]
        links.append(row)
    return {"file": path, "error": None, "links": links, "seconds": time.perf_counter() - start}


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
    ap.add_argument("roots", nargs="*", type=Path)
    ap.add_argument("--packages", nargs="+", default=[], metavar="NAME",
                    help="installed distributions whose shipped descriptions to run")
    ap.add_argument("--check", type=float, default=0.1, metavar="RTOL")
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--quiet", action="store_true", help="Totals only, no refusal lines.")
    args = ap.parse_args(argv)
    groups: dict[str, list[Path]] = {str(r): [r.resolve()] for r in args.roots}
    for name in args.packages:
        groups[name] = package_roots(name)
    if not groups:
        ap.error("give folders or --packages")
    # MuJoCo writes MUJOCO_LOG.TXT into the working folder for every model it refuses
    os.chdir(tempfile.mkdtemp(prefix="yardstick-"))
    files = [(g, p) for g, roots in groups.items() for p in find_descriptions(roots)]
    package_paths = [str(r) for roots in groups.values() for r in roots]
    totals = {"main": Counter(), "generated": Counter()}
    table = {g: Counter() for g in groups}
    refusals = []
    failures: dict[str, list] = {}  # message pattern -> [(package, file, message)]
    skips: dict[str, list] = {}  # the same for links refused inside a file read
    invalid: list[str] = []  # links whose computed inertial fails a validity test
    by_source = Counter()
    wall = time.perf_counter()
    with cf.ProcessPoolExecutor(args.jobs) as pool:
        futures = {pool.submit(run_one, str(p), package_paths, args.check): (g, p)
                   for g, p in files}
        for fut, (g, p) in futures.items():
            group = "generated" if any(x in p.parts for x in GENERATED) else "main"
            t, c = totals[group], table[g]
            t["files"] += 1
            try:
                res = fut.result(timeout=args.timeout)
            except Exception as exc:  # a timeout or a crashed worker: the file is refused
                res = {"file": str(p), "error": f"{type(exc).__name__}: {exc}", "links": []}
            if group == "main":
                c["files"] += 1
                c["seconds"] += res.get("seconds", args.timeout)
            if res.get("mujoco"):
                t["mujoco_refuses"] += 1
                c["mujoco_refuses"] += group == "main"
                if group == "main":
                    refusals.append(f"{p}: set apart, MuJoCo refuses it: {res['mujoco']}")
                continue
            if res["error"]:
                n = _candidates_of_failed(p)
                t["candidates"] += n
                t["files_refused"] += 1
                if group == "main":
                    c["files_refused"] += 1
                    c["candidates"] += n
                    failures.setdefault(_pattern(res["error"]), []).append((g, p, res["error"]))
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
                    skips.setdefault(_pattern(link["reason"] or ""), []).append(
                        (g, p, link["reason"] or ""))
                    refusals.append(f"{link['link']}: {p}: {_short(link['reason'])} "
                                    f"[helps: {helpful_option(link['reason'] or '')}]")
                if group == "main":
                    _count_link(c, link, args.check)
                    if any(ok is False for ok in link.get("computed_valid", {}).values()):
                        invalid.append(f"  {g}: {p.name}: {link['link']}: " + ", ".join(
                            t for t, ok in link["computed_valid"].items() if ok is False))
    wall = time.perf_counter() - wall
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
    print()
    print(doctor_table(table, args.check))
    print()
    print(f"files refused whole, by message ({sum(len(v) for v in failures.values())} files, "
          f"{len(failures)} distinct):")
    for hits in sorted(failures.values(), key=len, reverse=True):
        g, p, err = hits[0]
        print(f"  {len(hits)} x {g}: {_brief(err)}  (e.g. {p.name})")
    print(f"links refused, by message ({sum(len(v) for v in skips.values())} links, "
          f"{len(skips)} distinct):")
    for hits in sorted(skips.values(), key=len, reverse=True):
        g, p, err = hits[0]
        print(f"  {len(hits)} x {g}: {_brief(err)}  (e.g. {p.name})")
    print(f"computed inertials not valid ({len(invalid)} links): the test(s) failed")
    for line in invalid:
        print(line)
    print(f"run time: {wall:.1f} s wall, --jobs {args.jobs}")
    return 0


def _count_link(c: Counter, link: dict, rtol: float) -> None:
    """One computed or refused candidate link into its package's column."""
    c["candidates"] += 1
    if link["status"] != "computed":
        return
    c["computed"] += 1
    for test, ok in link["computed_valid"].items():
        c[f"computed_invalid:{test}"] += ok is False
    c["computed_invalid"] += any(ok is False for ok in link["computed_valid"].values())
    if not link["stated"]:
        return
    c["stated"] += 1
    for test, ok in link["stated_valid"].items():
        c[f"stated_invalid:{test}"] += ok is False
    c["stated_invalid"] += any(ok is False for ok in link["stated_valid"].values())
    worst = link["worst"]
    if worst is not None and worst <= rtol:
        c["agree"] += 1
    elif link["causes"] is not None:
        c["differ"] += 1
        if link["causes"]:
            c["diagnosed"] += 1
            for cause in set(link["causes"]):
                c[f"cause:{cause}"] += 1
        else:
            c["unexplained"] += 1
            # no named cause moves the COM: a stated COM away from the geometry's centroid is
            # a density that is not uniform (motors, electronics), which no cause models
            c["unexplained_com"] += link["com_rel"] is not None and link["com_rel"] > 0.01


CAUSES = ("about_point", "rotated", "axes_permuted", "length_unit", "mass_unit", "product_sign",
          "decimal_slip", "placeholder", "bounding_box", "convex_hull", "thin_shell",
          "mujoco_legacy", "other_geometry")


def doctor_table(table: dict[str, Counter], rtol: float) -> str:
    """A markdown table: one row per measure, one column per package and the total."""
    cols = list(table) + ["all"]
    total = Counter()
    for c in table.values():
        total.update(c)
    data = {**table, "all": total}
    rows = [("description files", "files"), ("  refused whole (read or parse error)",
                                              "files_refused"),
            ("  MJCF set apart (MuJoCo refuses it)", "mujoco_refuses"),
            ("links with geometry and mass", "candidates"), ("  computed", "computed"),
            ("  computed inertial invalid (any test)", "computed_invalid")]
    rows += [(f"    {t} false", f"computed_invalid:{t}") for t in TESTS]
    rows += [("computed links with a stated inertial", "stated"),
             ("  stated inertial invalid (any test)", "stated_invalid")]
    rows += [(f"    {t} false", f"stated_invalid:{t}") for t in TESTS]
    rows += [(f"  agree within {rtol:g}", "agree"), (f"  differ by more than {rtol:g}", "differ"),
             ("    diagnosed (one cause or more)", "diagnosed")]
    rows += [(f"      {cause}", f"cause:{cause}") for cause in CAUSES]
    rows += [("    unexplained", "unexplained"),
             ("      of which the COM is off by > 1 % of the link's size", "unexplained_com")]
    out = ["| measure | " + " | ".join(cols) + " |", "|---" * (len(cols) + 1) + "|"]
    for label, key in rows:
        out.append(f"| {label} | " + " | ".join(str(data[c][key]) for c in cols) + " |")
    out.append("| worker time, s | " + " | ".join(f"{data[c]['seconds']:.0f}" for c in cols)
               + " |")
    return "\n".join(out)


def _pattern(error: str) -> str:
    """An error message with its paths, numbers and quoted names blanked: one key per kind."""
    text = re.sub(r"(/[^\s:'\"]+)+", "<path>", error)
    text = re.sub(r"'[^']*'", "'…'", text)
    return re.sub(r"\d+(\.\d+)?(e[-+]?\d+)?", "N", text)


def _brief(text: str) -> str:
    """A message with each absolute path cut to its file name, on one line."""
    text = re.sub(r"\b\w+://(?:[^\s'\"/]+/)*", "", text)  # the folders of URIs
    text = re.sub(r"(^|[\s'\"])/(?:[^\s'\"/]+/)+", r"\1", text)  # of absolute paths
    return re.sub(r"\s+", " ", text)[:400]


def _short(text: str | None) -> str:
    return re.sub(r"\s+", " ", text or "")[:220]


if __name__ == "__main__":
    sys.exit(main())
