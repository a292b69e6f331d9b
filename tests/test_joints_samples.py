"""The joint sample scenes (sample_scenes/heavy_top, gyroscope, compound_pendulum) against what
their header comments say is right; each truth is derived here from the scene's own numbers
(the Lagrange top's cubic by numpy, scipy's elliptic functions and quadrature), never from what
massprops printed."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.integrate import quad
from scipy.special import ellipj, ellipk

from massprops.dynamics.scene import load_scene
from massprops.dynamics.simulate import simulate
from massprops.rotation import quat_to_matrix

SCENES = Path(__file__).resolve().parent.parent / "sample_scenes"
G = 9.81


def lagrange(m, arm, a_mom, c_mom, w3, theta0):
    """The top released at θ0 with spin w3 and nothing else: (u1, u2 = cos θ0, period of u,
    mean precession rate), from f(u) = (u0 - u)[β(1 - u²) - a²(u0 - u)] (Goldstein §5.7)."""
    beta, a, u0 = 2 * m * G * arm / a_mom, c_mom * w3 / a_mom, math.cos(theta0)
    roots = np.sort(np.roots([beta, -a * a, -(beta - a * a * u0)]).real)
    u1, u3 = roots
    mm = (u0 - u1) / (u3 - u1)
    lam = math.sqrt(beta * (u3 - u1)) / 2
    period = 2 * ellipk(mm) / lam

    def u_of(t):
        sn = ellipj(lam * t + ellipk(mm), mm)[0]
        return u1 + (u0 - u1) * sn**2

    turn = quad(lambda t: a * (u0 - u_of(t)) / (1 - u_of(t) ** 2), 0, period, limit=200)[0]
    return u1, u0, period, turn / period


def axis_cosine(tr, axis_body) -> np.ndarray:
    """cos θ of the body axis from the upward vertical, (n,)."""
    return (quat_to_matrix(tr.orientation) @ axis_body)[:, 2]


def precession_angle(tr, axis_body) -> np.ndarray:
    """Unwrapped azimuth (rad) of the body axis about the vertical, (n,)."""
    a = quat_to_matrix(tr.orientation) @ axis_body
    return np.unwrap(np.arctan2(a[:, 1], a[:, 0]))


def minima(t, x):
    """(times, values) of the sampled x's local minima, refined by the parabola through the
    three samples around each."""
    i = np.flatnonzero((x[1:-1] < x[:-2]) & (x[1:-1] <= x[2:])) + 1
    curvature = x[i - 1] - 2 * x[i] + x[i + 1]
    d = (x[i - 1] - x[i + 1]) / (2 * curvature)
    return t[i] + d * (t[1] - t[0]), x[i] - (x[i + 1] - x[i - 1]) ** 2 / (8 * curvature)


def test_heavy_top_nutates_and_precesses_as_its_cubic_says():
    scene = load_scene(SCENES / "heavy_top.yaml")
    m = 3 * math.sqrt(3)
    a_mom, c_mom = 13 * math.sqrt(3) / 8 + m, 5 * math.sqrt(3) / 4
    u1, u2, period, rate = lagrange(m, 1.0, a_mom, c_mom, 30.0, math.radians(30))
    assert math.isclose(math.degrees(math.acos(u1)), 37.3732, abs_tol=1e-4)  # the header's
    assert math.isclose(period, 0.936035, rel_tol=1e-6) and math.isclose(rate, 0.856922,
                                                                         rel_tol=1e-6)
    res = simulate(scene, every=1e-3)
    assert res.integrator == "exact"
    tr = res.trajectory
    u = axis_cosine(tr, np.array([0.0, 0.0, 1.0]))
    assert math.isclose(u.max(), u2, abs_tol=1e-12) and math.isclose(u.min(), u1, abs_tol=1e-7)
    lows, _ = minima(tr.t, u)
    assert abs((lows[-1] - lows[0]) / (len(lows) - 1) - period) < 1e-7
    (pivot,) = tr.joints
    assert math.isclose(pivot.force_world[0, 2], m * G * (1 - m * 0.25 / a_mom), rel_tol=1e-12)
    # sampled at exact fractions of the nutation period: whole periods from the start (a cusp)
    every = period / 200
    tr = simulate(scene, every=every).trajectory
    k = 200 * int(tr.t[-1] / period)
    phi = precession_angle(tr, np.array([0.0, 0.0, 1.0]))
    assert abs((phi[k] - phi[0]) / tr.t[k] - rate) < 1e-9 * rate
    mean_vertical = np.mean(tr.joints[0].force_world[:k, 2])  # the rectangle rule is
    assert abs(mean_vertical / (m * G) - 1) < 1e-9  # spectrally accurate on a period


def test_gyroscope_pivot_load_swings_between_its_turning_point_values():
    scene = load_scene(SCENES / "gyroscope.yaml")
    m, arm, c_mom = 0.5, 0.06, 4e-4
    a_mom = 2e-4 + m * arm * arm
    u1, u2, period, rate = lagrange(m, arm, a_mom, c_mom, 300.0, math.pi / 2)
    beta, a = 2 * m * G * arm / a_mom, c_mom * 300.0 / a_mom

    def vertical_load(u):  # m g + m l ü, ü = f'(u)/2, f = (u0 - u)[β(1 - u²) - a²(u0 - u)]
        f_prime = -(beta * (1 - u * u) - a * a * (u2 - u)) + (u2 - u) * (-2 * beta * u + a * a)
        return m * G + m * arm * f_prime / 2

    assert math.isclose(vertical_load(u2), 0.1 * m * G, rel_tol=1e-12)
    res = simulate(scene, every=1e-4)
    tr = res.trajectory
    (pivot,) = tr.joints
    fz = pivot.force_world[:, 2]
    assert math.isclose(fz.min(), vertical_load(u2), rel_tol=1e-9)
    assert math.isclose(fz.max(), vertical_load(u1), rel_tol=1e-6)  # sampled near the bottom
    assert math.isclose(math.degrees(math.acos(u1)), 94.6582, abs_tol=1e-4)
    assert math.isclose(period, 0.104202, rel_tol=1e-5)
    tr = simulate(scene, every=period / 200).trajectory
    k = 200 * 9
    phi = precession_angle(tr, np.array([1.0, 0.0, 0.0]))
    assert abs((phi[k] - phi[0]) / tr.t[k] - rate) < 1e-9 * rate
    assert res.diagnostics["energy_rel_drift"] < 1e-14


def test_compound_pendulum_swings_with_the_exact_period_and_bottom_load():
    scene = load_scene(SCENES / "compound_pendulum.yaml")
    m, length, width = 2.0, 1.0, 0.02
    i_point = m * (length**2 + width**2) / 12 + m * 0.25
    theta0 = math.radians(179)
    period = 4 * ellipk(math.sin(theta0 / 2) ** 2) * math.sqrt(i_point / (m * G * 0.5))
    assert math.isclose(period, 6.39006, rel_tol=1e-6)
    res = simulate(scene, rtol=1e-12, every=1e-3)
    tr = res.trajectory
    swing = tr.angular_velocity[:, 0]
    # the rod passes the bottom with |ω| largest: times of those passages, half a period apart
    i = np.flatnonzero((np.abs(swing[1:-1]) > np.abs(swing[:-2]))
                       & (np.abs(swing[1:-1]) >= np.abs(swing[2:]))) + 1
    assert len(i) >= 4
    assert abs((tr.t[i[-1]] - tr.t[i[0]]) / (len(i) - 1) - period / 2) < 2e-3
    bottom_rate = math.sqrt(2 * m * G * 0.5 * (1 - math.cos(theta0)) / i_point)
    _, peaks = minima(tr.t, -np.abs(swing))
    assert np.allclose(-peaks, bottom_rate, rtol=1e-8)
    (hinge,) = tr.joints
    load = np.linalg.norm(hinge.force_world, axis=1)
    _, peaks = minima(tr.t, -load)
    at_bottom = -peaks[-peaks > 2 * m * G]  # (the load also peaks, at ~m g, near the top)
    assert len(at_bottom) >= 4
    assert np.allclose(at_bottom, m * G + m * 0.5 * bottom_rate**2, rtol=1e-8)
    assert math.isclose(load[0], m * G * math.hypot(1 - 0.75 * math.sin(theta0) ** 2,
                                                    0.75 * math.sin(theta0)
                                                    * math.cos(theta0)), rel_tol=1e-6)
    assert np.max(np.abs(hinge.torque_world)) < 1e-12  # a symmetric rod
    assert res.diagnostics["energy_rel_drift"] < 1e-9
