"""A cut joint seen from its two bodies: its coordinates and rates measured from their poses and
velocities, and the spring, damper and drive of a cut one-axis joint as a pair of wrenches.

The tree integrates a tree joint's coordinate; a cut joint has none, so its coordinates are
measured: the turn is the angle about the axis (carried by the first body a, E_a = R_a R_a0ᵀ)
from a's copy of a normal n of the axis to b's copy (n fixed in each body at t = 0), the shift
(x_b − x_a)·e with x_a, x_b the joint point fixed in a and in b and e = E_a axis (world). The
rates are (ω_b − ω_a)·e and d/dt of the shift. Signs are the contract's: b relative to a.

A loaded cut joint (revolute or prismatic, `assemble.Tree.cut_loaded`) carries the tree joints'
load law, Q = stiffness (rest − coordinate) − damping rate + drive (start ≤ t < end), N·m or N,
applied as +Q on b and −Q on a: a torque Q e (revolute), or a force Q e along the line through
x_b (prismatic), so the pair's power is exactly Q times the measured rate. A revolute spring
counts its angle from ``rest`` within half a turn, in [−π, π) (the measured angle is an angle,
not a count of turns): its stored energy ½ k (coordinate − rest)² is continuous as long as the
joint stays within π of rest. `compiled.systems_loads.applied` computes the same from the
program's rows.
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.systems import tree as tr
from massprops.dynamics.systems.model import WORLD
from massprops.rotation import matrix_to_quat


def world_point(tree, kin, body: int, world0: np.ndarray) -> np.ndarray:
    """The point of ``body`` that was at ``world0`` (world, t = 0), now, world (m, from the
    kinematics' reference point, as its positions)."""
    if body == WORLD:
        return np.asarray(world0, float) - kin.ref
    b = tree.bodies[body]
    return kin.com[body] + kin.rotation[body] @ (b.rotation0.T @ (world0 - b.com0))


def carry(tree, kin, body: int) -> np.ndarray:
    """E = R R0ᵀ: the world frame at t = 0 carried by ``body`` (identity for the world)."""
    if body == WORLD:
        return np.eye(3)
    return kin.rotation[body] @ tree.bodies[body].rotation0.T


def omega(kin, body: int) -> np.ndarray:
    return np.zeros(3) if body == WORLD else kin.V[body, :3]


def perp(axis: np.ndarray) -> np.ndarray:
    """A unit normal of ``axis``: the one the turn of a cut joint is measured from."""
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    v = tr.cross(axis, helper)
    return v / np.linalg.norm(v)


def angle_about(axis: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    """Signed angle (right hand about ``axis``) from ``start`` to ``end`` projected on the plane
    normal to the axis."""
    s = start - (start @ axis) * axis
    e = end - (end @ axis) * axis
    return float(np.arctan2(axis @ tr.cross(s, e), s @ e))


def from_poses(tree, kin, sj):
    """A cut joint's (coordinates, rates) measured from its two bodies' poses (see the module
    doc); ``kin`` the tree's Kinematics, ``sj`` the SystemJoint."""
    ea, eb = carry(tree, kin, sj.a), carry(tree, kin, sj.b)
    rel = ea.T @ eb
    w_rel = ea.T @ (omega(kin, sj.b) - omega(kin, sj.a))
    if sj.kind == "spherical":
        return matrix_to_quat(rel), w_rel
    if sj.kind == "universal":
        a0, a1 = sj.axes
        target = rel @ a1
        q0 = angle_about(a0, a1, target)
        rest = tr.rot(a0, q0).T @ rel
        q1 = angle_about(a1, perp(a1), rest @ perp(a1))
        basis = np.stack([a0, tr.rot(a0, q0) @ a1], axis=1)
        return np.array([q0, q1]), np.linalg.lstsq(basis, w_rel, rcond=None)[0]
    axis = sj.axes[0]
    turn = angle_about(axis, perp(axis), rel @ perp(axis))
    xa = world_point(tree, kin, sj.a, sj.point)
    xb = world_point(tree, kin, sj.b, sj.point)
    e = ea @ axis
    shift = (xb - xa) @ e
    va = np.zeros(3) if sj.a == WORLD else kin.V[sj.a, 3:] + tr.cross(kin.V[sj.a, :3], xa)
    vb = np.zeros(3) if sj.b == WORLD else kin.V[sj.b, 3:] + tr.cross(kin.V[sj.b, :3], xb)
    shift_rate = (vb - va) @ e + (xb - xa) @ tr.cross(omega(kin, sj.a), e)
    if sj.kind == "revolute":
        return np.array([turn]), np.array([w_rel @ axis])
    if sj.kind == "prismatic":
        return np.array([shift]), np.array([shift_rate])
    return np.array([turn, shift]), np.array([w_rel @ axis, shift_rate])


def stretch(sj, coordinate: float) -> float:
    """coordinate − rest of a loaded cut joint (a revolute's within [−π, π), module doc)."""
    d = coordinate - sj.rest
    if sj.kind == "revolute":  # the formula compiled.systems_loads uses too
        d -= 2.0 * math.pi * math.floor(d / (2.0 * math.pi) + 0.5)
    return d


def add_loads(tree, scene, t: float, kin, fext: np.ndarray) -> None:
    """Add the loaded cut joints' wrench pairs to ``fext`` (n, 6) (spatial forces about O,
    world)."""
    for n in tree.cut_loaded:
        sj = scene.joints[tree.cut[n]]
        coord, rate = from_poses(tree, kin, sj)
        load = -sj.stiffness * stretch(sj, float(coord[0])) - sj.damping * float(rate[0])
        if sj.start <= t < sj.end:
            load += sj.drive
        e = carry(tree, kin, sj.a) @ sj.axes[0]
        pair = np.zeros(6)
        if sj.kind == "revolute":
            pair[:3] = load * e
        else:
            pair[:3] = load * tr.cross(world_point(tree, kin, sj.b, sj.point), e)
            pair[3:] = load * e
        if sj.b != WORLD:
            fext[sj.b] += pair
        if sj.a != WORLD:
            fext[sj.a] -= pair


def energy(tree, scene, kin) -> float:
    """J: the loaded cut joints' springs, ½ k (coordinate − rest)²."""
    out = 0.0
    for n in tree.cut_loaded:
        sj = scene.joints[tree.cut[n]]
        if sj.stiffness:
            out += 0.5 * sj.stiffness * stretch(sj, float(from_poses(tree, kin, sj)[0][0])) ** 2
    return out
