"""A robot description (URDF, SDF, MJCF) as a system: links -> bodies, joints -> joints.

Frames: the description's model frame is the world; every link sits where forward kinematics at
the zero pose (all joint coordinates 0) puts it (`robot.joints`). Links welded by fixed joints
are lumped into one body (masses, centres of mass and inertias summed by the parallel-axis rule
in the world frame at t = 0), named after the group's link nearest the base and carrying that
link's axes; so massless frames (base_footprint, tool frames) add no singular rows. A group
welded to the ground is the world. A group that a joint moves must carry mass (else the mass
matrix is singular): refused in one line naming the link and the joint.

The base: ``fixed`` welds every root link (a link no joint carries) and every floating joint to
the world; ``floating`` frees the roots and the bodies welded to the world; None follows the
description (URDF and SDF roots fixed, MJCF as written: a ``<freejoint>`` floats, a body without
a joint is welded). Joint limits are stated but not enforced, said once in the warnings, as are
what a simulation here leaves out (contacts, actuators, friction).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from massprops.dynamics.systems.assemble import build_tree, initial_coordinates, localized
from massprops.dynamics.systems.inertials import check_bodies, judged, sdf_defaults
from massprops.dynamics.systems.model import WORLD, JointCoupling, SystemBody, SystemJoint
from massprops.dynamics.systems.tree import kinematics, mass_matrix
from massprops.errors import RobotModelError
from massprops.robot.joints.frames import WORLD_LINK, Mechanism, RobotJoint, compose
from massprops.robot.mechanism import read_mechanism

__all__ = ["Description", "describe"]

INERTIALS = ("stated", "computed")
BASES = ("fixed", "floating")


@dataclass(frozen=True, eq=False)
class Description:
    """A description ready for a system scene: ``bodies`` and ``joints`` (systems values),
    ``gravity`` (3,) m/s² the description states (None: none stated), ``warnings`` one line each,
    ``body_of`` link name -> body index (WORLD for the ground), ``path`` the file, ``couplings``
    the description's joint relations over ``joints`` (mimic, MJCF joint/tendon equalities)."""

    path: Path
    bodies: tuple[SystemBody, ...]
    joints: tuple[SystemJoint, ...]
    gravity: np.ndarray | None
    warnings: tuple[str, ...]
    body_of: dict
    couplings: tuple[JointCoupling, ...] = ()


def describe(path: str | os.PathLike, *, inertials: str = "stated", base: str | None = None,
             package_paths=(), xacro_args=None) -> Description:
    """The bodies and joints of the description at ``path`` (see the module doc).

    inertials : "stated" (the file's inertials; an MJCF body without one gets MuJoCo's sum over
        its geoms) or "computed" (from the geometry, as ``massprops model`` computes them).
    base : "fixed", "floating" or None (the description's own). package_paths, xacro_args : as
        for ``massprops model`` (folders for package:// and model://; NAME -> VALUE of a
        .xacro file's $(arg NAME)). Raises RobotModelError.
    """
    # deferred: the robot analysis (parsers, mesh integrals) loads only for a description
    from massprops.robot.analyze import analyze_model, load_model

    path = Path(path)
    masses, warnings = {}, []
    model = load_model(path, package_paths=package_paths, xacro_args=xacro_args)
    auto = {link.name for link in model.links if link.stated is None and link.geometries
            and all(g.density is not None for g in link.geometries)}  # SDF <inertial auto>
    if inertials == "computed" or model.format == "mjcf" or auto:
        report = analyze_model(path, package_paths=package_paths, xacro_args=xacro_args)
        model = report.model
        if inertials == "computed" and report.errors:
            raise RobotModelError(report.errors[0])
        for r in report.links:
            use = r.computed if inertials == "computed" else (r.link.stated or r.computed)
            if use is None and r.status == "stated-only":
                use = r.link.stated
            if use is not None:
                masses[r.name] = (use.mass, np.asarray(use.center_of_mass, float),
                                  np.asarray(use.inertia, float))
            elif r.error and (model.format == "mjcf" or r.name in auto):
                # the simulator's inertia from geoms that cannot be read: not massless
                raise RobotModelError(report.errors[[x.name for x in report.links
                                                     if x.error].index(r.name)])
            elif inertials == "computed" and r.link.geometries:
                warnings.append(f"link {r.name!r}: no mass ({r.reason})")
    else:
        for link in model.links:
            if link.stated is not None:
                s = link.stated
                masses[link.name] = (s.mass, s.center_of_mass, s.inertia)
    if model.format == "sdf" and inertials == "stated":
        warnings += sdf_defaults(model, masses)
    nodes = {link.name: link.node for link in model.links}
    said, tol = judged(masses, path, nodes)
    warnings += said
    mech = read_mechanism(model)
    warnings += _said(mech, path)
    desc = _build(mech, masses, base, warnings, path)
    check_bodies(desc, tol, nodes)
    return desc


