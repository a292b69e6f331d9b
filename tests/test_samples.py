"""The bundled samples against the closed forms of sample_meshes/README.md, evaluated here."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import SAMPLES, rot_z

from massprops.inspection.file import inspect_file


def cuboid():
    r = rot_z(30.0)
    return 12.0, np.zeros(3), r @ np.diag([8.0, 13.0, 13.0]) @ r.T


def cube():
    return 1.0, np.full(3, 0.5), np.eye(3) / 6


def tetrahedron(a=1.0, b=2.0, c=3.0):
    v = a * b * c / 6
    j = np.array([[3 * (b * b + c * c), a * b, a * c],
                  [a * b, 3 * (a * a + c * c), b * c],
                  [a * c, b * c, 3 * (a * a + b * b)]]) * v / 80
    return v, np.array([a, b, c]) / 4, j


def prism(n=6, r=1.0, h=2.0):
    alpha = 2 * math.pi / n
    area = n / 2 * r * r * math.sin(alpha)
    polar = n * r**4 * math.sin(alpha) * (2 + math.cos(alpha)) / 12
    jxx = h * polar / 2 + area * h**3 / 12
    return area * h, np.zeros(3), np.diag([jxx, jxx, h * polar])


def torus(n=24, big=2.0, a=0.5):
    alpha = 2 * math.pi / n
    ns = n * math.sin(alpha)
    kappa = 1 - (1 - math.cos(alpha)) / 3
    i_r, i_r3, i_rz2 = 4 * a * a * big, 4 * a * a * big * (big**2 + a * a), 4 * a**4 * big / 3
    jxx = ns * (kappa * i_r3 / 2 + i_rz2)
    return ns * i_r, np.zeros(3), np.diag([jxx, jxx, ns * kappa * i_r3])


CASES = {"cuboid.vf": cuboid, "cuboid.vtx": cuboid, "cuboid.obj": cuboid, "cube.obj": cube,
         "tetrahedron.obj": tetrahedron, "prism.obj": prism, "torus.obj": torus}


@pytest.mark.parametrize("name", CASES)
def test_sample_matches_closed_form(name):
    volume, com, inertia = CASES[name]()
    got = inspect_file(SAMPLES / name).properties
    size = math.sqrt(np.trace(inertia) / volume)  # a radius of gyration
    assert abs(got.volume - volume) <= 1e-14 * volume
    assert np.max(np.abs(got.center_of_mass - com)) <= 1e-14 * size + 1e-16 * np.abs(com).max()
    assert np.max(np.abs(got.inertia - inertia)) <= 1e-14 * np.abs(inertia).max()
    # the rounding error bars must cover the true error
    bars = got.uncertainty.rounding
    assert abs(got.volume - volume) <= bars.volume
    assert np.all(np.abs(got.inertia - inertia) <= np.asarray(bars.inertia) + 1e-300)
    assert got.uncertainty.input is None


def test_sample_stl_is_float32_with_input_bar():
    volume, _, inertia = cuboid()
    got = inspect_file(SAMPLES / "cuboid.stl").properties
    unc = got.uncertainty
    assert unc.input is not None
    assert abs(got.volume - volume) <= unc.input.volume + unc.rounding.volume
    assert unc.input.volume < 1e-5 * volume  # float32 leaves ~1e-7 relative, not more
