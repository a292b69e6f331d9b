"""--shell against closed forms: flat polygon plates (exact), a mitred polygonal tube (exact), a
closed box of plates (mitred box shell minus its corner cubes: exact), a spherical shell (the
thick formula, within the model's bar and the tessellation's bracket); invariances."""

from __future__ import annotations

import math

import numpy as np
import pytest
from exact_moments import box as exact_box
from exact_moments import polygon_plate, prism, regular_polygon, spherical_shell
from repair_meshes import (
    BOX_TRIANGLES,
    fan_disc,
    hemisphere_bowl,
    icosphere,
    moved,
    polygon_tube,
    rotation,
)
from test_repair_union import bars

from massprops.errors import DegenerateMeshError, MeshFormatError, UsageError
from massprops.inspection.file import inspect_mesh
from massprops.mesh import Mesh
from massprops.repair import RepairOptions
from massprops.repair.shell import shell_properties


def shell(t: float) -> RepairOptions:
    return RepairOptions(shell=t)


def test_flat_polygon_plate_is_exact_in_any_pose():
    """A regular 7-gon plate (fanned from its centre), thickness T: mass ρTA, in-plane moments
    ρT ∫ y² + ρ A T³/12, normal moment ρT ∫(x² + y²) (exact polygon integrals), then turned and
    moved far away: J -> R J Rᵀ. The model's bar is zero: nothing turns."""
    xy = regular_polygon(7, 0.3) + [0.05, -0.02]
    t, rho = 0.004, 2700.0
    area, (fx, fy), (xx, yy, xy2) = polygon_plate(xy)
    a = float(area)
    c = np.array([float(fx / area), float(fy / area), 0.0])
    sxx, syy = float(xx) - a * c[0] ** 2, float(yy) - a * c[1] ** 2
    sxy = float(xy2) - a * c[0] * c[1]
    j = rho * t * np.array([[syy + a * t * t / 12, -sxy, 0], [-sxy, sxx + a * t * t / 12, 0],
                            [0, 0, sxx + syy]])
    r, shift = rotation((1, -2, 0.5), 0.8), np.array([1e3, 2e3, -5e2])
    # moved, the plate's coordinates are rounded at 1e3 m: a relative 1e-13 of its size
    for mesh, rot, move, tol in ((fan_disc(xy), np.eye(3), np.zeros(3), 1e-14),
                                 (moved(fan_disc(xy), r, shift), r, shift, 1e-11)):
        p = inspect_mesh(mesh, density=rho, repairs=shell(t)).properties
        b = bars(p)
        assert p.mass == pytest.approx(rho * t * a, rel=tol)
        np.testing.assert_allclose(p.center_of_mass, rot @ c + move, rtol=0, atol=1e-12)
        np.testing.assert_allclose(p.inertia, rot @ j @ rot.T, rtol=0,
                                   atol=tol * np.abs(j).max() + b["inertia"].max())
        assert p.uncertainty.repair.mass < 1e-12 * p.mass


def test_polygonal_tube_is_the_mitred_tube_exactly():
    """The side of a regular 12-gon prism as mid-surface: the mitred wall is the prism of apothem
    a + T/2 minus the prism of apothem a - T/2, with no corners (the rims are cut square)."""
    n, a, h, t = 12, 0.5, 1.3, 0.06
    truth = prism(regular_polygon(n, a + t / 2), 0, h) - prism(regular_polygon(n, a - t / 2), 0, h)
    p = shell_properties(polygon_tube(n, a, h), t).properties
    b = bars(p)
    assert p.volume == pytest.approx(float(truth.volume), rel=1e-13)
    np.testing.assert_allclose(p.center_of_mass, truth.com(), atol=1e-13)
    np.testing.assert_allclose(p.inertia, truth.inertia(), rtol=0, atol=1e-13)
    # the bar says how much a bent (round) join could differ, and contains the truth
    assert np.all(np.abs(p.inertia - truth.inertia()) <= b["inertia"] + 1e-13)
    assert 0 < b["inertia"].max() < 0.01 * np.abs(truth.inertia()).max()


def test_round_tube_formula_is_within_the_bar_for_a_fine_polygon():
    """A 256-gon tube against the round thick tube: J_zz = m (Ro² + Ri²)/2 with the polygon's
    mid-radius; the difference is the polygon's (bounded by the circumradius/apothem spread)."""
    n, a, h, t = 256, 0.5, 1.0, 0.02
    p = shell_properties(polygon_tube(n, a, h), t).properties
    ro, ri = a + t / 2, a - t / 2
    m = math.pi * (ro**2 - ri**2) * h
    jz = m * (ro**2 + ri**2) / 2
    spread = (1 / math.cos(math.pi / n)) ** 4 - 1  # circumradius vs apothem, to the 4th power
    assert p.inertia[2, 2] == pytest.approx(jz, rel=spread + bars(p)["inertia"][2, 2] / jz)


