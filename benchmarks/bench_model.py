"""Whole-model speed of `massprops model` against trimesh-based tools, and MuJoCo's own bodies.

1. A 20-link chain robot is written to a temporary folder: every link has one binary-STL torus
   (~50k triangles each, ~1M in total) as collision geometry with its own scale and origin, and a
   placeholder inertial. Whole processes, best of --repeat, interleaved:
   - massprops: ``massprops model robot.urdf --json`` (parse, read, health checks, exact
     integrals, comparison, report);
   - yourdfpy + trimesh (if installed): parse the URDF with yourdfpy, load each collision mesh
     with trimesh, scale and place it in the link frame (``apply_transform``), take its
     ``mass_properties`` and sum them by parallel axes (trimesh's ``inertia`` is about the COM);
   - yourdfpy loading the model with its collision meshes (its trimesh scene), no mass
     properties at all: the cost of merely loading the model in that tool chain.
   Prints times and ratios, and the largest difference between the two tool chains' link
   tensors (relative to each tensor's 2-norm).
2. If the ``mujoco`` package is installed: the same robot as MJCF (mesh ``inertia="exact"``,
   every geom at density 1000, no inertials) compiled by MuJoCo; massprops' bodies against
   MuJoCo's compiled ``body_mass``, ``body_ipos`` and ``body_inertia`` turned by ``body_iquat``
   (MuJoCo reports the principal moments and the principal frame's orientation). Prints the
   largest relative differences and the times (MuJoCo: compile in process; massprops: a whole
   process).

    python benchmarks/bench_model.py [--links 20] [--triangles 1000000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_inspect import run, torus_soup, write_binary_stl  # noqa: E402

PEER = r"""
import sys, json, numpy as np, trimesh, yourdfpy
if sys.argv[2] == "load":  # what a trimesh-based tool does to load the model with its meshes
    yourdfpy.URDF.load(sys.argv[1], load_collision_meshes=True, build_collision_scene_graph=True,
                       load_meshes=False, build_scene_graph=False)
    sys.exit()
robot = yourdfpy.URDF.load(sys.argv[1], load_meshes=False, build_scene_graph=False)
out = {}
for link in robot.robot.links:
    parts = []
    for c in link.collisions:
        g = c.geometry.mesh
        m = trimesh.load(robot._filename_handler(g.filename), force="mesh")
        if g.scale is not None:
            m.apply_scale(g.scale)
        m.apply_transform(c.origin if c.origin is not None else np.eye(4))
        p = m.mass_properties
        parts.append((p["mass"], p["center_mass"], p["inertia"]))
    total = sum(p[0] for p in parts)
    com = sum(p[0] * p[1] for p in parts) / total
    j = sum(p[2] + p[0] * (np.dot(p[1] - com, p[1] - com) * np.eye(3)
                          - np.outer(p[1] - com, p[1] - com)) for p in parts)
    out[link.name] = {"mass": total, "com": com.tolist(), "inertia": j.tolist()}
