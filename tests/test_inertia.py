"""Principal axes, change of axes and of reference point, against independent truth: tensors built
from known eigen-decompositions, point-mass sums, the seed's worked example, round-off stability."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from massprops.errors import UnphysicalInertiaError
from massprops.inertia import parallel_axis, parallel_axis_to_com, principal_axes, rotate_inertia


def rotation_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_from_quaternion(q) -> np.ndarray:
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


quaternions = st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(
    lambda q: np.linalg.norm(q) > 0.1)


def point_inertia(masses, points, about) -> np.ndarray:
    """J = Σ m (|r|² I - r rᵀ), r = p - about: the definition, summed directly."""
    j = np.zeros((3, 3))
    for m, p in zip(masses, points):
        r = np.asarray(p, dtype=float) - about
        j += m * (r @ r * np.eye(3) - np.outer(r, r))
    return j


def assert_proper_rotation(r: np.ndarray) -> None:
    assert np.abs(r.T @ r - np.eye(3)).max() < 2e-15
    assert abs(np.linalg.det(r) - 1) < 4e-15
    assert np.allclose(np.cross(r[:, 0], r[:, 1]), r[:, 2], rtol=0, atol=2e-15)


def assert_sign_rule(r: np.ndarray) -> None:
    for k in range(2):
        col = r[:, k]
        dominant = np.argmax(np.abs(col) >= np.abs(col).max() - 1e-9)
        assert col[dominant] > 0


# --- the seed's worked example (slides 13-14) -----------------------------------------------------
def test_seed_cuboid_principal_axes():
    """The 3x2x2 cuboid of mass 12 turned 30° about z: J = Rz diag(8, 13, 13) Rzᵀ."""
    j = np.array([[9.25, -5 * math.sin(math.pi / 6) * math.cos(math.pi / 6), 0.0],
                  [-5 * math.sin(math.pi / 6) * math.cos(math.pi / 6), 11.75, 0.0],
                  [0.0, 0.0, 13.0]])
    moments, axes = principal_axes(j)
    assert np.allclose(moments, [8, 13, 13], rtol=0, atol=1e-13)
    c, s = math.cos(math.pi / 6), math.sin(math.pi / 6)
    assert np.allclose(axes, [[c, -s, 0], [s, c, 0], [0, 0, 1]], rtol=0, atol=1e-12)
    assert_proper_rotation(axes)


# --- non-degenerate tensors -----------------------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(q=quaternions, gaps=st.tuples(st.floats(1e-3, 1.0), st.floats(1e-3, 1.0)),
       scale=st.sampled_from([1e-20, 1.0, 1e15]))
def test_distinct_moments_recovered_with_signs(q, gaps, scale):
    """J = Q diag(m) Qᵀ: the columns are ±Q's columns, signed by the rule, det +1."""
    m = scale * np.array([1.0, 1.0 + gaps[0], 1.0 + gaps[0] + gaps[1]])
    rot = rotation_from_quaternion(q)
    moments, axes = principal_axes(rot @ np.diag(m) @ rot.T)
    assert np.allclose(moments, m, rtol=1e-13, atol=0)
    for k in range(3):
        assert abs(abs(axes[:, k] @ rot[:, k]) - 1) < 1e-11
    assert_proper_rotation(axes)
    assert_sign_rule(axes)
    residual = axes.T @ (rot @ np.diag(m) @ rot.T) @ axes - np.diag(moments)
    assert np.abs(residual).max() < 2e-15 * m[2]


def test_sign_tie_first_component_decides():
    """Axis (1, -1, 0)/√2: the two components tie, the first is made positive."""
    u = np.array([1.0, -1.0, 0.0]) / math.sqrt(2)
    v = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
    basis = np.column_stack([u, v, [0.0, 0.0, 1.0]])
    j = basis @ np.diag([1.0, 2.0, 3.0]) @ basis.T
    for noise in (0.0, 1e-14, -1e-14):
        _, axes = principal_axes(j + noise * np.array([[1, 2, 0], [2, -1, 0], [0, 0, 0]]))
        assert np.allclose(axes[:, 0], u, atol=1e-12)
        assert np.allclose(axes[:, 1], v, atol=1e-12)
        assert np.allclose(axes[:, 2], [0, 0, 1], atol=1e-12)


# --- degenerate tensors ---------------------------------------------------------------------------
@pytest.mark.parametrize("j", [np.eye(3) * 4.0, np.eye(3) * 4.0 * (1 + 1e-12 * np.arange(3)),
                               np.zeros((3, 3))], ids=["cube", "cube-with-roundoff", "zero"])
def test_three_equal_moments_give_identity(j):
    moments, axes = principal_axes(j)
    assert np.array_equal(axes, np.eye(3))
    assert np.allclose(moments, np.diag(j), rtol=1e-11)


