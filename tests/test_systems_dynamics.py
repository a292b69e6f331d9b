"""Systems of bodies against independent truth: pendulum reactions in closed form, normal-mode
frequencies from M0⁻¹K0 built by hand, Freudenstein's equation, the slider-crank's position,
energy, convergence, and a one-link system against the one-body joint code."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.systems.run import simulate_system
from massprops.dynamics.systems.scene import load_system, parse_system, with_time

G = 9.81
SAMPLES = Path(__file__).resolve().parent.parent / "sample_scenes"


def _rod(name: str, top: float, length: float, mass: float) -> str:
    """A uniform thin rod hanging along -z from height ``top`` (its moment along itself tiny)."""
    i = mass * length * length / 12
    return (f"  {name}: {{mass: {mass!r}, inertia: [[{i!r}, 0, 0], [0, {i!r}, 0], [0, 0, 1e-9]], "
            f"position: [0, 0, {top - length / 2!r}]}}\n")


def _chain(n: int, length: float, mass: float, positions: str, duration: float) -> str:
    bodies = "".join(_rod(f"l{k}", -k * length, length, mass) for k in range(n))
    parents = ["world"] + [f"l{k}" for k in range(n - 1)]
    joints = "".join(f"  - {{name: j{k}, type: revolute, bodies: [{parents[k]}, l{k}], "
                     f"point: [0, 0, {-k * length!r}], axis: [0, 1, 0]}}\n"
                     for k in range(n))
    return (f"bodies:\n{bodies}joints:\n{joints}initial: {{positions: {{{positions}}}}}\n"
            f"forces: [{{type: gravity, g: [0, 0, {-G}]}}]\ntime: {{duration: {duration}}}\n")


def _run(text: str, every: float, rtol: float = 1e-10, **kw):
    scene = parse_system(text, source="test.yaml", base_dir=Path("."))
    return simulate_system(scene, rtol=rtol, every=every, estimate=False, **kw)


def test_pendulum_pivot_reaction_closed_form():
    m, length, theta0 = 2.0, 1.0, 1.0
    result = _run(_chain(1, length, m, f"j0: {theta0}", 2.0), every=0.05)
    s = result.samples
    theta = s.coordinates[0][:, 0]
    l_c = length / 2
    i_p = m * length**2 / 12 + m * l_c**2
    rate2 = 2 * m * G * l_c * (np.cos(theta) - np.cos(theta0)) / i_p  # energy, from rest
    alpha = -m * G * l_c * np.sin(theta) / i_p
    along = np.stack([np.sin(theta), 0 * theta, np.cos(theta)], axis=1)  # unit, pivot -> away
    across = np.stack([-np.cos(theta), 0 * theta, np.sin(theta)], axis=1)
    # r = l_c (-sin, 0, -cos): r̈ = l_c α (-cos, 0, sin) + l_c θ̇² (sin, 0, cos)
    expected = m * (l_c * alpha[:, None] * across + l_c * rate2[:, None] * along) \
        + m * np.array([0, 0, G])
    force = s.force[:, 0]
    scale = m * G
    # along the rod (toward the pivot: tension) and across it, separately
    assert np.max(np.abs(np.einsum("ij,ij->i", force - expected, along))) < 1e-9 * scale
    assert np.max(np.abs(np.einsum("ij,ij->i", force - expected, across))) < 1e-9 * scale
    assert np.max(np.abs(s.torque[:, 0])) < 1e-9 * scale * length  # a free, symmetric hinge
    assert np.ptp(np.einsum("ij,ij->i", force, across)) > 0.3 * scale  # the test has teeth


def _mode_check(n: int, m0: np.ndarray, k0: np.ndarray, length: float, mass: float,
                which: int = 0):
    """Start in mode ``which`` of M0⁻¹K0 (absolute angles φ) at amplitude 1e-4; the joints must
    follow ε v cos(ω t) over a period (nonlinear terms: ~ε² of it)."""
    w2, vecs = np.linalg.eig(np.linalg.solve(m0, k0))
    order = np.argsort(w2.real)
    omega = float(np.sqrt(w2.real[order[which]]))
    v = vecs[:, order[which]].real
    v = 1e-4 * v / np.max(np.abs(v))
    q = np.diff(np.concatenate([[0.0], v]))  # joint coordinates: relative angles
    positions = ", ".join(f"j{k}: {float(q[k])!r}" for k in range(n))
    period = 2 * np.pi / omega
    result = _run(_chain(n, length, mass, positions, period), every=period / 16, rtol=1e-12)
    phi = np.cumsum(np.stack([c[:, 0] for c in result.samples.coordinates], axis=1), axis=1)
    expected = np.cos(omega * result.samples.t)[:, None] * v
    assert np.max(np.abs(phi - expected)) < 1e-5 * np.max(np.abs(v))


def test_double_pendulum_normal_modes():
    m, length = 1.0, 1.0
    i = m * length**2 / 12
    m0 = np.array([[i + m * length**2 / 4 + m * length**2, m * length**2 / 2],
                   [m * length**2 / 2, i + m * length**2 / 4]])
    k0 = np.diag([m * G * (length / 2 + length), m * G * length / 2])
    _mode_check(2, m0, k0, length, m, which=0)
    _mode_check(2, m0, k0, length, m, which=1)


def test_chain_lowest_mode():
    n, m, length = 5, 0.1, 0.2
    i = m * length**2 / 12
    arms = np.array([[length if c < k else (length / 2 if c == k else 0.0) for c in range(n)]
                     for k in range(n)])  # ∂x_k/∂φ_c of body k's centre of mass
    m0 = m * arms.T @ arms + i * np.eye(n)
    k0 = np.diag([m * G * (length / 2 + length * (n - 1 - c)) for c in range(n)])
    _mode_check(n, m0, k0, length, m, which=0)


def test_four_bar_freudenstein_and_redundancy():
    scene = with_time(load_system(SAMPLES / "four_bar.yaml"), duration=1.5)
    result = simulate_system(scene, every=0.05, rtol=1e-10, estimate=False)
    s = result.samples
    crank, rocker = s.position[:, 0], s.position[:, 2]
    theta = np.arctan2(crank[:, 2], crank[:, 0])
    phi = np.arctan2(rocker[:, 2], rocker[:, 0] - 3.0)
    a, b, c, d = 1.0, 3.0, 2.5, 3.0
    k1, k2, k3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    residual = k1 * np.cos(phi) - k2 * np.cos(theta) + k3 - np.cos(theta - phi)
    assert np.max(np.abs(residual)) < 1e-9
    assert np.ptp(np.unwrap(theta)) > 2.0  # the crank really turned
    d_ = result.diagnostics
    assert d_["degrees_of_freedom"] == 1 and d_["redundant_constraints"] == 3
    assert d_["constraint_residual"]["position"] < 1e-12 * 3
    assert d_["energy_rel_drift"] < 1e-8


def test_slider_crank_position():
    scene = with_time(load_system(SAMPLES / "slider_crank.yaml"), duration=0.7)
    # the projection keeps the loop closed to round-off at any tolerance: a loose one will do
    result = simulate_system(scene, every=0.1, rtol=1e-7, estimate=False)
    s = result.samples
    crank, slider = s.position[:, 0], s.position[:, 2]
    theta = np.arctan2(crank[:, 2], crank[:, 0])
    r, rod = 0.5, 2.0
    x = r * np.cos(theta) + np.sqrt(rod * rod - (r * np.sin(theta)) ** 2)
    assert np.max(np.abs(slider[:, 0] - x)) < 1e-10
    # the frictionless slide pushes only across its axis
    assert np.max(np.abs(s.force[:, 3, 0])) < 1e-8 * np.max(np.abs(s.force[:, 3]))


def test_energy_conserved_double_pendulum():
    scene = with_time(load_system(SAMPLES / "double_pendulum.yaml"), duration=3.0)
    result = simulate_system(scene, rtol=1e-10, estimate=False)
    assert result.diagnostics["energy_rel_drift"] < 1e-9


@pytest.mark.slow
def test_convergence_order_and_estimate():
    scene = with_time(load_system(SAMPLES / "double_pendulum.yaml"), duration=2.0)
    from massprops.dynamics.systems.outputs import distance

    ref = simulate_system(scene, rtol=1e-13, every=0.1, estimate=False).samples
    steps, errors = [], []
    for rtol in (1e-5, 1e-6, 1e-7, 1e-8):
        run = simulate_system(scene, rtol=rtol, every=0.1)
        steps.append(run.steps)
        errors.append(distance(run.samples, ref, scene.size))
        assert errors[-1] < 10 * run.diagnostics["error_estimate"]  # honest estimate
    slope = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert 6.0 < slope < 11.0, (steps, errors)


@pytest.mark.slow  # the one-body run compiles its dop853 kernel on a cold cache (~10 s)
def test_one_link_system_equals_one_body_joint():
    from massprops.dynamics.scene import load_scene
    from massprops.dynamics.simulate import simulate

    one = load_scene(SAMPLES / "compound_pendulum.yaml")
    one = dataclasses.replace(one, time=dataclasses.replace(one.time, duration=3.0))
    ref = simulate(one, rtol=1e-12, every=0.5)
    q = one.initial.orientation
    from massprops.rotation import quat_to_matrix

    com = -quat_to_matrix(q) @ np.array([0, 0, 0.5])
    text = (f"bodies:\n  rod: {{mass: 2.0, inertia: [[0.16673333333333333, 0, 0], "
            f"[0, 0.16673333333333333, 0], [0, 0, 1.3333333333333333e-4]], "
            f"position: {com.tolist()}, orientation: {list(map(float, q))}}}\n"
            "joints:\n  - {name: hinge, type: revolute, bodies: [world, rod], point: [0, 0, 0], "
            "axis: [1, 0, 0]}\nforces: [{type: gravity, g: [0, 0, -9.81]}]\n"
            "time: {duration: 3.0}\n")
    sys_run = _run(text, every=0.5, rtol=1e-12).samples
    assert np.max(np.abs(sys_run.position[:, 0] - ref.trajectory.position)) < 1e-8
    assert np.max(np.abs(sys_run.velocity[:, 0] - ref.trajectory.velocity)) < 1e-7
    assert np.max(np.abs(sys_run.angular_velocity[:, 0]
                         - ref.trajectory.angular_velocity)) < 1e-7
    force = ref.trajectory.joints[0].force_world
    assert np.max(np.abs(sys_run.force[:, 0] - force)) < 1e-6 * np.max(np.abs(force))


@pytest.mark.slow  # four ladders and a reference, ~10 s
def test_precision_ladder_on_a_system():
    from massprops.dynamics.systems.precision import precision_system

    scene = with_time(load_system(SAMPLES / "double_pendulum.yaml"), duration=0.5)
    report = precision_system(scene).as_dict()
    assert report["reference"]["kind"] == "run" and report["reference"]["accuracy"] < 1e-11
    runs = report["runs"]
    assert {"integrator", "setting", "wall_time_s", "error", "steps"} <= set(runs[0])
    for run in runs:  # the estimate is honest on every rung: true error within 10x of it
        assert run["error"] < 10 * run["error_estimate"] + 3 * report["reference"]["accuracy"]
    for name in ("dop853", "rk4", "midpoint", "implicit"):  # each ladder converges
        ladder = [r["error"] for r in runs if r["integrator"] == name]
        assert len(ladder) >= 3 and ladder[-1] < 1e-3 * ladder[0], (name, ladder)


@pytest.mark.slow  # ~8 s: 7 bodies, 3 loops, a stiff spring, in plain numpy
def test_andrews_squeezer_against_the_test_set_reference():
    """Positions at t = 0.03 s against the published reference (Mazzia & Magherini's test set),
    which is good to a few 1e-10 relative: tested at 1e-9 of max(1, |value|), no tighter."""
    scene = load_system(SAMPLES / "andrews.yaml")
    result = simulate_system(scene, every=0.03, estimate=False)
    start = {"O": -0.0617138900142764496358948458001, "F": 0.0,
             "B": 0.455279819163070380255912382449, "H": 0.222668390165885884674473185609,
             "A5": 0.487364979543842550225598953530, "K": -0.222668390165885884674473185609,
             "A7": 1.23054744454982119249735015568}
    reference = {"O": 15.81077119629904, "F": -15.75637105984298, "B": 0.04082224013073101,
                 "H": -0.5347301163226948, "A5": 0.5244099658805304, "K": 0.5347301163226948,
                 "A7": 1.048080741042263}
    names = [j.name for j in scene.joints]
    for name, value in reference.items():
        got = result.samples.coordinates[names.index(name)][-1, 0] + start[name]
        assert abs(got - value) < 1e-9 * max(1.0, abs(value)), (name, got - value)
    d = result.diagnostics
    assert d["degrees_of_freedom"] == 1 and d["redundant_constraints"] == 9
    assert d["constraint_residual"]["position"] < 1e-14
