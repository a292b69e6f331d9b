"""The global error estimate of fixed-step runs: Richardson's rule with the observed ratio of the
2h and 4h companions (accuracy.global_estimate), and the probe of modes faster than the step
(systems/stiffness.py). Truth: error models with known terms, and a resolving dop853 run."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.accuracy import Scales, global_estimate, state_error
from massprops.dynamics.scene import load_scene
from massprops.dynamics.simulate import simulate
from massprops.dynamics.systems import stiffness

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
