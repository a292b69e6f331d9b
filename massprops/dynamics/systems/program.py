"""A system as arrays: the "system program" the compiled kernels step (`dynamics.compiled.
systems_*`), built once from a `System` (its Tree, loops and loads).

A tuple of C-contiguous arrays, int64 or float64, in this order (the kernels index it):
 Bodies and parents use -1 for the world (model.WORLD), as the kernels test body < 0.
 0 dims (5,) [nq, nv, m, bodies, tree joints];
 1 joints (nj, 8) int [kind code (KIND), parent body (-1 world), child, iq, iu, nq, nv,
   reversed]; 2 axes (nj, 2, 3) joint frame; 3 s_parent (nj, 3); 4 s_child (nj, 3);
 5 rot_parent0 (nj, 3, 3); 6 parent_joint (n,) body -> its tree joint;
 7 mass (n,); 8 inertia (n, 3, 3) body axes; 9 rotation0 (n, 3, 3); 10 com0 (n, 3);
 11 weight (n, 3) m g, N;
 12 primitives (np, 5) int [kind (PRIM), a, b, first row, the scene joint it belongs to];
   13 (np, 13) [pa, pb, ea, nb, length];
 14 forces (nf, 4) int [0 force / 1 torque / 2 drag, body, body frame, at a point];
 15 (nf, 8) [vector, point in the body frame, start, end]; a drag's [linear, angular, 0, ...,
   -inf, inf];
 16 springs (ns, 2) int [a, b]; 17 (ns, 9) [point on a, point on b, stiffness, rest, damping];
 18 loaded tree joints (nl,) int; 19 (nl, 6) [stiffness, rest, damping, drive, start, end];
 20 (4,) [system size m, CONSTRAINT_RANK_RTOL, the projection's position tolerance m,
   NEAR_SINGULAR_MARGIN]: the tolerances travel as data, so a compiled kernel never holds a
   stale copy of one;
 21 loaded cut joints (nc, 3) int [0 revolute / 1 prismatic, a, b]; 22 (nc, 21) [axis in a's
   frame, the normal the turn is measured from in a's frame and in b's, the joint point in a's
   and in b's frame, stiffness, rest, damping, drive, start, end] (`cutjoint`; body frames,
   world for the world);
 23 coupling terms (nt, 3) int [row, iq, iu]; 24 (nt, 2) [scale c, scale constant on a
   coupling's first term, else 0] (`loops.Coupling`: Φ_row = Σ scale c q[iq] − scale constant);
 25 axes in the parent's frame (nj, 2, 3), R_p0ᵀ a; 26 (nj, 3, 3) R_p0ᵀ R_c0, R_c0 the child's
   rotation0: a joint turning by Rot(a, q) in its frame gives the child
   R_parent Rot(R_p0ᵀ a, q) R_p0ᵀ R_c0, one 3 × 3 product fewer than through the joint frame;
 27 scene joints (J, 2) int [its tree joint (-1: a cut joint), its second body b]; 28 (J, 3)
   its point (the second point of a distance joint) fixed in b, b's frame (world for the
   world): what the outputs report per scene joint (`compiled.systems_outputs`).
Frames and meanings as in `tree`, `loops` and `System` (the numpy objects these mirror).
"""

from __future__ import annotations

import numpy as np

from massprops import tolerances
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
    ci, cf = _cut_loads(scene, tree)
    dims = np.array([tree.nq, tree.nv, system.m, n, nj], np.int64)
    rot0 = np.array([b.rotation0 for b in bodies], float).reshape(n, 3, 3)
    out = (dims, ji, axes, sp, sc, rp0, parent_joint,
           np.array([b.mass for b in bodies], float),
           np.array([b.inertia for b in bodies], float).reshape(n, 3, 3), rot0,
           np.array([b.com0 for b in bodies], float).reshape(n, 3),
           np.asarray(system.weights, float).reshape(n, 3), pi, pf, fi, ff, si, sf, li, lf,
           np.array([tree.size, tolerances.CONSTRAINT_RANK_RTOL,
                     tolerances.PROJECTION_ATOL_ULPS * tolerances.EPS * tree.size,
                     tolerances.NEAR_SINGULAR_MARGIN]), ci, cf, *_couplings(tree, row),
           np.einsum("kji,kaj->kai", rp0, axes),  # R_p0ᵀ a: the axes in the parent's frame
           np.einsum("kji,kjl->kil", rp0, rot0[ji[:, 2]]),  # R_p0ᵀ R_c0
           *_scene_joints(scene, tree))
    return tuple(np.ascontiguousarray(a) for a in out)


def _couplings(tree, first: int) -> tuple[np.ndarray, np.ndarray]:
    """Program entries 23 and 24: the couplings' terms, their rows from ``first`` on."""
    ti, tf = [], []
    for r, c in enumerate(tree.couplings):
        for k, (iq, iu, coef) in enumerate(c.terms):
            ti.append([first + r, iq, iu])
            tf.append([c.scale * coef, c.scale * c.constant if k == 0 else 0.0])
    return np.array(ti, np.int64).reshape(-1, 3), np.array(tf, float).reshape(-1, 2)


def _scene_joints(scene, tree) -> tuple[np.ndarray, np.ndarray]:
    """Program entries 27 and 28: each scene joint's tree joint, second body and point."""
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
    """Program entries 21 and 22: the loaded cut joints (module doc)."""
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

