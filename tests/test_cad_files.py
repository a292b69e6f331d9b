"""CAD files end to end: an assembly in millimetres, densities by name, open shells, units,
the missing extra, the tessellation cross-check, and the CLI."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("OCP")

import cadparts as cp  # noqa: E402

from massprops.cad import occ  # noqa: E402
from massprops.cad.inspect import inspect_cad  # noqa: E402
from massprops.cad.tessellate import tessellate  # noqa: E402
from massprops.errors import MeshTopologyError, UsageError  # noqa: E402
from massprops.mesh import Mesh  # noqa: E402
from massprops.mesh.health import prepare_mesh  # noqa: E402
from massprops.mesh.integral import mass_properties  # noqa: E402

FAR = 2.0**27  # mm: the third part sits ~1.3e8 mm (134 km) away


@pytest.fixture(scope="module")
def assembly(tmp_path_factory):
    path = tmp_path_factory.mktemp("cad") / "asm.step"
    cp.write_assembly([("bracket", cp.make("box", 10.0), (0.0, 0.0, 0.0)),
                       ("pin", cp.make("cylinder", 2.0), (100.0, 0.0, 0.0)),
                       ("far_ball", cp.make("sphere", 4.0), (FAR, 0.0, 0.0))], path)
    return path


def _truth(kind, a, at):
    volume, com, diag = cp.closed_forms(kind, a)
    mm = 0.001
    return volume * mm**3, (np.asarray(at) + com) * mm, np.asarray(diag) * mm**5


def test_assembly_in_millimetres_per_solid_and_total(assembly):
    result = inspect_cad(assembly, density_map=[("pin", 7800.0), ("b*", 2700.0)])
    names = [r.solid.name for r in result.solids]
    assert names == ["bracket", "pin", "far_ball"]
    assert [r.solid.path for r in result.solids] == [
        "assembly/bracket", "assembly/pin", "assembly/far_ball"]
    truths = [_truth("box", 10.0, (0, 0, 0)), _truth("cylinder", 2.0, (100, 0, 0)),
              _truth("sphere", 4.0, (FAR, 0, 0))]
    densities = [2700.0, 7800.0, 1.0]   # the map's first match; far_ball takes the default
    offsets_mm = [0.0, 100.0, FAR]  # where write_assembly placed each part, along x
    for r, (volume, com, diag), rho, x in zip(result.solids, truths, densities, offsets_mm):
        p = r.properties
        assert p.density == rho
        assert p.volume == pytest.approx(volume, rel=1e-13, abs=0)
        assert np.allclose(p.center_of_mass, com, rtol=0, atol=1e-13 * volume ** (1 / 3)
                           + np.spacing(np.abs(com)).max())
        assert np.allclose(np.diag(p.inertia), rho * diag, rtol=1e-13, atol=0)
        assert r.integration is None and r.input is not None
        # the part's placement in the assembly, translation in metres
        assert r.placement[:3, 3] == pytest.approx([x * 0.001, 0.0, 0.0], rel=1e-15, abs=0)
        assert np.array_equal(r.placement[:3, :3], np.eye(3))
    # the total by hand: masses, COM and parallel axes from the closed forms
    masses = np.array([rho * t[0] for rho, t in zip(densities, truths)])
    coms = np.array([t[1] for t in truths])
    total_com = coms[0] + (masses[:, None] * (coms - coms[0])).sum(axis=0) / masses.sum()
    inertia = np.zeros((3, 3))
    for m, c, (_, _, diag), rho in zip(masses, coms, truths, densities):
        d = c - total_com
        inertia += rho * np.diag(diag) + m * (d @ d * np.eye(3) - np.outer(d, d))
    props, _, data = result.total
    assert props.mass == pytest.approx(masses.sum(), rel=1e-13)
    assert np.allclose(props.center_of_mass, total_com, rtol=1e-13, atol=0)
    assert np.allclose(props.inertia, inertia, rtol=1e-12, atol=1e-12 * np.abs(inertia).max())
    assert data is not None
    dicts = result.as_dicts()
    assert dicts[-1]["total"] is True and len(dicts) == 4
    assert dicts[0]["cad"] == {"format": "step", "unit": "mm", "faces": {"plane": 6},
                               "tolerance": dicts[0]["cad"]["tolerance"]}
    assert dicts[-1]["warnings"] == []


def test_unused_density_pattern_is_a_warning(assembly):
    result = inspect_cad(assembly, density_map=[("nothing*", 5.0)])
    assert any("nothing*" in w for w in result.warnings)


def test_unit_that_disagrees_with_the_file_is_a_usage_error(assembly):
    with pytest.raises(UsageError, match="disagrees"):
        inspect_cad(assembly, unit="m")


def test_brep_takes_its_unit_from_the_option(tmp_path):
    cp.write_brep(cp.make("sphere", 3.0), tmp_path / "s.brep")
    result = inspect_cad(tmp_path / "s.brep", unit="cm")
    assert result.solids[0].properties.volume == pytest.approx(
        4 * math.pi * 27 / 3 * 1e-6, rel=1e-14)
    assert result.solids[0].solid.name == "solid1"


def test_open_shell_refused_unless_allowed(tmp_path):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    box = cp.make("box", 1.0)
    sewing = BRepBuilderAPI_Sewing()
    explorer = TopExp_Explorer(box, TopAbs_FACE)
    explorer.Next()   # leave the first face out: an open box
    while explorer.More():
        sewing.Add(explorer.Current())
        explorer.Next()
    sewing.Perform()
    cp.write_brep(sewing.SewedShape(), tmp_path / "open.brep")
    with pytest.raises(MeshTopologyError, match="open shell"):
        inspect_cad(tmp_path / "open.brep")
    result = inspect_cad(tmp_path / "open.brep", allow_open=True)
    assert result.solids[0].warnings


def test_missing_extra_names_the_file_and_the_install(monkeypatch):
    monkeypatch.setattr(occ, "_READY", False)
    monkeypatch.setitem(sys.modules, "OCP.Message", None)
    with pytest.raises(occ.CadExtraMissingError, match=r'part\.step.*massprops\[cad\]'):
        occ.require_occ("part.step")


@pytest.mark.parametrize("kind", ("drilled", "tilted"))
def test_tessellation_cross_check(kind):
    """The exact mesh integral of a fine tessellation differs from the CAD result by no more
    than the chord deflection's first-order bound (deflection x area)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf

    from massprops.cad.integrate import integrate_solid

    shape = cp.drilled_box(1.0, (3.0, 4.0, 5.0))
    if kind == "tilted":   # products of inertia non-zero: checks their sign convention
        trsf = gp_Trsf()
        trsf.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(1, 1, 1)), 0.7)
        shape = BRepBuilderAPI_Transform(shape, trsf, True).Shape()
    deflection = 1e-4
    vertices, faces = tessellate(shape, deflection)
    mesh, _ = prepare_mesh(Mesh(vertices, faces, name="tess"))
    mesh_props = mass_properties(mesh)
    exact = integrate_solid(shape, 1.0, kind)
    flux = deflection * exact.area
    assert abs(mesh_props.volume - exact.moments.volume) <= flux
    reach = float(np.max(exact.reach)) * 2
    assert np.max(np.abs(mesh_props.inertia - exact.moments.inertia)) <= 2 * reach**2 * flux
    assert np.abs(exact.moments.inertia - np.diag(np.diag(exact.moments.inertia))).max() > (
        1e-3 if kind == "tilted" else -1)


