"""A system as arrays: the "system program" the compiled kernels step (`dynamics.compiled.
systems_*`), built once from a `System` (its Tree, loops and loads).

A tuple of C-contiguous arrays, int64 or float64, each in the slot its name gives in
`dynamics.compiled.systems_layout` (``P_*``: the shapes and meanings are written there, beside
the names the kernels read them by).
Frames and meanings as in `tree`, `loops` and `System` (the numpy objects these mirror).
"""

from __future__ import annotations

import numpy as np

from massprops import tolerances
from massprops.dynamics.compiled import systems_layout as L
from massprops.dynamics.systems.cutjoint import perp
from massprops.dynamics.systems.model import WORLD

KIND = {"fixed": 0, "revolute": 1, "prismatic": 2, "cylindrical": 3, "universal": 4,
        "spherical": 5, "free": 6}
"""Joint kind codes (`compiled.systems_tree` names them)."""

PRIM = {"point": 0, "perp": 1, "line": 2, "dist": 3}
"""Constraint primitive codes (`compiled.systems_loops`)."""


def build_program(system) -> tuple:
    """The arrays of ``system`` (a `System`), see the module doc."""
    tree, scene = system.tree, system.scene
    bodies, joints = tree.bodies, tree.joints
    n, nj = len(bodies), len(joints)
    ji = np.zeros((nj, 8), np.int64)
    axes, sp, sc, rp0 = np.zeros((nj, 2, 3)), np.zeros((nj, 3)), np.zeros((nj, 3)), \
        np.zeros((nj, 3, 3))
    for k, j in enumerate(joints):
        ji[k] = [KIND[j.kind], j.parent, j.child, j.iq, j.iu, j.nq, j.nv, int(j.reversed)]
        axes[k, :len(j.axes)] = j.axes
        sp[k], sc[k], rp0[k] = j.s_parent, j.s_child, j.rot_parent0
    parent_joint = np.full(n, -1, np.int64)
    for body, k in tree.parent_joint.items():
        parent_joint[body] = k
    pi = np.zeros((len(tree.prims), 5), np.int64)
    pf = np.zeros((len(tree.prims), 13))
    row = 0
    for k, p in enumerate(tree.prims):
        pi[k] = [PRIM[p.kind], p.a, p.b, row, tree.cut[p.joint]]
        pf[k] = [*p.pa, *p.pb, *p.ea, *p.nb, p.length]
        row += p.rows
    nf = len(scene.forces)
    fi = np.zeros((nf + len(scene.drags), 4), np.int64)
    ff = np.zeros((nf + len(scene.drags), 8))
    for k, (f, local) in enumerate(zip(scene.forces, system.force_local)):
        fi[k] = [int(f.kind == "torque"), f.body, int(f.frame == "body"), int(local is not None)]
        ff[k] = [*f.vector, *(local if local is not None else np.zeros(3)), f.start, f.end]
    for k, d in enumerate(scene.drags, start=nf):
        fi[k] = [2, d.body, 0, 0]
        ff[k] = [d.linear, d.angular, 0, 0, 0, 0, -np.inf, np.inf]
    si = np.zeros((len(scene.springs), 2), np.int64)
    sf = np.zeros((len(scene.springs), 9))
    for k, (s, (la, lb)) in enumerate(zip(scene.springs, system.spring_local)):
        si[k] = [s.a, s.b]
        sf[k] = [*la, *lb, s.stiffness, s.rest_length, s.damping]
    li = np.array(tree.loaded, np.int64)
    lf = np.zeros((len(tree.loaded), 6))
    for k, jk in enumerate(tree.loaded):
        sj = scene.joints[joints[jk].source]
        lf[k] = [sj.stiffness, sj.rest, sj.damping, sj.drive, sj.start, sj.end]
    dims = np.zeros(5, np.int64)
    dims[L.D_NQ], dims[L.D_NV], dims[L.D_M], dims[L.D_BODIES], dims[L.D_JOINTS] = \
        tree.nq, tree.nv, system.m, n, nj
    tols = np.zeros(4)
    tols[L.T_SIZE], tols[L.T_RANK_RTOL] = tree.size, tolerances.CONSTRAINT_RANK_RTOL
    tols[L.T_PROJECTION_ATOL] = tolerances.PROJECTION_ATOL_ULPS * tolerances.EPS * tree.size
    tols[L.T_SINGULAR_MARGIN] = tolerances.NEAR_SINGULAR_MARGIN
    rot0 = np.array([b.rotation0 for b in bodies], float).reshape(n, 3, 3)
    slots = {
        L.P_DIMS: dims, L.P_JOINTS: ji, L.P_AXES: axes, L.P_S_PARENT: sp, L.P_S_CHILD: sc,
        L.P_ROT_PARENT0: rp0, L.P_PARENT_JOINT: parent_joint,
        L.P_MASS: np.array([b.mass for b in bodies], float),
        L.P_INERTIA: np.array([b.inertia for b in bodies], float).reshape(n, 3, 3),
        L.P_ROTATION0: rot0, L.P_COM0: np.array([b.com0 for b in bodies], float).reshape(n, 3),
        L.P_WEIGHT: np.asarray(system.weights, float).reshape(n, 3),
        L.P_PRIMS: pi, L.P_PRIM_VALUES: pf, L.P_FORCES: fi, L.P_FORCE_VALUES: ff,
        L.P_SPRINGS: si, L.P_SPRING_VALUES: sf, L.P_LOADED: li, L.P_LOADED_VALUES: lf,
        L.P_TOLERANCES: tols,
        L.P_AXES_PARENT: np.einsum("kji,kaj->kai", rp0, axes),  # R_p0ᵀ a
        L.P_TURN0: np.einsum("kji,kjl->kil", rp0, rot0[ji[:, 2]]),  # R_p0ᵀ R_c0
    }
    slots[L.P_CUT_LOADS], slots[L.P_CUT_LOAD_VALUES] = _cut_loads(scene, tree)
    slots[L.P_COUPLINGS], slots[L.P_COUPLING_VALUES] = _couplings(tree, row)
    slots[L.P_SCENE_JOINTS], slots[L.P_SCENE_POINTS] = _scene_joints(scene, tree)
    return tuple(np.ascontiguousarray(slots[k]) for k in range(L.PROGRAM_SLOTS))


