"""Extreme scenes end to end: every run ends with a result, exit 3 with one line, or a partial
output; never a traceback, a hang or a NaN in a result (issue 8 §3). Also the run bound
(massprops.dynamics.budget) and --debug.

Oracles: the JSON writer's own strictness (allow_nan=False: json.dumps raises on NaN/inf), the
closed form of the torque-free needle (the exact rung's error is round-off), the step counts the
bound is stated in, and the exit-code table. A bounded fuzz over extreme inertia ratios (to
1e-9), spins (to 1e5 rad/s), stiffness (to 1e12 N/m) and durations (to 1e6 s) for every
integrator runs in process with a small step budget (the mechanism is the same at any bound);
benchmarks/fuzz_dynamics.py runs the larger campaign as whole processes.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from massprops.dynamics.model import (
    Drag,
    Gravity,
    InitialState,
    OutputSettings,
    RigidBody,
    Scene,
    Spring,
    TimeSettings,
    Torque,
)
from massprops.dynamics.precision import precision
from massprops.dynamics.simulate import simulate
from massprops.errors import ComputationError, DivergenceError, MassPropsError, RunBudgetError

NEEDLE = RigidBody.from_inertia(1.0, np.diag([1e-6, 1.0, 1.0]))
NEEDLE_YAML = """body: {mass: 1.0, inertia: [[1.0e-6, 0, 0], [0, 1, 0], [0, 0, 1]]}
initial: {angular_velocity: [1000, 1, 0.5], angular_velocity_frame: body}
time: {duration: 2.0}
"""


def strict_json(obj) -> dict:
    """obj through the CLI's JSON writer rules: raises on NaN or inf anywhere."""
    return json.loads(json.dumps(obj, allow_nan=False))


def scene(body, forces=(), duration=1.0, integrator="auto", omega=(0.0, 0.0, 0.0), **time):
    ini = InitialState(angular_velocity=np.array(omega, float), angular_velocity_frame="body")
    return Scene(body=body, initial=ini, forces=tuple(forces),
                 time=TimeSettings(duration=duration, integrator=integrator, **time),
                 output=OutputSettings())


# --- the needle of the issue -------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.timeout(300)
def test_needle_precision_ladder_completes_with_a_row_per_rung():
    sc = scene(NEEDLE, duration=2.0, omega=(1000.0, 1.0, 0.5))
    report = precision(sc, integrators=["exact", "rk4", "midpoint", "splitting"])
    out = strict_json(report.as_dict())
    assert out["reference"]["kind"] == "exact"
    rows = out["runs"]
    assert {r["integrator"] for r in rows} == {"exact", "rk4", "midpoint", "splitting"}
    for r in rows:  # a number with no reason, or null with one
        assert (r["error"] is None) == (r["reason"] is not None), r
    exact = [r for r in rows if r["integrator"] == "exact"]
    assert exact[0]["error"] < 1e-12  # the closed form against itself: round-off only
    # the rk4 ladder reaches the round-off-free regime: its finest rung is accurate
    rk4 = [r for r in rows if r["integrator"] == "rk4" and r["error"] is not None]
    assert min(r["error"] for r in rk4) < 1e-6


@pytest.mark.slow
def test_needle_precision_cli_json(run, tmp_path):
    path = tmp_path / "needle.yaml"
    path.write_text(NEEDLE_YAML)
    res = run("precision", path, "--json", "-q", "--integrator", "rk4", "--integrator", "exact")
    assert res.exit_code == 0, res.stderr
    out = json.loads(res.stdout, parse_constant=lambda c: pytest.fail(f"{c} in JSON"))
    assert out["runs"] and all("reason" in r for r in out["runs"])


def test_a_diverged_run_leaves_no_zero_quaternion():
    """rk4 at 4x the coarse needle rung overflows: the quaternion used to be divided by inf into
    [0, 0, 0, 0] (finite) and reached the frames as a 'state'. Now the run fails there, and
    every sample it keeps is a rotation."""
    sc = scene(NEEDLE, duration=2.0, omega=(1000.0, 1.0, 0.5))
    with pytest.raises(DivergenceError) as info:
        simulate(sc, integrator="rk4", step=0.0032, every=0.2)
    kept = info.value.partial.trajectory
    assert kept.t[-1] < 2.0
    norms = np.linalg.norm(kept.orientation, axis=1)
    assert np.all(np.isfinite(kept.orientation)) and np.allclose(norms, 1.0, atol=1e-12)


