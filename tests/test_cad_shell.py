"""``--shell T`` on CAD surfaces against closed forms: the mid-surface model exact on a
spherical shell and an open cylindrical tube, the exact thick walls within its model bar, a
box's joins in the bar, free-form faces refused."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("OCP")

import cadparts as cp  # noqa: E402

from massprops.cad.inspect import inspect_cad  # noqa: E402
from massprops.errors import UsageError  # noqa: E402


def _lateral_face(radius: float, at=(0.0, 0.0, 0.0)):
    """The wall of a cylinder of radius r and height 2r, without its caps (an open tube)."""
    from OCP.BRep import BRep_Tool
    from OCP.Geom import Geom_CylindricalSurface
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    explorer = TopExp_Explorer(cp.make("cylinder", radius, at), TopAbs_FACE)
    while explorer.More():
        face = TopoDS.Face(explorer.Current())
        if isinstance(BRep_Tool.Surface_s(face), Geom_CylindricalSurface):
            return face
        explorer.Next()
    raise AssertionError("no cylindrical face")


def _within(value, truth, bar):
    return np.all(np.abs(np.asarray(value) - np.asarray(truth)) <= np.asarray(bar))


@pytest.mark.parametrize("off", (0.0, 2.0**24))
def test_spherical_shell(tmp_path, off):
    r, t, rho = 0.5, 0.004, 7800.0
    at = (off, -off, off / 2)
    cp.write_brep(cp.make("sphere", r, at), tmp_path / "s.brep")
    solid = inspect_cad(tmp_path / "s.brep", shell=t, density=rho).solids[0]
    p = solid.properties
    area = 4 * math.pi * r * r
    # the model: ρT A, and ∫x xᵀ dA + T²/12 ∫n nᵀ dA = (A r²/3 + T²/12 A/3) I about the centre
    model_j = 2 * rho * t * area / 3 * (r * r + t * t / 12)
    assert p.volume == pytest.approx(t * area, rel=1e-13)
    assert p.mass == pytest.approx(rho * t * area, rel=1e-13)
    assert np.allclose(p.center_of_mass, at, rtol=0, atol=1e-13 * r + 4e-16 * off)
    assert np.allclose(p.inertia, model_j * np.eye(3), rtol=0, atol=1e-13 * model_j)
    # the wall between r - T/2 and r + T/2 is what the model approximates: within its bar
    # (on a sphere the volume's curvature term is exact: bar and miss agree to round-off)
    bar, rounding = p.uncertainty.repair, p.uncertainty.rounding
    exact_v = 4 * math.pi / 3 * ((r + t / 2) ** 3 - (r - t / 2) ** 3)
    exact_j = 8 * math.pi / 15 * rho * ((r + t / 2) ** 5 - (r - t / 2) ** 5)
    assert abs(p.volume - exact_v) <= bar.volume + rounding.volume
    assert _within(np.diag(p.inertia), exact_j, np.diag(bar.inertia + rounding.inertia))
    # and the bar is of the model's own order, (T/r)², not wider than ~100x the miss
    assert np.max(np.diag(bar.inertia)) <= 100 * abs(model_j - exact_j)
    assert solid.repairs["shell"]["turning_edges"] == 0


def test_open_tube(tmp_path):
    r, t = 1.0, 0.01
    h = 2 * r
    cp.write_brep(_lateral_face(r), tmp_path / "tube.brep")
    solid = inspect_cad(tmp_path / "tube.brep", shell=t).solids[0]
    p = solid.properties
    area = 2 * math.pi * r * h
    q = t * np.diag([math.pi * r**3 * h, math.pi * r**3 * h, 2 * math.pi * r * h**3 / 12]) \
        + t**3 / 12 * math.pi * r * h * np.diag([1.0, 1.0, 0.0])
    model = np.trace(q) * np.eye(3) - q
    assert p.volume == pytest.approx(t * area, rel=1e-13)
    assert np.allclose(p.center_of_mass, (0, 0, h / 2), rtol=0, atol=1e-13)
    assert np.allclose(p.inertia, model, rtol=0, atol=1e-13 * np.max(model))
    # the exact annulus: its volume is the model's (the curvature terms cancel), Izz within
    exact_zz = math.pi * h * ((r + t / 2) ** 4 - (r - t / 2) ** 4) / 2
    bar = p.uncertainty.repair
    assert abs(p.inertia[2, 2] - exact_zz) <= bar.inertia[2, 2]
    assert solid.repairs["shell"]["turning_edges"] == 0   # free rims are cut square


def test_box_shell_puts_its_joins_in_the_bar(tmp_path):
    a, t = 1.0, 0.01
    cp.write_brep(cp.make("box", a), tmp_path / "b.brep")
    solid = inspect_cad(tmp_path / "b.brep", shell=t).solids[0]
    p = solid.properties
    area = 2 * (a * 2 * a + a * 3 * a + 2 * a * 3 * a)
    assert p.volume == pytest.approx(t * area, rel=1e-13)
    record = solid.repairs["shell"]
    assert record["turning_edges"] == 12 and record["folded_edges"] == 0
    # twelve right-angle joins: two kites of (T/2)² each per unit length
    edges = 4 * (a + 2 * a + 3 * a)
    assert record["model_volume_bound"] == pytest.approx(2 * (t / 2) ** 2 * edges, rel=1e-9)
    # a closed box's mitred wall (the box grown by T/2 minus the box shrunk by T/2): T A + 2T³
    exact = (a + t) * (2 * a + t) * (3 * a + t) - (a - t) * (2 * a - t) * (3 * a - t)
    assert abs(p.volume - exact) <= p.uncertainty.repair.volume


def test_free_form_faces_are_refused_with_the_way_out(tmp_path):
    cp.write_brep(cp.nurbs(cp.make("sphere", 1.0)), tmp_path / "n.brep")
    with pytest.raises(UsageError, match="tessellate"):
        inspect_cad(tmp_path / "n.brep", shell=0.01)


@pytest.mark.slow
def test_cli_shell_on_an_open_step_surface(tmp_path):
    r, t = 1.0, 0.01
    cp.write_step(_lateral_face(r), tmp_path / "tube.step", "M")
    run = subprocess.run([sys.executable, "-m", "massprops", "inspect", str(tmp_path / "tube.step"),
                          "--json", "--shell", str(t), "--density", "1000"],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    record = json.loads(run.stdout.splitlines()[0])
    assert record["repairs"]["shell"]["thickness"] == t
    assert record["mass"] == pytest.approx(1000 * t * 4 * math.pi * r * r, rel=1e-12)
    assert "repair" in record["uncertainty"]
    refused = subprocess.run([sys.executable, "-m", "massprops", "inspect",
                              str(tmp_path / "tube.step"), "--union"],
                             capture_output=True, text=True, timeout=120)
    assert refused.returncode == 2 and "--union" in refused.stderr
