"""What a system run reports at each sample: body states, joint coordinates, rates, reactions.

Reactions are the notes' g^(c) = M ḣ + b - g: each body's net spatial force with its computed
acceleration minus the applied loads and the cut joints' forces on it (λ), summed over each
subtree from the leaves in; a tree joint's reaction on its child is that sum less the joint's own
applied load (spring, damper, drive along its axis) and a coupling's generalised force on it
(`loops.Coupling`: λ times its row of G, like a motor's). A cut joint's reaction on its second
body is Σ λ ρ_b: its constraint force only, as for a tree joint, since a loaded cut joint's
spring, damper and drive are applied loads on its two bodies (`cutjoint`, in ``fext``). All are
reported on the scene joint's second body at the joint's point, world frame.

`evaluate` computes them for all samples in one compiled call (`compiled.systems_outputs`, ~µs a
sample); `reference` is the same in numpy, sample by sample from `System.solve` (~1 ms a sample
on one body), kept as the compiled form's independent reference in the tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from massprops.dynamics.compiled.systems_kernel import evaluate_samples
from massprops.dynamics.compiled.systems_loops import OK
from massprops.dynamics.compiled.systems_outputs import ENERGIES, OUTPUTS, STATES
from massprops.dynamics.systems import cutjoint
from massprops.dynamics.systems import tree as tr
from massprops.dynamics.systems.model import WORLD
from massprops.errors import ComputationError
from massprops.rotation import canonical, matrix_to_quat, quat_to_matrix, rotation_angle_between


@dataclass(frozen=True, eq=False)
class Samples:
    """t (n,); per body (name order of the scene) position, orientation [w,x,y,z] body -> world,
    velocity, angular_velocity (n, b, 3|4) world; per scene joint: coordinates and rates
    (lists of (n, k) arrays), force and torque (n, J, 3) on the second body at the joint's
    point, world; energy (n,) J or None; joint_points (n, J, 3) world; residual (n, 2) the
    constraints' largest position (m) and velocity (m/s) residuals (zeros without loops)."""

    t: np.ndarray
    position: np.ndarray
    orientation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    coordinates: list
    rates: list
    force: np.ndarray
    torque: np.ndarray
    energy: np.ndarray | None
    joint_points: np.ndarray | None = None  # (n, J, 3) each joint's point on its second body
    residual: np.ndarray | None = None  # (n, 2) the loops' largest |Φ| m and |Φ̇| m/s


def evaluate(system, t: np.ndarray, y: np.ndarray,
             energy: np.ndarray | None = None) -> Samples:
    """Samples of the states ``y`` (n, nq + nv) at times ``t``; ``energy`` (n,) J their
    energies where the caller has them (`energies`), else the samples carry none. Bodies,
    reactions and points in one compiled call for all samples (`compiled.systems_outputs`);
    the tree joints' coordinates and rates are slices of y; only the cut joints' coordinates
    are measured sample by sample (`cutjoint.from_poses`). `reference` is the numpy form."""
    scene, tree = system.scene, system.tree
    t = np.ascontiguousarray(t, dtype=float)
    y = np.ascontiguousarray(np.reshape(y, (len(t), system.nq + system.nv)), dtype=float)
    n, nb, nj = len(t), len(tree.bodies), len(scene.joints)
    table = _compiled(system, t, y, OUTPUTS, 18 * nb + 9 * nj + 2)
    com, rotation, motion = _bodies(table, n, nb)
    joints = table[:, 18 * nb:18 * nb + 9 * nj].reshape(n, nj, 9)
    coords, rates = _joint_states(system, y, rotation, com, motion)
    samples = Samples(t, com + system.origin, _quaternions(rotation),
                      motion[..., 3:].copy(), motion[..., :3].copy(),
                      coords, rates, joints[..., 0:3].copy(), joints[..., 3:6].copy(), energy,
                      joints[..., 6:9] + system.origin, table[:, -2:].copy())
    return _in_world(system, samples)


