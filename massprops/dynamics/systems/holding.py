"""Holding forces: what each joint's motor must exert to keep a pose at rest (static torques).

Inverse dynamics with zero rates and accelerations. The equations of motion M u̇ + h(q, u) =
τ + τ_motor + Gᵀλ at u = 0, u̇ = 0 leave τ_motor = h(q, 0) - τ(q, 0, t) - Gᵀλ: h(q, 0) is the
generalised weight and applied body loads (RNEA with the scene's forces at u = 0, via
`tree.generalized`), τ the joints' own springs and drives at time t (dampers are idle at rest).
On a tree G is empty and the answer is unique. With closed loops λ is free: the loop joints
carry part of the load; massprops takes the λ that makes the motors' forces smallest in the
Euclidean norm over the tree coordinates that are joints of the scene (a floating base's six
are excluded: nothing actuates them, what remains there is the wrench a support must give), and
says so in the output. A coupling's follower (a mimic joint) has no motor: its coupling carries
its whole load to the leaders, and its entry is zero. Cut joints hold nothing (their entries are
zeros). Units: N·m for a turn, N for a shift, one per rate coordinate, in the contract's signs
(the scene joint's own).
"""

from __future__ import annotations

import numpy as np

from massprops.dynamics.systems import tree as tr
from massprops.dynamics.systems.loops import terms

__all__ = ["LOOP_RULE", "by_scene_joint", "holding", "motor_forces"]

LOOP_RULE = ("minimum-norm: the loops' constraint forces take the load the motors need not "
             "give; the motors' forces are the smallest (Euclidean norm) that hold the pose (a "
             "mimic joint's is 0: its coupling carries its load)")


def _multipliers(g: np.ndarray, motor: np.ndarray, act: np.ndarray,
                 passive: np.ndarray) -> np.ndarray:
    """λ with (Gᵀλ)[passive] = motor[passive] (a coupling's follower has no motor: the coupling
    carries its whole load) and ‖motor − Gᵀλ‖ over ``act`` the least: the minimum-norm λ0 of
    the first, then the least squares in the null space of G[:, passive]ᵀ."""
    lam = np.zeros(g.shape[0])
    basis = np.eye(g.shape[0])
    if passive.size:  # one SVD of G[:, passive]ᵀ gives both
        uu, sv, vt = np.linalg.svd(g[:, passive].T)
        rank = int(np.sum(sv > 1e-12 * (sv[0] if sv.size else 0.0)))
        lam = vt[:rank].T @ ((uu[:, :rank].T @ motor[passive]) / sv[:rank])
        basis = vt[rank:].T
    if act.size and basis.shape[1]:
        rest = motor[act] - g[:, act].T @ lam
        lam = lam + basis @ np.linalg.lstsq(g[:, act].T @ basis, rest, rcond=None)[0]
    return lam


def motor_forces(system, t: float, q: np.ndarray, u: np.ndarray,
                 udot: np.ndarray | None = None):
    """(motor (nv,), kinematics, the joints' own forces τ (nv,)) of a tree moving with rates
    ``u`` and accelerations ``udot`` (None: 0) at ``q``, time ``t``: motor = M u̇ + h(q, u) − τ,
    what the motors add to the joints' springs, dampers and drives (RNEA: the bodies' net
    forces summed from the leaves in, projected on each joint's axes). Tree coordinates; loops'
    constraint forces are not in it (`holding` splits them)."""
    tree = system.tree
    kin = tr.kinematics(tree, q, u, udot)
    fext, tau = system.applied(t, kin, q, u)
    h = tr.generalized(tree, kin, tr.transmitted(tree, tr.body_forces(tree, kin, fext)))
    return h - tau, kin, tau


def holding(system, t: float, y: np.ndarray) -> list[np.ndarray]:
    """Per scene joint (scene order), the generalised forces (one per rate) its motor must exert
    to hold the configuration of state ``y`` at rest at time ``t``."""
    tree = system.tree
    q = y[:system.nq]
    motor, kin, _ = motor_forces(system, t, q, np.zeros(system.nv))
    if system.m:
        g = terms(tree.prims, kin, tr.jacobians(tree, kin), system.nv, tree.size,
                  tree.couplings, q)[1]
        followers = {c.terms[0][1] for c in tree.couplings}
        act = np.array([i for j in tree.joints if j.kind != "free"
                        for i in range(j.iu, j.iu + j.nv) if i not in followers], dtype=int)
        lam = _multipliers(g, motor, act, np.array(sorted(followers), dtype=int))
        motor = motor - g.T @ lam
    return by_scene_joint(system, q, motor)


def by_scene_joint(system, q: np.ndarray, motor: np.ndarray) -> list[np.ndarray]:
    """Tree generalised forces ``motor`` (nv,) per scene joint, in the scene's signs and order
    (a cut joint's: zeros; a ball's: a torque in its moving frame, as its rates)."""
    tree, scene = system.tree, system.scene
    out = []
    for k, sj in enumerate(scene.joints):
        where, n = tree.of_scene[k]
        count = {"revolute": 1, "prismatic": 1, "cylindrical": 2, "universal": 2,
                 "spherical": 3}.get(sj.kind, 0)
        if where == "cut":
            out.append(np.zeros(count))
            continue
        j = tree.joints[n]
        f = motor[j.iu:j.iu + j.nv]
        if j.kind == "spherical":  # a torque in the tree's moving frame, as its rates
            f = tr.joint_rates(j, q[j.iq:j.iq + 4], f)
        elif j.reversed:  # the scene's coordinates are the tree's turned around (assemble.py)
            if j.kind == "universal":
                f = -f[::-1]
            else:
                f = -f
        out.append(np.array(f, float))
    return out
