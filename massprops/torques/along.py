"""Inverse dynamics along a motion: each motor's torque (or force) and power, each joint's
reaction, per sample, and per motor its peak, RMS, peak power and energy, against its limit.

The robot is a system (`dynamics.any_scene.load`: a description or a `model:`/`bodies:` scene)
with a spanning tree and no closed loop (loops are not followed yet). Its joints named in the
motion follow it; every other moving joint is held at 0 by its motor (said in a note). At each
sample the tree's RNEA gives motor = M u̇ + h(q, u) − τ (`systems.holding.motor_forces`: what
the motors add to the joints' springs, dampers and drives), and the joints' reactions on their
second bodies at their points, world frame, as `simulate` reports them (`systems.outputs
.reactions`, the motors' axial part left out). A sample's bar is the largest change of a
motor's force when the motion's accelerations are those of the spline through every other
sample, divided by 15 (`motion`), the largest within 5 samples of it (the spline's span): the
sampling's error on the torques.

Limits: a URDF joint's ``<limit effort>``, an SDF joint's ``<axis><limit><effort>`` (N·m or N);
none from MJCF yet. A limit of 0 or below is no limit (URDF's default when the attribute is
missing is 0, "none stated").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from massprops.errors import CheckFailedError, SceneError
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


def _effort_limits(scene) -> dict[str, float]:
    """Joint name -> effort limit (N·m or N) stated in the scene's description, where any."""
    if getattr(scene, "robot", None) is None:
        return {}
    # deferred: the description read again only for its limits
    from massprops.robot.analyze import load_model
    from massprops.robot.mechanism import read_mechanism

    out: dict[str, float] = {}
    for j in read_mechanism(load_model(scene.robot)).joints:
        node = j.node
        limit = None
        if node is not None:
            found = node.find("limit") if node.tag == "joint" else None
            if found is not None and "effort" in found.attrs:  # URDF
                limit = found.attrs["effort"]
            axis = node.find("axis")
            sdf = axis.find("limit") if axis is not None else None
            effort = sdf.find("effort") if sdf is not None else None
            if effort is not None:  # SDF
                limit = effort.text
        try:
            value = float(limit) if limit is not None else 0.0
        except ValueError:
            value = 0.0
        if value > 0 and math.isfinite(value):
            out[j.name] = value
    return out


def torques_along(scene, motion: Motion, *, check: bool = False, margin: float = 0.0
                  ) -> Torques:
    """Each motor's force along ``motion`` (see the module); with ``check``, CheckFailedError
    (exit 4) naming the joint, the time and the value where a peak exceeds its limit less
    ``margin`` (a fraction: 0.2 asks for 20 % headroom), after the results are made."""
    # deferred: the systems engine, loaded when a run starts
    from massprops.dynamics.systems.assemble import tree_order
    from massprops.dynamics.systems.holding import by_scene_joint, motor_forces
    from massprops.dynamics.systems.outputs import reactions
    from massprops.dynamics.systems.run import prepare
    from massprops.dynamics.systems.system import Solution

    system, _, notes = prepare(scene)
    if system.m:
        raise SceneError(f"{scene.source}: closed loops or couplings: torques along a motion "
                         "follow trees only so far")
    if system.falling is not None:
        raise SceneError(f"{scene.source}: a floating base: its motion is not driven; give the "
                         "description a fixed base (a model: scene's base: fixed)")
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
        driven[name] = tree.joints[tree.of_scene[index[name]][1]]
    moving = [j.name for j in scene.joints if j.kind in ONE_AXIS]
    held = [n for n in moving if n not in driven]
    if held:
        notes.append(f"{motion.source}: not in the motion, held at 0 by their motors: "
                     f"{', '.join(held)}")
    n, nv = len(motion.t), system.nv
    q = np.zeros((n, system.nq))
    u, udot, udot_coarse = (np.zeros((n, nv)) for _ in range(3))
    for name, j in driven.items():
        sign = tree_order(j, np.ones(1))[0]
        q[:, j.iq] = sign * motion.q[name]
        u[:, j.iu] = sign * motion.rate[name]
        udot[:, j.iu] = sign * motion.acc[name]
        coarse = motion.coarse[name]
        udot_coarse[:, j.iu] = sign * (motion.acc[name] if coarse is None else coarse)
    names = [sj.name for sj in scene.joints]
    force = np.zeros((n, len(names), 3))
    torque = np.zeros((n, len(names), 3))
    motors = []
    bars = np.zeros(n)
    for i in range(n):
        t = float(motion.t[i])
        motor, kin, _ = motor_forces(system, t, q[i], u[i], udot[i])
        sol = Solution(udot[i], np.zeros(0), 0, kin, np.zeros((0, 6)), np.zeros((0, 6)))
        reactions(system, t, np.concatenate([q[i], u[i]]), sol, force[i], torque[i], motor)
        motors.append(by_scene_joint(system, q[i], motor))
        if np.any(udot_coarse[i] != udot[i]):
            other, _, _ = motor_forces(system, t, q[i], u[i], udot_coarse[i])
            bars[i] = float(np.max(np.abs(other - motor))) / RICHARDSON
    bars = _envelope(bars, SPLINE_ORDER)
    rates = [by_scene_joint(system, q[i], u[i]) for i in range(n)]
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
    return _summarize(scene, rows, motion.t, check, margin, notes)


def _envelope(bars: np.ndarray, half: int) -> np.ndarray:
    """Each sample's bar the largest within ``half`` samples of it: the two splines' difference
    passes through zero where the true error need not (a pointwise Richardson estimate can be
    0 beside an error), while the error itself varies over the spline's span of samples."""
    if len(bars) == 0:
        return bars
    padded = np.pad(bars, half, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1)
    return windows.max(axis=1)


def _summarize(scene, rows: list[dict], t: np.ndarray, check: bool, margin: float,
               notes: list[str]) -> Torques:
    limits = _effort_limits(scene)
    summary: dict[str, Any] = {}
    failed = []
    for name in rows[0]["joints"] if rows else ():
        tau = np.array([r["joints"][name]["torque"][0] for r in rows])
        power = np.array([r["joints"][name]["power"][0] for r in rows])
        peak_at = int(np.argmax(np.abs(tau)))
        peak = float(abs(tau[peak_at]))
        span = float(t[-1] - t[0])
        rms = math.sqrt(trapezoid(tau ** 2, t) / span) if span > 0 else peak
        limit = limits.get(name)
        summary[name] = {"peak": [peak], "peak_t": [float(t[peak_at])], "rms": [rms],
                         "peak_power": [float(np.max(np.abs(power)))],
                         "energy": [trapezoid(power, t)],
                         "limit": [limit], "margin": [None if limit is None
                                                      else 1.0 - peak / limit]}
        if check and limit is not None and peak > limit * (1.0 - margin):
            failed.append(f"{scene.source}: joint {name} needs {peak:.6g} at t = "
                          f"{t[peak_at]:.6g} s, beyond its limit {limit:.6g}"
                          + (f" less {margin:.0%} headroom" if margin else "")
                          + f" (margin {1.0 - peak / limit:+.1%})")
    verdict = "not checked" if not check else "fail" if failed else "ok"
    return Torques(rows, {"summary": summary, "samples": len(rows), "check": verdict}, notes,
                   failed)


def raise_if_failed(result: Torques) -> None:
    """CheckFailedError (exit 4) with the first failed limit's line, if any failed."""
    if result.failed:
        more = f" (and {len(result.failed) - 1} more)" if len(result.failed) > 1 else ""
        raise CheckFailedError(result.failed[0] + more)
