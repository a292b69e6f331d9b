"""massprops' systems against references derived apart from it (issue 17 §4): the compound
double pendulum's Lagrange equations and the four-bar reduced to its crank angle
(tests/system_truth.py), integrated by scipy at rtol 1e-13 and checked against the same
equations at 30 digits in mpmath. No timing here (benchmarks/bench_systems_peers.py)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import mpmath as mp
import numpy as np
import pytest
import system_truth as truth
import yaml
from scipy.integrate import solve_ivp

import massprops

SAMPLES = Path(__file__).resolve().parent.parent / "sample_scenes"


def _float_truth(problem: str, t_end: float) -> np.ndarray:
    """The joint angles at t_end from the hand-derived equations, scipy DOP853 at 1e-13."""
    if problem == "double_pendulum":
        y = solve_ivp(truth.double_pendulum_rhs(), (0.0, t_end), truth.double_pendulum_start(),
                      method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
        return np.array([y[0], y[1] - y[0]])
    bar = truth.FourBar()
    y = solve_ivp(bar.rhs(), (0.0, t_end), bar.start(), method="DOP853", rtol=1e-13,
                  atol=1e-13).y[:, -1]
    return np.array([bar.joint_a(y[0])])


def test_truth_uses_the_samples_numbers():
    dp = yaml.safe_load((SAMPLES / "double_pendulum.yaml").read_text())
    upper, lower = dp["bodies"]["upper"], dp["bodies"]["lower"]
    assert [upper["mass"], lower["mass"]] == [truth.DP["m1"], truth.DP["m2"]]
    assert [upper["inertia"][1][1], lower["inertia"][1][1]] == [truth.DP["I1"], truth.DP["I2"]]
    elbow = dp["joints"][1]["point"][2]
    assert -upper["position"][2] == truth.DP["a1"] and -elbow == truth.DP["L1"]
    assert elbow - lower["position"][2] == truth.DP["a2"]
    assert dp["initial"]["positions"] == {"shoulder": truth.DP["shoulder"],
                                          "elbow": truth.DP["elbow"]}
    fb = yaml.safe_load((SAMPLES / "four_bar.yaml").read_text())
    points = {j["name"]: (j["point"][0], j["point"][2]) for j in fb["joints"]}
    assert all(points[k] == tuple(truth.FB[k]) for k in "ABCD")
    for name, body in fb["bodies"].items():
        assert body["mass"] == truth.FB["mass"][name]
        assert body["inertia"][1][1] == truth.FB["Iyy"][name]
        assert (body["position"][0], body["position"][2]) == truth.FB["com"][name]
    assert fb["initial"]["rates"]["A"] == truth.FB["rate_A"]


def test_four_bar_reduction_closes_the_loop():
    """β, φ from the circles satisfy Freudenstein's equation all the way round, and the
    assembly pose is found again on its branch."""
    bar = truth.FourBar()
    beta0, phi0 = bar.angles(bar.psi0)
    c = truth.FB["C"]
    assert math.isclose(phi0, math.atan2(c[1], c[0] - 3.0), abs_tol=1e-14)
    assert math.isclose(beta0, math.atan2(c[1] - truth.FB["B"][1], c[0] - truth.FB["B"][0]),
                        abs_tol=1e-14)
    for psi in np.linspace(0.0, 2 * math.pi, 37):
        assert abs(bar.freudenstein(psi, bar.angles(psi)[1])) < 1e-13


@pytest.mark.slow
def test_float_truth_matches_30_digits():
    """The float64 path of the references against the same equations in mpmath (GBS)."""
    dp = truth.double_pendulum_reference(0.5, steps_per_s=20, levels=8)
    assert np.abs(_float_truth("double_pendulum", 0.5) - np.array(dp, float)).max() < 1e-12
    with mp.workdps(30):
        fb = float(truth.four_bar_reference(0.25, steps_per_s=20, levels=8))
    assert abs(_float_truth("four_bar", 0.25)[0] - fb) < 1e-12


@pytest.mark.slow
@pytest.mark.parametrize(("problem", "t_end"), [("double_pendulum", 1.0), ("four_bar", 0.4)])
def test_massprops_against_independent_reference(tmp_path, problem, t_end):
    """The sample (duration cut to t_end) at rtol 1e-12 through the public API: its joint
    angles within 1e-9 rad of the hand-derived equations."""
    text = re.sub(r"duration: [0-9.]+", f"duration: {t_end}",
                  (SAMPLES / f"{problem}.yaml").read_text())
    path = tmp_path / f"{problem}.yaml"
    path.write_text(text)
    result = massprops.simulate(massprops.load_scene(path), rtol=1e-12, every=t_end)
    joints = result.as_dict()["final"]["joints"]
    names = ["shoulder", "elbow"] if problem == "double_pendulum" else ["A"]
    ours = np.array([joints[n]["coordinates"][0] for n in names])
    assert np.abs(ours - _float_truth(problem, t_end)).max() < 1e-9
