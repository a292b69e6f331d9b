"""The integrator family against independent truth: closed-form motions, published tableau
conditions, observed convergence order, conservation laws, stability theory for stiff scenes.

The time-stepping methods run on the systems engine's step loop (conftest.integrate: the one body
as the system of one body, as simulate runs it); the one-body kernels (splitting, exact) are
called through their ``run_segment`` contract."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import (
    body,
    integrate,
    program_for,
    quat_axis_angle,
    rotation_matrices,
    scene_of,
    state,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from massprops.dynamics.forces import energy
from massprops.dynamics.integrators import (
    INTEGRATORS,
    SYSTEM_METHODS,
    IntegratorSpec,
    register,
)
from massprops.dynamics.integrators import _dop853_tableau as dop
from massprops.dynamics.integrators.base import KINDS, STATUS, STEPS
from massprops.dynamics.integrators.stepped import RADAU_A
from massprops.dynamics.model import (
    Gravity,
    PointForce,
    Spring,
    Torque,
)
from massprops.errors import UsageError

ACCURATE = {"rk4": 1e-3, "dop853": 1e-10, "implicit": 1e-2, "midpoint": 1e-3}
"""A setting per method at which each resolves the smooth test motions well."""
TOLERANCE = {"rk4": 1e-9, "dop853": 1e-8, "implicit": 1e-8, "midpoint": 2e-5}
"""What each method reaches at that setting on those motions (relative to their scale)."""
FIXED = [name for name in ACCURATE if INTEGRATORS[name].kind == "fixed"]
COARSE = 0.1
"""A coarse step (s) or tolerance (rtol): motions polynomial in t are exact whatever it is."""


# --- helpers: scenes, states and a segment walker like the simulate module's -------------------


def same_rotation_error(q, q_exact) -> np.ndarray:
    """Distance between rotations (q and -q are the same rotation)."""
    return np.minimum(np.abs(q - q_exact).max(axis=-1), np.abs(q + q_exact).max(axis=-1))


STEPPING = sorted(n for n, spec in INTEGRATORS.items()
                  if spec.kind != "exact" and n not in SYSTEM_METHODS)
"""The one-body kernels' contract tests below use a torqued problem; ``exact`` has its own test
(torque-free); the time-stepping methods have no one-body kernel."""

OFF_STEP = np.linspace(0.0, 2.9, 59) + 0.00037  # sample times that fall between steps


# --- the registry ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(INTEGRATORS))
def test_registry_entry_is_complete(name):
    spec = INTEGRATORS[name]
    assert spec.name == name
    assert spec.kind in KINDS
    assert isinstance(spec.order, int)
    assert spec.order >= 1 if spec.kind != "exact" else spec.order == 0  # 0: no truncation
    assert spec.description and "\n" not in spec.description and len(spec.description) < 100
    # a time-stepping method is the systems engine's (its records carry no kernel); the others
    # are one body's own, each with its kernel
    assert (spec.run_segment is None) == (name in SYSTEM_METHODS)
    assert (spec.tableau is not None) == (name in SYSTEM_METHODS)


def test_register_refuses_a_taken_name():
    with pytest.raises(ValueError, match="already registered"):
        register(IntegratorSpec("rk4", "fixed", 4, "again"))


def test_spec_refuses_an_unknown_kind():
    with pytest.raises(ValueError, match="kind"):
        IntegratorSpec("x", "variable", 4, "x")


# --- the published tableaus ----------------------------------------------------------------------
def test_dop853_tableau_is_consistent():
    """Row sums equal the abscissae; b integrates polynomials of degree <= 7 exactly (order 8
    quadrature); the embedded solutions are consistent (error weights sum to 0)."""
    np.testing.assert_allclose(dop.A.sum(axis=1), dop.C, atol=1e-14)
    for k in range(1, 9):
        assert dop.B @ dop.C[:12] ** (k - 1) == pytest.approx(1.0 / k, abs=1e-14)
    assert dop.ER.sum() == pytest.approx(0.0, abs=1e-14)
    assert dop.BHH.sum() == pytest.approx(1.0, abs=1e-14)
    assert dop.BHH @ dop.C[:12] == pytest.approx(0.5, abs=1e-14)  # the 3rd-order one: degree 1


def test_radau_tableau_satisfies_the_collocation_conditions():
    """The nodes are (4 ∓ √6)/10 and 1 (the published ones); C(3): Σ_j a_ij c_j^(k-1) =
    c_i^k / k; B(5): Σ_j b_j c_j^(k-1) = 1/k (order 5)."""
    a = np.array(RADAU_A)
    c = np.array([(4 - math.sqrt(6)) / 10, (4 + math.sqrt(6)) / 10, 1.0])
    for k in range(1, 4):
        np.testing.assert_allclose(a @ c ** (k - 1), c ** k / k, atol=1e-15)
    for k in range(1, 6):
        assert a[2] @ c ** (k - 1) == pytest.approx(1.0 / k, abs=1e-15)


def radau_r(z: complex) -> complex:
    """The Radau IIA stability function from its tableau: 1 + z bᵀ (I - zA)⁻¹ 1."""
    a = np.array(RADAU_A, dtype=complex)
    return 1 + z * a[2] @ np.linalg.solve(np.eye(3) - z * a, np.ones(3))


@pytest.mark.parametrize("z", [10j, -1e3, 100j + -5, 1e6j], ids=["10i", "-1e3", "-5+100i", "1e6i"])
def test_radau_stability_function_matches_closed_form(z):
    closed = (1 + 2 * z / 5 + z * z / 20) / (1 - 3 * z / 5 + 3 * z * z / 20 - z ** 3 / 60)
    assert radau_r(z) == pytest.approx(closed, rel=1e-9, abs=1e-15)
    assert abs(radau_r(z)) < 1


# --- exact solutions -----------------------------------------------------------------------------
UNIFORM = {
    "gravity": ([Gravity(np.array([0.3, -0.2, -9.81]))], np.array([0.3, -0.2, -9.81])),
    "world-force": ([PointForce(np.array([1.0, 2.0, -4.0]))], np.array([0.5, 1.0, -2.0])),
    "body-force": ([PointForce(np.array([1.0, 2.0, -4.0]), frame="body")],
                   np.array([0.5, 1.0, -2.0])),
}


@pytest.mark.parametrize("name", ACCURATE)
@pytest.mark.parametrize("kind", UNIFORM)
def test_uniform_acceleration_is_exact(name, kind):
    """r = r0 + v0 t + a t²/2: a polynomial every method here integrates exactly, dense output
    included (body force on a body that does not turn = constant in world)."""
    forces, acc = UNIFORM[kind]
    r0, v0 = np.array([0.5, -1.0, 2.0]), np.array([1.0, 2.0, 3.0])
    duration = 2.95
    run = integrate(name, program_for(forces), state(r0, v0), duration, COARSE,
                    OFF_STEP)
    t = OFF_STEP[:, None]
    np.testing.assert_allclose(run.y_out[:, 0:3], r0 + v0 * t + 0.5 * acc * t * t, atol=1e-12)
    np.testing.assert_allclose(run.y_out[:, 3:6], v0 + acc * t, atol=1e-12)
    np.testing.assert_allclose(run.y[0:3], r0 + v0 * duration + 0.5 * acc * duration ** 2,
                               atol=1e-12)
    assert run.t_reached == duration and run.stats[STATUS] == 0


def oscillator(t, x0, v0, omega, zeta):
    """Closed form of x'' + 2ζω x' + ω² x = 0 (under-damped, ζ < 1), x and x'."""
    wd = omega * math.sqrt(1 - zeta * zeta)
    a, b = x0, (v0 + zeta * omega * x0) / wd
    decay = np.exp(-zeta * omega * t)
    c, s = np.cos(wd * t), np.sin(wd * t)
    x = decay * (a * c + b * s)
    v = decay * ((b * wd - zeta * omega * a) * c - (a * wd + zeta * omega * b) * s)
    return x, v


@pytest.mark.parametrize("name", ACCURATE)
@pytest.mark.parametrize("zeta", [0.0, 0.1], ids=["undamped", "damped"])
def test_harmonic_oscillator_matches_closed_form(name, zeta):
    """Spring of rest length 0 at the COM: each axis is x'' + (c/m) x' + (k/m) x = 0."""
    mass, omega = 2.0, 3.0
    k, c = mass * omega ** 2, 2 * zeta * omega * mass
    anchor = np.array([0.5, -0.2, 0.1])
    d0, v0 = np.array([0.3, 0.1, -0.2]), np.array([0.1, 0.4, 0.0])
    program = program_for([Spring(anchor, k, damping=c)], body(mass=mass))
    run = integrate(name, program, state(anchor + d0, v0), 2.95, ACCURATE[name], OFF_STEP)
    x, v = oscillator(OFF_STEP[:, None], d0, v0, omega, zeta)
    tol = TOLERANCE[name]
    assert np.abs(run.y_out[:, 0:3] - anchor - x).max() < tol
    assert np.abs(run.y_out[:, 3:6] - v).max() < omega * tol
    x_end, v_end = oscillator(2.95, d0, v0, omega, zeta)
    assert np.abs(run.y[0:3] - anchor - x_end).max() < tol
    assert np.abs(run.y[3:6] - v_end).max() < omega * tol


