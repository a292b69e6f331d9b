"""Bodies held by joints against independent truth: the compound pendulum's periods (small
oscillations and the exact elliptic period), the heavy symmetric top's closed form against a
separate scipy integration of Euler's equations about the pivot, its conserved quantities at
t = 100 s, the reaction of a gyroscope in steady precession (textbook), the reactions against
m·a_com - f from finite differences of the dense output, the constraint held to round-off by
every integrator, and two spherical joints as one hinge sharing its load."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from massprops.dynamics.integrators import INTEGRATORS
from massprops.dynamics.precision import precision
from massprops.dynamics.scene import parse_scene
from massprops.dynamics.simulate import simulate
from massprops.rotation import quat_from_axis_angle, quat_to_matrix, rotation_angle_between

G = 9.81


def parse(text: str):
    return parse_scene(text, source="scene.yaml", base_dir=Path("."))


def yaml_list(a) -> str:
    return "[" + ", ".join(repr(float(x)) for x in np.ravel(a)) + "]"


def crossings(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Times where the sampled x goes from negative to positive (linear interpolation)."""
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


def parallel_axis(j_com, mass, d):
    """J about the point at offset d from the centre of mass: J + m(|d|² E - d dᵀ)."""
    d = np.asarray(d, float)
    return np.asarray(j_com, float) + mass * (d @ d * np.eye(3) - np.outer(d, d))


# --- the compound pendulum ------------------------------------------------------------------------
J_ASYM = np.array([[0.10, 0.02, 0.01], [0.02, 0.12, -0.015], [0.01, -0.015, 0.05]])
E_HINGE = np.array([1.0, 1.0, 0.0]) / math.sqrt(2.0)
P_HINGE = np.array([0.3, 0.3, 0.4])  # on the line through (0, 0, 0.4) along E_HINGE


def pendulum(theta0: float, duration: float, integrator="dop853", extra="") -> str:
    """A 2 kg body with a non-diagonal inertia, hinged about a non-principal axis 0.4 m above
    its centre of mass (hanging at the identity orientation), turned theta0 about the hinge."""
    q = quat_from_axis_angle(E_HINGE, theta0)
    return f"""\
body: {{mass: 2.0, inertia: {J_ASYM.tolist()}}}
joints:
  - {{type: revolute, point: {yaml_list(P_HINGE)}, axis: {yaml_list(E_HINGE)},
     anchor: {yaml_list(P_HINGE)}, world_axis: {yaml_list(E_HINGE)}}}
initial: {{orientation: {yaml_list(q)}}}
forces:
  - {{type: gravity, g: [0, 0, -9.81]}}
{extra}time: {{duration: {duration}, integrator: {integrator}, rtol: 1.0e-12}}
"""


def pendulum_constants():
    """(I about the hinge axis, m g d): the parallel-axis theorem about a line, by hand."""
    i_axis = E_HINGE @ J_ASYM @ E_HINGE + 2.0 * 0.4**2
    return i_axis, 2.0 * G * 0.4


def swing_rate(result) -> np.ndarray:
    return result.trajectory.angular_velocity @ E_HINGE


def test_compound_pendulum_small_oscillation_period():
    theta0 = 1e-3
    res = simulate(parse(pendulum(theta0, 8.0)), every=1e-3)
    i_axis, mgd = pendulum_constants()
    period = 2 * math.pi * math.sqrt(i_axis / mgd) * (1 + theta0**2 / 16)
    up = crossings(res.trajectory.t, swing_rate(res))
    measured = (up[-1] - up[0]) / (len(up) - 1)
    assert abs(measured / period - 1) < 1e-8, (measured, period)
    assert res.diagnostics["constraint_drift"] < 1e-14  # m and rad: round-off