def energies(system, y: np.ndarray) -> np.ndarray:
    """(n,) J: `System.energy` of each state ``y`` (n, nq + nv) (kinematics only: also of a
    state where the accelerations cannot be solved, e.g. a diverged run's), in one compiled
    call."""
    y = np.ascontiguousarray(np.reshape(y, (-1, system.nq + system.nv)), dtype=float)
    return _compiled(system, np.zeros(len(y)), y, ENERGIES, 1)[:, 0]


def body_states(system, y: np.ndarray):
    """(position, orientation, velocity, angular velocity) of every body at the states ``y``
    (n, nq + nv): kinematics only, no accelerations or reactions (for comparing runs)."""
    y = np.ascontiguousarray(np.reshape(y, (-1, system.nq + system.nv)), dtype=float)
    n, nb = len(y), len(system.tree.bodies)
    com, rotation, motion = _bodies(_compiled(system, np.zeros(n), y, STATES, 18 * nb), n, nb)
    return com + system.origin, _quaternions(rotation), motion[..., 3:].copy(), \
        motion[..., :3].copy()


def _compiled(system, t: np.ndarray, y: np.ndarray, mode: int, width: int) -> np.ndarray:
    """The compiled outputs' table (n, width) of the states y at t (`systems_outputs`)."""
    out = np.empty((len(t), width))
    if not len(t):
        return out
    istats = np.array([0, 0, 0, OK, 0, -1, -1], dtype=np.int64)
    evaluate_samples(system.program, t, y, out, istats, mode)
    if istats[3] != OK:  # M is positive definite at any finite state of a valid scene
        at = float(t[istats[4]])
        raise ComputationError(f"{system.scene.source}: the outputs at t = {at:.6g} s cannot "
                               "be evaluated: the mass matrix is not positive definite there "
                               "(the state went wild)")
    return out


def _bodies(table: np.ndarray, n: int, nb: int):
    """(com (n, b, 3) m, rotation (n, b, 3, 3), (ω, v_com) (n, b, 6)) of the table's body
    columns (`systems_outputs._bodies`)."""
    bodies = table[:, :18 * nb].reshape(n, nb, 18)
    return bodies[..., 0:3], bodies[..., 3:12].reshape(n, nb, 3, 3), bodies[..., 12:18]


def _quaternions(rotation: np.ndarray) -> np.ndarray:
    """[w, x, y, z] (..., 4) of rotations (..., 3, 3), canonical (w ≥ 0), all at once."""
    if rotation.size == 0:
        return np.zeros(rotation.shape[:-2] + (4,))
    return matrix_to_quat(rotation)


