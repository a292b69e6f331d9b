"""The system samples built in each peer from the sample YAML's own numbers (read by pyyaml, not
by massprops): MuJoCo (MJCF), Pinocchio (a model of revolute-y joints; the four-bar in one
coordinate by coordinate partitioning) and exudyn (its own solvers, see _peer_exudyn.py).

Each ``*_runner(sample, ...)`` returns ``(prepare_s, run)``: the build time (MuJoCo's compile,
Pinocchio's model) and ``run(setting) -> (angles (rad), note)`` integrating the sample over its
duration; ``angles`` are the joint coordinates massprops reports (the turn of each hinge about
its +y axis from the assembly pose), for the double pendulum [shoulder, elbow], for the
four-bar [A].
"""

from __future__ import annotations

import math
import time

import numpy as np


def bodies_joints(sample: dict):
    """[(name, mass, com (3,), inertia (3, 3))], [(name, parent, child, point (3,))], in the
    YAML's order, and the world gravity vector."""
    bodies = [(name, float(b["mass"]), np.array(b["position"], float),
               np.array(b["inertia"], float)) for name, b in sample["bodies"].items()]
    joints = [(j["name"], j["bodies"][0], j["bodies"][1], np.array(j["point"], float))
              for j in sample["joints"]]
    for j in sample["joints"]:
        assert j["type"] == "revolute" and list(map(float, j["axis"])) == [0.0, 1.0, 0.0]
    gravity = np.array(sample["forces"][0]["g"], float)
    return bodies, joints, gravity


def _chain(sample: dict):
    """The tree part (every joint whose child is a body not yet reached), and the loop's cut
    joint (a joint closing onto an already-placed body, or None)."""
    bodies, joints, gravity = bodies_joints(sample)
    placed, tree, cut = {"world"}, [], None
    for j in joints:
        if j[2] not in placed and j[1] in placed:
            tree.append(j)
            placed.add(j[2])
        elif j[1] not in placed and j[2] in placed:  # written child-first: swap
            tree.append((j[0], j[2], j[1], j[3]))
            placed.add(j[1])
        else:
            cut = j
    return {b[0]: b for b in bodies}, tree, cut, gravity


# --- MuJoCo --------------------------------------------------------------------------------------
def _f(values) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(values))


def mjcf(sample: dict, integrator: str, timestep: float, solref_scale: float = 2.0) -> str:
    """MJCF: every body frame at the world origin in the assembly pose (so qpos 0 is the
    assembly), hinges at the joints' world points about +y, inertials at the centres of mass
    with the full tensor; the four-bar's cut joint an equality connect, as stiff as MuJoCo
    allows (timeconst = solref_scale × timestep, the refsafe floor at 2; impedance 0.9999)."""
    bodies, tree, cut, gravity = _chain(sample)
    children: dict[str, list] = {}
    for j in tree:
        children.setdefault(j[1], []).append(j)

    def body_xml(j):
        name, _, child, point = j
        _, mass, com, inertia = bodies[child]
        full = [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2],
                inertia[1, 2]]
        inner = "".join(body_xml(c) for c in children.get(child, []))
        return (f'<body name="{child}" pos="0 0 0"><joint name="{name}" type="hinge" '
                f'axis="0 1 0" pos="{_f(point)}"/><inertial pos="{_f(com)}" mass="{mass!r}" '
                f'fullinertia="{_f(full)}"/>{inner}</body>')

    world = "".join(body_xml(j) for j in children.get("world", []))
    equality = ""
    if cut is not None:
        name, first, second, point = cut
        body1, body2 = (second, first) if first == "world" else (first, second)
        equality = (f'<equality><connect name="{name}" body1="{body1}" body2="{body2}" '
                    f'anchor="{_f(point)}" solref="{solref_scale * timestep!r} 1" '
                    'solimp="0.9999 0.9999 0.001 0.5 2"/></equality>')
    return (f'<mujoco><option timestep="{timestep!r}" integrator="{integrator}" '
            f'gravity="{_f(gravity)}"><flag contact="disable"/></option>'
            f"<worldbody>{world}</worldbody>{equality}</mujoco>")


def mujoco_runner(sample: dict, qpos0, qvel0, integrator: str, steps: int):
    """(compile_s, run): the sample over its duration in ``steps`` equal MuJoCo steps."""
    import mujoco  # optional peer

    duration = float(sample["time"]["duration"])
    start = time.perf_counter()
    model = mujoco.MjModel.from_xml_string(mjcf(sample, integrator, duration / steps))
    data = mujoco.MjData(model)
    prepare = time.perf_counter() - start

    def run():
        mujoco.mj_resetData(model, data)
        data.qpos[:] = qpos0
        data.qvel[:] = qvel0
        mujoco.mj_step(model, data, nstep=steps)
        residual = float(np.abs(data.efc_pos[:data.nefc]).max()) if data.nefc else 0.0
        return np.array(data.qpos), residual

    return prepare, run


# --- Pinocchio -----------------------------------------------------------------------------------
def pinocchio_model(sample: dict):
    """A Pinocchio model of the sample's tree (revolute-y joints placed at their world points,
    identity orientation: the assembly pose is q = 0), a frame on the cut joint's second body
    at the cut point (or None), the tree joints' names."""
    import pinocchio as pin  # optional peer

    bodies, tree, cut, gravity = _chain(sample)
    model = pin.Model()
    ids, points = {"world": 0}, {"world": np.zeros(3)}
    for name, parent, child, point in tree:
        placement = pin.SE3(np.eye(3), point - points[parent])
        jid = model.addJoint(ids[parent], pin.JointModelRY(), placement, name)
        _, mass, com, inertia = bodies[child]
        model.appendBodyToJoint(jid, pin.Inertia(mass, com - point, inertia), pin.SE3.Identity())
        ids[child], points[child] = jid, point
    model.gravity.linear = gravity
    frame = None
    if cut is not None:
        moving = cut[2] if cut[1] == "world" else cut[1]
        frame = model.addFrame(pin.Frame("cut", ids[moving], 0,
                                         pin.SE3(np.eye(3), cut[3] - points[moving]),
                                         pin.FrameType.OP_FRAME))
    return model, frame, [j[0] for j in tree], (cut[3] if cut is not None else None)