def test_compound_pendulum_large_swing_has_the_elliptic_period():
    theta0 = 2.5  # rad from the bottom
    res = simulate(parse(pendulum(theta0, 12.0)), every=1e-3)
    i_axis, mgd = pendulum_constants()
    period = 4 * ellipk(math.sin(theta0 / 2) ** 2) * math.sqrt(i_axis / mgd)
    up = crossings(res.trajectory.t, swing_rate(res))
    measured = (up[-1] - up[0]) / (len(up) - 1)
    assert abs(measured / period - 1) < 1e-8, (measured, period)
    # the energy, from the world quantities: ½ m v² + ½ ω·J ω + m g z
    tr = res.trajectory
    a = quat_to_matrix(tr.orientation)
    j_world = a @ J_ASYM @ np.transpose(a, (0, 2, 1))
    e = 0.5 * 2.0 * np.einsum("ni,ni->n", tr.velocity, tr.velocity) + 0.5 * np.einsum(
        "ni,nij,nj->n", tr.angular_velocity, j_world, tr.angular_velocity) + 2.0 * G * (
        tr.position[:, 2])
    assert np.max(np.abs(e - e[0])) < 1e-10 * mgd


# --- the heavy symmetric top ----------------------------------------------------------------------
R_TILT = quat_to_matrix(quat_from_axis_angle(np.array([1.0, -2.0, 0.5]) / math.sqrt(5.25), 0.9))
L_TOP, M_TOP = 0.35, 1.5
J_TOP = R_TILT @ np.diag([0.02, 0.02, 0.03]) @ R_TILT.T  # symmetric about R_TILT e_z
TIP = -L_TOP * R_TILT[:, 2]  # the pivot, on the symmetry axis below the centre of mass


def top(q0, w0, duration: float, integrator="auto", every=0.05) -> str:
    return f"""\
body: {{mass: {M_TOP}, inertia: {J_TOP.tolist()}}}
joints: [{{type: spherical, point: {yaml_list(TIP)}, anchor: [0.1, -0.2, 0.3]}}]
initial: {{orientation: {yaml_list(q0)}, angular_velocity: {yaml_list(w0)},
          angular_velocity_frame: body}}
forces: [{{type: gravity, g: [0, 0, -9.81]}}]
time: {{duration: {duration}, integrator: {integrator}, rtol: 1.0e-12}}
output: {{every: {every}}}
"""


Q_TOP = quat_from_axis_angle(np.array([0.3, 0.9, -0.2]) / math.sqrt(0.94), 1.1)
W_TOP = np.array([3.0, -2.0, 25.0])


def euler_about_pivot(a0, w0_body, t_eval):
    """An independent reference: A (9) and ω (body, 3) under J_P ω̇ + ω × J_P ω = c × Aᵀ m g,
    the inertia about the pivot in body axes (not diagonalised), scipy DOP853 at rtol 1e-13."""
    j_p = parallel_axis(J_TOP, M_TOP, TIP)
    j_inv = np.linalg.inv(j_p)
    weight = np.array([0.0, 0.0, -G * M_TOP])

    def rhs(_, y):
        a, w = y[:9].reshape(3, 3), y[9:]
        n = np.cross(-TIP, a.T @ weight)
        wx = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
        return np.concatenate([(a @ wx).ravel(), j_inv @ (n - np.cross(w, j_p @ w))])

    sol = solve_ivp(rhs, (t_eval[0], t_eval[-1]), np.concatenate([np.ravel(a0), w0_body]),
                    method="DOP853", rtol=1e-13, atol=1e-15, t_eval=t_eval)
    return sol.y[:9].T.reshape(-1, 3, 3), sol.y[9:].T


def orientation_error(a, q):
    """rad between rotation matrices a (n, 3, 3) and quaternions q (n, 4)."""
    u, _, vt = np.linalg.svd(a)  # the nearest rotation: the reference drifts off orthogonal
    return rotation_angle_between(q, _quats(u @ vt))


def _quats(m):
    from massprops.rotation import matrix_to_quat

    return matrix_to_quat(m)


@pytest.mark.slow
def test_heavy_top_closed_form_against_euler_equations_about_the_pivot():
    res = simulate(parse(top(Q_TOP, W_TOP, 4.0)))
    assert res.integrator == "exact" and res.steps == 0
    tr = res.trajectory
    a_ref, w_ref = euler_about_pivot(quat_to_matrix(Q_TOP), W_TOP, tr.t)
    assert np.max(orientation_error(a_ref, tr.orientation)) < 2e-11
    assert np.max(np.abs(tr.angular_velocity_body - w_ref)) < 2e-11 * np.linalg.norm(W_TOP)