def _joint_states(system, y: np.ndarray, rotation: np.ndarray, com: np.ndarray,
                  motion: np.ndarray) -> tuple[list, list]:
    """Per scene joint (coordinates, rates) (n, k) at the states ``y`` (n, nq + nv), in the
    contract's signs (`_joint_state`): a tree joint's are slices of y, a cut joint's are
    measured from the bodies' poses (rotation, com and motion = (ω, v_com) of the compiled
    outputs)."""
    scene, tree, nq = system.scene, system.tree, system.nq
    coords, rates = [], []
    n = len(y)
    spatial = None  # V = (ω, v_O) about the frame's origin, formed for a cut joint only
    for k, sj in enumerate(scene.joints):
        where, idx = tree.of_scene[k]
        if sj.kind in ("fixed", "distance"):
            c, r = np.zeros((n, 0)), np.zeros((n, 0))
        elif where == "tree":
            j = tree.joints[idx]
            qj, uj = y[:, j.iq:j.iq + j.nq], y[:, nq + j.iu:nq + j.iu + j.nv]
            if j.kind == "spherical" and j.reversed:
                c, r = qj * np.array([1.0, -1.0, -1.0, -1.0]), -uj
            elif j.kind == "spherical":  # `tree.joint_rates`, all samples at once
                c, r = qj.copy(), np.einsum("nij,nj->ni", quat_to_matrix(qj), uj)
            elif not j.reversed:
                c, r = qj.copy(), uj.copy()
            elif j.kind == "universal":
                c, r = -qj[:, ::-1], -uj[:, ::-1]
            else:
                c, r = -qj, -uj
        else:
            if spatial is None:
                spatial = np.concatenate([motion[..., :3], motion[..., 3:]
                                          - np.cross(motion[..., :3], com)], axis=-1)
            if sj.kind in ("revolute", "prismatic", "cylindrical"):
                c, r = _cut_state(tree, sj, rotation, com, spatial)
            else:  # a cut ball or universal joint, sample by sample
                c, r = np.zeros((n, _ncoord(sj.kind))), np.zeros((n, _nrate(sj.kind)))
                for s in range(n):
                    # poses and motions only: what a cut joint's state is measured from
                    kin = tr.Kinematics(rotation[s], com[s], spatial[s], np.empty((0, 6)),
                                        np.empty((0, 6, 6)), [], [])
                    c[s], r[s] = cutjoint.from_poses(tree, kin, sj)
        if where == "cut" and sj.kind in ("revolute", "cylindrical", "universal"):
            for col in ([0] if sj.kind != "universal" else [0, 1]):  # measured: continuous
                c[:, col] = np.unwrap(c[:, col])
        coords.append(c)
        rates.append(r)
    return coords, rates


def _cut_state(tree, sj, rotation: np.ndarray, com: np.ndarray, motion: np.ndarray):
    """`cutjoint.from_poses` of a cut revolute, prismatic or cylindrical joint ``sj`` at all
    samples at once (rotation (n, b, 3, 3), com (n, b, 3), V = motion (n, b, 6))."""
    n = len(rotation)

    def side(body):  # (E = R R0ᵀ, ω, v_O, the joint's point) of one side, (n, ...)
        if body == WORLD:
            z = np.zeros((n, 3))
            return np.broadcast_to(tr.EYE3, (n, 3, 3)), z, z, np.broadcast_to(sj.point, (n, 3))
        b = tree.bodies[body]
        r = rotation[:, body]
        local = b.rotation0.T @ (sj.point - b.com0)
        return (r @ b.rotation0.T, motion[:, body, :3], motion[:, body, 3:],
                com[:, body] + r @ local)

    (ea, wa, va, xa), (eb, wb, vb, xb) = side(sj.a), side(sj.b)
    axis = sj.axes[0]
    normal = cutjoint.perp(axis)
    rel = np.einsum("nji,njk->nik", ea, eb)  # E_aᵀ E_b
    w_rel = np.einsum("nji,nj->ni", ea, wb - wa)
    start = normal - (normal @ axis) * axis
    end = rel @ normal
    end = end - (end @ axis)[:, None] * axis
    turn = np.arctan2(np.cross(start, end) @ axis, end @ start)
    e = ea @ axis
    d = xb - xa
    shift = np.einsum("ni,ni->n", d, e)
    rate = np.einsum("ni,ni->n", vb + np.cross(wb, xb) - va - np.cross(wa, xa), e) \
        + np.einsum("ni,ni->n", d, np.cross(wa, e))
    spin = w_rel @ axis
    if sj.kind == "revolute":
        return turn[:, None], spin[:, None]
    if sj.kind == "prismatic":
        return shift[:, None], rate[:, None]
    return np.stack([turn, shift], -1), np.stack([spin, rate], -1)


