"""massprops.rotation against independent truth: Rodrigues' formula, exact trigonometry at 30
digits (mpmath), group laws (composition = matrix product, inverse = transpose), round trips."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from massprops.errors import UsageError
from massprops.rotation import (
    canonical,
    matrix_to_quat,
    quat_conjugate,
    quat_from_axis_angle,
    quat_from_rotvec,
    quat_multiply,
    quat_normalize,
    quat_rotate,
    quat_to_matrix,
    quat_to_rotvec,
    rotation_angle_between,
)

EPS = np.finfo(float).eps

unit_vectors = st.tuples(*[st.floats(-1, 1) for _ in range(3)]).filter(
    lambda v: 0.1 < math.hypot(*v)).map(lambda v: np.array(v) / math.hypot(*v))
angles = st.floats(-math.pi, math.pi)


def rodrigues(axis: np.ndarray, angle: float) -> np.ndarray:
    """R = I + sin θ K + (1 - cos θ) K², K the cross-product matrix of the unit axis."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


@settings(max_examples=80, deadline=None)
@given(axis=unit_vectors, angle=angles)
def test_matrix_matches_rodrigues(axis, angle):
    q = quat_from_axis_angle(axis, angle)
    np.testing.assert_allclose(quat_to_matrix(q), rodrigues(axis, angle), atol=4 * EPS)


@settings(max_examples=80, deadline=None)
@given(a1=unit_vectors, t1=angles, a2=unit_vectors, t2=angles)
def test_composition_is_the_matrix_product(a1, t1, a2, t2):
    p, q = quat_from_axis_angle(a1, t1), quat_from_axis_angle(a2, t2)
    np.testing.assert_allclose(quat_to_matrix(quat_multiply(p, q)),
                               rodrigues(a1, t1) @ rodrigues(a2, t2), atol=8 * EPS)


@settings(max_examples=80, deadline=None)
@given(axis=unit_vectors, angle=angles)
def test_matrix_quat_round_trip(axis, angle):
    r = rodrigues(axis, angle)
    q = matrix_to_quat(r)
    assert q[0] >= 0
    assert abs(np.linalg.norm(q) - 1) < 2 * EPS
    np.testing.assert_allclose(quat_to_matrix(q), r, atol=8 * EPS)
    np.testing.assert_allclose(q, canonical(quat_from_axis_angle(axis, angle)), atol=4 * EPS)


@pytest.mark.parametrize("axis", [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [1, -2, 0.5]],
                         ids=["x", "y", "z", "diagonal", "skew"])
def test_half_turns_use_every_branch(axis):
    """180° turns have w = 0: the trace pivot fails there, a diagonal pivot must be used."""
    axis = np.array(axis, float) / np.linalg.norm(axis)
    q = matrix_to_quat(rodrigues(axis, math.pi))
    assert abs(q[0]) < 4 * EPS
    np.testing.assert_allclose(np.abs(q[1:]), np.abs(axis), atol=4 * EPS)
    np.testing.assert_allclose(quat_to_matrix(q), rodrigues(axis, math.pi), atol=8 * EPS)


def test_vectorised_over_leading_axes():
    rng = np.random.default_rng(0)
    q = quat_normalize(rng.normal(size=(5, 7, 4)))
    m = quat_to_matrix(q)
    assert m.shape == (5, 7, 3, 3)
    np.testing.assert_allclose(m @ np.swapaxes(m, -1, -2), np.broadcast_to(np.eye(3), m.shape),
                               atol=8 * EPS)
    np.testing.assert_allclose(np.linalg.det(m), 1.0, atol=8 * EPS)
    np.testing.assert_allclose(matrix_to_quat(m), canonical(q), atol=8 * EPS)
    v = rng.normal(size=(5, 7, 3))
    np.testing.assert_allclose(quat_rotate(q, v), np.einsum("...ij,...j", m, v), atol=1e-15)


def test_conjugate_is_the_inverse():
    q = quat_normalize([0.3, -0.2, 0.9, 0.1])
    np.testing.assert_allclose(quat_multiply(q, quat_conjugate(q)), [1, 0, 0, 0], atol=2 * EPS)
    np.testing.assert_allclose(quat_to_matrix(quat_conjugate(q)), quat_to_matrix(q).T, atol=4 * EPS)


def test_body_to_world_convention():
    """A quarter turn about world z takes the body x axis to world y: v_world = A v_body."""
    q = quat_from_axis_angle([0, 0, 1], math.pi / 2)
    np.testing.assert_allclose(quat_rotate(q, [1, 0, 0]), [0, 1, 0], atol=2 * EPS)