# --- --debug -----------------------------------------------------------------------------------
def test_debug_shows_the_traceback_with_the_contract_exit_code(run, tmp_path):
    path = tmp_path / "torqued.yaml"
    path.write_text(NEEDLE_YAML + "forces: [{type: torque, vector: [0, 0, 1]}]\n")
    plain = run("simulate", path, "--integrator", "exact", "-q")
    debug = run("--debug", "simulate", path, "--integrator", "exact", "-q")
    assert plain.exit_code == debug.exit_code == 2
    assert "Traceback" not in plain.stderr and len(plain.stderr.strip().splitlines()) == 1
    assert "Traceback (most recent call last)" in debug.stderr
    assert "UsageError" in debug.stderr


# --- the run bound -----------------------------------------------------------------------------
def test_fixed_step_run_beyond_the_bound_is_refused_up_front(run, tmp_path):
    path = tmp_path / "long.yaml"
    path.write_text("body: {mass: 1, inertia: [[1,0,0],[0,2,0],[0,0,3]]}\n"
                    "forces: [{type: torque, vector: [0, 0, 0.1]}]\n"
                    "time: {duration: 1.0e+6, integrator: rk4, step: 1.0e-3}\n")
    res = run("simulate", path, "-q")
    assert res.exit_code == 3
    (line,) = res.stderr.strip().splitlines()
    assert "1e+09 steps" in line and "2e+07" in line and "time.step" in line


def test_adaptive_run_stops_at_the_bound_and_keeps_what_it_computed(run, tmp_path):
    path = tmp_path / "spin.yaml"
    out = tmp_path / "traj.csv"
    path.write_text("body: {mass: 1, inertia: [[1,0,0],[0,2,0],[0,0,3]]}\n"
                    "initial: {angular_velocity: [100, 2, 3]}\n"
                    "forces: [{type: torque, vector: [0, 0, 0.1]}]\n"
                    "time: {duration: 1000, rtol: 1.0e-10}\n")
    res = run("simulate", path, "-q", "--max-steps", "5000", "--output", out, "--every", "1")
    assert res.exit_code == 3
    (line,) = res.stderr.strip().splitlines()
    assert "t = " in line and "--max-steps" in line and "spin.yaml" in line
    rows = out.read_text().splitlines()
    assert 2 < len(rows) < 1002  # the header, t = 0, ... up to where it stopped


def test_the_bound_stops_a_run_within_its_steps():
    sc = scene(RigidBody.from_inertia(1.0, np.diag([1.0, 2.0, 3.0])), [Torque(np.ones(3))],
               duration=1e4, integrator="dop853", omega=(50.0, 1.0, 1.0))
    with pytest.raises(RunBudgetError) as info:
        simulate(sc, max_steps=20_000)
    part = info.value.partial
    # stopped at the first chunk end past the bound, or earlier by its projected pace
    assert 0 < part.steps < 20_000 + 60_000 and "max_steps" in info.value.settings
    assert 0 < part.trajectory.t[-1] < 1e4
    strict_json(part.as_dict())


def test_a_step_cut_into_countless_pieces_ends_at_once_with_the_reason():
    """A 5 g body on an 8e9 N/m spring at a 1 m lever (rate ~1.5e8/s; found by the fuzz): the
    implicit method's Newton iteration fails at every nominal step of 6 ms. The one-body kernel
    cut each step into thousands of pieces and ran into the run bound for minutes; as a system
    of one body, a step whose Newton fails in 64 pieces ends the run there, saying so."""
    body = RigidBody.from_inertia(0.005, np.diag([2e-5, 1.8e-4, 1.9e-4]))
    spring = Spring(np.zeros(3), 8e9, point=np.array([-0.83, -0.24, -0.52]))
    sc = scene(body, [spring], duration=7000.0, integrator="implicit", step=6e-3)
    with pytest.raises(DivergenceError, match="Newton iterations failed") as info:
        simulate(sc)
    assert "shorten" in str(info.value) and "use integrator implicit" not in str(info.value)


def test_a_run_whose_pace_overshoots_the_bound_stops_early(monkeypatch):
    """Between compiled calls the run's pace is projected (budget.exhausted): a run that would
    need far more than the bound stops at the first check past PROJECT_AFTER steps, keeping
    what it computed. Both thresholds are scaled down here: the mechanism is the same at any
    size."""
    from massprops.dynamics import budget
    from massprops.dynamics.systems import integrate

    monkeypatch.setattr(integrate, "CALL_STEPS", 2_000)
    monkeypatch.setattr(budget, "PROJECT_AFTER", 10_000)
    sc = scene(RigidBody.from_inertia(1.0, np.diag([1.0, 2.0, 3.0])), [Torque(np.ones(3))],
               duration=1e5, integrator="dop853", omega=(50.0, 1.0, 1.0))
    with pytest.raises(RunBudgetError, match="at its pace so far") as info:
        simulate(sc, max_steps=200_000)
    assert 10_000 <= info.value.partial.steps < 14_000  # stopped at the first check past 1e4
    strict_json(info.value.partial.as_dict())