@pytest.mark.parametrize("name", ACCURATE)
@pytest.mark.parametrize("axis", [0, 1, 2], ids=["axis1", "axis2", "axis3"])
@pytest.mark.parametrize("rot_only", [False, True], ids=["full", "rotation-only"])
def test_constant_torque_about_a_principal_axis(name, axis, rot_only):
    """From rest: ω = τ/I t about the axis, turned angle τ t² / (2 I)."""
    moments, tau = np.array([1.0, 2.0, 3.0]), 0.6
    vector = np.zeros(3)
    vector[axis] = tau
    program = program_for([Torque(vector, frame="body")])
    y0 = state()[6:] if rot_only else state()
    t = OFF_STEP
    run = integrate(name, program, y0, 2.95, ACCURATE[name], t, rot_only=rot_only)
    o = 0 if rot_only else 6
    w_exact = np.zeros((t.size, 3))
    w_exact[:, axis] = tau / moments[axis] * t
    e_axis = np.eye(3)[axis]
    q_exact = np.array([quat_axis_angle(e_axis, tau * ti * ti / (2 * moments[axis])) for ti in t])
    assert np.abs(run.y_out[:, o + 4:o + 7] - w_exact).max() < TOLERANCE[name]
    assert same_rotation_error(run.y_out[:, o:o + 4], q_exact).max() < TOLERANCE[name]