def reference(system, t: np.ndarray, y: np.ndarray,
              energy: np.ndarray | None = None) -> Samples:
    """`evaluate` in numpy, sample by sample from `System.solve`: the independent reference of
    the compiled outputs (tests), and a single sample's outputs without the compiled kernel
    (a duration-0 run)."""
    scene, tree = system.scene, system.tree
    n, nb, nj = len(t), len(tree.bodies), len(scene.joints)
    pos, quat = np.empty((n, nb, 3)), np.empty((n, nb, 4))
    vel, omega = np.empty((n, nb, 3)), np.empty((n, nb, 3))
    force, torque = np.zeros((n, nj, 3)), np.zeros((n, nj, 3))
    points = np.zeros((n, nj, 3))
    coords = [np.zeros((n, _ncoord(j.kind))) for j in scene.joints]
    rates = [np.zeros((n, _nrate(j.kind))) for j in scene.joints]
    for s in range(n):
        sol = system.solve(float(t[s]), y[s], check=False)
        kin = sol.kin
        pos[s], vel[s] = kin.com + kin.ref, kin.V[:, 3:] + np.cross(kin.V[:, :3], kin.com)
        omega[s] = kin.V[:, :3]
        quat[s] = canonical(matrix_to_quat(kin.rotation))
        reactions(system, float(t[s]), y[s], sol, force[s], torque[s])
        for k in range(nj):
            c, r = _joint_state(system, k, y[s], kin)
            coords[k][s], rates[k][s] = c, r
            points[s, k] = _world_point(tree, kin, scene.joints[k].b,
                                        _joint_point(scene, k)) + kin.ref
    for k, j in enumerate(scene.joints):  # angles of joints measured from poses: continuous
        if tree.of_scene[k][0] == "cut" and j.kind in ("revolute", "cylindrical", "universal"):
            turns = [0] if j.kind != "universal" else [0, 1]
            for col in turns:
                coords[k][:, col] = np.unwrap(coords[k][:, col])
    pos += system.origin  # back from the assembly's middle (assemble.localized)
    points += system.origin
    residual = np.array([system.residual(row) for row in y]).reshape(n, 2)
    return _in_world(system, Samples(t, pos, quat, vel, omega, coords, rates, force, torque,
                                     energy, points, residual))


def _in_world(system, samples: Samples) -> Samples:
    """``samples`` of a run in the falling frame (`falling`) carried to the world's; others as
    they are."""
    return samples if system.falling is None else system.falling.to_world(samples, system.origin)


def _joint_point(scene, k: int) -> np.ndarray:
    """A joint's point on its second body, world at t = 0 (a distance joint: its second
    point)."""
    j = scene.joints[k]
    return j.points[1] if j.kind == "distance" else j.point


def _ncoord(kind: str) -> int:
    return {"revolute": 1, "prismatic": 1, "cylindrical": 2, "universal": 2, "spherical": 4}.get(
        kind, 0)


def _nrate(kind: str) -> int:
    return {"revolute": 1, "prismatic": 1, "cylindrical": 2, "universal": 2, "spherical": 3}.get(
        kind, 0)


