"""From a SystemScene to a `Tree`: the spanning tree, cut joints, and the initial state.

The tree is grown breadth-first from the world, each body's joints in the order: named in
``initial``, then loaded (damping, a spring, a drive), then the rest, each in scene order; a
distance joint and a description's loop joint are always cut; in each part that nothing joins
to the world the first body gets a free joint (a floating base) and the tree grows from it.
Breadth-first growth alone may still cut a named or loaded joint (the joint where a loop's two
branches meet), so each such cut joint, named ones first, then loaded ones, each in scene order,
is exchanged with a tree joint of the loop it closes that ranks below it (unloaded and unnamed
first, then for a named joint a loaded one; among equals the last in scene order), and the tree
is grown again over the joints so chosen. A loop with no such joint keeps its cut: a named cut
joint is refused (its coordinates follow from the others), a loaded one carries its load on the
cut (`cutjoint`). A scene with no named or loaded joint on a cut keeps the breadth-first cut.
Every refusal names the scene's file, line and key.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from massprops import tolerances
from massprops.dynamics.systems.loops import Coupling, Primitive, primitives
from massprops.dynamics.systems.model import ONE_AXIS, WORLD, SystemScene
from massprops.dynamics.systems.tree import NQ, NV, TreeJoint, joint_rates, quat_matrix
from massprops.errors import SceneError


@dataclass(eq=False)
class Tree:
    """bodies (SystemBody); joints (TreeJoint, parents before children); parent_joint: body ->
    index of the tree joint that carries it; cut: indices of the scene's cut joints; prims: their
    primitives; of_scene: scene joint index -> ("tree", k) or ("cut", k); nq, nv; loaded: the
    tree joints with a spring, damper or drive, cut_loaded: the cut joints with one."""

    bodies: tuple
    joints: list
    parent_joint: dict
    cut: list
    prims: list[Primitive]
    of_scene: dict
    nq: int
    nv: int
    size: float
    loaded: list = field(default_factory=list)  # tree joint indices with springs/drives
    cut_loaded: list = field(default_factory=list)  # indices into ``cut`` with springs/drives
    couplings: list[Coupling] = field(default_factory=list)  # rows after the primitives'


def localized(scene: SystemScene) -> tuple[SystemScene, np.ndarray]:
    """(``scene`` moved by −o, o): o (3,) m world is the middle of the box around the bodies'
    centres of mass and the joints' points, so that the moved assembly sits about the origin.

    The engine's spatial vectors and inertias are world-frame about the origin (`tree`): an
    assembly d away from it keeps a body's inertia only to (d / size)² × eps (the parallel-axis
    term m d² swamps it) and its velocities to (d / size) × eps (v_O = v − ω × c). The double
    pendulum 1e3 m away ended 2.6e-9 rad off after 2 s and 1e6 m away took two million steps
    for 5 ms; about its own middle it is the same run wherever it sits. Gravity, directions,
    velocities and joint coordinates are unchanged by the move; positions and points out of
    the run get o back (`outputs`)."""
    points = [b.com0 for b in scene.bodies] + [j.point for j in scene.joints
                                               if j.point is not None]
    origin = 0.5 * (np.min(points, axis=0) + np.max(points, axis=0))
    if not origin.any():
        return scene, origin

    def moved(p):
        return None if p is None else p - origin

    return dataclasses.replace(
        scene,
        bodies=tuple(dataclasses.replace(b, com0=b.com0 - origin) for b in scene.bodies),
        joints=tuple(dataclasses.replace(j, point=moved(j.point), points=moved(j.points))
                     for j in scene.joints),
        forces=tuple(dataclasses.replace(f, point=moved(f.point)) for f in scene.forces),
        springs=tuple(dataclasses.replace(s, points=moved(s.points)) for s in scene.springs),
    ), origin


def _loaded(j) -> bool:
    return j.kind in ONE_AXIS and bool(j.damping or j.stiffness or j.drive)


def _priority(scene: SystemScene, k: int) -> int:
    j = scene.joints[k]
    named = j.name in scene.initial.positions or j.name in scene.initial.rates
    return 0 if named else (1 if _loaded(j) else 2)


def _grow(scene: SystemScene, order: list, allowed: set | None):
    """Breadth-first spanning tree over the joints in ``allowed`` (None: every joint that may be
    a tree joint): ([(scene joint, parent, child, reversed)], used joints, floating bases)."""
    bodies = scene.bodies
    placed, frontier = {WORLD}, [WORLD]
    in_tree: list[tuple[int, int, int, bool]] = []
    used: set = set()
    free: list[int] = []
    while frontier or len(placed) <= len(bodies):
        if not frontier:  # the rest hangs on a floating base: the first unplaced body
            free.append(next(i for i in range(len(bodies)) if i not in placed))
            placed.add(free[-1])
            frontier = [free[-1]]
        nxt = []
        for node in frontier:
            for k in order:
                j = scene.joints[k]
                if k in used or j.kind == "distance" or j.loop or node not in (j.a, j.b) \
                        or (allowed is not None and k not in allowed):
                    continue
                other = j.b if j.a == node else j.a
                if other in placed:
                    continue
                used.add(k)
                placed.add(other)
                in_tree.append((k, node, other, j.a != node))
                nxt.append(other)
        frontier = nxt
    return in_tree, used, free


def _tree_path(scene: SystemScene, used: set, a: int, b: int) -> list[int]:
    """The tree joints (scene indices) on the path from body ``a`` to body ``b``."""
    links: dict = {}
    for k in used:
        j = scene.joints[k]
        links.setdefault(j.a, []).append((k, j.b))
        links.setdefault(j.b, []).append((k, j.a))
    came: dict[int, tuple[int, int] | None] = {a: None}
    todo = [a]
    while todo and b not in came:
        node = todo.pop()
        for k, other in links.get(node, ()):
            if other not in came:
                came[other] = (k, node)
                todo.append(other)
    path, node = [], b
    while (step := came.get(node)) is not None:
        k, node = step
        path.append(k)
    return path


def _exchanged(scene: SystemScene, used: set) -> set:
    """``used`` with each named, then loaded, cut joint exchanged for a lower-ranked tree joint
    of its loop where the loop has one (the module doc's rule)."""
    used = set(used)
    for level in (0, 1):
        for k, j in enumerate(scene.joints):
            if k in used or j.loop or j.kind == "distance" or _priority(scene, k) != level:
                continue
            lower = [m for m in _tree_path(scene, used, j.a, j.b) if _priority(scene, m) > level]
            if lower:
                used.remove(max(lower, key=lambda m: (_priority(scene, m), m)))
                used.add(k)
    return used


def build_tree(scene: SystemScene) -> Tree:
    """The spanning tree of ``scene``'s joints (see the module doc)."""
    bodies = scene.bodies
    order = sorted(range(len(scene.joints)), key=lambda k: (_priority(scene, k), k))
    in_tree, used, free = _grow(scene, order, None)
    chosen = _exchanged(scene, used)
    if chosen != used:
        in_tree, used, free = _grow(scene, order, chosen)
    joints, iq, iu = [], 0, 0
    for i in free:  # floating bases first: they are roots
        joints.append(TreeJoint("free", WORLD, i, np.zeros((0, 3)), np.zeros(3), np.zeros(3),
                                np.eye(3), iq, iu, None))
        iq, iu = iq + NQ["free"], iu + NV["free"]
    for k, parent, child, rev in in_tree:
        j = scene.joints[k]
        point = j.point
        axes = np.asarray(j.axes, float)
        if rev and j.kind == "universal":
            axes = axes[::-1].copy()
        rp0 = np.eye(3) if parent == WORLD else bodies[parent].rotation0
        cp0 = np.zeros(3) if parent == WORLD else bodies[parent].com0
        joints.append(TreeJoint(j.kind, parent, child, axes, rp0.T @ (point - cp0),
                                bodies[child].rotation0.T @ (point - bodies[child].com0),
                                rp0, iq, iu, k, rev))
        iq, iu = iq + NQ[j.kind], iu + NV[j.kind]
    joints = _parents_first(joints)
    parent_joint = {j.child: n for n, j in enumerate(joints)}
    of_scene = {j.source: ("tree", n) for n, j in enumerate(joints) if j.source is not None}
    cut = [k for k in range(len(scene.joints)) if k not in used]
    prims: list[Primitive] = []
    for n, k in enumerate(cut):
        j = scene.joints[k]
        for name, values in (("positions", scene.initial.positions),
                             ("rates", scene.initial.rates)):
            if j.name in values:
                raise SceneError(f"{scene.where(f'initial.{name}.{j.name}')}joint {j.name!r} "
                                 "closes a loop whose other joints are named too (or is a "
                                 "description's loop joint): its coordinates follow from the "
                                 f"others; remove it from initial.{name}")
        of_scene[k] = ("cut", n)
        prims += primitives(j, n, bodies)
    loaded = [n for n, j in enumerate(joints) if j.source is not None
              and _loaded(scene.joints[j.source])]
    cut_loaded = [n for n, k in enumerate(cut) if _loaded(scene.joints[k])]
    couplings = [_coupling(scene, c, joints, of_scene) for c in scene.couplings]
    return Tree(bodies, joints, parent_joint, cut, prims, of_scene, iq, iu, scene.size, loaded,
                cut_loaded, couplings)


def _coupling(scene: SystemScene, c, joints: list[TreeJoint], of_scene: dict) -> Coupling:
    """A scene's `JointCoupling` over tree coordinates: each joint a one-axis tree joint (a
    reversed one's coordinate is the scene's negated); the row in metres (× the system size
    where the follower turns)."""
    terms = []
    for k, coef in c.terms:
        j = scene.joints[k]
        where, n = of_scene[k]
        if j.kind not in ("revolute", "prismatic") or where != "tree":
            why = "closes a loop" if where == "cut" else f"is {j.kind}"
            raise SceneError(f"{c.where}{c.name}: joint {j.name!r} {why}: only the coordinates "
                             "of revolute and prismatic joints of the tree can be coupled")
        tj = joints[n]
        terms.append((tj.iq, tj.iu, -coef if tj.reversed else coef))
    follower = scene.joints[c.terms[0][0]]
    scale = scene.size if follower.kind == "revolute" else 1.0
    return Coupling(c.name, tuple(terms), float(c.constant), scale)


def tree_order(j: TreeJoint, value: np.ndarray) -> np.ndarray:
    """A one- or two-axis joint's scene coordinates (or rates) as the tree keeps them: a joint
    the tree runs from its second body to its first turns or shifts the other way, and a
    universal joint's axes come in the other order (`build_tree`)."""
    if not j.reversed:
        return value
    return -(value[::-1] if j.kind == "universal" else value)


def _parents_first(joints: list[TreeJoint]) -> list[TreeJoint]:
    """The joints ordered so that a body's joint comes after its parent's (BFS already is)."""
    done, out = {WORLD}, []
    pending = list(joints)
    while pending:
        rest = []
        for j in pending:
            if j.parent in done:
                out.append(j)
                done.add(j.child)
            else:
                rest.append(j)
        pending = rest
    return out


# --- the initial state --------------------------------------------------------------------------
_CANNOT_MOVE = ("fixed", "distance")


def initial_coordinates(scene: SystemScene, tree: Tree, notes: list[str] | None = None
                        ) -> tuple[np.ndarray, np.ndarray, set, set]:
    """q0, u0 from ``initial`` (tree coordinates), and the sets of u indices the scene fixed
    (named rates) and of q tangent indices it fixed (named positions). A spherical joint's
    quaternion is normalised, and said in ``notes`` where its norm misses 1 by more than
    QUATERNION_UNIT_RTOL (as a scene's orientations are, `dynamics.scene`)."""
    q, u = np.zeros(tree.nq), np.zeros(tree.nv)
    fixed_q: set[int] = set()
    fixed_u: set[int] = set()
    for j in tree.joints:
        if j.kind in ("spherical", "free"):
            q[j.iq + (3 if j.kind == "free" else 0)] = 1.0
    rates: dict[int, np.ndarray] = {}
    for key, values in (("positions", scene.initial.positions), ("rates", scene.initial.rates)):
        for name, value in values.items():
            k = next(i for i, j in enumerate(scene.joints) if j.name == name)
            sj = scene.joints[k]
            where = scene.where(f"initial.{key}.{name}")
            if sj.kind in _CANNOT_MOVE:
                raise SceneError(f"{where}a {sj.kind} joint cannot move, so it takes no "
                                 f"initial {key[:-1]}; remove it")
            j = tree.joints[tree.of_scene[k][1]]
            value = np.asarray(value, float)
            if key == "rates":
                if value.size != j.nv:
                    raise SceneError(f"{where}expected {j.nv} rate(s) for a {j.kind} joint, "
                                     f"got {value.size}")
                rates[k] = value  # set once every named position is known
                continue
            if j.kind == "spherical":
                if value.size != 4 or not np.linalg.norm(value) > 0:
                    raise SceneError(f"{where}expected a quaternion [w, x, y, z] for a "
                                     "spherical joint")
                norm = float(np.linalg.norm(value))
                value = value / norm
                if notes is not None and not abs(norm - 1.0) <= \
                        tolerances.QUATERNION_UNIT_RTOL:
                    shown = ", ".join(f"{c:.6g}" for c in value)
                    notes.append(f"{where}normalised to [{shown}] (its norm was {norm:.6g}; a "
                                 "rotation's quaternion has norm 1)")
                q[j.iq:j.iq + 4] = value * np.array([1, -1, -1, -1]) if j.reversed else value
            else:
                if value.size != j.nq:
                    raise SceneError(f"{where}expected {j.nq} value(s) for a {j.kind} joint, "
                                     f"got {value.size}")
                q[j.iq:j.iq + j.nq] = tree_order(j, value)
            fixed_q.update(range(j.iu, j.iu + j.nv))
    for k, value in rates.items():
        j = tree.joints[tree.of_scene[k][1]]
        if j.kind == "spherical":  # the scene's joint frame -> the tree's moving one
            u[j.iu:j.iu + 3] = joint_rates(j, q[j.iq:j.iq + 4], np.eye(3)).T @ value  # a turn
        else:
            u[j.iu:j.iu + j.nv] = tree_order(j, value)
        fixed_u.update(range(j.iu, j.iu + j.nv))
    for name, (v, w) in scene.initial.velocities.items():
        i = next(i for i, b in enumerate(tree.bodies) if b.name == name)
        j = tree.joints[tree.parent_joint[i]]
        if j.kind != "free":
            raise SceneError(f"{scene.where('initial.bodies.' + name)}body {name!r} is held by "
                             "a joint: give its joints' rates in initial.rates instead")
        u[j.iu:j.iu + 3] = v
        u[j.iu + 3:j.iu + 6] = quat_matrix(q[j.iq + 3:j.iq + 7]).T @ w  # ω = Q u
        fixed_u.update(range(j.iu, j.iu + 6))
    return q, u, fixed_q, fixed_u