def test_closed_box_of_plates_is_the_mitred_box_shell_minus_its_corner_cubes():
    """Cube [-1/2, 1/2]³ as mid-surface, wall T: the mitred wall is the box of side 1 + T minus
    the box of side 1 - T. The model joins faces at edges but not at the 8 corners, where it
    misses one cube of side T/2 outside and one inside. So model + 16 cubes = the mitred shell,
    exactly; and the model is within its bar of the mitred shell."""
    t = 0.08
    v = np.array([[(i >> 2) & 1, (i >> 1) & 1, i & 1] for i in range(8)], dtype=float) - 0.5
    cube = Mesh(v, BOX_TRIANGLES.astype(np.int64), name="cube")
    hi, lo = 0.5 + t / 2, 0.5 - t / 2
    shell_truth = exact_box([-hi] * 3, [hi] * 3) - exact_box([-lo] * 3, [lo] * 3)
    corners = None
    for sx in (-1, 1):
        for sy in (-1, 1):
            for sz in (-1, 1):
                s = np.array([sx, sy, sz])
                for near, far in ((0.5, hi), (lo, 0.5)):
                    a, b = s * near, s * far
                    c = exact_box(np.minimum(a, b), np.maximum(a, b))
                    corners = c if corners is None else corners + c
    p = shell_properties(cube, t).properties
    model = shell_truth - corners
    assert p.volume == pytest.approx(float(model.volume), rel=1e-14)
    np.testing.assert_allclose(p.inertia, model.inertia(), atol=1e-14)
    b = bars(p)
    assert abs(p.volume - float(shell_truth.volume)) <= b["volume"]
    assert np.all(np.abs(p.inertia - shell_truth.inertia()) <= b["inertia"])


@pytest.mark.parametrize("subdivisions", [3, 4])
def test_spherical_shell_thick_formula_within_bar_and_tessellation(subdivisions):
    """Icosphere of circumradius 1 (vertices on the sphere) as mid-surface, T = 0.04. The exact
    thick shell (2/5) m (Ro⁵ - Ri⁵)/(Ro³ - Ri³) of the round sphere must lie within the model's
    bar of the result once the polyhedron's own departure from the sphere is allowed for: the
    surface lies between its inradius r and 1, so its area and ∫|x|² dA lie between those of
    the spheres of radius r and 1."""
    t = 0.04
    mesh = icosphere(subdivisions)
    p = shell_properties(mesh, t).properties
    tri = mesh.vertices[mesh.faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    inradius = float(np.min(np.abs(np.einsum("ij,ij->i", normal, tri[:, 0]))
                            / np.linalg.norm(normal, axis=1)))
    b = bars(p)
    m_lo, j_lo = spherical_shell(inradius - t / 2, inradius + t / 2)
    m_hi, j_hi = spherical_shell(1 - t / 2, 1 + t / 2)
    assert m_lo - b["mass"] <= p.mass <= m_hi + b["mass"]
    assert np.all((j_lo - b["principal_moments"] <= p.principal_moments)
                  & (p.principal_moments <= j_hi + b["principal_moments"]))
    # the thin-wall model's own error is O((T/R)²): the bar is of that order, not O(T/R)
    assert b["principal_moments"].max() < 2 * (t / 1) ** 2 * j_hi
    assert b["principal_moments"].max() > 5 / 12 * (t / 1) ** 2 * j_hi * 0.5


def test_open_bowl_and_sheet_give_numbers_with_bars():
    """An open hemispherical bowl and a flat sheet: numbers
    with bars. The bowl's mass is ρT times its area (summed here with numpy), its COM about half
    way up (a thin hemisphere's is at R/2), and about the axis J ≈ 2/3 m R²."""
    bowl = hemisphere_bowl()
    p = inspect_mesh(bowl, density=1000, repairs=shell(0.002)).properties
    tri = bowl.vertices[bowl.faces]
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum() / 2
    assert p.mass == pytest.approx(1000 * 0.002 * area, rel=1e-13)
    assert p.center_of_mass[2] == pytest.approx(0.5, rel=0.05)
    assert p.inertia[2, 2] == pytest.approx(2 / 3 * p.mass, rel=0.02)
    b = bars(p)
    assert 0 < b["mass"] < 1e-3 * p.mass
    sheet = fan_disc(np.array([[0, 0], [2, 0], [2, 1], [0, 1.0]]))
    q = inspect_mesh(sheet, density=7850, repairs=shell(0.001)).properties
    assert q.mass == pytest.approx(7850 * 0.001 * 2, rel=1e-14)


def test_mass_given_sets_the_density():
    xy = regular_polygon(5, 1.0)
    a = shell_properties(fan_disc(xy), 0.01, density=3.0).properties
    b = shell_properties(fan_disc(xy), 0.01, mass=6.0).properties
    assert b.mass == 6.0 and b.density == pytest.approx(6.0 / a.volume, rel=1e-15)
    np.testing.assert_allclose(b.inertia, a.inertia * (6.0 / a.mass), rtol=1e-14)


def test_refusals():
    with pytest.raises(UsageError, match="shell thickness must be a positive finite number"):
        shell_properties(fan_disc(regular_polygon(4, 1.0)), -1.0)
    line = Mesh(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]]), np.array([[0, 1, 2]]), name="l")
    with pytest.raises(DegenerateMeshError, match="l: the surface has no area"):
        shell_properties(line, 0.01)
    bad = fan_disc(regular_polygon(4, 1.0))
    bad.vertices[0, 0] = np.nan
    with pytest.raises(MeshFormatError, match="disc: expected finite vertex coordinates"):
        shell_properties(bad, 0.01)


def test_a_thick_wall_is_warned():
    result = inspect_mesh(icosphere(2), repairs=shell(0.3))
    assert any(w.startswith("the thin-wall model is uncertain by up to") for w in result.warnings)