def _cli(*args, cwd=None):
    import os

    env = dict(os.environ)
    return subprocess.run([sys.executable, "-m", "massprops", *args], capture_output=True,
                          text=True, env=env, timeout=120)


@pytest.mark.slow
def test_cli_json_and_urdf(assembly, tmp_path):
    run = _cli("inspect", str(assembly), "--json", "--density", "1000")
    assert run.returncode == 0, run.stderr
    records = [json.loads(line) for line in run.stdout.splitlines()]
    assert [r["solid"] for r in records] == ["bracket", "pin", "far_ball", "total"]
    assert records[1]["uncertainty"]["integration"] is None
    assert records[1]["cad"]["unit"] == "mm"
    run = _cli("inspect", str(assembly), "--unit", "m")
    assert run.returncode == 2 and "disagrees" in run.stderr
    run = _cli("inspect", str(assembly), "--format", "urdf")
    assert run.returncode == 0 and run.stdout.count("<inertial>") == 3
    # the far ball's inertial is in its own frame: its COM is at its own origin
    import re

    far = run.stdout.split("far_ball")[1]
    xyz = [float(x) for x in re.search(r'xyz="([^"]*)"', far).group(1).split()]
    assert max(abs(x) for x in xyz) < 1e-15   # 4 mm ball: round-off only


