"""The splitting integrators (splitting, splitting4, splitting6) against independent truth.

Oracles: the composition order conditions and the local order of the same compositions on two
non-commuting matrices (scipy's expm); closed forms (uniform acceleration, constant torque about a
principal axis, exponential decay under drag); conservation laws (|H| in world and the energy of
a free body over 1e6 steps, the energy of conservative scenes over long runs); time symmetry
Ψ_-h ∘ Ψ_h = id; observed convergence order against DOP853 at rtol 1e-14 (or 1e-13).
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import body, integrate, program_for, quat_axis_angle, rotation_matrices, state
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm

from massprops.dynamics.forces import energy
from massprops.dynamics.integrators import INTEGRATORS
from massprops.dynamics.integrators._subflows import drift_work, kick_program, kick_work
from massprops.dynamics.integrators.base import STATUS, STEPS
from massprops.dynamics.integrators.splitting import (
    KAHAN_LI_S9_ORDER6,
    MCLACHLAN_S5_ORDER4,
    STRANG,
    composed_step,
)
from massprops.dynamics.model import (
    Drag,
    Gravity,
    PointForce,
    Spring,
    Torque,
)
from massprops.errors import UsageError

METHODS = {"splitting": (STRANG, 2), "splitting4": (MCLACHLAN_S5_ORDER4, 4),
           "splitting6": (KAHAN_LI_S9_ORDER6, 6)}
"""name -> (composition coefficients, nominal order)."""


# --- helpers -----------------------------------------------------------------------------------


def rotation_angle_error(q, q_ref) -> float:
    """Largest angle (rad) between the rotations of two (n, 4) quaternion arrays."""
    dots = np.abs(np.einsum("ij,ij->i", np.atleast_2d(q), np.atleast_2d(q_ref)))
    return float(np.max(2 * np.arccos(np.clip(dots, 0.0, 1.0))))


def world_momentum(moments, y_out) -> np.ndarray:
    """(n, 3) angular momentum in world, A(q) J' ω', from full-layout rows."""
    return np.einsum("nij,nj->ni", rotation_matrices(y_out[:, 6:10]),
                     np.asarray(moments) * y_out[:, 10:13])


# --- the composition coefficients ---------------------------------------------------------------
@pytest.mark.parametrize("name", METHODS)
def test_coefficients_satisfy_the_order_conditions(name):
    """Symmetric compositions of a symmetric method: palindromic, Σγ = 1, and Σγ³ = 0 (order 4),
    Σγ⁵ = 0 (order 6); HLW, Geometric Numerical Integration, §V.3."""
    gam, order = METHODS[name]
    g = np.array(gam)
    np.testing.assert_array_equal(g, g[::-1])
    assert g.sum() == pytest.approx(1.0, abs=4e-16)
    for k in range(3, order, 2):
        assert np.sum(g ** k) == pytest.approx(0.0, abs=1e-14), k


def test_kahan_li_middle_coefficient_matches_the_published_value():
    assert KAHAN_LI_S9_ORDER6[4] == pytest.approx(0.79854399093482996340, abs=4e-16)


STRANG_STEPS = {"splitting": (0.1, 0.05, 0.025), "splitting4": (0.05, 0.025, 0.0125),
                "splitting6": (0.2, 0.1, 0.05)}


@pytest.mark.parametrize("name", METHODS)
def test_local_order_on_non_commuting_matrices(name):
    """ẏ = (A + B) y split into A and B, the Strang step e^{hA/2} e^{hB} e^{hA/2} composed with
    the method's γ: the one-step error against e^{h(A+B)} is O(h^(p+1)). This checks the full
    set of order conditions (including the non-commutative ones), not only Σγ^k."""
    gam, order = METHODS[name]
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(4, 4)), rng.normal(size=(4, 4))

    def composed(h):
        m = np.eye(4)
        for g in gam:
            m = expm(0.5 * g * h * a) @ expm(g * h * b) @ expm(0.5 * g * h * a) @ m
        return m

    errors = [np.abs(composed(h) - expm(h * (a + b))).max() for h in STRANG_STEPS[name]]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert orders == pytest.approx([order + 1] * 2, abs=0.3), errors


# --- observed order of the integrators ---------------------------------------------------------
def torqued_problem(damped: bool):
    """Everything coupled: asymmetric body, gravity, a body torque, a world force off the COM, a
    spring off the COM; ``damped`` adds a damped spring with a rest length and drag."""
    forces = [Gravity(np.array([0.0, 0.0, -9.81])), Torque(np.array([0.2, -0.1, 0.3]), "body"),
              PointForce(np.array([0.5, 0.0, 0.2]), point=np.array([0.0, 0.3, 0.0])),
              Spring(np.array([0.0, 0.0, 1.0]), 6.0, point=np.array([0.2, 0.0, 0.1]))]
    if damped:
        forces += [Spring(np.array([0.5, 0.0, 0.0]), 3.0, rest_length=0.3, damping=0.5,
                          point=np.array([-0.1, 0.2, 0.0])), Drag(0.3, 0.2)]
    y0 = state((0.1, 0.0, 0.2), (0.0, 0.3, 0.0), quat_axis_angle([0, 0.6, 0.8], 0.4),
               (0.4, -0.3, 0.6))
    return program_for(forces), y0


ORDER_DURATION = 2.0
OFF_STEP = np.linspace(0.0, 1.9, 20) + 0.00137
"""Dense-output times that fall between steps for every step size used below."""


@pytest.fixture(scope="module")
def references():
    """DOP853 at rtol 1e-14 (error ~1e-13) for both problems: final state and dense output."""
    out = {}
    for damped in (False, True):
        program, y0 = torqued_problem(damped)
        y, y_out, stats, _, _ = integrate("dop853", program, y0, ORDER_DURATION, 1e-14, OFF_STEP)
        assert stats[STATUS] == 0
        out[damped] = (y, y_out)
    return out


ORDER_STEPS = {"splitting": 0.05, "splitting4": 0.1, "splitting6": 0.2}


@pytest.mark.parametrize("damped", [False, True], ids=["conservative", "damped"])
@pytest.mark.parametrize("name", METHODS)
def test_observed_order_at_steps_and_in_dense_output(name, damped, references):
    """Halving h divides the error by 2^p, within ±0.3 in p, at the end point and at off-step
    output times (partial steps: full order). With damping the kicks are implicit-midpoint
    steps, which the composition must not degrade."""
    program, y0 = torqued_problem(damped)
    ref_y, ref_out = references[damped]
    h = ORDER_STEPS[name]
    end, dense = [], []
    for i in range(3):
        y, y_out, stats, _, _ = integrate(name, program, y0, ORDER_DURATION, h / 2 ** i, OFF_STEP)
        assert stats[STATUS] == 0
        end.append(np.abs(y - ref_y).max())
        dense.append(np.abs(y_out - ref_out).max())
    for errors in (end, dense):
        orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
        assert orders == pytest.approx([METHODS[name][1]] * 2, abs=0.3), (end, dense)


@pytest.mark.parametrize("name,h", [("splitting", 0.025), ("splitting4", 0.05),
                                    ("splitting6", 0.1)], ids=list(METHODS))
def test_error_estimate_has_the_size_of_the_true_error(name, h, references):
    program, y0 = torqued_problem(False)
    y, _, _, err, _ = integrate(name, program, y0, ORDER_DURATION, h)
    true = np.abs(y - references[False][0]).max()
    assert true / 3 < err < 30 * true


# --- motions the splitting reproduces exactly ---------------------------------------------------
UNIFORM = {"gravity": ([Gravity(np.array([0.3, -0.2, -9.81]))], np.array([0.3, -0.2, -9.81])),
           "world-force": ([PointForce(np.array([1.0, 2.0, -4.0]))], np.array([0.5, 1.0, -2.0]))}
COARSE_TIMES = np.linspace(0.0, 2.9, 30) + 0.00037


@pytest.mark.parametrize("kind", UNIFORM)
@pytest.mark.parametrize("name", METHODS)
def test_uniform_acceleration_is_exact(name, kind):
    """r = r0 + v0 t + a t²/2 whatever the step: kicks and drifts are exact flows here."""
    forces, acc = UNIFORM[kind]
    r0, v0 = np.array([0.5, -1.0, 2.0]), np.array([1.0, 2.0, 3.0])
    y, y_out, _, _, _ = integrate(name, program_for(forces), state(r0, v0, w=(0.3, -0.2, 0.5)),
                               2.95, 0.1, COARSE_TIMES)
    t = COARSE_TIMES[:, None]
    np.testing.assert_allclose(y_out[:, 0:3], r0 + v0 * t + 0.5 * acc * t * t, atol=1e-12)
    np.testing.assert_allclose(y_out[:, 3:6], v0 + acc * t, atol=1e-12)
    np.testing.assert_allclose(y[0:3], r0 + v0 * 2.95 + 0.5 * acc * 2.95 ** 2, atol=1e-12)


@pytest.mark.parametrize("rot_only", [False, True], ids=["full", "rotation-only"])
@pytest.mark.parametrize("axis", [0, 1, 2], ids=["axis1", "axis2", "axis3"])
@pytest.mark.parametrize("name", METHODS)
def test_constant_torque_about_a_principal_axis_is_exact(name, axis, rot_only):
    """From rest: ω = τ t / I about the axis and the angle τ t² / (2 I), at any step (the
    velocity-Verlet structure integrates a constant angular acceleration exactly)."""
    moments, tau = np.array([1.0, 2.0, 3.0]), 0.6
    vector = np.zeros(3)
    vector[axis] = tau
    program = program_for([Torque(vector, frame="body")])
    y0 = state()[6:] if rot_only else state()
    _, y_out, _, _, _ = integrate(name, program, y0, 2.95, 0.1, COARSE_TIMES, rot_only=rot_only)
    o = 0 if rot_only else 6
    t = COARSE_TIMES
    w_exact = np.zeros((t.size, 3))
    w_exact[:, axis] = tau / moments[axis] * t
    q_exact = np.array([quat_axis_angle(np.eye(3)[axis], tau * ti * ti / (2 * moments[axis]))
                        for ti in t])
    np.testing.assert_allclose(y_out[:, o + 4:o + 7], w_exact, atol=1e-13)
    assert rotation_angle_error(y_out[:, o:o + 4], q_exact) < 1e-7  # arccos: ~sqrt(eps)


@pytest.mark.slow
@pytest.mark.parametrize("moments", [(1.0, 2.0, 3.0), (1.0, 1.0, 3.0)],
                         ids=["asymmetric", "symmetric"])
def test_a_million_torque_free_steps_keep_the_invariants_at_round_off(moments):
    """With no force term a step is the exact free flow: over 1e6 steps (1000 s, ~1300 rad
    turned) |H| and the energy move by round-off only (a random walk of ~1e-16 per step gives
    ~1e-13; a bias of 0.1 ulp per step, which the drift once had, gives ~1e-11), |q| = 1 to the
    last ulps (re-normalised only once it wanders, exact.QUATERNION_RENORM). The direction of H
    in the world follows the orientation: ~2e-13 after 1e6 steps (1.3e-12 when every step was
    re-normalised, which tilted the axis consistently)."""
    program = program_for([], body(moments))
    t_out = np.linspace(0.0, 1000.0, 11) + 0.00037  # between steps: partial steps
    t_out[0], t_out[-1] = 0.0, 1000.0
    y0 = state(q=quat_axis_angle([0.6, 0, 0.8], 0.7), w=(0.5, 1.2, -0.7))
    _, y_out, stats, _, _ = integrate("splitting", program, y0, 1000.0, 1e-3, t_out)
    assert stats[STEPS] == 1_000_000 and stats[STATUS] == 0
    h_world = world_momentum(program.inertia, y_out)
    h_norm = np.linalg.norm(h_world, axis=1)
    assert np.abs(h_norm / h_norm[0] - 1).max() < 1e-12
    assert np.abs(h_world - h_world[0]).max() < 1e-12 * h_norm[0]
    kinetic = 0.5 * np.einsum("ni,i,ni->n", y_out[:, 10:13], program.inertia, y_out[:, 10:13])
    assert np.abs(kinetic / kinetic[0] - 1).max() < 1e-12
    assert np.abs(np.linalg.norm(y_out[:, 6:10], axis=1) - 1).max() <= 6 * np.finfo(float).eps


@pytest.mark.slow
@pytest.mark.parametrize("name", ["splitting4", "splitting6"])
def test_compositions_with_backward_substeps_keep_a_free_rotation(name):
    """Gravity at the COM: kicks change v only, so the rotation stays free through the
    composition's backward drifts: |H| in world holds to round-off, the COM follows its
    parabola, over 5e4 steps."""
    g = np.array([0.0, 0.0, -9.81])
    program = program_for([Gravity(g)], body((1.0, 1.7, 2.2)))
    r0, v0 = np.array([0.3, 0.0, 1.0]), np.array([1.0, -0.5, 4.0])
    y0 = state(r0, v0, quat_axis_angle([1, 2, 3], 0.3), (0.9, -0.4, 0.6))
    t_out = np.array([0.0, 50.0])
    y, y_out, stats, _, _ = integrate(name, program, y0, 50.0, 1e-3, t_out)
    assert stats[STATUS] == 0
    h_world = world_momentum(program.inertia, y_out)
    assert np.linalg.norm(h_world[1] - h_world[0]) < 1e-11 * np.linalg.norm(h_world[0])
    r_exact = r0 + v0 * 50.0 + 0.5 * g * 50.0 ** 2
    np.testing.assert_allclose(y[0:3], r_exact, rtol=1e-11)


@settings(max_examples=50, deadline=None)
@given(moments=st.tuples(*[st.floats(0.1, 3.0)] * 3).map(sorted),
       w=st.tuples(*[st.floats(-3, 3)] * 3).filter(lambda w: np.linalg.norm(w) > 0.1),
       h=st.floats(1e-3, 2.0))
def test_any_free_rotation_keeps_energy_and_momentum(moments, w, h):
    if moments[2] > moments[0] + moments[1]:  # not a rigid body (triangle inequality)
        return
    program = program_for([], body(moments))
    _, y_out, _, _, _ = integrate("splitting", program, state(w=w), 20 * h, h,
                               np.array([0.0, 20 * h]))
    h_world = world_momentum(program.inertia, y_out)
    assert np.linalg.norm(h_world[1] - h_world[0]) < 1e-13 * np.linalg.norm(h_world[0])
    kinetic = 0.5 * np.einsum("ni,i,ni->n", y_out[:, 10:13], program.inertia, y_out[:, 10:13])
    assert abs(kinetic[1] / kinetic[0] - 1) < 1e-13


# --- symmetry and long-run energy -------------------------------------------------------------
@settings(max_examples=50, deadline=None)
@given(name=st.sampled_from(list(METHODS)), h=st.floats(0.01, 0.2),
       w=st.tuples(*[st.floats(-2, 2)] * 3), v=st.tuples(*[st.floats(-1, 1)] * 3),
       damped=st.booleans())
def test_a_step_is_time_symmetric(name, h, w, v, damped):
    """Ψ_-h(Ψ_h(y)) = y: every sub-flow is symmetric (exact flows; implicit midpoint for the
    damped kicks) and the composition is palindromic."""
    program, _ = torqued_problem(damped)
    y0 = state((0.1, 0.0, 0.2), v, quat_axis_angle([0, 0.6, 0.8], 0.4), w)
    kp = kick_program(program.active(0.0), program.codes, program.params, program.mass,
                      program.inertia, 6)
    gam = np.array(METHODS[name][0])
    y = y0.copy()
    composed_step(y, h, gam, kp, kick_work(13), drift_work())
    composed_step(y, -h, gam, kp, kick_work(13), drift_work())
    np.testing.assert_allclose(y, y0, atol=1e-12)


def conservative_scene():
    forces = [Gravity(np.array([0.0, 0.0, -9.81])),
              Spring(np.array([0.0, 0.0, 1.0]), 4.0, rest_length=0.2,
                     point=np.array([0.3, 0.1, 0.0]))]
    y0 = state((0.2, 0.0, 0.5), (0.0, 0.3, 0.0), quat_axis_angle([0, 0.6, 0.8], 0.4),
               (0.4, -0.3, 0.6))
    return program_for(forces, body((1.0, 2.0, 3.0))), y0


def energy_error_windows(name, step=0.02, duration=1000.0):
    """max |E - E0| over the first and over the last tenth of a long run, and max |E/E0 - 1|."""
    program, y0 = conservative_scene()
    t_out = np.arange(0.0, duration + 0.5, 0.5) + 0.0037
    t_out[0], t_out[-1] = 0.0, duration
    _, y_out, stats, _, _ = integrate(name, program, y0, duration, step, t_out)
    assert stats[STATUS] == 0
    e = energy(y_out, program)
    de = np.abs(e - e[0])
    tenth = de.size // 10
    return de[:tenth].max(), de[-tenth:].max(), de.max() / abs(e[0])


@pytest.mark.slow
@pytest.mark.parametrize("name,bound", [("splitting", 3e-3), ("splitting4", 3e-7),
                                        ("splitting6", 3e-10)], ids=list(METHODS))
def test_energy_error_is_bounded_without_drift(name, bound):
    """Gravity and an undamped spring off the COM (conservative, not integrable), 5e4 steps:
    the method is symplectic, so the energy error oscillates; it does not grow."""
    first, last, worst = energy_error_windows(name)
    assert last < 2 * first
    assert worst < bound


def test_energy_window_comparison_detects_a_drift():
    """Control: RK4 (not symplectic) drifts on the same scene, and the comparison sees it."""
    first, last, _ = energy_error_windows("rk4")
    assert last > 3 * first


# --- fast spin: where the exact drift pays -------------------------------------------------------
FAST = {
    "needle": ((1e-6, 1.0, 1.0), (1e3, 0.3, 0.1)),  # spinning about its axis (I1 = 1e-6)
    "disk": ((1.0, 1.0, 2.0), (0.3, 0.1, 1e3)),  # flat disk spinning about its symmetry axis
}


def fast_spin_scene(kind):
    """1 kg, 1e3 rad/s, a spring at a point 0.5 m off the COM and gravity (conservative)."""
    moments, w = FAST[kind]
    forces = [Spring(np.zeros(3), 2.0, point=np.array([0.5, 0.0, 0.0])),
              Gravity(np.array([0.0, 0.0, -9.81]))]
    return program_for(forces, body(moments, mass=1.0)), state(r=(0.1, 0.0, 0.0), w=w)


@pytest.mark.parametrize("kind", FAST)
def test_fast_spin_at_a_coarse_step(kind):
    """h = 1e-3 at 1e3 rad/s turns the body by 1 rad per step. RK4 there is off by tenths of
    a radian after 1 s (it needs h ~ 1e-5); the splitting, whose drift is exact, is accurate to
    ~1e-6 and stays bounded over 10 s (energy)."""
    program, y0 = fast_spin_scene(kind)
    ref, _, stats, _, _ = integrate("dop853", program, y0, 1.0, 1e-13)
    assert stats[STATUS] == 0
    rk4, _, stats_rk4, _, _ = integrate("rk4", program, y0, 1.0, 1e-3)
    assert stats_rk4[STATUS] == 1 or rotation_angle_error(rk4[6:10], ref[6:10]) > 0.05
    y, _, stats, _, _ = integrate("splitting", program, y0, 1.0, 1e-3)
    assert stats[STATUS] == 0
    assert rotation_angle_error(y[6:10], ref[6:10]) < 1e-5
    assert np.abs(y[10:13] - ref[10:13]).max() < 1e-6 * np.linalg.norm(ref[10:13])
    assert np.abs(y[0:6] - ref[0:6]).max() < 1e-3
    t_out = np.linspace(0.0, 10.0, 101)
    _, y_out, stats, _, _ = integrate("splitting", program, y0, 10.0, 1e-3, t_out)
    e = energy(y_out, program)
    assert stats[STATUS] == 0 and np.abs(e / e[0] - 1).max() < 1e-4


# --- damping -----------------------------------------------------------------------------------
def test_strong_drag_decays_at_any_step():
    """Drag rate c/m = 1e4 /s at h = 1e-2 (h·rate = 100): the implicit-midpoint kicks never
    amplify, so the speed decays step by step, where RK4 (limit h·rate < 2.8) blows up."""
    program = program_for([Drag(2e4, 3e4)], body(mass=2.0))
    y0 = state(v=(1.0, -2.0, 0.5), w=(0.5, 1.0, -0.3))
    t_out = np.linspace(0.0, 1.0, 101)
    _, y_out, stats, _, _ = integrate("splitting", program, y0, 1.0, 1e-2, t_out)
    assert stats[STATUS] == 0 and np.isfinite(y_out).all()
    speed = np.linalg.norm(y_out[:, 3:6], axis=1)
    assert np.all(np.diff(speed) <= 0) and speed[-1] < speed[0]
    _, _, stats_rk4, _, _ = integrate("rk4", program, y0, 1.0, 1e-2)
    assert stats_rk4[STATUS] == 1


@pytest.mark.parametrize("name,tol", [("splitting", 1e-5), ("splitting4", 1e-9),
                                      ("splitting6", 1e-11)], ids=list(METHODS))
def test_drag_matches_its_closed_form(name, tol):
    """Spin about a principal axis with linear and angular drag: v = v0 e^(-ct/m),
    ω = ω0 e^(-c't/I), turned angle ω0 I/c' (1 - e^(-c't/I)), r likewise."""
    c, c_ang, mass, moments = 0.8, 0.5, 2.0, np.array([1.0, 2.0, 3.0])
    program = program_for([Drag(c, c_ang)], body(moments, mass))
    v0, w0 = np.array([1.0, -2.0, 0.5]), 1.5
    t = np.array([0.0, 0.7137, 2.0])
    _, y_out, stats, _, _ = integrate(name, program, state(v=v0, w=(0.0, w0, 0.0)), 2.0, 0.01, t)
    decay_v, decay_w = np.exp(-c * t / mass), np.exp(-c_ang * t / moments[1])
    np.testing.assert_allclose(y_out[:, 3:6], v0 * decay_v[:, None], atol=tol)
    np.testing.assert_allclose(y_out[:, 0:3], v0 * (mass / c) * (1 - decay_v)[:, None],
                               atol=tol)
    np.testing.assert_allclose(y_out[:, 11], w0 * decay_w, atol=tol)
    angle = w0 * moments[1] / c_ang * (1 - decay_w)
    q_exact = np.array([quat_axis_angle([0, 1, 0], a) for a in angle])
    assert rotation_angle_error(y_out[:, 6:10], q_exact) < max(tol, 1e-7)


# --- arguments ---------------------------------------------------------------------------------
@pytest.mark.parametrize("name", METHODS)
def test_moments_out_of_order_are_refused(name):
    program, y0 = torqued_problem(False)
    arrays = (program.active(0.0), program.codes, program.params, program.mass,
              np.array([2.0, 1.0, 3.0]))
    with pytest.raises(UsageError, match=f"integrator {name}: expected the principal moments"):
        INTEGRATORS[name].run_segment(y0.copy(), 0.0, 1.0, 0.1, arrays, False, np.empty(0),
                                      np.empty((0, 13)), np.zeros(5, dtype=np.int64))


@pytest.mark.parametrize("name", METHODS)
def test_registered_as_fixed_step_with_its_order(name):
    spec = INTEGRATORS[name]
    assert spec.kind == "fixed" and spec.order == METHODS[name][1] and not spec.stiff
