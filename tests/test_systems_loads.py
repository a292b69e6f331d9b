"""Systems: loads and signs against closed forms (a slider on a joint spring, two free bodies on a
spring, a constant force, a drive), and joints declared against the tree's direction."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from massprops.dynamics.systems.run import simulate_system
from massprops.dynamics.systems.scene import parse_system

BOX = "{mass: 2.0, inertia: [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]], "
ROD = "{mass: 1.0, inertia: [[0.0834, 0, 0], [0, 0.0834, 0], [0, 0, 0.001]], "


def _run(text: str, every: float, rtol: float = 1e-11):
    scene = parse_system(text, source="t.yaml", base_dir=Path("."))
    return simulate_system(scene, rtol=rtol, every=every, estimate=False)


def test_prismatic_joint_spring_is_a_harmonic_oscillator():
    k, m, x0 = 50.0, 2.0, 0.1
    text = (f"bodies:\n  s: {BOX}position: [0, 0, 0]}}\n"
            "joints:\n  - {name: p, type: prismatic, bodies: [world, s], point: [0, 0, 0], "
            f"axis: [1, 0, 0], stiffness: {k}, rest: 0.0}}\n"
            f"initial: {{positions: {{p: {x0}}}}}\ntime: {{duration: 1.0}}\n")
    result = _run(text, every=0.1)
    s = result.samples
    w = np.sqrt(k / m)
    assert np.allclose(s.coordinates[0][:, 0], x0 * np.cos(w * s.t), atol=1e-9)
    assert np.allclose(s.position[:, 0, 0], x0 * np.cos(w * s.t), atol=1e-9)
    # the joint's spring is an applied load along the axis, not a reaction
    assert np.max(np.abs(s.force[:, 0, 0])) < 1e-9
    assert result.diagnostics["energy_rel_drift"] < 1e-9


def test_two_free_bodies_on_a_spring():
    k, m1, m2, d0 = 30.0, 2.0, 2.0, 0.05
    text = (f"bodies:\n  a: {BOX}position: [-0.5, 0, 0]}}\n"
            f"  b: {BOX}position: [{0.5 + d0}, 0, 0]}}\n"
            "forces:\n  - {type: spring, bodies: [a, b], points: [[-0.5, 0, 0], "
            f"[{0.5 + d0}, 0, 0]], stiffness: {k}, rest_length: 1.0}}\n"
            "time: {duration: 1.0}\n")
    s = _run(text, every=0.1).samples
    w = np.sqrt(k * (m1 + m2) / (m1 * m2))
    gap = s.position[:, 1, 0] - s.position[:, 0, 0] - 1.0
    assert np.allclose(gap, d0 * np.cos(w * s.t), atol=1e-9)
    assert np.allclose(s.position[:, 0, 0] + s.position[:, 1, 0], d0, atol=1e-12)  # momentum


def test_drag_on_a_thrown_body_and_on_a_pendulum():
    """Linear drag c and gravity g on a free body: v(t) = v∞ + (v0 − v∞) e^(−kt), k = c / m,
    v∞ = g / k; angular drag a on an isotropic inertia I: ω(t) = ω0 e^(−a t / I). On a
    pendulum: no energy drift is claimed under drag, and it slows the swing."""
    c, a, m, inertia = 0.8, 0.05, 2.0, 0.1
    v0, w0, g = np.array([3.0, -1.0, 4.0]), np.array([0.3, 2.0, -1.0]), np.array([0, 0, -9.81])
    text = (f"bodies:\n  b: {BOX}position: [0, 0, 0]}}\n"
            f"initial: {{bodies: {{b: {{velocity: {v0.tolist()}, "
            f"angular_velocity: {w0.tolist()}}}}}}}\n"
            "forces:\n  - {type: gravity, g: [0, 0, -9.81]}\n"
            f"  - {{type: drag, linear: {c}, angular: {a}}}\n"
            "time: {duration: 2.0}\n")
    s = _run(text, every=0.5, rtol=1e-12).samples
    k, t = c / m, s.t[:, None]
    terminal = g / k
    v = terminal + (v0 - terminal) * np.exp(-k * t)
    x = terminal * t + (v0 - terminal) * (1 - np.exp(-k * t)) / k
    assert np.allclose(s.velocity[:, 0], v, rtol=0, atol=1e-10)
    assert np.allclose(s.position[:, 0], x, rtol=0, atol=1e-10)
    assert np.allclose(s.angular_velocity[:, 0], w0 * np.exp(-a * t / inertia), atol=1e-10)
    pendulum = (f"bodies:\n  r: {ROD}position: [0, 0, -0.5]}}\n"
                "joints:\n  - {name: h, type: revolute, bodies: [world, r], point: [0, 0, 0], "
                "axis: [0, 1, 0]}\ninitial: {rates: {h: 3.0}}\n"
                "forces:\n  - {type: gravity, g: [0, 0, -9.81]}\n")
    def energy(samples) -> np.ndarray:  # the rod swings about y: its moment there is 0.0834
        v, w, z = samples.velocity[:, 0], samples.angular_velocity[:, 0], samples.position[:, 0, 2]
        return 0.5 * np.sum(v * v, axis=1) + 0.5 * 0.0834 * w[:, 1] ** 2 + 9.81 * z

    free = energy(_run(pendulum + "time: {duration: 2.0}\n", every=0.1).samples)
    dragged = _run(pendulum + "  - {type: drag, body: r, linear: 0.2}\ntime: {duration: 2.0}\n",
                   every=0.1)
    assert dragged.diagnostics["energy_rel_drift"] is None  # drag: no energy to conserve
    assert np.ptp(free) < 1e-9 * abs(free[0])
    lost = energy(dragged.samples)
    assert np.all(np.diff(lost) < 0) and lost[-1] < free[0] - 0.05 * abs(free[0])


def test_constant_force_and_drive():
    text = (f"bodies:\n  f: {BOX}position: [0, 0, 0]}}\n  r: {ROD}position: [5, 0, 0]}}\n"
            "joints:\n  - {name: h, type: revolute, bodies: [world, r], point: [5, 0, 0], "
            "axis: [0, 0, 1], torque: 0.5, start: 0.2, end: 0.6}\n"
            "forces:\n  - {type: force, body: f, vector: [0, 4.0, 0], frame: body}\n"
            "time: {duration: 1.0}\n")
    s = _run(text, every=0.1).samples
    assert np.allclose(s.position[:, 0, 1], 0.5 * (4.0 / 2.0) * s.t**2, atol=1e-10)
    # the drive turns the rod about its own axis (moment 0.001): θ̈ = 0.5 / 0.001 in the window
    alpha = 0.5 / 0.001
    on = np.clip(s.t, 0.2, 0.6) - 0.2
    theta = 0.5 * alpha * on**2 + alpha * 0.4 * np.clip(s.t - 0.6, 0.0, None)
    assert np.allclose(s.coordinates[0][:, 0], theta, rtol=1e-9, atol=1e-9)


def test_joints_declared_against_the_tree_keep_the_contract_signs():
    """The elbow written [lower, upper] is the same hinge: its coordinate and rate are the turn
    of `upper` relative to `lower`, the opposite sign, and its reaction is the force on
    `upper`, the opposite of the force on `lower`."""
    base = (f"bodies:\n  upper: {ROD}position: [0, 0, -0.5]}}\n"
            f"  lower: {ROD}position: [0, 0, -1.5]}}\n"
            "joints:\n  - {name: s, type: revolute, bodies: [world, upper], point: [0, 0, 0], "
            "axis: [0, 1, 0]}\n  - {name: e, type: revolute, bodies: [upper, lower], "
            "point: [0, 0, -1], axis: [0, 1, 0], stiffness: 3.0, damping: 0.1}\n"
            "initial: {positions: {s: 0.4, e: 0.3}, rates: {e: 0.5}}\n"
            "forces: [{type: gravity, g: [0, 0, -9.81]}]\ntime: {duration: 1.0}\n")
    flipped = base.replace("bodies: [upper, lower]", "bodies: [lower, upper]").replace(
        "e: 0.3}, rates: {e: 0.5}", "e: -0.3}, rates: {e: -0.5}")
    a, b = _run(base, every=0.1).samples, _run(flipped, every=0.1).samples
    assert np.max(np.abs(a.position - b.position)) < 1e-10
    assert np.allclose(a.coordinates[1], -b.coordinates[1], atol=1e-10)
    assert np.allclose(a.rates[1], -b.rates[1], atol=1e-9)
    assert np.allclose(a.force[:, 1], -b.force[:, 1], atol=1e-8)
    assert np.allclose(a.torque[:, 1], -b.torque[:, 1], atol=1e-8)