SIMULATION_SCOPE = ("joint limits are not enforced", "contacts, actuators and friction are "
                    "out of scope")
"""How the warnings about what a simulation leaves out begin: a command that simulates nothing
(``torques``) leaves them unsaid."""


def _said(mech: Mechanism, path: Path) -> list[str]:
    out = list(mech.remarks)
    if any(j.limits for j in mech.joints):
        named = [j.name for j in mech.joints if j.limits]
        out.append(f"{SIMULATION_SCOPE[0]} (the systems engine has no limits or contacts): "
                   f"{', '.join(named[:4])}{' ...' if len(named) > 4 else ''}")
    extra = "".join(f", {n}" for n in mech.notes)
    out.append(f"{SIMULATION_SCOPE[1]} and not simulated"
               f"{' (the description has ' + extra[2:] + ')' if extra else ''}")
    return out


# --- the bodies ---------------------------------------------------------------------------------
def _effective(mech: Mechanism, base: str | None) -> list[RobotJoint]:
    """The joints with the base rule applied: a root's weld or release, free joints resolved."""
    out = []
    carried = {j.child for j in mech.joints if not j.loop}
    for j in mech.joints:
        kind = j.kind
        if not j.loop and j.parent == WORLD_LINK:
            if kind == "fixed" and base == "floating":
                kind = "free"
            elif kind == "free" and base == "fixed":
                kind = "fixed"
        elif kind == "free" and base == "fixed":
            kind = "fixed"
        out.append(j if kind == j.kind else _with_kind(j, kind))
    for link in mech.poses:
        if link not in carried and link != WORLD_LINK:
            kind = "free" if base == "floating" else "fixed"
            out.append(RobotJoint(f"{link}.base", kind, WORLD_LINK, link,
                                  (np.eye(3), np.zeros(3)), np.zeros((0, 3)), None))
    return out


def _with_kind(j: RobotJoint, kind: str) -> RobotJoint:
    return RobotJoint(j.name, kind, j.parent, j.child, j.frame, j.axes, j.node)


def _groups(links: list[str], joints: list[RobotJoint]) -> dict:
    """link -> the representative of its fixed group (union-find over the fixed joints)."""
    up = {name: name for name in [*links, WORLD_LINK]}

    def find(x: str) -> str:
        while up[x] != x:
            up[x] = up[up[x]]
            x = up[x]
        return x

    for j in joints:
        if j.kind == "fixed" and not j.loop:
            a, b = find(j.parent), find(j.child)
            if a != b:
                up[b] = a
    return {name: find(name) for name in up}


def _build(mech: Mechanism, masses: dict, base: str | None, warnings: list[str],
           path: Path) -> Description:
    joints = _effective(mech, base)
    links = list(mech.poses)
    group = _groups(links, joints)
    world = group[WORLD_LINK]
    # each group's head is its one link carried by a joint that moves (or frees) it
    carrier = {j.child: j for j in joints if not j.loop}
    heads = [n for n in links if group[n] != world and carrier[n].kind != "fixed"]
    head_of = {group[h]: h for h in heads}
    index = {name: k for k, name in enumerate(heads)}
    body_of = {n: WORLD if group[n] == world else index[head_of[group[n]]] for n in links}
    bodies = [_lumped(head, [n for n in links if body_of[n] == index[head]], mech.poses,
                      masses)
              for head in heads]
    sys_joints = []
    for j in joints:
        if (j.kind in ("fixed", "free")) and not j.loop:  # a loop weld is a cut fixed joint
            continue
        a = WORLD if j.parent == WORLD_LINK else body_of[j.parent]
        b = WORLD if j.child == WORLD_LINK else body_of[j.child]
        if a == b:
            raise RobotModelError(f"{_where(j, path)}joint {j.name!r} joins links that fixed "
                                  "joints weld into one body; it cannot move: make it fixed")
        rot, point = compose(mech.poses[j.child], j.frame)
        sys_joints.append(SystemJoint(j.name, j.kind, a, b, point, (rot @ j.axes.T).T,
                                      damping=j.damping, stiffness=j.stiffness, rest=j.rest,
                                      loop=j.loop))
    _check_masses(bodies, sys_joints, heads, path, mech)
    couplings = _couplings(mech, sys_joints, path, warnings)
    return Description(path, tuple(bodies), tuple(sys_joints), mech.gravity, tuple(warnings),
                       body_of, couplings)