@pytest.mark.parametrize("q, expected", [
    ([-1, 0, 0, 0], [1, 0, 0, 0]),
    ([-0.5, 0.5, -0.5, 0.5], [0.5, -0.5, 0.5, -0.5]),
    ([0, 0, -1, 0], [0, 0, 1, 0]),
    ([0, 0, 0, -1], [0, 0, 0, 1]),
    ([0.6, -0.8, 0, 0], [0.6, -0.8, 0, 0]),
], ids=["minus-identity", "negative-w", "w-zero-y", "w-zero-z", "already"])
def test_canonical(q, expected):
    out = canonical(q)
    np.testing.assert_array_equal(out, expected)
    assert not np.any(np.signbit(out) & (out == 0)), "no negative zeros in the output"


@pytest.mark.parametrize("theta", [1e-300, 1e-100, 1e-16, 1e-12, 1e-8, 1e-5, 1e-4, 0.3, 3.0],
                         ids=lambda t: f"{t:g}")
def test_exp_log_accurate_at_every_angle(theta):
    """Against sin and cos at 30 digits: relative error of the vector part ~ eps at any angle."""
    axis = np.array([2.0, -3.0, 6.0]) / 7.0
    rotvec = theta * axis
    q = quat_from_rotvec(rotvec)
    with mpmath.workdps(30):
        th = mpmath.sqrt(sum(mpmath.mpf(float(x)) ** 2 for x in rotvec))
        w_ref = float(mpmath.cos(th / 2))
        v_ref = [float(mpmath.sin(th / 2) / th * mpmath.mpf(float(x))) for x in rotvec]
    assert abs(q[0] - w_ref) <= EPS
    np.testing.assert_allclose(q[1:], v_ref, rtol=4 * EPS, atol=0)
    np.testing.assert_allclose(quat_to_rotvec(q), rotvec, rtol=8 * EPS, atol=0)


def test_log_of_identity_and_half_turn():
    np.testing.assert_array_equal(quat_to_rotvec([1, 0, 0, 0]), [0, 0, 0])
    np.testing.assert_allclose(quat_to_rotvec([0, 0, 0, 1]), [0, 0, math.pi], rtol=EPS)
    # w < 0 is first made canonical: the turn is π - 2e-20 about -y.
    np.testing.assert_allclose(quat_to_rotvec([-1e-20, 0, 1, 0]), [0, -math.pi, 0], rtol=EPS)


@pytest.mark.parametrize("theta", [1e-12, 1e-9, 1e-6, 1e-3, 1.0, 3.0, math.pi - 1e-9, math.pi],
                         ids=lambda t: f"{t:.3g}")
def test_angle_between(theta):
    q1 = quat_normalize([0.2, -0.4, 0.7, 0.5])
    step = quat_from_axis_angle([0.0, 0.6, 0.8], theta)
    for q2 in (quat_multiply(q1, step), -quat_multiply(q1, step)):  # sign does not matter
        got = float(rotation_angle_between(q1, q2))
        assert abs(got - theta) <= 8 * EPS * max(theta, 1.0) + 4 * EPS, (got, theta)


def test_angle_between_broadcasts():
    q = quat_from_axis_angle(np.tile([1.0, 0, 0], (4, 1)), [0.0, 0.1, 0.2, 0.3])
    np.testing.assert_allclose(rotation_angle_between([1, 0, 0, 0], q), [0, 0.1, 0.2, 0.3],
                               rtol=4 * EPS, atol=0)


@pytest.mark.parametrize("call, shape", [
    (lambda: quat_to_matrix([1, 0, 0]), "(3,)"),
    (lambda: quat_multiply(np.zeros((2, 4)), np.zeros(5)), "(5,)"),
    (lambda: matrix_to_quat(np.eye(4)), "(4, 4)"),
    (lambda: quat_from_rotvec([1, 2]), "(2,)"),
], ids=["matrix-of-3", "multiply-5", "matrix-4x4", "rotvec-2"])
def test_shape_errors_say_expected_and_received(call, shape):
    with pytest.raises(UsageError, match=r"expected .* of shape \(\.\.\., [34](, 3)?\), got "
                       + shape.replace("(", r"\(").replace(")", r"\)")):
        call()


def test_zero_quaternion_and_axis_are_refused():
    with pytest.raises(UsageError, match="non-zero"):
        quat_normalize([0, 0, 0, 0])
    with pytest.raises(UsageError, match="non-zero"):
        quat_to_matrix([0, 0, 0, 0])
    with pytest.raises(UsageError, match="non-zero rotation axis"):
        quat_from_axis_angle([0, 0, 0], 1.0)