def _top_invariants(tr):
    """(energy J, vertical angular momentum about the pivot, spin about the axis), from the
    trajectory's world quantities alone."""
    a = quat_to_matrix(tr.orientation)
    j_world = a @ J_TOP @ np.transpose(a, (0, 2, 1))
    h_com = np.einsum("nij,nj->ni", j_world, tr.angular_velocity)
    r = tr.position - np.array([0.1, -0.2, 0.3])
    h_pivot = h_com + M_TOP * np.cross(r, tr.velocity)
    energy = 0.5 * M_TOP * np.sum(tr.velocity**2, axis=1) + 0.5 * np.einsum(
        "ni,ni->n", tr.angular_velocity, h_com) + M_TOP * G * tr.position[:, 2]
    spin = np.einsum("ni,ni->n", tr.angular_velocity, a @ R_TILT[:, 2])
    return energy, h_pivot[:, 2], spin


def test_heavy_top_conserves_its_invariants_to_round_off_at_100_s():
    res = simulate(parse(top(Q_TOP, W_TOP, 100.0, every=0.5)))
    energy, lz, spin = _top_invariants(res.trajectory)
    e_scale = 0.5 * float(W_TOP @ parallel_axis(J_TOP, M_TOP, TIP) @ W_TOP)
    assert np.max(np.abs(energy - energy[0])) < 1e-12 * e_scale
    h_scale = float(np.linalg.norm(parallel_axis(J_TOP, M_TOP, TIP) @ W_TOP))
    assert np.max(np.abs(lz - lz[0])) < 1e-12 * h_scale
    assert np.max(np.abs(spin - spin[0])) < 1e-12 * np.linalg.norm(W_TOP)
    turned = np.linalg.norm(W_TOP) * 100.0  # round-off grows like eps·|ω|·t
    assert res.diagnostics["vertical_angular_momentum_rel_drift"] < 4 * 2.2e-16 * turned
    assert res.diagnostics["axial_angular_momentum_rel_drift"] < 4 * 2.2e-16 * turned
    # ... and is still a solution of the equations there: restart the reference at t = 99.5
    tr = res.trajectory
    a0 = quat_to_matrix(tr.orientation[-2])
    a_ref, w_ref = euler_about_pivot(a0, tr.angular_velocity_body[-2], tr.t[-2:])
    assert orientation_error(a_ref[-1:], tr.orientation[-1:])[0] < 1e-12
    assert np.max(np.abs(tr.angular_velocity_body[-1] - w_ref[-1])) < 1e-12 * 25


@pytest.mark.parametrize("name", ["dop853", "splitting6", "implicit"])
def test_integrators_agree_with_the_closed_form_on_the_top(name):
    exact = simulate(parse(top(Q_TOP, W_TOP, 2.0, integrator="exact")))
    other = simulate(parse(top(Q_TOP, W_TOP, 2.0, integrator=name)),
                     step=2e-3 if name == "splitting6" else 1e-3)
    assert np.max(rotation_angle_between(exact.trajectory.orientation,
                                         other.trajectory.orientation)) < 1e-8
    estimate = other.diagnostics["error_estimate"]
    assert estimate is not None and estimate < 1e-7