@pytest.mark.parametrize("name", ACCURATE)
def test_torque_free_symmetric_top(name):
    """I1 = I2: ω3 constant and (ω1, ω2) turns at Ω = (I3 - I1)/I1 ω3 in the body; the angular
    momentum is constant in world."""
    moments = np.array([1.0, 1.0, 2.5])
    w0 = np.array([0.3, -0.4, 2.0])
    program = program_for([], body(moments))
    run = integrate(name, program, state(q=quat_axis_angle([0.6, 0, 0.8], 0.7), w=w0), 2.95,
                    ACCURATE[name], OFF_STEP)
    big_omega = (moments[2] - moments[0]) / moments[0] * w0[2]
    turn = (w0[0] + 1j * w0[1]) * np.exp(1j * big_omega * OFF_STEP)
    w = run.y_out[:, 10:13]
    tol = TOLERANCE[name] * 10
    assert np.abs(w[:, 0] - turn.real).max() < tol
    assert np.abs(w[:, 1] - turn.imag).max() < tol
    assert np.abs(w[:, 2] - w0[2]).max() < tol
    h_world = np.einsum("nij,nj->ni", rotation_matrices(run.y_out[:, 6:10]), moments * w)
    assert np.abs(h_world - h_world[0]).max() < tol


# --- convergence order ---------------------------------------------------------------------------
def torqued_problem():
    """A smooth problem that couples everything: asymmetric body, gravity, a body torque, a
    world force off the COM, a spring off the COM."""
    forces = [Gravity(np.array([0.0, 0.0, -9.81])), Torque(np.array([0.2, -0.1, 0.3]), "body"),
              PointForce(np.array([0.5, 0.0, 0.2]), point=np.array([0.0, 0.3, 0.0])),
              Spring(np.array([0.0, 0.0, 1.0]), 6.0, point=np.array([0.2, 0.0, 0.1]))]
    y0 = state((0.1, 0.0, 0.2), (0.0, 0.3, 0.0), quat_axis_angle([0, 0.6, 0.8], 0.4),
               (0.4, -0.3, 0.6))
    return program_for(forces), y0


