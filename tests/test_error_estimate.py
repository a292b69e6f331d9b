"""The global error estimate of fixed-step runs: Richardson's rule with the observed ratio of the
2h and 4h companions (accuracy.global_estimate), and the probe of modes faster than the step
(systems/stiffness.py). Truth: error models with known terms, and a resolving dop853 run."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.accuracy import UNRESOLVED_ESTIMATE, Scales, global_estimate, state_error
from massprops.dynamics.scene import load_scene
from massprops.dynamics.simulate import simulate
from massprops.dynamics.systems import stiffness
from massprops.errors import ComputationError
from massprops.rotation import rotation_angle_between

SCENES = Path(__file__).resolve().parent.parent / "sample_scenes"


def distances(error_of_step, h: float) -> tuple[float, float, float]:
    """(true error at h, |y_h - y_2h|, |y_2h - y_4h|) for scalar runs y_k = truth + error(k)."""
    e1, e2, e4 = (error_of_step(k * h) for k in (1, 2, 4))
    return abs(e1), abs(e1 - e2), abs(e2 - e4)


@pytest.mark.parametrize("order", [2, 4, 5, 6])
def test_asymptotic_runs_give_the_classical_rule_exactly(order):
    true, d1, d2 = distances(lambda h: 3.0 * h**order, 1e-2)
    assert global_estimate("fixed", order, d1, d2) == pytest.approx(true, rel=1e-12)


@pytest.mark.parametrize("order, reduced", [(5, 3), (4, 2), (6, 1)], ids=["radau-stage-order",
                                                                         "4-to-2", "6-to-1"])
def test_order_reduction_is_seen_and_not_understated(order, reduced):
    """A method of order p whose error behaves like h^q, q < p (a stiff mode, a Newton floor):
    the classical rule divides by 2^p - 1 and understates it 2^(p-q)-fold; the observed ratio
    gives the error exactly."""
    true, d1, d2 = distances(lambda h: -0.7 * h**reduced, 1e-2)
    classical = d1 / (2**order - 1)
    assert true / classical >= 2 ** (order - reduced) - 1
    assert global_estimate("fixed", order, d1, d2) == pytest.approx(true, rel=1e-12)


def test_an_order_that_keeps_falling_as_h_shrinks_is_not_credited_beyond_the_assumed_order():
    """Order reduction under way (Radau IIA on a stiff problem): the error falls like h^4.3
    between 4h and 2h but only like h^3 between 2h and h, so the ratio the companions show
    (~20) overstates how much the run at h gained. Crediting at most 2^3 (the stage order)
    keeps the estimate above the truth; crediting the observed ratio does not."""
    e = {4: 20.0 * 13.0, 2: 13.0, 1: 1.0}  # the heavy_top_damped ratios, in units of e(h)
    d1, d2 = e[2] - e[1], e[4] - e[2]
    assert global_estimate("fixed", 5, d1, d2) < e[1]  # 12/19: understated
    assert global_estimate("fixed", 5, d1, d2, assumed_order=3) == pytest.approx(12 / 7)
    assert global_estimate("fixed", 5, d1, d2, assumed_order=3) >= e[1]
    # beyond 2 * 2^order the run is not asymptotic at all: the distance itself, as before
    assert global_estimate("fixed", 5, 1.0, 70.0, assumed_order=3) == 1.0


def test_noise_is_reported_at_its_own_size():
    """Round-off amplified near a separatrix: runs that differ at random by σ (no truncation
    error at all, the hardest case). Three runs cannot tell more: the estimate is within 10x of
    the truth in ~89 % of draws; the classical rule (÷ 63 for order 6) in ~10 %."""
    rng = np.random.default_rng(7)
    ok = classical_ok = 0
    for _ in range(2000):
        e1, e2, e4 = rng.normal(0.0, 1e-7, 3)
        true, d1, d2 = abs(e1), abs(e1 - e2), abs(e2 - e4)
        ok += true <= 10 * global_estimate("fixed", 6, d1, d2)
        classical_ok += true <= 10 * d1 / 63
    assert ok >= 0.85 * 2000 and classical_ok <= 0.15 * 2000


def test_a_diverged_second_companion_leaves_the_unscaled_distance():
    assert global_estimate("fixed", 4, 0.3, None) == 0.3
    assert global_estimate("fixed", 4, 0.3, math.inf) == 0.3


def test_adaptive_runs_take_the_distance_as_it_is():
    assert global_estimate("adaptive", 8, 2e-9, None) == 2e-9


# --- the probe of unresolved fast modes -----------------------------------------------------------
def test_an_oscillation_faster_than_the_step_is_in_the_estimate():
    """unstable.yaml: a 1000 rad/s spring; Radau at h = 8 ms damps the 1 cm oscillation away
    (the truth keeps it): the error is the whole oscillation, and the estimate says so (the
    companions alone said 1e-5)."""
    sc = load_scene(SCENES / "unstable.yaml")
    result = simulate(sc, integrator="implicit", step=0.008)
    truth = simulate(sc, integrator="dop853", rtol=1e-11).trajectory
    scales = Scales.of(sc.body.size, truth, sc.time.duration)
    true = state_error(result.trajectory, truth, scales)
    assert true > 0.5  # the oscillation is gone from the run
    assert true / 10 <= result.diagnostics["error_estimate"] <= 100 * true


def test_a_step_that_resolves_every_rate_runs_no_probe(monkeypatch):
    """Same scene, h·ρ = 0.5: nothing is unresolved, the probe's runs must cost nothing; at
    h = 8 ms (h·ρ = 8) they run."""
    steps = []
    run = stiffness.integrate

    def spy(system, y0, t_out, setting, *args):
        steps.append(setting)
        return run(system, y0, t_out, setting, *args)

    monkeypatch.setattr(stiffness, "integrate", spy)
    sc = load_scene(SCENES / "unstable.yaml")
    result = simulate(sc, integrator="implicit", step=5e-4)
    assert result.diagnostics["error_estimate"] is not None
    assert steps == []
    simulate(sc, integrator="implicit", step=0.008)
    assert steps == [0.008, stiffness.PROBE_RTOL]  # the method, and dop853 resolving the mode


def test_a_failed_probe_or_runaway_companion_gives_no_estimate_not_infinity(monkeypatch):
    """The JSON output refuses inf (allow_nan=False): an estimate whose size is unknown is null."""
    # the implicit method runs the body as a system of one body: the systems' probe
    monkeypatch.setattr("massprops.dynamics.systems.methods.unresolved_mode_error",
                        lambda *_args: math.inf)
    sc = load_scene(SCENES / "unstable.yaml")
    assert simulate(sc, integrator="implicit", step=0.008).diagnostics["error_estimate"] is None


# --- a step that turns a body by radians (issue 30) ----------------------------------------------
def test_one_step_s_error_on_a_rotation_is_the_method_s_own():
    """`turn_error` against the stability functions written out by hand: rk4 multiplies a
    rotation's quaternion (y' = i φ y per step φ = θ/2) by its Taylor polynomial of degree 4,
    the implicit midpoint rule by (1 + iφ/2) / (1 − iφ/2), which turns by 2 atan(φ/2) exactly:
    the body by 4 atan(θ/4)."""
    from massprops.dynamics.accuracy import followed_turn, turn_error
    from massprops.dynamics.integrators import INTEGRATORS

    for theta in (0.01, 0.3, 1.0, 2.0, 3.5):
        phi = theta / 2
        taylor = 1 + 1j * phi - phi**2 / 2 - 1j * phi**3 / 6 + phi**4 / 24
        rk4 = 2 * abs(np.angle(taylor) - phi)
        assert turn_error(INTEGRATORS["rk4"].tableau, theta) == pytest.approx(rk4, rel=1e-9,
                                                                               abs=1e-15)
        midpoint = theta - 4 * math.atan(theta / 4)
        assert turn_error(INTEGRATORS["midpoint"].tableau, theta) == pytest.approx(
            midpoint, rel=1e-9, abs=1e-15)
    # order p: the error of one step falls as θ^(p+1)
    for name in ("rk4", "midpoint", "implicit", "dop853"):
        spec = INTEGRATORS[name]
        small = [turn_error(spec.tableau, t) for t in (1.0, 0.5)]
        # (a phase error: Radau's leading term, C z^6, is real on the imaginary axis: θ^7)
        assert spec.order + 0.8 < math.log2(small[0] / small[1]) < spec.order + 2.2
        assert 1.0 < followed_turn(spec.tableau) < 20.0


SPIN, DURATION = 10.0, 10.0
SYMMETRIC = "{mass: 1.0, inertia: [[1, 0, 0], [0, 1, 0], [0, 0, 2]]}"
FAST_RUNS = [("rk4", {"step": 0.1}), ("rk4", {"step": 0.3}), ("midpoint", {"step": 0.1}),
             ("implicit", {"step": 1.0}), ("dop853", {"rtol": 0.5}), ("dop853", {"rtol": 0.05})]


def _spin_scene(tmp_path, body: str, omega: str, duration: float, extra: str = ""):
    path = tmp_path / "spin.yaml"
    path.write_text(f"body: {body}\ninitial: {{angular_velocity: {omega}, "
                    f"angular_velocity_frame: body}}\n{extra}time: {{duration: {duration}}}\n")
    return load_scene(path)


@pytest.mark.parametrize("method, setting", FAST_RUNS,
                         ids=[f"{m}-{next(iter(s.values()))}" for m, s in FAST_RUNS])
def test_a_step_that_turns_a_body_by_radians_never_claims_accuracy(tmp_path, method, setting):
    """A symmetric body spinning about its axis at 10 rad/s turns uniformly: q(t) =
    [cos(ωt/2), 0, 0, sin(ωt/2)], the truth each run is measured against. Where the run's
    steps turn it by a radian or more, its estimate is at least 1e-2 and at least its true
    error."""
    sc = _spin_scene(tmp_path, SYMMETRIC, f"[0, 0, {SPIN}]", DURATION)
    res = simulate(sc, integrator=method, **setting)
    turn = SPIN * DURATION / res.steps
    assert turn >= 1.0  # the case this test is about
    traj = res.trajectory
    half = 0.5 * SPIN * traj.t
    truth = np.column_stack([np.cos(half), 0 * half, 0 * half, np.sin(half)])
    true = float(np.max(rotation_angle_between(traj.orientation, truth)))
    estimate = res.diagnostics["error_estimate"]
    assert estimate is not None and estimate >= 1e-2, (turn, estimate, true)
    assert estimate >= 0.9 * true, (turn, estimate, true)


TORQUED = [("rk4", {}), ("midpoint", {}), ("implicit", {}), ("dop853", {"rtol": 0.5})]


@pytest.mark.parametrize("body", ["{mass: 2.0, inertia: [[1, 0, 0], [0, 2, 0], [0, 0, 3]]}",
                                  SYMMETRIC], ids=["asymmetric", "symmetric"])
@pytest.mark.parametrize("method, setting", TORQUED, ids=[m for m, _ in TORQUED])
def test_a_torqued_body_over_1e12_s_is_not_called_accurate(tmp_path, body, method, setting):
    """The issue's run: a torque about a principal axis from rest, 1e12 s at the default
    step (duration / 1000 = 1e9 s): the body turns by n t² / (2 J) ~ 1e23 rad, far beyond
    anything a step of 1e9 s follows (or float64 resolves). ω = n t / J is linear, which every
    method integrates exactly, and the companions agreed with the run by chance: rk4 said
    1.5e-14. Now the estimate says the run resolves nothing, and a warning says so (or the run
    fails, exit 3, saying what to change: no claim either)."""
    torque = "forces: [{type: torque, vector: [0, 0, 1], frame: body}]\n"
    sc = _spin_scene(tmp_path, body, "[0, 0, 0]", 1e12, torque)
    try:
        res = simulate(sc, integrator=method, **setting)
    except ComputationError as exc:  # a failure claims nothing; it says what to change
        assert "step" in str(exc) or "duration" in str(exc), exc
        return
    moment = 3.0 if "3]]" in body else 2.0
    turned = 0.5 * 1e12**2 / moment
    assert turned / res.steps > 1e3
    estimate = res.diagnostics["error_estimate"]
    assert estimate is not None and estimate >= UNRESOLVED_ESTIMATE, estimate
    assert any("not to be trusted" in note for note in res.notes)