def test_gyroscope_in_steady_precession_carries_the_textbook_reaction():
    """Axle horizontal, spin w3, precession Ω = m g l / (C w3) (exact at θ = 90°): the centre of
    mass circles at radius l, so the pivot pushes up with m g and inward with m Ω² l."""
    m, arm, c_mom, a_mom, w3 = 0.8, 0.07, 6e-4, 4e-4, 250.0
    omega = m * G * arm / (c_mom * w3)
    text = f"""\
body: {{mass: {m}, inertia: [[{c_mom}, 0, 0], [0, {a_mom}, 0], [0, 0, {a_mom}]]}}
joints: [{{type: spherical, point: [{-arm}, 0, 0], anchor: [0, 0, 0.2]}}]
initial: {{angular_velocity: [{w3}, 0, {omega}]}}
forces: [{{type: gravity, g: [0, 0, -9.81]}}]
time: {{duration: 3.0, rtol: 1.0e-12}}
output: {{every: 0.01}}
"""
    for name, tol in (("exact", 1e-12), ("dop853", 1e-9), ("splitting6", 1e-9)):
        res = simulate(parse(text), integrator=name, step=1e-3)
        tr = res.trajectory
        radial = tr.position - np.array([0.0, 0.0, 0.2])
        assert np.max(np.abs(radial[:, 2])) < tol * arm  # the axle stays horizontal
        expected = -m * omega**2 * radial + np.array([0.0, 0.0, m * G])
        (joint,) = tr.joints
        assert joint.torque_world is None
        assert np.max(np.abs(joint.force_world - expected)) < tol * m * G, name
        body_frame = np.einsum("nji,nj->ni", quat_to_matrix(tr.orientation), expected)
        assert np.max(np.abs(joint.force_body - body_frame)) < tol * m * G, name


# --- reactions against the trajectory itself ------------------------------------------------------
def second_difference(x: np.ndarray, h: float) -> np.ndarray:
    """d²x/dt² at the interior samples (3 on each side dropped), sixth-order central."""
    c = np.array([1 / 90, -3 / 20, 3 / 2, -49 / 18, 3 / 2, -3 / 20, 1 / 90])
    n = len(x)
    return sum(c[k] * x[k:n - 6 + k] for k in range(7)) / (h * h)


def first_difference(x: np.ndarray, h: float) -> np.ndarray:
    """dx/dt at the interior samples (3 on each side dropped), sixth-order central."""
    c = np.array([-1 / 60, 3 / 20, -3 / 4, 0.0, 3 / 4, -3 / 20, 1 / 60])
    n = len(x)
    return sum(c[k] * x[k:n - 6 + k] for k in range(7)) / h


def test_reaction_force_equals_m_a_minus_f_from_the_dense_output():
    """The nutating gyroscope sample: λ from the equations against m·a_com - m g, a_com by
    finite differences of the sampled positions (two spacings: their difference bounds the
    differencing error), within that bound plus the run's own error estimate."""
    scene = parse((Path(__file__).parent.parent / "sample_scenes" / "gyroscope.yaml")
                  .read_text().replace("duration: 1.0", "duration: 0.3"))
    m = scene.body.mass
    res = simulate(scene, integrator="dop853", rtol=1e-12, every=5e-4)
    tr = res.trajectory
    weight = np.array([0.0, 0.0, -G * m])
    fine = m * second_difference(tr.position, 5e-4) - weight
    coarse = m * second_difference(tr.position[::2], 1e-3) - weight
    (joint,) = tr.joints
    ours = joint.force_world[3:-3]
    differencing = np.max(np.abs(fine[3::2][:len(coarse)] - coarse))  # same instants
    scale = m * G * 2  # the load's size
    bound = differencing + res.diagnostics["error_estimate"] * scale
    assert np.max(np.abs(ours - fine)) < 2 * bound + 1e-9 * scale
    assert bound < 1e-6 * scale  # the check is a sharp one


