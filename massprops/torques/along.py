"""Inverse dynamics along a motion: each motor's torque (or force) and power, each joint's
reaction, per sample, and per motor its peak, RMS, peak power and energy, against its limit.

The robot is a system (`dynamics.any_scene.load`: a description or a `model:`/`bodies:` scene)
with a fixed base. Its joints named in the motion follow it. On a tree every other moving joint
is held at 0 by its motor (said in a note); with closed loops the others are passive, solved on
the constraints from the driven ones (`_Follow`), and the motors act on the driven joints
alone, the loops' forces minimum-norm where redundant (said in a note). At each
sample the tree's RNEA gives motor = M u̇ + h(q, u) − τ (`systems.holding.motor_forces`: what
the motors add to the joints' springs, dampers and drives), and the joints' reactions on their
second bodies at their points, world frame, as `simulate` reports them (`systems.outputs
.reactions`, the motors' axial part left out). A sample's bar is the largest change of a
motor's force when the motion's accelerations are those of the spline through every other
sample, divided by 15 (`motion`), the largest within 5 samples of it (the spline's span): the
sampling's error on the torques.

Limits: a URDF joint's ``<limit effort velocity>``, an SDF joint's ``<axis><limit><effort>`` and
``<velocity>`` (N·m or N; rad/s or m/s); none from MJCF yet. A limit of 0 or below is no limit
(URDF's default when the attribute is missing is 0, "none stated").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from massprops.errors import CheckFailedError, SceneError, UsageError, setting_ref
from massprops.torques.motion import RICHARDSON, SPLINE_ORDER, Motion, trapezoid

ONE_AXIS = ("revolute", "prismatic")


@dataclass
class Torques:
    """The samples (``rows``: the contract's per-sample objects) and the summary object;
    ``notes`` what the run said; ``failed`` the --check's one-line verdicts."""

    rows: list[dict]
    summary: dict
    notes: list[str] = field(default_factory=list)
    failed: list[str] = field(default_factory=list)


def _limits(scene, notes: list[str], strict: bool) -> dict[str, tuple[float | None, float | None]]:
    """Joint name -> (effort N·m or N, velocity rad/s or m/s) limits stated in the scene's
    description, None where a value is not stated (or is 0 or less: URDF's "none"). The
    description is read again for them; where that fails (a .xacro that needs its arguments)
    a note says so and no limit is known, unless ``strict`` (a check was asked for: its error
    stands)."""
    if getattr(scene, "robot", None) is None:
        return {}
    # deferred: the description read again only for its limits
    from massprops.errors import MassPropsError
    from massprops.robot.analyze import load_model
    from massprops.robot.mechanism import read_mechanism

    try:
        joints = read_mechanism(load_model(scene.robot)).joints
    except MassPropsError as exc:
        if strict:
            raise
        notes.append(f"{scene.robot}: its limits could not be read again ({exc}); none "
                     "is reported")
        return {}
    out: dict[str, tuple[float | None, float | None]] = {}
    for j in joints:
        node = j.node
        if node is None:
            continue
        urdf = node.find("limit") if node.tag == "joint" else None
        axis = node.find("axis")
        sdf = axis.find("limit") if axis is not None else None
        stated = []
        for key in ("effort", "velocity"):
            text = None
            if urdf is not None and key in urdf.attrs:
                text = urdf.attrs[key]
            element = sdf.find(key) if sdf is not None else None
            if element is not None:
                text = element.text
            stated.append(_positive(text))
        if any(v is not None for v in stated):
            out[j.name] = (stated[0], stated[1])
    return out


def _positive(text: str | None) -> float | None:
    try:
        value = float(text) if text is not None else 0.0
    except ValueError:
        return None
    return value if value > 0 and math.isfinite(value) else None


def load_robot(path, *, inertials: str | None = None, package_paths=(), xacro_args=None):
    """The system whose motors are asked about: a robot description at its zero pose with its
    ``inertials`` ("stated", the default, or "computed" from its geometry), or a system scene
    (which names its own: a ``model:`` scene's ``inertials:``). SceneError, RobotModelError,
    UsageError (``inertials`` with a scene file; a one-body scene, which has no motors)."""
    # deferred: the scene kinds, decided where they are read
    from massprops.dynamics import any_scene
    from massprops.dynamics.systems.robot_scene import description_scene, is_description

    if is_description(path):
        return description_scene(path, duration=0.0, package_paths=package_paths,
                                 xacro_args=xacro_args, inertials=inertials or "stated")
    if inertials is not None:
        raise UsageError(f"{path}: {setting_ref('inertials')} applies to a robot description "
                         "given directly; a model: scene names its own (inertials:)")
    scene = any_scene.load(path, package_paths=package_paths, xacro_args=xacro_args)
    if not any_scene.is_system(scene):
        raise UsageError(f"{path}: one body has no motors; torques takes a robot description "
                         "or a system scene")
    return scene


def warnings(scene) -> list[str]:
    """What reading the robot said, less what only a simulation leaves out (limits, contacts):
    torques simulate nothing."""
    from massprops.dynamics.systems.description import SIMULATION_SCOPE  # deferred: as above

    return [w for w in scene.warnings if not w.startswith(SIMULATION_SCOPE)]


def with_inertials_spread(chosen: Torques, other: Torques) -> Torques:
    """``chosen`` with each sample's bar widened by the largest difference of a motor's force
    from ``other``'s (the same motion with the other inertials: the stated ones against those
    of the geometry), the spread the description's own disagreement leaves."""
    for row, alt in zip(chosen.rows, other.rows):
        spread = max((abs(a - b) for name, j in row["joints"].items()
                      for a, b in zip(j["torque"], alt["joints"][name]["torque"])), default=0.0)
        row["bar"] = max(row["bar"], spread)
    widest = max((r["bar"] for r in chosen.rows), default=0.0)
    chosen.notes.append(f"each sample's bar holds the spread between the stated and the "
                        f"computed inertials' torques too (up to {widest:.3g} N·m or N)")
    return chosen


def torques_along(scene, motion: Motion, *, check: bool = False, margin: float = 0.0
                  ) -> Torques:
    """Each motor's force along ``motion`` (see the module); with ``check``, CheckFailedError
    (exit 4) naming the joint, the time and the value where a peak exceeds its limit less
    ``margin`` (a fraction: 0.2 asks for 20 % headroom), after the results are made."""
    # deferred: the systems engine, loaded when a run starts
    from massprops.dynamics.systems.run import prepare

    system, y0, _ = prepare(scene)  # its notes are of the scene's start: not followed here
    notes: list[str] = []
    if system.falling is not None:
        raise SceneError(f"{scene.source}: a floating base: its motion is not driven; give the "
                         "description a fixed base (a model: scene's base: fixed)")
    driven = _driven(scene, system, motion, notes)
    follow = _Follow(system, y0, driven, motion)
    n = len(motion.t)
    names = [sj.name for sj in scene.joints]
    force = np.zeros((n, len(names), 3))
    torque = np.zeros((n, len(names), 3))
    motors, rates = [], []
    bars = np.zeros(n)
    for i in range(n):
        y, motor, other = follow.sample(i, force[i], torque[i])
        motors.append(follow.by_joint(y, motor))
        rates.append(follow.by_joint(y, y[system.nq:]))
        if other is not None:
            bars[i] = float(np.max(np.abs(other - motor))) / RICHARDSON
    if follow.redundant:
        notes.append(f"{scene.source}: redundant constraints: the loops' forces are the "
                     "minimum-norm set (the reactions they share are not determined)")
    bars = _envelope(bars, SPLINE_ORDER)
    rows = []
    for i in range(n):
        joints = {}
        for k, name in enumerate(names):
            if scene.joints[k].kind not in ONE_AXIS:
                continue
            tau = motors[i][k]
            joints[name] = {"torque": tau.tolist(), "power": (tau * rates[i][k]).tolist(),
                            "force": force[i, k].tolist(), "torque_world": torque[i, k].tolist()}
        rows.append({"t": float(motion.t[i]), "joints": joints, "bar": bars[i]})
    speeds = {name: np.array([abs(float(rates[i][k][0])) for i in range(n)])
              for k, name in enumerate(names) if scene.joints[k].kind in ONE_AXIS}
    return _summarize(scene, rows, speeds, motion.t, check, margin, notes)


def _driven(scene, system, motion: Motion, notes: list[str]) -> dict:
    """Scene joint name -> its tree joint, for each joint the motion names (SceneError for a
    name the scene has not, a joint of several axes, or a loop's cut joint)."""
    tree = system.tree
    index = {j.name: k for k, j in enumerate(scene.joints)}
    unknown = [n for n in motion.names if n not in index]
    if unknown:
        raise SceneError(f"{motion.source}: no joint {unknown[0]!r} in {scene.source} (its "
                         f"joints: {', '.join(index)})")
    driven = {}
    for name in motion.names:
        sj = scene.joints[index[name]]
        if sj.kind not in ONE_AXIS:
            raise SceneError(f"{motion.source}: {name} is a {sj.kind} joint; a motion drives "
                             "one-axis joints (revolute, prismatic) so far")
        where, k = tree.of_scene[index[name]]
        if where == "cut":
            raise SceneError(f"{motion.source}: {name} closes a loop (the spanning tree cuts "
                             "it): drive a joint of the tree instead, e.g. the crank")
        driven[name] = tree.joints[k]
    if not system.m:
        held = [j.name for j in scene.joints if j.kind in ONE_AXIS and j.name not in driven]
        if held:
            notes.append(f"{motion.source}: not in the motion, held at 0 by their motors: "
                         f"{', '.join(held)}")
    return driven


def _at(coarse: np.ndarray | None, fine: np.ndarray, i: int) -> float:
    """The coarse spline's acceleration at sample i, the given one where there is no spline."""
    return float(fine[i] if coarse is None else coarse[i])


class _Follow:
    """The system along the motion, sample by sample: the driven tree coordinates as given, the
    loops' others solved on the constraints (positions by Newton from the sample before, rates
    and accelerations from G u = 0 and G u̇ = −Φ̈₀), then the motors' forces (on the driven
    joints only, where there are loops; on every joint of a tree, the undriven ones held) and
    the loops' forces from M u̇ + h − τ = B τ_m + Gᵀλ, minimum-norm where redundant."""

    def __init__(self, system, y0: np.ndarray, driven: dict, motion: Motion) -> None:
        from massprops.dynamics.systems.assemble import tree_order  # deferred: as the caller

        self.system, self.motion = system, motion
        self.y = y0.copy()
        self.index = np.array([j.iu for j in driven.values()], dtype=int)
        self.q_index = np.array([j.iq for j in driven.values()], dtype=int)
        self.sign = np.array([tree_order(j, np.ones(1))[0] for j in driven.values()])
        self.names = list(driven)
        self.redundant = False
        nv = system.nv
        self.dependent = np.array([k for k in range(nv) if k not in set(self.index)], dtype=int)

    def _given(self, i: int, key: str) -> np.ndarray:
        m = self.motion
        table = {"q": m.q, "rate": m.rate, "acc": m.acc}.get(key)
        if key == "coarse":
            return self.sign * np.array([_at(m.coarse[n], m.acc[n], i) for n in self.names])
        return self.sign * np.array([table[n][i] for n in self.names])  # type: ignore[index]

    def sample(self, i: int, force: np.ndarray, torque: np.ndarray):
        """(y, motor (nv,), the motor at the coarse spline's accelerations or None) at sample i;
        the reactions into ``force``, ``torque``."""
        from massprops.dynamics.systems import tree as tr  # deferred: as the caller
        from massprops.dynamics.systems.loops import terms
        from massprops.dynamics.systems.outputs import reactions
        from massprops.dynamics.systems.system import Solution

        system, tree = self.system, self.system.tree
        nq, nv = system.nq, system.nv
        t = float(self.motion.t[i])
        y = self.y.copy() if system.m else np.zeros(nq + nv)
        y[self.q_index] = self._given(i, "q")
        y[nq + self.index] = self._given(i, "rate")
        udot = np.zeros(nv)
        udot[self.index] = self._given(i, "acc")
        coarse = udot.copy()
        coarse[self.index] = self._given(i, "coarse")
        g = np.zeros((0, nv))
        gdot = np.zeros(0)
        rho = (np.zeros((0, 6)), np.zeros((0, 6)))
        if system.m:
            from massprops.dynamics.systems.system import UnclosedLoop  # deferred: as above

            fixed = set(self.index.tolist())
            try:
                y, _, _ = system.project(y, (fixed, fixed), iterations=50)
            except UnclosedLoop as exc:  # the motion's fault, not the run's: exit 1
                raise SceneError(f"{self.motion.source}: at t = {t:.6g} s the loop cannot "
                                 f"close with the given coordinates (it misses by "
                                 f"{exc.residual:.3g} m)") from exc
            q, u = y[:nq], y[nq:]
            kin0 = tr.kinematics(tree, q, u)
            _, g, gdot, rho_b, rho_a = terms(tree.prims, kin0, tr.jacobians(tree, kin0), nv,
                                             tree.size, tree.couplings, q)
            rho = (rho_b, rho_a)
            gd = g[:, self.dependent]
            if np.linalg.matrix_rank(gd) < len(self.dependent):
                raise SceneError(f"{self.motion.source}: the motion leaves the mechanism free "
                                 "to move: name more of its joints (a motion drives every "
                                 "degree of freedom)")
            for acc in (udot, coarse):
                acc[self.dependent] = np.linalg.lstsq(
                    gd, -gdot - g[:, self.index] @ acc[self.index], rcond=None)[0]
        q, u = y[:nq], y[nq:]
        motor, lam, kin = self._motors(t, q, u, udot, g)
        other = None
        if np.any(coarse != udot):
            other, _, _ = self._motors(t, q, u, coarse, g)
        sol = Solution(udot, lam, len(lam), kin, *rho)
        reactions(system, t, y, sol, force, torque, motor)
        self.y = y
        return y, motor, other

    def _motors(self, t: float, q, u, udot, g):
        """(motor (nv,), λ (m,), the kinematics at these accelerations): M u̇ + h − τ =
        motor + Gᵀλ, the motors on the driven coordinates only where there are loops (else on
        every one)."""
        from massprops.dynamics.systems.holding import motor_forces  # deferred: as the caller

        needed, kin, _ = motor_forces(self.system, t, q, u, udot)
        if not len(g):
            return needed, np.zeros(0), kin
        nv = self.system.nv
        select = np.zeros((nv, len(self.index)))
        select[self.index, np.arange(len(self.index))] = 1.0
        a = np.hstack([select, g.T])
        x, _, rank, _ = np.linalg.lstsq(a, needed, rcond=None)
        if rank < a.shape[1]:
            self.redundant = True
        motor = np.zeros(nv)
        motor[self.index] = x[:len(self.index)]
        return motor, x[len(self.index):], kin

    def by_joint(self, y: np.ndarray, values: np.ndarray) -> list[np.ndarray]:
        """Tree values (nv,) per scene joint, in the scene's signs (`holding.by_scene_joint`)."""
        from massprops.dynamics.systems.holding import by_scene_joint  # deferred: as caller

        return by_scene_joint(self.system, y[:self.system.nq], values)


def _envelope(bars: np.ndarray, half: int) -> np.ndarray:
    """Each sample's bar the largest within ``half`` samples of it: the two splines' difference
    passes through zero where the true error need not (a pointwise Richardson estimate can be
    0 beside an error), while the error itself varies over the spline's span of samples."""
    if len(bars) == 0:
        return bars
    padded = np.pad(bars, half, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1)
    return windows.max(axis=1)


def _summarize(scene, rows: list[dict], speeds: dict[str, np.ndarray], t: np.ndarray,
               check: bool, margin: float, notes: list[str]) -> Torques:
    """The summary per motor (the contract's keys, and ``peak_rate``, ``rate_limit``: the
    fastest |q̇| and the velocity limit) and, with ``check``, one line per limit passed (an
    effort limit by the peak, a velocity limit by the fastest rate, each less ``margin``)."""
    limits = _limits(scene, notes, check)
    summary: dict[str, Any] = {}
    failed = []
    for name in rows[0]["joints"] if rows else ():
        tau = np.array([r["joints"][name]["torque"][0] for r in rows])
        power = np.array([r["joints"][name]["power"][0] for r in rows])
        peak_at = int(np.argmax(np.abs(tau)))
        peak = float(abs(tau[peak_at]))
        fast_at = int(np.argmax(speeds[name]))
        fast = float(speeds[name][fast_at])
        span = float(t[-1] - t[0])
        rms = math.sqrt(trapezoid(tau ** 2, t) / span) if span > 0 else peak
        limit, rate_limit = limits.get(name, (None, None))
        summary[name] = {"peak": [peak], "peak_t": [float(t[peak_at])], "rms": [rms],
                         "peak_power": [float(np.max(np.abs(power)))],
                         "energy": [trapezoid(power, t)],
                         "limit": [limit], "margin": [None if limit is None
                                                      else 1.0 - peak / limit],
                         "peak_rate": [fast], "rate_limit": [rate_limit]}
        if not check:
            continue
        headroom = f" less {margin:.0%} headroom" if margin else ""
        if limit is not None and peak > limit * (1.0 - margin):
            failed.append(f"{scene.source}: joint {name} needs {peak:.6g} at t = "
                          f"{t[peak_at]:.6g} s, beyond its limit {limit:.6g}{headroom} "
                          f"(margin {1.0 - peak / limit:+.1%})")
        if rate_limit is not None and fast > rate_limit * (1.0 - margin):
            failed.append(f"{scene.source}: joint {name} moves at {fast:.6g} at t = "
                          f"{t[fast_at]:.6g} s, beyond its velocity limit {rate_limit:.6g}"
                          f"{headroom} (margin {1.0 - fast / rate_limit:+.1%})")
    verdict = "not checked" if not check else "fail" if failed else "ok"
    return Torques(rows, {"summary": summary, "samples": len(rows), "check": verdict}, notes,
                   failed)


def raise_if_failed(result: Torques) -> None:
    """CheckFailedError (exit 4) with the first failed limit's line, if any failed."""
    if result.failed:
        more = f" (and {len(result.failed) - 1} more)" if len(result.failed) > 1 else ""
        raise CheckFailedError(result.failed[0] + more)