def _at_point(f: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A spatial force (n_O, f) as (force, torque about p)."""
    return f[3:], f[:3] - tr.cross(p, f[3:])


def reactions(system, t: float, y: np.ndarray, sol, force: np.ndarray, torque: np.ndarray,
              motor: np.ndarray | None = None) -> None:
    """Each scene joint's reaction on its second body at its point (world; into ``force`` and
    ``torque`` (J, 3)) at state ``y`` with the accelerations and multipliers of ``sol``; a
    joint's own drive, and ``motor`` (nv,) where motors act, are not reactions (what acts along
    a one-axis joint's axis is left out)."""
    scene, tree = system.scene, system.tree
    kin = sol.kin
    q, u = y[:system.nq], y[system.nq:]
    fext, tau = system.applied(t, kin, q, u)
    if motor is not None:
        tau = tau + motor
    net = tr.body_forces(tree, kin, fext)
    cut_b = np.zeros((len(tree.cut), 6))
    r = 0
    for p in tree.prims:
        for k in range(p.rows):
            fb, fa = sol.lam[r + k] * sol.rho_b[r + k], sol.lam[r + k] * sol.rho_a[r + k]
            cut_b[p.joint] += fb
            if p.b != WORLD:
                net[p.b] -= fb
            if p.a != WORLD:
                net[p.a] -= fa
        r += p.rows
    tau = tau.copy()
    for c in tree.couplings:  # a coupling's reaction drives its joints, as a motor would
        for _, iu, coef in c.terms:
            tau[iu] += sol.lam[r] * c.scale * coef
        r += 1
    through = tr.transmitted(tree, net)
    for k, sj in enumerate(scene.joints):
        where, n = tree.of_scene[k]
        if where == "cut":
            x = _world_point(tree, kin, sj.b, _joint_point(scene, k))
            force[k], torque[k] = _at_point(cut_b[n], x)
            continue
        j = tree.joints[n]
        f = through[n].copy()
        if j.nv and j.kind in ("revolute", "prismatic") and tau[j.iu] != 0.0:
            w = kin.S[n][:3, 0] if j.kind == "revolute" else kin.S[n][3:, 0]
            if j.kind == "revolute":
                f[:3] -= tau[j.iu] * w
            else:
                p = kin.point[n]
                f[:3] -= tau[j.iu] * tr.cross(p, w)
                f[3:] -= tau[j.iu] * w
        if j.reversed:
            f = -f
        force[k], torque[k] = _at_point(f, kin.point[n])


def _world_point(tree, kin, body: int, world0: np.ndarray) -> np.ndarray:
    return cutjoint.world_point(tree, kin, body, world0)


def _joint_state(system, k: int, y: np.ndarray, kin):
    """(coordinates, rates) of scene joint k, in the contract's signs."""
    scene, tree = system.scene, system.tree
    sj = scene.joints[k]
    where, n = tree.of_scene[k]
    q, u = y[:system.nq], y[system.nq:]
    if sj.kind in ("fixed", "distance"):
        return np.zeros(0), np.zeros(0)
    if where == "tree":
        j = tree.joints[n]
        qj, uj = q[j.iq:j.iq + j.nq], u[j.iu:j.iu + j.nv]
        if j.kind == "spherical":
            return (qj * np.array([1, -1, -1, -1]) if j.reversed else qj,
                    tr.joint_rates(j, qj, uj))
        if not j.reversed:
            return qj, uj
        if j.kind == "universal":
            return -qj[::-1], -uj[::-1]
        return -qj, -uj
    return cutjoint.from_poses(tree, kin, sj)


def evaluate_states(system, t: np.ndarray, y: np.ndarray) -> Samples:
    """Body states only (no joints, reactions or energy) of ``system`` (a `System`) at (t, y):
    for comparing runs."""
    pos, quat, vel, omega = body_states(system, y)
    none = np.zeros((len(t), 0, 3))
    return _in_world(system, Samples(t, pos, quat, vel, omega, [], [], none, none, None))


def distance(a: Samples, b: Samples, size: float, scales: Samples | None = None) -> float:
    """The contract's error between two system runs: the largest over the bodies of position
    error / system size, orientation angle, velocity errors relative to the largest speeds (of
    ``scales``, default ``a``: a run over a part of the time compares in its whole run's)."""
    like = a if scales is None else scales
    duration = float(like.t[-1]) or 1.0
    v_scale = max(float(np.abs(like.velocity).max()), size / duration)
    w_scale = max(float(np.abs(like.angular_velocity).max()), 1.0 / duration)
    parts = [np.linalg.norm(a.position - b.position, axis=-1).max() / size,
             rotation_angle_between(a.orientation.reshape(-1, 4),
                                    b.orientation.reshape(-1, 4)).max(),
             np.linalg.norm(a.velocity - b.velocity, axis=-1).max() / v_scale,
             np.linalg.norm(a.angular_velocity - b.angular_velocity, axis=-1).max() / w_scale]
    return float(max(parts))