def _couplings(mech: Mechanism, sys_joints: list[SystemJoint], path: Path,
               warnings: list[str]) -> tuple:
    """The mechanism's couplings over the system joints (by name). A fixed joint's coordinate
    is 0: its term drops out; a coupling whose follower is fixed (a reduced model's welded
    gripper) has nothing to move and is left out, said in ``warnings``."""
    index = {j.name: k for k, j in enumerate(sys_joints)}
    kinds = {j.name: j.kind for j in mech.joints}
    out, still = [], []
    for c in mech.couplings:
        where = f"{c.node.file or path}:{c.node.line}: <{c.node.tag}>: "
        terms = []
        for name, coef in c.terms:
            if name not in kinds:
                raise RobotModelError(f"{where}{c.name}: joint {name!r} is not a joint of the "
                                      "description; check the spelling")
            if kinds[name] != "fixed" and name not in index:
                raise RobotModelError(f"{where}{c.name}: joint {name!r} is {kinds[name]}: it "
                                      "has no one coordinate to couple")
            if name in index:
                terms.append((index[name], float(coef)))
        follower = c.terms[0][0]
        if not terms or terms[0][0] != index.get(follower):
            still.append(follower)
            continue
        out.append(JointCoupling(c.name, tuple(terms), float(c.constant), where))
    if still:
        warnings.append(f"the couplings (mimic) of fixed joint(s) {', '.join(still[:4])}"
                        f"{' ...' if len(still) > 4 else ''} are left out: nothing moves them")
    return tuple(out)


def _lumped(head: str, members: list[str], poses: dict, masses: dict) -> SystemBody:
    """One body from the links of a fixed group, in the head link's axes (world at t = 0)."""
    rot0 = poses[head][0]
    total, first = 0.0, np.zeros(3)
    parts = []
    for name in members:
        if name not in masses or masses[name][0] <= 0:
            continue
        m, c, j = masses[name]
        r, t = poses[name]
        parts.append((m, r @ c + t, r @ j @ r.T))
        total += m
        first += m * (r @ c + t)
    com = first / total if total > 0 else poses[head][1]
    inertia = np.zeros((3, 3))
    for m, c, jw in parts:
        d = c - com
        inertia += jw + m * ((d @ d) * np.eye(3) - np.outer(d, d))
    spread = max((float(np.linalg.norm(poses[n][1] - com)) for n in members), default=0.0)
    # a point mass's inertia may carry -1e-20 round-off (`inertials.judged`): no square root of it
    gyration = float(np.sqrt(max(np.trace(inertia), 0.0) / (2 * total))) if total > 0 else 0.0
    return SystemBody(head, float(total), rot0.T @ inertia @ rot0, rot0, com,
                      max(2 * spread, 2 * gyration))


def _where(j: RobotJoint | None, path: Path) -> str:
    if j is None or j.node is None:
        return f"{path}: "
    return f"{j.node.file or path}:{j.node.line}: "


def _check_masses(bodies, joints, heads, path: Path, mech: Mechanism) -> None:
    """Every body a joint moves carries mass in its subtree (the part of the tree it moves)."""
    children: dict[int, list[int]] = {}
    parent_joint = {}
    for j in joints:
        if not j.loop:
            children.setdefault(j.a, []).append(j.b)
            parent_joint[j.b] = j
    by_name = {j.name: j for j in mech.joints}

    def subtree_mass(i: int) -> float:
        return bodies[i].mass + sum(subtree_mass(c) for c in children.get(i, ()))

    for i in range(len(bodies)):
        if subtree_mass(i) > 0:
            continue
        j = parent_joint.get(i)
        what = f"joint {j.name!r} moves it" if j is not None else "it floats free (base)"
        raise RobotModelError(f"{_where(by_name.get(j.name) if j else None, path)}link "
                              f"{heads[i]!r} and what it carries have no mass, but {what}: the "
                              "motion is undefined; give the link an inertial or make the "
                              "joint fixed")


_SINGULAR = 1e-12  # λ_min / λ_max of the mass matrix below which a motion carries no inertia
# (written inertials are ~1e-6 at the least against ~1e2 for a whole arm: far above round-off)


def check_mass_matrix(scene) -> None:
    """RobotModelError (one line) when the mass matrix at the start (the engine's own assembly
    and CRBA, as the run will use them) is singular: some joint motion moves no mass and no
    inertia (two joints on one axis with a massless link between)."""
    scene, _ = localized(scene)  # about its middle: M's smallest eigenvalue kept wherever it is
    tree = build_tree(scene)
    if tree.nv == 0:
        return
    q, _, _, _ = initial_coordinates(scene, tree)
    matrix = mass_matrix(tree, kinematics(tree, q, np.zeros(tree.nv)))
    values = np.linalg.eigvalsh(matrix)  # the vectors only to name the joints of a failure
    if values[0] > _SINGULAR * max(values[-1], 0.0):
        return
    values, vectors = np.linalg.eigh(matrix)
    weight = np.abs(vectors[:, 0])
    names = [scene.joints[j.source].name if j.source is not None else "the floating base"
             for j in tree.joints if j.nv and weight[j.iu:j.iu + j.nv].max() > 0.1 * weight.max()]
    raise RobotModelError(f"{scene.robot}: the mass matrix is singular: joint(s) "
                          f"{', '.join(names)} move no mass or inertia along one motion (e.g. "
                          "two joints on one axis with a massless link between); give the "
                          "links between them an inertial or make one joint fixed")