@pytest.fixture(scope="module")
def torqued_reference():
    program, y0 = torqued_problem()
    ref = integrate("dop853", program, y0, 2.0, 1e-14)
    assert ref.stats[STATUS] == 0
    return ref.y


ORDER_STEPS = {"rk4": 0.1, "implicit": 0.2, "midpoint": 0.05}


@pytest.mark.parametrize("name", FIXED)
def test_observed_order_of_fixed_step_methods(name, torqued_reference):
    program, y0 = torqued_problem()
    h = ORDER_STEPS[name]
    errors = [np.abs(integrate(name, program, y0, 2.0, h / 2 ** i).y - torqued_reference).max()
              for i in range(3)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert orders == pytest.approx([INTEGRATORS[name].order] * 2, abs=0.3), errors


# --- dop853: tolerance, dense output, conservation ----------------------------------------------
def test_dop853_error_follows_rtol():
    omega = 3.0
    program = program_for([Spring(np.zeros(3), omega ** 2)], body(mass=1.0))
    y0 = state((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    errors = []
    for rtol in (1e-5, 1e-7, 1e-9, 1e-11):
        run = integrate("dop853", program, y0, 10.0, rtol)
        exact = np.array([math.cos(omega * 10), math.sin(omega * 10) / omega])
        errors.append(np.abs(run.y[0:2] - exact).max())
        assert errors[-1] < 100 * rtol
    assert all(a > b for a, b in zip(errors, errors[1:]))


@pytest.mark.parametrize("rtol", [1e-6, 1e-9], ids=["1e-6", "1e-9"])
def test_dop853_dense_output_between_steps(rtol):
    omega = 3.0
    program = program_for([Spring(np.zeros(3), omega ** 2)], body(mass=1.0))
    t = np.sort(np.random.default_rng(1).uniform(0, 10, 500))
    run = integrate("dop853", program, state((1.0, 0, 0), (0, 1.0, 0)), 10.0, rtol, t)
    assert run.stats[STEPS] < 200  # far fewer steps than outputs: the values are interpolated
    assert np.abs(run.y_out[:, 0] - np.cos(omega * t)).max() < 100 * rtol
    assert np.abs(run.y_out[:, 1] - np.sin(omega * t) / omega).max() < 100 * rtol


def torque_free_invariants(program, y_out):
    moments = program.inertia
    w = y_out[:, 10:13]
    h_world = np.einsum("nij,nj->ni", rotation_matrices(y_out[:, 6:10]), moments * w)
    return 0.5 * np.einsum("ni,i,ni->n", w, moments, w), h_world


@pytest.mark.parametrize("name,setting,tol", [("dop853", 1e-12, 1e-10), ("midpoint", 0.02, 1e-10),
                                              ("implicit", 0.01, 1e-8)],
                         ids=["dop853", "midpoint", "implicit"])
def test_torque_free_asymmetric_body_conserves_energy_and_momentum(name, setting, tol):
    """Energy and the world angular momentum of a torque-free body are constant; the implicit
    midpoint rule keeps the energy exactly (a quadratic invariant) even with a coarse step."""
    program = program_for([], body((1.0, 2.0, 3.0)))
    t = np.linspace(0, 20, 201)
    run = integrate(name, program, state(w=(0.5, 0.2, -0.7)), 20.0, setting, t)
    e, h = torque_free_invariants(program, run.y_out)
    assert np.abs(e / e[0] - 1).max() < tol
    assert np.abs(h - h[0]).max() / np.linalg.norm(h[0]) < (1e-10 if name == "dop853" else 1e-3)


@settings(max_examples=20, deadline=None)
@given(w=st.tuples(*[st.floats(-2, 2)] * 3).filter(lambda w: np.linalg.norm(w) > 0.1))
def test_dop853_conserves_the_invariants_of_any_free_rotation(w):
    program = program_for([], body((1.0, 1.7, 2.2)))
    run = integrate("dop853", program, state(w=w), 5.0, 1e-11, np.array([0.0, 5.0]))
    e, h = torque_free_invariants(program, run.y_out)
    assert abs(e[1] / e[0] - 1) < 1e-9
    assert np.linalg.norm(h[1] - h[0]) < 1e-9 * np.linalg.norm(h[0])


# --- stiff scenes --------------------------------------------------------------------------------
STIFF_K, STIFF_STEP = 1e8, 1e-3


def stiff_spring():
    """k = 1e8 N/m on 1 kg at the COM (ω = 1e4 rad/s), displaced 1 cm, the body spinning."""
    program = program_for([Spring(np.zeros(3), STIFF_K)], body(mass=1.0))
    return program, state((0.01, 0.0, 0.0), w=(0.1, 0.2, 0.3))


def test_the_stiff_step_is_beyond_the_explicit_limit():
    """RK4 is stable on the imaginary axis up to |hω| = 2√2: h = 1e-3 is 3.5 times that."""
    limit = 2 * math.sqrt(2) / math.sqrt(STIFF_K)
    assert limit == pytest.approx(2.83e-4, rel=1e-3)
    assert STIFF_STEP > 3 * limit


def test_implicit_damps_the_stiff_mode_and_keeps_the_spin():
    program, y0 = stiff_spring()
    t = np.linspace(0, 1, 1001)  # every step
    run = integrate("implicit", program, y0, 1.0, STIFF_STEP, t)
    assert run.stats[STATUS] == 0 and np.isfinite(run.y_out).all()
    e = energy(run.y_out, program)
    assert np.all(np.diff(e) <= 1e-12 * e[0])  # non-increasing
    z = 1j * math.sqrt(STIFF_K) * STIFF_STEP  # one step scales the mode's energy by |R(z)|²
    spring_energy = e - e[-1]
    assert spring_energy[1] / spring_energy[0] == pytest.approx(abs(radau_r(z)) ** 2, rel=1e-3)
    assert spring_energy[-1] < 1e-9 * spring_energy[0]
    free = integrate("dop853", program_for([], body(mass=1.0)), y0, 1.0, 1e-12)
    np.testing.assert_allclose(run.y[6:13], free.y[6:13], atol=1e-11)  # the slow spin is kept


def test_midpoint_keeps_the_stiff_mode_energy():
    program, y0 = stiff_spring()
    t = np.linspace(0, 1, 101)
    run = integrate("midpoint", program, y0, 1.0, STIFF_STEP, t)
    assert run.stats[STATUS] == 0
    e = energy(run.y_out, program)
    assert np.abs(e / e[0] - 1).max() < 1e-9


def test_rk4_beyond_its_limit_reports_nonfinite():
    program, y0 = stiff_spring()
    t = np.linspace(0, 1, 11)
    run = integrate("rk4", program, y0, 1.0, STIFF_STEP, t)
    assert run.stats[STATUS] == 1
    assert 0 < run.t_reached < 1.0
    assert np.isfinite(run.y).all()  # the last finite state
    assert np.isnan(run.y_out[t > run.t_reached]).all()


def test_implicit_follows_the_slow_mode_of_a_strong_damper():
    """k = 1e4, c = 1e6 on 1 kg (overdamped): x = A e^(λ1 t) + B e^(λ2 t), the fast mode
    (λ2 ~ -1e6/s) 1000 times beyond the step."""
    k, c = 1e4, 1e6
    program = program_for([Spring(np.zeros(3), k, damping=c)], body(mass=1.0))
    disc = math.sqrt(c * c - 4 * k)
    lam1, lam2 = (-c + disc) / 2, (-c - disc) / 2
    x0, v0 = 0.2, 0.0
    b = (v0 - lam1 * x0) / (lam2 - lam1)
    a = x0 - b
    t = np.linspace(0.01, 3, 300)
    run = integrate("implicit", program, state((x0, 0, 0), (v0, 0, 0)), 3.0, 1e-3, t)
    exact = a * np.exp(lam1 * t) + b * np.exp(lam2 * t)
    assert run.stats[STATUS] == 0
    assert np.abs(run.y_out[:, 0] - exact).max() < 1e-9 * x0


# --- segments and windows ------------------------------------------------------------------------
@pytest.mark.parametrize("name", ACCURATE)
def test_a_window_shorter_than_the_step_is_resolved(name):
    """A 0.04 s push inside a 0.1 s step gives exactly Δv = F Δt / m (piecewise closed form)."""
    force = np.array([2.0, 0.0, -1.0])
    program = program_for([PointForce(force, start=0.33, end=0.37)])
    v0 = np.array([0.1, 0.2, 0.0])
    run = integrate(name, program, state(v=v0), 1.0, COARSE)
    dv = force * 0.04 / 2.0
    np.testing.assert_allclose(run.y[3:6], v0 + dv, atol=1e-13)
    # r(1) = v0·1 + Δv·(1 - 0.37) + Δv/2·0.04 (uniform acceleration during the push)
    np.testing.assert_allclose(run.y[0:3], v0 + dv * 0.63 + 0.5 * dv * 0.04, atol=1e-13)


@pytest.mark.parametrize("name", [*ACCURATE, "splitting"])
def test_a_run_split_at_a_step_edge_equals_one_run(name):
    """A window edge at a step edge (a force of nothing from t = 0.5 on) splits the run into two
    segments: a fixed-step method takes the very same steps, an adaptive one lands on the edge
    and agrees to its tolerance."""
    forces, y0 = torqued_problem()
    setting = 0.1 if INTEGRATORS[name].kind == "fixed" else 1e-10
    whole = integrate(name, forces, y0, 1.0, setting)
    scene = scene_of(forces)
    split = program_for([*scene.forces, PointForce(np.zeros(3), start=0.5)], scene.body)
    assert split.breakpoints(0.0, 1.0).tolist() == [0.5]
    halves = integrate(name, split, y0, 1.0, setting)
    tol = 1e-13 if INTEGRATORS[name].kind == "fixed" else 1e-8
    np.testing.assert_allclose(halves.y, whole.y, atol=tol)


# --- the contract ------------------------------------------------------------------------------
def contract_setting(spec) -> float:
    return 0.01 if spec.kind == "fixed" else 1e-8


@pytest.mark.parametrize("name", STEPPING)
def test_contract_lands_on_t1_fills_outputs_and_accumulates_stats(name):
    spec = INTEGRATORS[name]
    program, y0 = torqued_problem()
    arrays = (program.active(0.5), program.codes, program.params, program.mass, program.inertia)
    t_out = np.array([0.2, 0.2, 0.25, 0.3])
    y_out = np.full((4, 13), np.nan)
    stats = np.zeros(5, dtype=np.int64)
    stats[STEPS] = 7
    y = y0.copy()
    err, t_reached = spec.run_segment(y, 0.2, 0.3, contract_setting(spec), arrays, False, t_out,
                                      y_out, stats)
    assert t_reached == 0.3 and stats[STATUS] == 0
    assert stats[STEPS] > 7 and math.isfinite(err) and err >= 0
    np.testing.assert_array_equal(y_out[0], y0)
    np.testing.assert_array_equal(y_out[1], y0)
    np.testing.assert_allclose(y_out[3], y, atol=1e-15)
    assert abs(np.linalg.norm(y[6:10]) - 1) < 1e-14
    assert abs(np.linalg.norm(y_out[2, 6:10]) - 1) < 1e-14


@pytest.mark.parametrize("name", STEPPING)
def test_contract_zero_length_segment_changes_nothing(name):
    spec = INTEGRATORS[name]
    program, y0 = torqued_problem()
    arrays = (program.active(0.5), program.codes, program.params, program.mass, program.inertia)
    y = y0.copy()
    y_out = np.empty((1, 13))
    result = spec.run_segment(y, 0.5, 0.5, contract_setting(spec), arrays, False,
                              np.array([0.5]), y_out, np.zeros(5, dtype=np.int64))
    assert result == (0.0, 0.5)
    np.testing.assert_array_equal(y, y0)
    np.testing.assert_array_equal(y_out[0], y0)


@pytest.mark.parametrize("name", STEPPING)
def test_contract_a_nonfinite_state_is_reported_not_integrated(name):
    spec = INTEGRATORS[name]
    program, y0 = torqued_problem()
    arrays = (program.active(0.5), program.codes, program.params, program.mass, program.inertia)
    y0[11] = math.inf
    stats = np.zeros(5, dtype=np.int64)
    y_out = np.zeros((2, 13))
    _, t_reached = spec.run_segment(y0, 0.0, 1.0, contract_setting(spec), arrays, False,
                                    np.array([0.5, 1.0]), y_out, stats)
    assert stats[STATUS] == 1 and t_reached == 0.0
    assert np.isnan(y_out).all()


@pytest.mark.parametrize("what,args,match", [
    ("negative setting", dict(setting=-1.0), "expected a .* > 0"),
    ("nan setting", dict(setting=math.nan), "expected a .* > 0"),
    ("wrong y length", dict(y=np.zeros(12)), r"\(13,\) float64"),
    ("int y", dict(y=np.zeros(13, dtype=np.int64)), r"\(13,\) float64"),
    ("t1 before t0", dict(t1=-1.0), "t0 <= t1"),
    ("t_out outside", dict(t_out=np.array([2.0])), "sorted within"),
    ("t_out unsorted", dict(t_out=np.array([0.5, 0.2])), "sorted within"),
    ("y_out shape", dict(y_out=np.zeros((1, 7))), r"\(1, 13\)"),
    ("stats dtype", dict(stats=np.zeros(5)), "int64"),
], ids=lambda v: v if isinstance(v, str) else "")
@pytest.mark.parametrize("name", STEPPING)
def test_contract_bad_arguments_raise_usage_error(name, what, args, match):
    spec = INTEGRATORS[name]
    program, y0 = torqued_problem()
    call = dict(y=y0, t0=0.0, t1=1.0, setting=contract_setting(spec),
                program_arrays=(program.active(0.5), program.codes, program.params, program.mass,
                                program.inertia), rot_only=False, t_out=np.array([0.5]),
                y_out=np.zeros((1, 13)), stats=np.zeros(5, dtype=np.int64))
    call.update(args)
    with pytest.raises(UsageError, match=match) as info:
        spec.run_segment(**call)
    assert name in str(info.value)


@settings(max_examples=50, deadline=None)
@given(t0=st.floats(0, 100), duration=st.floats(1e-6, 2.0), h=st.floats(1e-3, 0.5))
def test_fixed_steps_land_exactly_on_t1(t0, duration, h):
    """n = ceil(duration / h) equal steps (a ratio within 1e-12 of an integer counts as it)."""
    t1 = t0 + duration
    if t1 <= t0:
        return
    program = program_for([Torque(np.array([0.0, 0.1, 0.0]))])
    arrays = (program.active(0.0), program.codes, program.params, program.mass, program.inertia)
    stats = np.zeros(5, dtype=np.int64)
    _, t_reached = INTEGRATORS["splitting"].run_segment(state()[6:], t0, t1, h, arrays, True,
                                                        np.empty(0), np.empty((0, 7)), stats)
    n = int(stats[STEPS])
    assert t_reached == t1
    assert n * h >= (t1 - t0) * (1 - 1e-12)
    assert (n - 1) * h < t1 - t0


def test_exact_contract_on_a_torque_free_rotation_state():
    """exact: rotation-only state; outputs filled, lands on t1, nothing counted as steps."""
    from massprops.dynamics.exact import free_rotation

    spec = INTEGRATORS["exact"]
    inertia = np.array([1.0, 2.0, 3.0])
    y0 = np.array([1.0, 0, 0, 0, 0.3, 1.0, 0.2])
    arrays = (np.zeros(0, bool), np.zeros(0, np.int64), np.zeros((0, 10)), 1.0, inertia)
    t_out = np.array([0.0, 0.7, 2.0])
    y_out = np.full((3, 7), np.nan)
    stats = np.zeros(5, dtype=np.int64)
    y = y0.copy()
    err, t_reached = spec.run_segment(y, 0.0, 2.0, 0.0, arrays, True, t_out, y_out, stats)
    q, w = free_rotation(inertia, y0[:4], y0[4:], t_out)
    assert (err, t_reached) == (0.0, 2.0) and not stats.any()
    np.testing.assert_array_equal(y_out[:, :4], q)
    np.testing.assert_array_equal(y_out[:, 4:], w)
    np.testing.assert_array_equal(y, y_out[-1])
    with pytest.raises(UsageError, match="rotation-only"):
        spec.run_segment(np.zeros(13), 0.0, 1.0, 0.0, arrays, False, np.zeros(0),
                         np.zeros((0, 13)), stats)