print(json.dumps(out))
"""


def rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    def r(axis, a):
        c, s = math.cos(a), math.sin(a)
        m = np.eye(3)
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
        return m
    return r(2, yaw) @ r(1, pitch) @ r(0, roll)


def build(folder: Path, links: int, triangles: int) -> tuple[Path, Path]:
    """Write the meshes, robot.urdf and robot.xml (MJCF); returns the two description paths."""
    rng = np.random.default_rng(3)
    per = max(200, triangles // links)
    urdf = ['<?xml version="1.0"?>', '<robot name="bench">']
    mjcf = ['<mujoco model="bench">', "  <asset>"]
    bodies = []
    for k in range(links):
        stl = folder / f"link{k}.stl"
        write_binary_stl(stl, torus_soup(per, major=0.05 + 0.01 * k, minor=0.02))
        xyz = rng.uniform(-0.1, 0.1, 3)
        angles = rng.uniform(-1.0, 1.0, 3)
        scale = rng.uniform(0.5, 1.5, 3)
        s = " ".join(repr(float(x)) for x in scale)
        urdf += [f'  <link name="link{k}">',
                 '    <inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" '
                 'iyz="0" izz="1"/></inertial>',
                 f'    <collision><origin xyz="{" ".join(map(repr, xyz.tolist()))}" '
                 f'rpy="{" ".join(map(repr, angles.tolist()))}"/>',
                 f'      <geometry><mesh filename="{stl.name}" scale="{s}"/></geometry>',
                 "    </collision>", "  </link>"]
        if k:
            urdf.append(f'  <joint name="j{k}" type="revolute"><parent link="link{k - 1}"/>'
                        f'<child link="link{k}"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>'
                        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')
        mjcf.append(f'    <mesh name="m{k}" file="{stl.name}" scale="{s}" inertia="exact"/>')
        quat = _quat(rpy(*angles))
        bodies.append((k, xyz, quat))
    urdf.append("</robot>")
    mjcf += ["  </asset>", "  <worldbody>"]
    for k, xyz, quat in bodies:
        mjcf.append("    " * 1 + "  " * k + f'<body name="link{k}" pos="0 0 0.2">'
                    f'<joint type="hinge"/><geom type="mesh" mesh="m{k}" '
                    f'pos="{" ".join(map(repr, xyz.tolist()))}" '
                    f'quat="{" ".join(map(repr, quat.tolist()))}"/>')
    mjcf += ["    " + "  " * k + "</body>" for k in reversed(range(links))]
    mjcf += ["  </worldbody>", "</mujoco>"]
    (folder / "robot.urdf").write_text("\n".join(urdf) + "\n")
    (folder / "robot.xml").write_text("\n".join(mjcf) + "\n")
    return folder / "robot.urdf", folder / "robot.xml"


def _quat(a: np.ndarray) -> np.ndarray:
    from massprops.rotation import matrix_to_quat

    return matrix_to_quat(a)


def massprops_links(path: Path, *extra: str) -> dict:
    out = subprocess.run([sys.executable, "-m", "massprops", "model", "--json", *extra,
                          str(path)], capture_output=True, text=True, check=True)
    return {r["link"]: r["computed"] for r in map(json.loads, out.stdout.splitlines())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", type=int, default=20)
    ap.add_argument("--triangles", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    py = sys.executable
    have_peer = importlib.util.find_spec("yourdfpy") is not None
    with tempfile.TemporaryDirectory() as tmp:
        urdf, mjcf = build(Path(tmp), args.links, args.triangles)
        print(f"robot: {args.links} links, ~{args.triangles:,} triangles of binary STL in total")
        ours = [py, "-m", "massprops", "model", "--json", str(urdf)]
        rows = {"massprops model": ours}
        if have_peer:
            rows["yourdfpy load (meshes)"] = [py, "-c", PEER, str(urdf), "load"]
            rows["yourdfpy + trimesh"] = [py, "-c", PEER, str(urdf), "mass"]
        else:
            print("yourdfpy is not installed: no trimesh-based peer (pip install yourdfpy)")
        best = {name: (math.inf, 0.0) for name in rows}
        for _ in range(args.repeat):  # interleaved, so load from others hits each alike
            for name, cmd in rows.items():
                t, mem = run(cmd, 1)
                best[name] = (min(best[name][0], t), max(best[name][1], mem))
        base = best["massprops model"][0]
        print(f"{'whole process':<22}{'time [s]':>10}{'/ massprops':>13}{'peak RSS [MiB]':>16}")
        for name, (t, mem) in best.items():
            print(f"{name:<22}{t:>10.3f}{t / base:>13.2f}{mem:>16.0f}")
        ours_links = massprops_links(urdf, "--density", "1")
        if have_peer:
            peer = json.loads(subprocess.run([py, "-c", PEER, str(urdf), "mass"],
                                             capture_output=True, text=True,
                                             check=True).stdout)
            worst = max(np.linalg.norm(np.array(ours_links[k]["inertia"])
                                       - np.array(v["inertia"]), 2)
                        / np.linalg.norm(np.array(v["inertia"]), 2) for k, v in peer.items())
            print(f"largest link-tensor difference, massprops vs trimesh: {worst:.2e} "
                  "(relative, 2-norm)")
        compare_mujoco(mjcf, args.repeat)


def compare_mujoco(mjcf: Path, repeat: int) -> None:
    if importlib.util.find_spec("mujoco") is None:
        print("mujoco is not installed: no comparison with MuJoCo's compiled bodies "
              "(pip install mujoco)")
        return
    import mujoco

    from massprops.rotation import quat_to_matrix

    t_mj = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        model = mujoco.MjModel.from_xml_path(str(mjcf))
        t_mj = min(t_mj, time.perf_counter() - t0)
    t_mp, _ = run([sys.executable, "-m", "massprops", "model", "--json", str(mjcf)], repeat)
    ours = massprops_links(mjcf)
    worst = {"mass": 0.0, "com": 0.0, "inertia": 0.0}
    for name, c in ours.items():
        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
        a = quat_to_matrix(model.body_iquat[b])
        j = a @ np.diag(model.body_inertia[b]) @ a.T
        size = math.sqrt(np.trace(j) / model.body_mass[b])  # a length of the body
        worst["mass"] = max(worst["mass"], abs(c["mass"] - model.body_mass[b]) / c["mass"])
        worst["com"] = max(worst["com"], float(np.linalg.norm(
            np.array(c["center_of_mass"]) - model.body_ipos[b])) / size)
        worst["inertia"] = max(worst["inertia"], float(np.linalg.norm(
            np.array(c["inertia"]) - j, 2) / np.linalg.norm(j, 2)))
    print(f"MuJoCo {mujoco.__version__} vs massprops on the same MJCF ({len(ours)} bodies): "
          f"largest relative difference mass {worst['mass']:.1e}, COM {worst['com']:.1e} "
          f"(of the radius of gyration), inertia {worst['inertia']:.1e} (2-norm)")
    print(f"MuJoCo compile (in process) {t_mj:.3f} s; massprops model (whole process) "
          f"{t_mp:.3f} s")


if __name__ == "__main__":
    main()
