"""CAD solids against closed forms: exact on analytic faces at any offset and size; on NURBS
faces the integration bar holds (true error within it, and it within 100x of the true error)."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("OCP")

import cadparts as cp  # noqa: E402

from massprops.cad.integrate import integrate_solid  # noqa: E402
from massprops.cad.read import read_cad  # noqa: E402

# powers of two: a solid made at such an offset is stored exactly (its corners are exact sums),
# so the closed forms are the truth of the file and any error is the integral's
SIZES = (2.0**-20, 1.0, 2.0**10)          # ~1e-6 m, 1 m, ~1e3 m
OFFSETS = (0.0, 2.0**14, 2.0**27)         # up to ~1.3e8 sizes away
KINDS = ("box", "cylinder", "sphere", "torus", "cone")


def _check(integral, volume, com, diag, scale=1.0, rtol=1e-13, exact_input=True):
    m = integral.moments
    assert m.volume == pytest.approx(volume * scale**3, rel=rtol, abs=0)
    got_com = integral.origin + m.com_local
    size = volume ** (1 / 3) * scale
    assert np.max(np.abs(got_com - np.asarray(com) * scale)) <= rtol * size + np.max(
        np.spacing(np.abs(got_com)))
    inertia = m.inertia
    big = max(diag) * scale**5
    assert np.max(np.abs(np.diag(inertia) - np.asarray(diag) * scale**5)) <= rtol * big
    off = inertia - np.diag(np.diag(inertia))
    assert np.max(np.abs(off)) <= rtol * big
    # analytic solids made in memory: the rounding bar alone must hold (a file's printed
    # numbers are the input bar's business)
    if integral.integration is None and exact_input:
        assert abs(m.volume - volume * scale**3) <= m.volume_err
        assert np.all(np.abs(np.diag(inertia) - np.asarray(diag) * scale**5)
                      <= np.diag(m.inertia_err))


@pytest.mark.parametrize("kind", KINDS)
def test_analytic_solids_exact_at_every_size_and_offset(kind):
    for a in SIZES:
        for off in OFFSETS:
            at = np.array([off, -off / 2, off / 4]) * a
            volume, com, diag = cp.closed_forms(kind, a)
            integral = integrate_solid(cp.make(kind, a, tuple(at)), 1.0, kind)
            assert integral.integration is None  # all faces analytic
            _check(integral, volume, at + np.asarray(com), diag)


def test_drilled_and_filleted_boxes_exact_far_away():
    a, r = 1.0, 0.25
    hole = math.pi * (a / 2) ** 2 * 2 * a
    for off in OFFSETS:
        at = np.array([off, off / 2, -off]) * a
        centre = at + a
        drilled = integrate_solid(cp.drilled_box(a, tuple(at)), 1.0, "drilled")
        s = 2 * a
        ixx = s**3 * (s * s + s * s) / 12 - hole * (3 * (a / 2) ** 2 + (2 * a) ** 2) / 12
        izz = s**5 / 6 - hole * (a / 2) ** 2 / 2
        _check(drilled, s**3 - hole, centre, (ixx, ixx, izz))
        filleted = integrate_solid(cp.filleted_box(a, r, tuple(at)), 1.0, "filleted")
        volume, diag = cp.filleted_box_forms(a, r)
        assert filleted.faces.get("cylinder") == 4
        _check(filleted, volume, centre, diag)


def test_step_and_brep_files_keep_far_parts_exact(tmp_path):
    a, off = 0.5, 2.0**26
    at = (off * a, 0.0, -off * a)
    volume, com, diag = cp.closed_forms("torus", a)
    shape = cp.make("torus", a, at)
    cp.write_step(shape, tmp_path / "t.step", "M")
    cp.write_brep(shape, tmp_path / "t.brep")
    for name in ("t.step", "t.brep"):
        cad = read_cad(tmp_path / name)
        assert cad.unit == "m" and len(cad.solids) == 1
        _check(integrate_solid(cad.solids[0].shape, cad.scale, name), volume,
               np.asarray(at) + com, diag, exact_input=False)


def test_millimetre_step_converts_after_integrating(tmp_path):
    a = 7.0   # mm
    at = (2.0**20, 0.0, 0.0)
    volume, com, diag = cp.closed_forms("cylinder", a)
    cp.write_step(cp.make("cylinder", a, at), tmp_path / "c.step", "MM")
    cad = read_cad(tmp_path / "c.step")
    assert (cad.unit, cad.scale) == ("mm", 0.001)
    _check(integrate_solid(cad.solids[0].shape, cad.scale, "c"), volume,
           np.asarray(at) + com, diag, scale=0.001, exact_input=False)


@pytest.mark.parametrize("kind", ("sphere", "torus", "cylinder", "cone", "box"))
def test_nurbs_forms_exact_with_an_honest_bar(kind):
    """NURBS forms of the analytic solids: the faces whose domain is their parameter rectangle
    (a sphere's, a torus's, a cylinder's wall) by our own rule, the trimmed caps by
    OpenCASCADE's adaptive one; the 1e-12 target met with room, the true error within the bar
    and the bar within 100x of the error (or of the rounding bar, below which no error can be
    told apart)."""
    for a in (2.0**-20, 1.0):
        integral = integrate_solid(cp.nurbs(cp.make(kind, a)), 1.0, kind)
        assert integral.faces.get("bspline", 0) >= 1
        assert integral.method == "own"   # flat spline faces (caps) by Green's theorem
        volume, com, diag = cp.closed_forms(kind, a)
        bar_v, bar_c, bar_j = integral.integration
        m = integral.moments
        err_v = abs(m.volume - volume)
        err_j = np.abs(np.diag(m.inertia) - np.asarray(diag))
        assert err_v <= 1e-13 * volume and np.max(err_j) <= 1e-13 * max(diag)
        assert err_v <= bar_v + m.volume_err
        assert bar_v <= 100 * max(err_v, m.volume_err)
        bar_jd, round_jd = np.diag(bar_j), np.diag(m.inertia_err)
        assert np.all(err_j <= bar_jd + round_jd)
        assert np.all(bar_jd <= 100 * np.maximum(err_j, round_jd))
        assert np.max(np.abs(integral.origin + m.com_local - com)) <= 1e-13 * a + np.max(
            bar_c + m.com_local_err)


def test_flat_nurbs_faces_with_holes_are_ours():
    """NURBS forms of the drilled and the filleted box: flat spline faces with a hole or rounded
    corners (ours, by Green's theorem along their edges), the hole's wall and the fillets
    (rectangles: ours); the closed forms within the bars, the bars within 100x."""
    a, r = 1.0, 0.25
    hole = math.pi * (a / 2) ** 2 * 2 * a
    s = 2 * a
    ixx = s**3 * (s * s + s * s) / 12 - hole * (3 * (a / 2) ** 2 + (2 * a) ** 2) / 12
    izz = s**5 / 6 - hole * (a / 2) ** 2 / 2
    cases = ((cp.drilled_box(a), s**3 - hole, (ixx, ixx, izz)),
             (cp.filleted_box(a, r), *cp.filleted_box_forms(a, r)))
    for shape, volume, diag in cases:
        integral = integrate_solid(cp.nurbs(shape), 1.0, "box")
        assert integral.method == "own"
        m = integral.moments
        bar_v, _, bar_j = integral.integration
        err_v = abs(m.volume - volume)
        assert err_v <= min(bar_v + m.volume_err, 1e-13 * volume)
        assert bar_v <= max(100 * err_v, 1e-13 * volume)
        err_j = np.abs(np.diag(m.inertia) - np.asarray(diag))
        assert np.all(err_j <= np.minimum(np.diag(bar_j + m.inertia_err), 1e-13 * max(diag)))
        assert np.all(np.diag(bar_j) <= np.maximum(100 * err_j, 1e-13 * max(diag)))


@pytest.mark.parametrize("form", ("analytic", "nurbs"))
def test_trimmed_walls_are_ours_and_add_up(form, tmp_path):
    """A cylinder cut by an oblique plane: its wall trimmed by an ellipse (not a parameter line:
    the fixed rule was 1.5e-9 off there with no bar), by our trimmed-face rule, the caps by
    Green's theorem; the closed forms within the bars. The wall's boundary in its parameters is
    a B-spline fitted to 1e-7 (the file's tolerance), so the truth holds within the input bar,
    not the integration bar alone."""
    from massprops.cad.inspect import inspect_cad

    r, h, m = 1.0, 2.0, 0.5
    shape = cp.slanted_cylinder(r, h, m)
    cp.write_brep(shape if form == "analytic" else cp.nurbs(shape), tmp_path / "s.brep")
    solid = inspect_cad(tmp_path / "s.brep").solids[0]
    assert solid.integral.method == "own" and solid.integration is not None
    volume, com, inertia = cp.slanted_cylinder_forms(r, h, m)
    bars = (solid.integration, solid.input, solid.properties.uncertainty.rounding)
    p = solid.properties
    assert abs(p.volume - volume) <= sum(b.volume for b in bars)
    assert abs(p.volume - volume) <= 1e-9 * volume   # the parts add up: no cone missing
    assert np.all(np.abs(p.center_of_mass - com) <= sum(b.center_of_mass for b in bars))
    assert np.all(np.abs(p.inertia - np.asarray(inertia)) <= sum(b.inertia for b in bars))


@pytest.mark.parametrize("kind", ("sphere", "cylinder"))
def test_far_nurbs_forms_within_their_bars(kind, tmp_path):
    """Moved 2^27 sizes away, the poles are stored rounded to that distance's ulps (the file
    holds them so: ~1e-9 in volume): the input bar covers that, and the integration bar stays
    at round-off."""
    from massprops.cad.inspect import inspect_cad

    a, off = 1.0, 2.0**27
    at = (off, -off / 2, off / 4)
    cp.write_brep(cp.moved(cp.nurbs(cp.make(kind, a)), at), tmp_path / "far.brep")
    solid = inspect_cad(tmp_path / "far.brep").solids[0]
    volume, com, diag = cp.closed_forms(kind, a)
    bars = (solid.integration, solid.input, solid.properties.uncertainty.rounding)
    assert abs(solid.properties.volume - volume) <= sum(b.volume for b in bars)
    err_j = np.abs(np.diag(solid.properties.inertia) - np.asarray(diag))
    assert np.all(err_j <= sum(np.diag(b.inertia) for b in bars))
    assert solid.integration.volume <= 1e-13 * volume


def test_far_nurbs_input_bar_covers_the_rounded_poles(tmp_path):
    """A NURBS torus moved 1e10 sizes out has its poles rounded to the coordinates' ulps,
    each on its own: its volume moves by ~1e-6 (the file holds those rounded poles, so this is
    input, not integration), and the input bar covers it."""
    from massprops.cad.inspect import inspect_cad

    volume, _, _ = cp.closed_forms("torus", 1.0)
    far = 1e10
    shape = cp.moved(cp.nurbs(cp.make("torus", 1.0)), (0.7 * far, -0.3 * far, far))
    cp.write_brep(shape, tmp_path / "far.brep")
    solid = inspect_cad(tmp_path / "far.brep").solids[0]
    assert solid.integral.valid is True
    bars = (solid.integration, solid.input, solid.properties.uncertainty.rounding)
    error = abs(solid.properties.volume - volume)
    assert error > 10 * solid.integration.volume     # the poles' rounding dominates
    assert error <= sum(b.volume for b in bars) <= 1e-4 * volume


def test_nurbs_rule_in_small_blocks_agrees(monkeypatch):
    """A surface of many spans is evaluated in blocks of u rows: blocks of a few points give
    the same moments (to round-off) as one block."""
    import massprops.cad.nurbs as nurbs

    shape = cp.nurbs(cp.make("torus", 1.0))
    whole = integrate_solid(shape, 1.0, "torus")
    monkeypatch.setattr(nurbs, "_BLOCK_POINTS", 7)
    blocked = integrate_solid(shape, 1.0, "torus")
    volume, _, diag = cp.closed_forms("torus", 1.0)
    assert blocked.moments.volume == pytest.approx(whole.moments.volume, rel=1e-14)
    assert blocked.moments.volume == pytest.approx(volume, rel=1e-14)
    assert np.allclose(np.diag(blocked.moments.inertia), diag, rtol=1e-14, atol=0)


def test_lofted_bspline_wall_with_analytic_caps_agrees_with_opencascade():
    """A loft through three circles: one B-spline wall and two planar caps (both ours), added
    as cones from one apex. The loft approximates the frustum (2.4e-9 off,
    inside the file's 1e-7 tolerance: the input bar), so the check is against OpenCASCADE's
    own finest level on the same surfaces, within both bars."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire
    from OCP.BRepGProp import BRepGProp
    from OCP.BRepOffsetAPI import BRepOffsetAPI_ThruSections
    from OCP.gp import gp_Ax2, gp_Circ, gp_Dir, gp_Pnt
    from OCP.GProp import GProp_GProps

    loft = BRepOffsetAPI_ThruSections(True, False)
    for r, z in ((1.0, 0.0), (0.75, 1.0), (0.5, 2.0)):
        edge = BRepBuilderAPI_MakeEdge(gp_Circ(gp_Ax2(gp_Pnt(0, 0, z), gp_Dir(0, 0, 1)), r))
        loft.AddWire(BRepBuilderAPI_MakeWire(edge.Edge()).Wire())
    loft.CheckCompatibility(False)
    loft.Build()
    shape = loft.Shape()
    integral = integrate_solid(shape, 1.0, "loft")
    assert integral.method == "own"   # the wall by the surface rule, the caps by Green's
    levels = []
    for eps in (1e-12, 1e-14):
        props = GProp_GProps()
        BRepGProp.VolumeProperties_s(shape, props, eps, True)
        levels.append((props.Mass(), props.MatrixOfInertia().Value(3, 3)))
    occ_bar_v = 2 * abs(levels[1][0] - levels[0][0]) + 1e-15 * levels[1][0]
    occ_bar_j = 2 * abs(levels[1][1] - levels[0][1]) + 1e-15 * levels[1][1]
    bar_v, _, bar_j = integral.integration
    m = integral.moments
    assert abs(m.volume - levels[1][0]) <= bar_v + m.volume_err + occ_bar_v
    assert abs(m.inertia[2, 2] - levels[1][1]) <= bar_j[2, 2] + m.inertia_err[2, 2] + occ_bar_j
    frustum = math.pi * 2.0 * (1.0 + 0.5 + 0.25) / 3
    assert abs(m.volume / frustum - 1) < 1e-8


def test_a_face_the_rule_does_not_settle_on_goes_to_opencascade(monkeypatch):
    """Orders that never agree (an agreement of 0) up to the last one allowed: the solid goes to
    the adaptive rule, whose bar still holds the error."""
    import massprops.cad.nurbs as nurbs

    monkeypatch.setattr(nurbs, "NURBS_AGREEMENT", 0.0)
    monkeypatch.setattr(nurbs, "NURBS_MAX_ORDER", 17)
    integral = integrate_solid(cp.nurbs(cp.make("sphere", 1.0)), 1.0, "sphere")
    assert integral.method == "adaptive"
    volume, _, _ = cp.closed_forms("sphere", 1.0)
    assert abs(integral.moments.volume - volume) <= integral.integration[0]


@pytest.mark.parametrize("offset", (0.0, 2.0**10))
def test_bspline_prism_bar_covers_the_error_and_says_something(offset):
    """A prism of a periodic cubic B-spline profile: the side a surface of linear extrusion
    (converted exactly, our surface rule), the caps planes bounded by the spline (ours, by
    Green's theorem along it). Truth: the profile's area moments by Green's theorem per span.
    OpenCASCADE's rules left 7.9e-7 (inertia) and 9.6e-9 (COM) with a bar of 3.3e-13."""
    height = 1.5
    at = (offset, -offset / 2, offset / 4)
    integral = integrate_solid(cp.bspline_prism(height=height, at=at), 1.0, "prism")
    assert integral.faces == {"extrusion": 1, "plane": 2} and integral.method == "own"
    a, sx, sy, sxx, syy, sxy = cp.profile_moments(cp.PROFILE)
    cx, cy = sx / a, sy / a
    xx, yy, xy = sxx - a * cx * cx, syy - a * cy * cy, sxy - a * cx * cy
    volume = height * a
    com = np.array([cx + at[0], cy + at[1], at[2] + height / 2])
    side = a * height**3 / 12
    inertia = np.array([[height * yy + side, -height * xy, 0.0],
                        [-height * xy, height * xx + side, 0.0],
                        [0.0, 0.0, height * (xx + yy)]])
    m = integral.moments
    bar_v, bar_c, bar_j = integral.integration
    err_v = abs(m.volume - volume)
    err_c = np.abs(integral.origin + m.com_local - com)
    err_j = np.abs(m.inertia - inertia)
    assert err_v <= bar_v + m.volume_err
    assert np.all(err_c <= bar_c + m.com_local_err + np.spacing(np.abs(com)))
    assert np.all(err_j <= bar_j + m.inertia_err)
    # and the bar says something: within 100x of the error, or at most 1e-13 of the value
    size = volume ** (1 / 3)
    big = np.abs(inertia).max()
    assert bar_v <= max(100 * err_v, 1e-13 * volume)
    assert np.all(bar_c <= np.maximum(100 * err_c, 1e-13 * size))
    assert np.all(bar_j <= np.maximum(100 * err_j, 1e-13 * big))


@pytest.mark.parametrize("kind", ("sphere", "cylinder", "cone", "drilled"))
def test_trimmed_face_rule_on_every_face_against_closed_forms(kind):
    """The trimmed-face rule (Green's theorem in the face's parameters) taking every face of
    NURBS and analytic solids whose boundaries are exact (rectangles, circles: no fitted
    parameter curve), about the closed-form COM: the volume and the second moments against the
    closed forms, within its bar, and the bar within 100x of the error (or 1e-13)."""
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    from massprops.cad.trimmed import trimmed_face

    a = 1.0
    if kind == "drilled":
        hole = math.pi * (a / 2) ** 2 * 2 * a
        s = 2 * a
        ixx = s**3 * (s * s + s * s) / 12 - hole * (3 * (a / 2) ** 2 + (2 * a) ** 2) / 12
        izz = s**5 / 6 - hole * (a / 2) ** 2 / 2
        shape, volume, com, diag = cp.drilled_box(a), s**3 - hole, (a, a, a), (ixx, ixx, izz)
    else:
        shape = cp.make(kind, a)
        volume, com, diag = cp.closed_forms(kind, a)
    for solid in (shape, cp.nurbs(shape)):
        total, bar = np.zeros(14), np.zeros(13)
        explorer = TopExp_Explorer(solid, TopAbs_FACE)
        while explorer.More():
            values, err = trimmed_face(TopoDS.Face(explorer.Current()), np.asarray(com, float))
            total += values
            bar += err
            explorer.Next()
        second = np.sum(diag) / 2 * np.eye(3) - np.diag(diag)   # ∫ d dᵀ about the COM
        err_v = abs(total[0] - volume)
        err_c = np.abs(total[1:4])
        err_s = np.abs(total[4:13].reshape(3, 3) - second)
        big = np.abs(second).max()
        assert err_v <= bar[0] + 1e-15 * volume and err_v <= 1e-13 * volume
        assert np.all(err_c <= bar[1:4] + 1e-15 * volume * a)
        assert np.all(err_s <= bar[4:13].reshape(3, 3) + 1e-15 * big)
        assert bar[0] <= max(100 * err_v, 1e-13 * volume)
        assert np.all(bar[4:13].reshape(3, 3) <= np.maximum(100 * err_s, 1e-13 * big))


@pytest.mark.parametrize("kind", ("sphere", "torus"))
def test_offset_faces_by_our_trimmed_rule(kind):
    """A NURBS sphere and torus offset outward by 0.25 (one Geom_OffsetSurface face each): the
    sphere of radius 1.25, the torus of minor radius 0.75; closed forms within the bar, the bar
    within 100x of the error (or 1e-13)."""
    from OCP.BRepOffsetAPI import BRepOffsetAPI_MakeOffsetShape

    maker = BRepOffsetAPI_MakeOffsetShape()
    maker.PerformBySimple(cp.nurbs(cp.make(kind, 1.0)), 0.25)
    integral = integrate_solid(maker.Shape(), 1.0, kind)
    assert integral.faces == {"offset": 1} and integral.method == "own"
    if kind == "sphere":
        volume = 4 * math.pi * 1.25**3 / 3
        diag = (0.4 * volume * 1.25**2,) * 3
    else:
        big, r = 2.0, 0.75
        volume = 2 * math.pi**2 * big * r * r
        diag = (volume * (big * big / 2 + 5 * r * r / 8),) * 2 + (
            volume * (big * big + 0.75 * r * r),)
    m = integral.moments
    bar_v, _, bar_j = integral.integration
    err_v = abs(m.volume - volume)
    err_j = np.abs(np.diag(m.inertia) - np.asarray(diag))
    assert err_v <= bar_v + m.volume_err and err_v <= 1e-13 * volume
    assert np.all(err_j <= np.diag(bar_j + m.inertia_err))
    assert bar_v <= max(100 * err_v, 1e-13 * volume)
    assert np.all(np.diag(bar_j) <= np.maximum(100 * err_j, 1e-13 * max(diag)))