def _couplings(tree, first: int) -> tuple[np.ndarray, np.ndarray]:
    """The program's `P_COUPLINGS` and `P_COUPLING_VALUES`: the couplings' terms, their rows
    from ``first`` on."""
    ti, tf = [], []
    for r, c in enumerate(tree.couplings):
        for k, (iq, iu, coef) in enumerate(c.terms):
            ti.append([first + r, iq, iu])
            tf.append([c.scale * coef, c.scale * c.constant if k == 0 else 0.0])
    return np.array(ti, np.int64).reshape(-1, 3), np.array(tf, float).reshape(-1, 2)


def _scene_joints(scene, tree) -> tuple[np.ndarray, np.ndarray]:
    """The program's `P_SCENE_JOINTS` and `P_SCENE_POINTS`: each scene joint's tree joint,
    second body and point."""
    ji = np.zeros((len(scene.joints), 2), np.int64)
    jp = np.zeros((len(scene.joints), 3))
    for k, j in enumerate(scene.joints):
        where, n = tree.of_scene[k]
        point = np.asarray(j.points[1] if j.kind == "distance" else j.point, float)
        ji[k] = [n if where == "tree" else -1, j.b]
        jp[k] = point if j.b == WORLD else tree.bodies[j.b].rotation0.T @ (
            point - tree.bodies[j.b].com0)
    return ji, jp


def _cut_loads(scene, tree) -> tuple[np.ndarray, np.ndarray]:
    """The program's `P_CUT_LOADS` and `P_CUT_LOAD_VALUES`: the loaded cut joints."""
    bodies = tree.bodies
    ci = np.zeros((len(tree.cut_loaded), 3), np.int64)
    cf = np.zeros((len(tree.cut_loaded), 21))

    def local(body, vector, point=False):  # world at t = 0 -> the body's frame
        if body == WORLD:
            return vector
        b = bodies[body]
        return b.rotation0.T @ (vector - b.com0 if point else vector)

    for k, n in enumerate(tree.cut_loaded):
        sj = scene.joints[tree.cut[n]]
        axis, normal = sj.axes[0], perp(sj.axes[0])
        ci[k] = [int(sj.kind == "prismatic"), sj.a, sj.b]
        cf[k] = [*local(sj.a, axis), *local(sj.a, normal), *local(sj.b, normal),
                 *local(sj.a, sj.point, True), *local(sj.b, sj.point, True), sj.stiffness,
                 sj.rest, sj.damping, sj.drive, sj.start, sj.end]
    return ci, cf