def test_mesh_commands_do_not_import_opencascade(tmp_path):
    (tmp_path / "t.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                    "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    obj = str(tmp_path / "t.obj")
    code = (f"import sys, runpy; sys.argv = ['massprops', 'inspect', {obj!r}, '--json']\n"
            "try:\n    runpy.run_module('massprops', run_name='__main__')\n"
            "except SystemExit:\n    pass\n"
            "assert not any(m.startswith('OCP') for m in sys.modules), 'OCP imported'\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr


def test_align_writes_exact_geometry_in_the_principal_frame(assembly, tmp_path):
    from massprops.cad.write import align_cad
    from massprops.errors import OutputExistsError

    before = inspect_cad(assembly)
    props = before.total[0]
    for name in ("aligned.step", "aligned.brep"):
        aligned = align_cad(before, tmp_path / name)
        assert not aligned.tessellated
        # BREP carries no unit: the geometry was written in the input's (mm)
        after = inspect_cad(tmp_path / name, unit="mm" if name.endswith("brep") else None
                            ).total[0]
        size = props.volume ** (1 / 3)
        # the COM at the origin and the inertia diagonal, up to the far part's round-off
        assert np.max(np.abs(after.center_of_mass)) <= 1e-9 * FAR * 1e-3
        assert after.mass == pytest.approx(props.mass, rel=1e-12)
        off = after.inertia - np.diag(np.diag(after.inertia))
        assert np.max(np.abs(off)) <= 1e-9 * props.principal_moments.max()
        assert np.allclose(np.diag(after.inertia), props.principal_moments, rtol=1e-9)
        assert size > 0
    with pytest.raises(OutputExistsError):
        align_cad(before, assembly, force=True)
    aligned = align_cad(before, tmp_path / "aligned.stl")
    assert aligned.tessellated and (tmp_path / "aligned.stl").stat().st_size > 0


def test_iges_round_trip_and_its_printed_digits(assembly, tmp_path):
    from massprops.cad.write import align_cad

    before = inspect_cad(assembly)
    align_cad(before, tmp_path / "aligned.igs")
    after = inspect_cad(tmp_path / "aligned.igs")
    assert after.file.format == "iges" and after.file.unit == "mm"
    assert after.total[0].mass == pytest.approx(before.total[0].mass, rel=1e-12)
    # 10 printed digits: the far ball (1.3e8 mm out) is uncertain by ~1e-2 mm of its surface,
    # far above its modelling tolerance
    far = max(after.solids, key=lambda r: abs(r.properties.center_of_mass).max())
    area = 4 * math.pi * 4.0**2 * 1e-6
    largest = FAR * 1e-3 / math.sqrt(3)   # its largest coordinate after the rotation, m
    assert far.input.volume >= area * 0.5e-9 * largest


def test_colour_from_the_file_is_reported(tmp_path):
    from OCP.Quantity import Quantity_Color, Quantity_TOC_RGB
    from OCP.STEPCAFControl import STEPCAFControl_Writer
    from OCP.STEPControl import STEPControl_AsIs
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TDocStd import TDocStd_Document
    from OCP.XCAFDoc import XCAFDoc_ColorType, XCAFDoc_DocumentTool

    doc = TDocStd_Document(TCollection_ExtendedString("t"))
    XCAFDoc_DocumentTool.SetLengthUnit_s(doc, 0.001)
    label = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main()).AddShape(cp.make("box", 1.0), False)
    TDataStd_Name.Set_s(label, TCollection_ExtendedString("redbox"))
    XCAFDoc_DocumentTool.ColorTool_s(doc.Main()).SetColor(
        label, Quantity_Color(1.0, 0.0, 0.0, Quantity_TOC_RGB), XCAFDoc_ColorType.XCAFDoc_ColorGen)
    writer = STEPCAFControl_Writer()
    writer.SetColorMode(True)
    writer.SetNameMode(True)
    assert writer.Transfer(doc, STEPControl_AsIs)
    assert int(writer.Write(str(tmp_path / "red.step"))) == 1
    record = inspect_cad(tmp_path / "red.step").as_dicts()[0]
    assert record["solid"] == "redbox" and record["cad"]["colour"] == [1.0, 0.0, 0.0]


@pytest.mark.parametrize("fmt", ("step", "iges"))
def test_units_round_trip(fmt, tmp_path):
    """A sphere of radius 2 written in m, mm and inches reads back in that unit (converted
    after integrating)."""
    from massprops.cad.write import _write_native

    for unit, metres in (("m", 1.0), ("mm", 1e-3), ("in", 0.0254)):
        path = tmp_path / f"s_{unit}.{fmt}"
        assert _write_native(cp.make("sphere", 2.0), fmt, unit, str(path))
        result = inspect_cad(path)
        assert result.file.unit == unit
        assert result.solids[0].properties.volume == pytest.approx(
            4 * math.pi * 8 / 3 * metres**3, rel=1e-14)


def test_total_mass_sets_one_uniform_density(assembly):
    result = inspect_cad(assembly, mass=2.0)
    densities = {r.properties.density for r in result.solids}
    assert len(densities) == 1
    assert result.total[0].mass == pytest.approx(2.0, rel=1e-14)
    with pytest.raises(UsageError):
        inspect_cad(assembly, mass=2.0, density_map=[("pin", 1.0)])


@pytest.mark.parametrize("kind", ("box", "cylinder", "torus"))
def test_align_far_part_in_millimetres_lands_on_the_origin(kind, tmp_path):
    """A 10 mm part, tilted, 1e6 sizes away in a millimetre STEP file: aligned, the written
    file's COM is at the origin within the bars. One float for that COM is rounded to half an
    ulp of 1.5e7 mm (8e-11 of the part); the geometry is moved by the local origin first (exact
    near it), then by the COM from it, then rotated. BREP keeps every digit: round-off only;
    STEP prints ~12 digits, and its re-read part is within its own bars."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf

    from massprops.cad.write import align_cad

    trsf = gp_Trsf()
    trsf.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(1, 2, 3)), 0.7)
    shape = BRepBuilderAPI_Transform(cp.make(kind, 10.0), trsf, True).Shape()
    cp.write_step(cp.moved(shape, (1.3e7, -0.7e7, 0.4e7)), tmp_path / "far.step", "MM")
    before = inspect_cad(tmp_path / "far.step")
    for name in ("aligned.brep", "aligned.step"):
        align_cad(before, tmp_path / name)
        after = inspect_cad(tmp_path / name, unit="mm" if name.endswith("brep") else None
                            ).solids[0]
        size = after.properties.volume ** (1 / 3)
        com = np.abs(after.properties.center_of_mass)
        bars = [after.properties.uncertainty.rounding, after.integration]
        computed = sum(b.center_of_mass for b in bars if b is not None)
        if name.endswith("brep"):
            assert np.all(com <= computed) and com.max() <= 1e-13 * size
        else:
            assert np.all(com <= computed + after.input.center_of_mass)
        assert after.properties.mass == pytest.approx(before.solids[0].properties.mass,
                                                      rel=1e-12)