def test_hinge_reaction_torque_equals_dh_dt_minus_applied_moment():
    """An unbalanced body on a hinge: the hinge's couple across its axis against dH_P/dt minus
    the weight's moment about the hinge point, H_P from the trajectory and differenced."""
    res = simulate(parse(pendulum(1.5, 2.0)), every=5e-4)
    tr = res.trajectory
    a = quat_to_matrix(tr.orientation)
    j_world = a @ J_ASYM @ np.transpose(a, (0, 2, 1))
    r = tr.position - P_HINGE
    h_point = np.einsum("nij,nj->ni", j_world, tr.angular_velocity) + 2.0 * np.cross(
        r, tr.velocity)
    weight = np.array([0.0, 0.0, -2.0 * G])
    expected = first_difference(h_point, 5e-4) - np.cross(r, weight)[3:-3]
    (joint,) = tr.joints
    assert np.max(np.abs(joint.torque_world @ E_HINGE)) < 1e-13  # across the axis only
    expected_across = expected - np.outer(expected @ E_HINGE, E_HINGE)
    assert np.max(np.abs(expected @ E_HINGE)) < 1e-7  # the applied moment drives the axis
    assert np.max(np.abs(joint.torque_world[3:-3] - expected_across)) < 1e-7
    assert np.max(np.linalg.norm(joint.torque_world, axis=1)) > 0.01  # it is not trivial
    force = 2.0 * second_difference(tr.position, 5e-4) - weight
    assert np.max(np.abs(joint.force_world[3:-3] - force)) < 1e-6


# --- the constraint, every integrator -------------------------------------------------------------
BUSY_HINGE = pendulum(0.7, 0.5, extra="""\
  - {type: spring, anchor: [0.5, 0, 0], point: [0.1, 0, 0], stiffness: 20, damping: 0.3}
  - {type: drag, linear: 0.2, angular: 0.05}
  - {type: force, vector: [0, 0.5, 1], frame: body, point: [0, 0.1, 0], start: 0.1, end: 0.3}
""").replace("forces:\n", "forces:\n")


@pytest.mark.parametrize("name", sorted(INTEGRATORS))
def test_every_integrator_holds_the_joints_to_round_off(name):
    busy_top = top(Q_TOP, W_TOP, 0.5, integrator=name).replace(
        "forces: [{type: gravity, g: [0, 0, -9.81]}]",
        "forces: [{type: gravity, g: [0, 0, -9.81]}, {type: spring, anchor: [0, 0, 1], "
        "stiffness: 3}, {type: drag, linear: 0.1}]")
    for text in (BUSY_HINGE, busy_top):
        scene = parse(text.replace("integrator: dop853", f"integrator: {name}"))
        if name == "exact":
            continue  # these scenes have no closed form (exact refuses them)
        res = simulate(scene, step=1e-3)
        assert res.diagnostics["constraint_drift"] < 1e-14, (name, res.diagnostics)
        assert res.diagnostics["energy_rel_drift"] is None  # spring damping and drag


def test_energy_is_kept_by_the_symplectic_splitting_on_a_held_body():
    """Bounded energy error, no secular drift: four times longer, not four times worse."""
    drifts = []
    for duration in (10.0, 40.0):
        res = simulate(parse(top(Q_TOP, W_TOP, duration, integrator="splitting")), step=2e-3)
        drifts.append(res.diagnostics["energy_rel_drift"])
        assert res.diagnostics["constraint_drift"] < 1e-14
    assert drifts[0] < 1e-4 and drifts[1] < 1.5 * drifts[0], drifts


# --- two spherical joints, the torque-free body, auto, precision ----------------------------------
def test_two_spherical_joints_move_as_one_hinge_and_share_its_load():
    one = pendulum(1.0, 1.0)
    p2 = P_HINGE - 0.5 * E_HINGE
    two = one.replace(one[one.index("joints:"):one.index("initial:")], f"""\
joints:
  - {{type: spherical, point: {yaml_list(P_HINGE)}, anchor: {yaml_list(P_HINGE)}}}
  - {{type: spherical, point: {yaml_list(p2)}, anchor: {yaml_list(p2)}}}
""")
    # two systems now (a tree revolute; a tree ball and a cut one, projected): the same motion
    # to their error estimates, where one pinned model gave the same numbers
    runs = [simulate(parse(text), every=0.01) for text in (one, two)]
    a, b = (run.trajectory for run in runs)
    estimates = sum(run.diagnostics["error_estimate"] for run in runs)
    assert np.max(rotation_angle_between(a.orientation, b.orientation)) < 10 * estimates
    (hinge,) = a.joints
    first, second = b.joints
    assert first.kind == second.kind == "spherical" and first.torque_world is None
    scale = np.abs(hinge.force_world).max()
    assert np.allclose(first.force_world + second.force_world, hinge.force_world, rtol=0,
                       atol=1e-9 * scale)
    d = -0.5 * E_HINGE  # world: the hinge axis does not turn
    assert np.allclose(np.cross(d, second.force_world), hinge.torque_world, rtol=0,
                       atol=1e-9 * scale)
    assert np.max(np.abs(second.force_world @ E_HINGE)) < 1e-9 * scale  # the floating bearing


