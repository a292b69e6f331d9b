"""SDF 1.11 ``<cone>``: a solid cone along z with its frame at mid-height (sdformat's Cone puts
the inertial 0.25 L below the frame). Against the closed form, and against a fine mesh of the
same cone integrated by massprops (an independent path: the divergence theorem on triangles)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from massprops.robot.inertials.primitives import cone


def cone_obj(radius: float, height: float, n: int) -> str:
    """A closed n-gon pyramid (base at z = -h/2, apex at +h/2), outward faces."""
    lines = [f"v {radius * math.cos(2 * math.pi * k / n)} "
             f"{radius * math.sin(2 * math.pi * k / n)} {-height / 2}" for k in range(n)]
    lines += [f"v 0 0 {height / 2}", f"v 0 0 {-height / 2}"]
    apex, centre = n + 1, n + 2
    for k in range(n):
        a, b = k + 1, (k + 1) % n + 1
        lines.append(f"f {a} {b} {apex}")
        lines.append(f"f {b} {a} {centre}")
    return "\n".join(lines) + "\n"


def sdf(shape: str, pose: str) -> str:
    return (f'<sdf version="1.11"><model name="m"><link name="l"><inertial><mass>2</mass>'
            '<inertia><ixx>1</ixx><iyy>1</iyy><izz>1</izz></inertia></inertial>'
            f'<collision name="c"><pose>{pose}</pose><geometry>{shape}</geometry></collision>'
            '</link></model></sdf>')


def test_cone_closed_form():
    r, h = 0.3, 0.8
    c = cone(r, h)
    assert c.volume == pytest.approx(math.pi * r * r * h / 3, rel=1e-15)
    # about the apex, I_zz = 3/10 V r², I_xx = V (3r²/20 + 3h²/5); shift by (3h/4)² to the COM
    jxx_apex = c.volume * (3 * r * r / 20 + 3 * h * h / 5)
    assert c.inertia[0, 0] == pytest.approx(jxx_apex - c.volume * (0.75 * h) ** 2, rel=1e-14)
    assert c.inertia[2, 2] == pytest.approx(0.3 * c.volume * r * r, rel=1e-15)


def test_sdf_cone_matches_a_fine_mesh_of_it(tmp_path, run):
    r, h, pose = 0.3, 0.8, "0.1 0.2 0.3 0.4 -0.2 0.7"
    (tmp_path / "cone.obj").write_text(cone_obj(r, h, 4000))
    rows = {}
    for name, shape in (("prim", f"<cone><radius>{r}</radius><length>{h}</length></cone>"),
                        ("mesh", "<mesh><uri>cone.obj</uri></mesh>")):
        (tmp_path / f"{name}.sdf").write_text(sdf(shape, pose))
        result = run("model", tmp_path / f"{name}.sdf", "--json")
        assert result.exit_code == 0, result.stderr
        rows[name] = json.loads(result.stdout.splitlines()[0])["computed"]
    # the 4000-gon's volume is short of the cone's by ~(2π/n)²/6 = 4e-7 relative
    for key in ("center_of_mass", "inertia"):
        assert np.allclose(rows["prim"][key], rows["mesh"][key], rtol=2e-6, atol=1e-9), key
    # the COM sits L/4 above the base, i.e. L/4 below the frame origin along the cone's axis
    com = np.asarray(rows["prim"]["center_of_mass"])
    assert np.linalg.norm(com - [0.1, 0.2, 0.3]) == pytest.approx(h / 4, rel=1e-12)