def test_too_many_samples_are_refused_before_any_allocation():
    sc = scene(NEEDLE, duration=1e6, omega=(1.0, 0.0, 0.0))
    with pytest.raises(RunBudgetError, match="output samples"):
        simulate(sc, every=1e-6)


def test_fast_long_torque_free_spin_is_exact_and_immediate():
    """1e5 rad/s for 1e6 s: 1e11 rad; the closed form takes no steps."""
    sc = scene(RigidBody.from_inertia(1.0, np.diag([1e-9, 1.0, 1.0 + 1e-9])), duration=1e6,
               omega=(1e5, 1e-3, 2e-3))
    res = simulate(sc)
    assert res.integrator == "exact" and res.steps == 0
    out = strict_json(res.as_dict())
    assert out["diagnostics"]["angular_momentum_rel_drift"] < 1e-9


# --- bounded fuzz: every integrator over extreme scenes -----------------------------------------
MOMENTS = st.sampled_from([(1e-9, 1.0, 1.0), (1e-6, 1.0, 1.0 + 1e-6), (0.5, 0.5, 1.0),
                           (1.0, 2.0, 3.0), (1e-3, 0.5, 0.501), (1.0, 1.0, 1.0)])
FORCES = st.sampled_from(["none", "gravity", "torque", "stiff spring", "damped spring", "drag"])


def forces_of(kind: str, body: RigidBody, spin: float, k: float):
    if kind == "gravity":
        return [Gravity(np.array([0.0, 0.0, -9.81]))]
    if kind == "torque":
        return [Torque(float(body.principal_moments[2]) * np.array([0.3, -1.0, 0.5]))]
    if kind == "stiff spring":
        return [Spring(np.zeros(3), k, point=np.array([0.0, 0.0, 0.1]))]
    if kind == "damped spring":
        return [Spring(np.zeros(3), k, point=np.array([0.1, 0.0, 0.0]),
                       damping=math.sqrt(k * body.mass))]
    if kind == "drag":
        return [Drag(1.0, float(body.principal_moments[0]))]
    return []


@pytest.mark.timeout(600)
@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(moments=MOMENTS, spin=st.sampled_from([0.0, 1.0, 1e3, 1e5]),
       duration=st.sampled_from([1e-3, 1.0, 1e3, 1e6]), forces=FORCES,
       k=st.sampled_from([1.0, 1e6, 1e12]),
       integrator=st.sampled_from(["auto", "exact", "rk4", "dop853", "implicit", "midpoint",
                                   "splitting", "splitting4", "splitting6"]))
@pytest.mark.slow
def test_every_run_ends_in_a_result_or_a_clean_error(moments, spin, duration, forces, k,
                                                     integrator):
    body = RigidBody.from_inertia(1.0, np.diag(moments))
    sc = scene(body, forces_of(forces, body, spin, k), duration=duration, integrator=integrator,
               omega=(spin, 1e-3 * spin + 0.1, 0.0))
    try:
        res = simulate(sc, max_steps=20_000)
    except (DivergenceError, RunBudgetError) as exc:
        assert "\n" not in str(exc)
        if exc.partial is not None:
            strict_json(exc.partial.as_dict())
        return
    except MassPropsError as exc:  # exact on a torqued scene, a refused setting: one line
        assert isinstance(exc, ComputationError) or "exact" in str(exc) or "rtol" in str(exc)
        assert "\n" not in str(exc)
        return
    out = strict_json(res.as_dict())
    assert np.all(np.isfinite(res.trajectory.orientation))
    assert abs(np.linalg.norm(out["final"]["orientation"]) - 1.0) < 1e-6


def test_a_nan_newton_correction_is_not_convergence():
    """numba's and Python's max(0.0, nan) is 0.0: the Newton norm takes the worst correction
    with `worst`, which keeps a NaN (a stiff spring's stage Jacobians gave NaN corrections that
    passed as converged, and the run "diverged" where its Newton had failed)."""
    from massprops.dynamics.integrators._shared import worst

    assert math.isnan(worst.py_func(0.0, math.nan)) and math.isnan(worst.py_func(math.nan, 1.0))
    assert worst.py_func(2.0, 1.0) == 2.0 and worst.py_func(1.0, 2.0) == 2.0
