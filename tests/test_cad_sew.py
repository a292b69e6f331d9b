"""IGES as CAD tools write it by default: loose faces (brep mode 0), no solid around them. The
faces are sewn within the file's tolerance into a closed solid, oriented outward, said so in
the warnings, and the closed forms lie within the reported bars; what does not close is
refused in one line."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("OCP")

import cadparts as cp  # noqa: E402

from massprops.cad.inspect import inspect_cad  # noqa: E402
from massprops.errors import MeshTopologyError  # noqa: E402

# size a in the file's unit: 1 mm, 1 m and 100 m parts, in millimetres and in metres
PARTS = [(kind, a, unit) for kind in ("box", "cylinder", "sphere", "torus", "cone")
         for a, unit in ((1.0, "MM"), (1.0, "M"), (1e5, "MM"))]


def _bars(solid):
    bars = (solid.integration, solid.input, solid.properties.uncertainty.rounding)
    return [b for b in bars if b is not None]


def _within(solid, volume, com, diag, scale):
    p = solid.properties
    bars = _bars(solid)
    assert abs(p.volume - volume * scale**3) <= sum(b.volume for b in bars)
    err_c = np.abs(p.center_of_mass - np.asarray(com) * scale)
    assert np.all(err_c <= sum(b.center_of_mass for b in bars))
    err_j = np.abs(p.inertia - np.diag(diag) * scale**5)
    assert np.all(err_j <= sum(b.inertia for b in bars))
    # the bar is the file's tolerance at work, not a shrug: a few 1e-5 of the part at most
    assert sum(b.volume for b in bars) <= 1e-3 * volume * scale**3
    # the walls (surfaces of revolution in IGES) by our own rule: its bar covers its error
    # against the closed forms and says something (within 100x, or at most 1e-13 relative)
    q = solid.integration
    if q is not None:
        r = solid.properties.uncertainty.rounding
        err_v = abs(p.volume - volume * scale**3)
        assert err_v <= q.volume + r.volume
        assert q.volume <= max(100 * err_v, 1e-13 * p.volume)
        assert np.all(err_j <= q.inertia + r.inertia)
        assert np.all(q.inertia <= np.maximum(100 * err_j, 1e-13 * np.abs(p.inertia).max()))


@pytest.mark.parametrize("kind,a,unit", PARTS)
def test_default_mode_iges_is_sewn_into_the_solid(kind, a, unit, tmp_path):
    path = tmp_path / f"{kind}.igs"
    cp.write_iges_faces(cp.make(kind, a), path, unit)
    result = inspect_cad(path)
    assert len(result.solids) == 1
    solid = result.solids[0]
    assert solid.solid.closed and solid.solid.sewn is not None
    assert solid.solid.name == "solid1"
    assert any("sewn from" in w for w in solid.warnings)
    volume, com, diag = cp.closed_forms(kind, a)
    _within(solid, volume, com, diag, 1.0 if unit == "M" else 1e-3)
    # the sewing tolerance is in the input bar: at least tolerance x area on the volume
    area = solid.integral.area
    assert solid.input.volume >= solid.solid.sewn * (1.0 if unit == "M" else 1e-3) * area


def test_default_mode_drilled_box(tmp_path):
    """Sixteenth part: a cube with a through hole (planes with a circular hole, a cylinder's
    wall), 10 mm."""
    a = 10.0
    path = tmp_path / "drilled.igs"
    cp.write_iges_faces(cp.drilled_box(a), path)
    solid = inspect_cad(path).solids[0]
    assert solid.solid.closed and solid.solid.faces == 7
    hole = math.pi * (a / 2) ** 2 * 2 * a
    s = 2 * a
    ixx = s**3 * (s * s + s * s) / 12 - hole * (3 * (a / 2) ** 2 + (2 * a) ** 2) / 12
    izz = s**5 / 6 - hole * (a / 2) ** 2 / 2
    _within(solid, s**3 - hole, (a, a, a), (ixx, ixx, izz), 1e-3)


def test_loose_faces_that_do_not_close_are_refused(tmp_path):
    """Five faces of a box: sewn, they leave a square hole wider than any tolerance."""
    from OCP.BRep import BRep_Builder
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS_Compound

    compound = TopoDS_Compound()
    builder = BRep_Builder()
    builder.MakeCompound(compound)
    explorer = TopExp_Explorer(cp.make("box", 5.0), TopAbs_FACE)
    explorer.Next()
    while explorer.More():
        builder.Add(compound, explorer.Current())
        explorer.Next()
    path = tmp_path / "open.igs"
    cp.write_iges_faces(compound, path)
    with pytest.raises(MeshTopologyError, match="do not close when sewn") as info:
        inspect_cad(path)
    assert "\n" not in str(info.value)


def test_two_parts_written_as_faces_sew_into_two_solids(tmp_path):
    """Loose faces of two parts apart from each other: two solids, each its own closed form."""
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Compound

    compound = TopoDS_Compound()
    builder = BRep_Builder()
    builder.MakeCompound(compound)
    builder.Add(compound, cp.make("sphere", 3.0))
    builder.Add(compound, cp.make("box", 2.0, (20.0, 0.0, 0.0)))
    path = tmp_path / "two.igs"
    cp.write_iges_faces(compound, path)
    result = inspect_cad(path)
    assert [r.solid.name for r in result.solids] == ["solid1", "solid2"]
    for solid, kind, at in zip(result.solids, ("sphere", "box"), ((0, 0, 0), (20, 0, 0))):
        a = 3.0 if kind == "sphere" else 2.0
        volume, com, diag = cp.closed_forms(kind, a)
        _within(solid, volume, np.asarray(at) + com, diag, 1e-3)