def test_a_torque_free_body_about_a_fixed_point_is_exact_and_keeps_its_momentum():
    text = top(Q_TOP, np.array([4.0, -3.0, 2.0]), 10.0).replace(
        "forces: [{type: gravity, g: [0, 0, -9.81]}]\n", "")
    body = text.replace(str(J_TOP.tolist()), "[[0.02, 0.003, -0.001], [0.003, 0.03, 0.002], "
                        "[-0.001, 0.002, 0.045]]")
    exact = simulate(parse(body))
    assert exact.integrator == "exact"
    assert exact.diagnostics["angular_momentum_rel_drift"] < 1e-13
    dop = simulate(parse(body), integrator="dop853", rtol=1e-13)
    assert np.max(rotation_angle_between(exact.trajectory.orientation,
                                         dop.trajectory.orientation)) < 1e-10


def test_auto_picks_implicit_for_a_stiffly_damped_hinge_and_it_decays():
    damping = 2.0e6  # rate damping / I_axis ~ 5e6/s: ~2e7 explicit steps over 10 s
    text = pendulum(0.5, 10.0, integrator="auto").replace(
        "world_axis: ", f"damping: {damping}, world_axis: ")
    res = simulate(parse(text))
    assert res.integrator == "implicit", res.reason
    # overdamped: creeps back at rate m g d / c, far slower than it would swing
    i_axis, mgd = pendulum_constants()
    rate = swing_rate(res)
    assert np.all(np.abs(rate) < 0.5 * mgd / damping * 1.01)
    assert res.diagnostics["constraint_drift"] < 1e-14


def test_precision_measures_against_the_closed_form_on_a_top():
    report = precision(parse(top(Q_TOP, W_TOP, 1.0)), integrators=["dop853"])
    assert report.reference["kind"] == "exact"
    errors = [r.error for r in report.runs]
    assert min(errors) < 1e-10
    hinge = precision(parse(pendulum(0.5, 1.0)), integrators=["rk4"])
    assert hinge.reference["kind"] == "run"


def test_trajectory_files_carry_the_reaction_columns(tmp_path):
    from massprops.dynamics.trajectory import write_trajectory

    res = simulate(parse(pendulum(0.5, 0.2)), every=0.1)
    write_trajectory(res.trajectory, tmp_path / "t.csv")
    header = (tmp_path / "t.csv").read_text().splitlines()[0].split(",")
    assert header[-12:] == ["j0_fx [N]", "j0_fy [N]", "j0_fz [N]", "j0_fx_body [N]",
                            "j0_fy_body [N]", "j0_fz_body [N]", "j0_tx [N*m]", "j0_ty [N*m]",
                            "j0_tz [N*m]", "j0_tx_body [N*m]", "j0_ty_body [N*m]",
                            "j0_tz_body [N*m]"]
    table = np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=1)
    assert np.array_equal(table[:, -12:-9], res.trajectory.joints[0].force_world)
    write_trajectory(res.trajectory, tmp_path / "t.npz")
    with np.load(tmp_path / "t.npz") as npz:
        assert np.array_equal(npz["joint0_torque_world"], res.trajectory.joints[0].torque_world)