def pinocchio_chain_rhs(model):
    """ẏ = [v, ABA(q, v, 0)] for y = [q, v] (a tree)."""
    import pinocchio as pin  # optional peer

    data, nq = model.createData(), model.nq
    tau = np.zeros(model.nv)

    def f(t, y):
        return np.concatenate([y[nq:], pin.aba(model, data, y[:nq], y[nq:], tau)])

    return f


class PinocchioLoop:
    """A one-loop planar mechanism in its first joint's coordinate (coordinate partitioning):
    the others follow from the loop (Newton on the cut point's x and z, warm-started), the
    acceleration from the KKT system of CRBA's M, the non-linear effects and the cut point's
    Jacobian (x and z rows: the loop is planar in x-z, its y row is redundant)."""

    ROWS = [0, 2]

    def __init__(self, model, frame: int, target: np.ndarray) -> None:
        import pinocchio as pin  # optional peer

        self.pin, self.model, self.frame, self.target = pin, model, frame, target
        self.data = model.createData()
        self.reset()
        self.newton_iterations = 0

    def reset(self) -> None:
        """Start from the assembly pose (q = 0) again."""
        self.q = np.zeros(self.model.nq)
        self.tangent: np.ndarray | None = None  # ∂q_others/∂q0 at self.q

    def _jacobian(self, q):
        pin, model, data = self.pin, self.model, self.data
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacement(model, data, self.frame)
        jac = pin.computeFrameJacobian(model, data, q, self.frame,
                                       pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:3]
        return data.oMf[self.frame].translation - self.target, jac[self.ROWS]

    def close(self, q0: float) -> np.ndarray:
        """q with q[0] = q0 and the others solving the loop: Newton from the last solution
        moved along the loop's tangent (without the predictor a long trial step of a loose
        rtol lands Newton on the mirrored assembly)."""
        # long moves (trial stages of a loose rtol) marched in pieces of <= 0.1 rad, so Newton
        # follows the branch instead of landing on the mirrored assembly
        pieces = max(1, math.ceil(abs(q0 - self.q[0]) / 0.1))
        for target in np.linspace(self.q[0], q0, pieces + 1)[1:]:
            q = self.q.copy()
            if self.tangent is not None:
                q[1:] += self.tangent * (target - q[0])
            q[0] = target
            for _ in range(30):
                phi, jac = self._jacobian(q)
                step = _solve2(jac[:, 1:], phi[self.ROWS])
                q[1:] -= step
                self.newton_iterations += 1
                if np.abs(step).max() < 1e-10:  # Newton: the next correction is ~1e-20
                    break
            self.q = q
            self.tangent = -_solve2(jac[:, 1:], jac[:, 0])
        return self.q

    def rhs(self):
        pin, model, data = self.pin, self.model, self.data

        def f(t, y):
            q = self.close(y[0])
            _, jac = self._jacobian(q)
            v = np.empty(model.nv)
            v[0] = y[1]
            v[1:] = -_solve2(jac[:, 1:], jac[:, 0] * y[1])
            mass = pin.crba(model, data, q)
            mass = np.triu(mass) + np.triu(mass, 1).T
            bias = pin.nonLinearEffects(model, data, q, v)
            pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
            gamma = -pin.getFrameClassicalAcceleration(
                model, data, self.frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED).linear[self.ROWS]
            n, m = model.nv, len(self.ROWS)
            kkt = np.zeros((n + m, n + m))
            kkt[:n, :n], kkt[:n, n:], kkt[n:, :n] = mass, jac.T, jac
            acc = np.linalg.solve(kkt, np.concatenate([-bias, gamma]))
            return np.array([y[1], acc[0]])

        return f


def _solve2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a⁻¹ b for a 2 × 2 a (Cramer: np.linalg.solve's checks cost ~25 µs a call)."""
    det = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    return np.array([b[0] * a[1, 1] - a[0, 1] * b[1], a[0, 0] * b[1] - a[1, 0] * b[0]]) / det


def four_bar_rates(sample: dict, rate_a: float) -> np.ndarray:
    """The tree joints' rates [A, B, C] that keep the loop closed with A at ``rate_a``
    (the cut point's velocity x and z rows = 0, from the joints' world points)."""
    _, tree, cut, _ = _chain(sample)
    points = [j[3] for j in tree] + [cut[3]]
    # point i's velocity from joint k's unit rate about +y: ŷ × (p_i − p_k) in x-z
    rows = np.array([[(cut[3] - p)[2], -(cut[3] - p)[0]] for p in points[:3]]).T
    rest = -np.linalg.solve(rows[:, 1:], rows[:, 0] * rate_a)
    return np.array([rate_a, *rest])


def wrap_close(angle: float, reference: float) -> float:
    """angle + 2πk nearest to reference (MuJoCo and Pinocchio hinges are not wrapped, but a
    coordinate recovered from a pose would be)."""
    return angle + 2 * math.pi * round((reference - angle) / (2 * math.pi))
