"""One serial arm written three ways for the mechanism tests: as URDF, as MJCF (for MuJoCo) and
as plain data. Written from the numbers here, never from massprops' output.

The arm: a base welded to the world (a massless base_footprint above it), a yaw joint (z), a
shoulder and an elbow (y), a prismatic slide along the forearm (x), a wrist roll (x), and a
massless tool frame welded to the wrist. Joint origins carry rpy turns and the inertials sit off
their link origins with turned, full tensors, so every frame convention is exercised.
"""

from __future__ import annotations

import math

import numpy as np

# name, type, parent, child, origin xyz, origin rpy, axis
JOINTS = [
    ("yaw", "revolute", "base", "turret", (0.0, 0.0, 0.12), (0.0, 0.0, 0.3), (0, 0, 1)),
    ("shoulder", "revolute", "turret", "upper", (0.03, 0.0, 0.1), (0.2, 0.0, 0.0), (0, 1, 0)),
    ("elbow", "revolute", "upper", "fore", (0.45, 0.02, 0.0), (0.0, 0.1, 0.0), (0, 1, 0)),
    ("slide", "prismatic", "fore", "sleeve", (0.2, 0.0, 0.0), (0.0, 0.0, 0.0), (1, 0, 0)),
    ("wrist", "revolute", "sleeve", "hand", (0.15, 0.0, 0.0), (0.0, 0.0, -0.4), (1, 0, 0)),
]
# link: mass, com xyz, inertial rpy, (ixx, iyy, izz, ixy, ixz, iyz)
LINKS = {
    "base": (6.0, (0.0, 0.0, 0.05), (0, 0, 0), (0.06, 0.06, 0.08, 0, 0, 0)),
    "turret": (2.0, (0.01, 0.0, 0.05), (0.1, 0.0, 0.0), (0.010, 0.012, 0.008, 0.001, 0, 0)),
    "upper": (1.5, (0.22, 0.01, 0.0), (0.0, 0.0, 0.2), (0.003, 0.030, 0.031, 0, 0.0005, 0)),
    "fore": (0.8, (0.12, 0.0, 0.01), (0.0, 0.3, 0.0), (0.001, 0.012, 0.012, 0, 0, 0.0002)),
    "sleeve": (0.4, (0.05, 0.0, 0.0), (0, 0, 0), (0.0004, 0.002, 0.002, 0, 0, 0)),
    "hand": (0.3, (0.04, 0.01, 0.0), (0.0, 0.0, 0.5), (0.0003, 0.0006, 0.0007, 0.0001, 0, 0)),
}
MASSLESS = ("base_footprint", "tool")


def rpy(r: float, p: float, y: float) -> np.ndarray:
    def rot(axis: int, a: float) -> np.ndarray:
        c, s = math.cos(a), math.sin(a)
        m = np.eye(3)
        i, j = (axis + 1) % 3, (axis + 2) % 3
        m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
        return m

    return rot(2, y) @ rot(1, p) @ rot(0, r)


def tensor(six) -> np.ndarray:
    ixx, iyy, izz, ixy, ixz, iyz = six
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


def quat(m: np.ndarray) -> list[float]:
    """[w, x, y, z] of a rotation matrix (trace method; the test arms have no half turns)."""
    w = math.sqrt(max(0.0, 1 + m[0, 0] + m[1, 1] + m[2, 2])) / 2
    return [w, (m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w),
            (m[1, 0] - m[0, 1]) / (4 * w)]


def _f(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def urdf(joints=JOINTS, links=LINKS, damping=None) -> str:
    """The arm as URDF; ``damping``: joint name -> N·m·s/rad (or N·s/m)."""
    out = ['<robot name="arm">', '  <link name="world"/>', '  <link name="base_footprint"/>',
           '  <joint name="mount" type="fixed"><parent link="world"/>'
           '<child link="base_footprint"/></joint>',
           '  <joint name="foot" type="fixed"><parent link="base_footprint"/>'
           '<child link="base"/><origin xyz="0 0 0.01"/></joint>']
    for name, (m, com, r, six) in links.items():
        ixx, iyy, izz, ixy, ixz, iyz = six
        out.append(f'  <link name="{name}"><inertial><origin xyz="{_f(com)}" rpy="{_f(r)}"/>'
                   f'<mass value="{m!r}"/><inertia ixx="{ixx!r}" ixy="{ixy!r}" ixz="{ixz!r}" '
                   f'iyy="{iyy!r}" iyz="{iyz!r}" izz="{izz!r}"/></inertial></link>')
    for name, kind, parent, child, xyz, r, axis in joints:
        extra = ""
        if damping and name in damping:
            extra = f'<dynamics damping="{damping[name]!r}"/>'
        out.append(f'  <joint name="{name}" type="{kind}"><parent link="{parent}"/>'
                   f'<child link="{child}"/><origin xyz="{_f(xyz)}" rpy="{_f(r)}"/>'
                   f'<axis xyz="{_f(axis)}"/><limit lower="-3" upper="3" effort="50" '
                   f'velocity="5"/>{extra}</joint>')
    last = joints[-1][3]
    out.append('  <link name="tool"/>')
    out.append(f'  <joint name="tool_mount" type="fixed"><parent link="{last}"/>'
               '<child link="tool"/><origin xyz="0.1 0 0"/></joint>')
    out.append("</robot>")
    return "\n".join(out)


def mjcf(joints=JOINTS, links=LINKS, damping=None, timestep=1e-4) -> str:
    """The same arm as MJCF: contacts off, RK4, no armature, inertias turned into the body
    frame by hand (fullinertia, no quat)."""
    children: dict[str, list] = {}
    for j in joints:
        children.setdefault(j[2], []).append(j)

    def inertial(name: str) -> str:
        m, com, r, six = links[name]
        a = rpy(*r)
        t = a @ tensor(six) @ a.T
        full = [t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2]]
        return f'<inertial pos="{_f(com)}" mass="{m!r}" fullinertia="{_f(full)}"/>'

    def body(j) -> str:
        name, kind, parent, child, xyz, r, axis = j
        typ = "hinge" if kind == "revolute" else "slide"
        d = f' damping="{damping[name]!r}"' if damping and name in damping else ""
        inner = "".join(body(c) for c in children.get(child, []))
        return (f'<body name="{child}" pos="{_f(xyz)}" quat="{_f(quat(rpy(*r)))}">'
                f'{inertial(child)}<joint name="{name}" type="{typ}" axis="{_f(axis)}"{d}/>'
                f'{inner}</body>')

    top = "".join(body(c) for c in children.get("base", []))
    return (f'<mujoco><option timestep="{timestep!r}" integrator="RK4">'
            '<flag contact="disable"/></option><compiler angle="radian"/><worldbody>'
            f'<body name="base" pos="0 0 0.01">{inertial("base")}{top}</body>'
            '</worldbody></mujoco>')


def run_mujoco(xml: str, qpos: dict, qvel: dict, duration: float) -> dict:
    """Joint name -> qpos after ``duration`` s of MuJoCo's RK4 from the given start."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    for name, value in qpos.items():
        data.qpos[model.joint(name).qposadr[0]] = value
    for name, value in qvel.items():
        data.qvel[model.joint(name).dofadr[0]] = value
    for _ in range(round(duration / model.opt.timestep)):
        mujoco.mj_step(model, data)
    return {model.joint(i).name: float(data.qpos[model.jnt_qposadr[i]])
            for i in range(model.njnt)}