@pytest.mark.parametrize(("case", "angle", "w_body"), [
    ("released upright with a push: through the top", 0.0, [0.7, 0.2, 20.0]),
    ("a spherical pendulum in a plane: through the bottom", 2.5, [0.0, 0.0, 0.0]),
    ("hanging straight down, pushed sideways", math.pi, [1.0, 0.0, 0.0]),
    ("tilted 1e-3 rad: passes 2e-5 rad from the top", 1e-3, [0.3, 0.0, 20.0]),
    ("steady precession at 60°", None, None),
], ids=["top", "plane", "bottom", "near-top", "steady"])
@pytest.mark.slow
def test_the_closed_form_through_and_near_the_poles(case, angle, w_body):
    """The branches of the half-angle form (a pole passed exactly, a turning point a hair from
    one, a double root) against Euler's equations about the pivot in scipy."""
    axis = R_TILT[:, 2]  # the body's symmetry axis (body coordinates)
    if angle is None:  # A Ω² cos θ - C ω3 Ω + m g l = 0, the slow root
        theta, spin = 1.0, 60.0
        j_p = parallel_axis(J_TOP, M_TOP, TIP)
        a_mom = float(R_TILT[:, 0] @ j_p @ R_TILT[:, 0])
        c_mom = float(axis @ j_p @ axis)
        mgl = M_TOP * G * L_TOP
        omega = (c_mom * spin - math.sqrt((c_mom * spin) ** 2 - 4 * a_mom * math.cos(theta)
                                          * mgl)) / (2 * a_mom * math.cos(theta))
    else:
        theta = angle
    # the axis turned theta from the vertical about world x, body x-y free
    upright = _quats(np.column_stack([R_TILT[:, 0], R_TILT[:, 1], axis]).T)  # axis -> z
    q0 = quat_multiply_np(quat_from_axis_angle([1.0, 0.0, 0.0], theta), upright)
    a0 = quat_to_matrix(q0)
    if angle is None:
        w_world = (spin - omega * math.cos(theta)) * (a0 @ axis) + omega * np.array([0, 0, 1.0])
        w0 = a0.T @ w_world
    else:
        w0 = R_TILT @ np.asarray(w_body)  # given in the axis' own frame
    res = simulate(parse(top(q0, w0, 2.0, integrator="exact", every=0.02)))
    tr = res.trajectory
    a_ref, w_ref = euler_about_pivot(a0, w0, tr.t)
    assert np.max(orientation_error(a_ref, tr.orientation)) < 5e-11, case
    assert np.max(np.abs(tr.angular_velocity_body - w_ref)) < 5e-11 * max(
        1.0, float(np.linalg.norm(w0))), case


def quat_multiply_np(p, q):
    from massprops.rotation import quat_multiply

    return quat_multiply(p, q)


def test_a_hinge_drive_and_damper_follow_their_closed_forms():
    """No gravity: I θ̈ = τ - c θ̇ on the hinge axis, τ on for 0.5 <= t < 1.5 s. With c = 0:
    θ̇ = τ (t - 0.5)/I inside the window, constant after; with c: θ̇ relaxes to τ/c at rate c/I
    and decays after."""
    i_axis = pendulum_constants()[0]
    tau = 0.8
    for damping in (0.0, 0.3):
        text = pendulum(0.0, 2.0).replace("forces:\n  - {type: gravity, g: [0, 0, -9.81]}\n",
                                          "").replace(
            "world_axis: ", f"torque: {tau}, start: 0.5, end: 1.5, damping: {damping}, "
                            "world_axis: ")
        res = simulate(parse(text), every=0.01)
        t, rate = res.trajectory.t, swing_rate(res)
        if damping == 0.0:
            expected = tau * np.clip(t - 0.5, 0.0, 1.0) / i_axis
        else:
            k = damping / i_axis
            on = tau / damping * (1 - np.exp(-k * np.clip(t - 0.5, 0.0, 1.0)))
            expected = np.where(t < 1.5, on, on * np.exp(-k * np.clip(t - 1.5, 0.0, None)))
        assert np.max(np.abs(rate - expected)) < 1e-10 * tau / i_axis, damping
        (hinge,) = res.trajectory.joints  # the drive is applied, not a reaction
        assert np.max(np.abs(hinge.torque_world @ E_HINGE)) < 1e-14
        assert (res.diagnostics["energy_rel_drift"] is None
                and res.diagnostics["axial_angular_momentum_rel_drift"] is None)