@pytest.mark.parametrize("moments, expected", [
    ([5.0, 5.0, 9.0], np.eye(3)),                                 # z-cylinder, squat: I_z largest
    ([5.0, 5.0, 1.0], np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0]])),  # long: I_z smallest
], ids=["z-disc", "z-rod"])
def test_z_cylinder_keeps_the_mesh_axes(moments, expected):
    got_moments, axes = principal_axes(np.diag(moments))
    assert np.allclose(got_moments, sorted(moments))
    assert np.array_equal(axes, expected.astype(float))


def test_tilted_cylinder_uses_the_mesh_axis_in_its_plane():
    """Axis u = (1, 1, 0)/√2 of a rod: e_z lies in the plane of the two equal moments and is kept.

    The pair is ordered by dominant component: u × e_z = (1, -1, 0)/√2 (x and y tie, x decides,
    x positive) comes first, so the frame closes with col0 × col1 = -e_z.
    """
    u = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
    j = 7.0 * np.eye(3) - 5.0 * np.outer(u, u)     # moment 2 about u, 7 about any normal to u
    moments, axes = principal_axes(j)
    assert np.allclose(moments, [2, 7, 7])
    assert np.allclose(axes[:, 0], u, atol=1e-14)
    assert np.allclose(axes[:, 1], [1 / math.sqrt(2), -1 / math.sqrt(2), 0], atol=1e-14)
    assert np.allclose(axes[:, 2], [0, 0, -1], atol=1e-14)
    assert_proper_rotation(axes)


@settings(max_examples=60, deadline=None)
@given(q=quaternions, kind=st.sampled_from(["distinct", "low pair", "high pair", "triple"]),
       noise=st.lists(st.floats(-1, 1), min_size=6, max_size=6))
def test_axes_stable_under_roundoff(q, kind, noise):
    """A 1e-14 relative perturbation moves no axis by more than 1e-9, degenerate or not."""
    m = {"distinct": [1.0, 2.0, 3.5], "low pair": [1.0, 1.0, 3.0],
         "high pair": [1.0, 3.0, 3.0], "triple": [2.0, 2.0, 2.0]}[kind]
    rot = rotation_from_quaternion(q)
    j = rot @ np.diag(m) @ rot.T
    n = np.zeros((3, 3))
    n[np.triu_indices(3)] = noise
    n = n + n.T
    moments, axes = principal_axes(j)
    moments2, axes2 = principal_axes(j * (1 + 1e-14 * n))
    assert np.abs(axes2 - axes).max() <= 1e-9
    assert np.abs(moments2 - moments).max() <= 1e-12 * max(m)
    assert_proper_rotation(axes)
    assert_sign_rule(axes)
    assert np.abs(axes @ np.diag(moments) @ axes.T - j).max() < 1e-12 * max(m)


def test_rejects_bad_input():
    with pytest.raises(UnphysicalInertiaError, match="3x3"):
        principal_axes(np.eye(2))
    with pytest.raises(UnphysicalInertiaError, match="finite"):
        principal_axes(np.diag([1.0, np.nan, 1.0]))


# --- change of axes ------------------------------------------------------------------------------
@settings(max_examples=30, deadline=None)
@given(q=quaternions)
def test_rotate_inertia_matches_rotated_point_masses(q):
    """v_a = A v_b for every point ⇒ J_a (summed from the rotated points) = A J_b Aᵀ."""
    rng = np.random.default_rng(0)
    pts, masses = rng.standard_normal((7, 3)), rng.random(7) + 0.1
    a = rotation_from_quaternion(q)
    j_b = point_inertia(masses, pts, np.zeros(3))
    j_a = point_inertia(masses, pts @ a.T, np.zeros(3))
    assert np.allclose(rotate_inertia(j_b, a), j_a, rtol=0, atol=1e-13 * np.abs(j_a).max())
    assert np.array_equal(rotate_inertia(j_b, a), rotate_inertia(j_b, a).T)


# --- change of reference point --------------------------------------------------------------------
def test_parallel_axis_matches_point_masses_about_another_point():
    rng = np.random.default_rng(1)
    pts, masses = rng.standard_normal((9, 3)), rng.random(9) + 0.1
    m = masses.sum()
    com = masses @ pts / m
    point = np.array([3.0, -2.0, 0.5])
    j_com = point_inertia(masses, pts, com)
    j_point = point_inertia(masses, pts, point)
    assert np.allclose(parallel_axis(j_com, m, point - com), j_point, rtol=0, atol=1e-12)
    assert np.allclose(parallel_axis_to_com(j_point, m, point - com), j_com, rtol=0, atol=1e-12)


def test_parallel_axis_keeps_a_tiny_moment_along_the_offset():
    """A needle's 1e-12 axial moment survives a 1e3 m shift along its axis and back exactly."""
    j = np.diag([1e-12, 1.0, 1.0])
    there = parallel_axis(j, 2.0, [1e3, 0.0, 0.0])
    assert there[0, 0] == 1e-12 and there[1, 1] == 1.0 + 2e6
    back = parallel_axis_to_com(there, 2.0, [1e3, 0.0, 0.0])
    assert back[0, 0] == 1e-12
