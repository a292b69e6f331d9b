"""Primitive solids against independent truth: textbook closed forms in exact arithmetic, and
slice-by-slice quadrature of the solid (discs and ellipses stacked along the axis)."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from scipy.integrate import quad

from massprops.robot.inertials.primitives import (
    PRIMITIVES,
    box,
    capsule,
    cylinder,
    ellipsoid,
    sphere,
)


def test_box_exact_in_fractions():
    a, b, c = Fraction(3, 10), Fraction(1, 5), Fraction(7, 20)
    s = box(float(a), float(b), float(c))
    v = a * b * c
    expected = [v * (b * b + c * c) / 12, v * (a * a + c * c) / 12, v * (a * a + b * b) / 12]
    assert s.volume == pytest.approx(float(v), rel=2e-15)
    assert np.allclose(np.diag(s.inertia), [float(e) for e in expected], rtol=2e-15, atol=0)
    assert np.count_nonzero(s.inertia - np.diag(np.diag(s.inertia))) == 0


def _stack(radius_x, radius_y, z0, z1):
    """Volume, J_xx, J_yy, J_zz (unit density) of a solid of elliptic slices with semi-axes
    radius_x(z), radius_y(z), centred on the z axis: a slice of area πab has ∫x² = πa³b/4."""
    def area(z):
        return math.pi * radius_x(z) * radius_y(z)

    def x2(z):
        return math.pi * radius_x(z) ** 3 * radius_y(z) / 4

    def y2(z):
        return math.pi * radius_x(z) * radius_y(z) ** 3 / 4

    def q(f):
        return quad(f, z0, z1, epsabs=0, epsrel=2e-14, limit=200)[0]

    v = q(area)
    z2 = q(lambda z: area(z) * z * z)
    return v, q(y2) + z2, q(x2) + z2, q(lambda z: x2(z) + y2(z))


def _check(solid, truth):
    v, jxx, jyy, jzz = truth
    assert solid.volume == pytest.approx(v, rel=1e-12)
    assert np.allclose(np.diag(solid.inertia), [jxx, jyy, jzz], rtol=1e-12, atol=0)


def test_sphere_by_slices_and_formula():
    r = 0.37
    s = sphere(r)
    def disc(z):
        return math.sqrt(max(0.0, r * r - z * z))

    _check(s, _stack(disc, disc, -r, r))
    assert s.inertia[0, 0] == pytest.approx(2 / 5 * (4 / 3 * math.pi * r**3) * r * r, rel=1e-15)


def test_cylinder_by_slices():
    r, length = 0.2, 0.9
    _check(cylinder(r, length), _stack(lambda z: r, lambda z: r, -length / 2, length / 2))


@pytest.mark.parametrize("length", [0.0, 0.05, 0.4, 3.0])
def test_capsule_by_slices(length):
    r = 0.12
    h = length / 2

    def radius(z):
        over = max(0.0, abs(z) - h)
        return math.sqrt(max(0.0, r * r - over * over))

    truth = _stack(radius, radius, -h - r, h + r)
    _check(capsule(r, length), truth)


def test_capsule_of_zero_length_is_the_sphere():
    assert np.allclose(capsule(0.3, 0.0).inertia, sphere(0.3).inertia, rtol=1e-15, atol=0)


def test_ellipsoid_by_slices():
    a, b, c = 0.3, 0.1, 0.5

    def shrink(z):
        return math.sqrt(max(0.0, 1 - (z / c) ** 2))

    _check(ellipsoid(a, b, c), _stack(lambda z: a * shrink(z), lambda z: b * shrink(z), -c, c))


@pytest.mark.parametrize("kind,dims", [("box", (0.3, 0.1, 0.5)), ("sphere", (0.2,)),
                                       ("cylinder", (0.1, 0.6)), ("capsule", (0.1, 0.6)),
                                       ("ellipsoid", (0.3, 0.1, 0.5))])
def test_half_extents_bound_the_turned_surface_tightly(kind, dims):
    """The axis-aligned box after a rotation, against points sampled on the turned surface."""
    rng = np.random.default_rng(7)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    from massprops.rotation import quat_to_matrix

    a = quat_to_matrix(q)
    solid = PRIMITIVES[kind](*dims)
    d = rng.normal(size=(200000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    if kind == "box":
        pts = np.clip(d * 10, -1, 1) * np.array(dims) / 2
    elif kind == "sphere":
        pts = d * dims[0]
    elif kind == "ellipsoid":
        pts = d * np.array(dims)
    else:
        r, half = dims[0], dims[1] / 2
        pts = d * r
        if kind == "capsule":
            pts[:, 2] += np.sign(pts[:, 2]) * half
        else:  # cylinder: the rim circles are where the extremes lie
            pts[:, :2] = d[:, :2] / np.linalg.norm(d[:, :2], axis=1)[:, None] * r
            pts[:, 2] = np.sign(d[:, 2]) * half
    reach = np.abs(pts @ a.T).max(axis=0)
    half_ext = solid.half_extents(a)
    assert np.all(reach <= half_ext * (1 + 1e-12))
    assert np.all(reach >= half_ext * (1 - 2e-3))  # sampling gets within a hair of the bound


@pytest.mark.parametrize("bad", [(0.0, 1.0, 1.0), (-1.0, 1.0, 1.0), (float("nan"), 1.0, 1.0)])
def test_non_positive_dimensions_refused(bad):
    with pytest.raises(ValueError, match="positive"):
        box(*bad)
