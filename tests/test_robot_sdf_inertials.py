"""SDFormat's own inertial rules (sdformat's Link and Collision, as Gazebo simulates them): a link
without ``<inertial>`` has 1 kg and unit moments at its origin; ``<inertial auto="true">`` (1.11)
integrates the collisions at their ``<density>`` (else the inertial's, else 1000 kg/m³), scaled
to ``<mass>`` when one is given. Checked against closed forms of a box."""

from __future__ import annotations

import json

import pytest

from massprops.dynamics.systems.description import describe

BOX = ('<collision name="c{k}"><pose>{x} 0 0 0 0 0</pose>{density}<geometry><box><size>{a} {b} {c}'
       '</size></box></geometry></collision>')


def model(links: str, joints: str = "") -> str:
    return f'<sdf version="1.11"><model name="m">{links}{joints}</model></sdf>'


def hinge(name, child):
    return (f'<joint name="{name}" type="revolute"><parent>world</parent><child>{child}</child>'
            '<axis><xyz>0 1 0</xyz></axis></joint>')


def test_a_link_without_inertial_is_sdformats_default(tmp_path, run):
    (tmp_path / "d.sdf").write_text(model('<link name="arm"><pose>0.5 0 0 0 0 0</pose></link>',
                                          hinge("j", "arm")))
    desc = describe(tmp_path / "d.sdf")
    arm = desc.bodies[0]
    assert arm.mass == 1.0 and list(arm.com0) == [0.5, 0.0, 0.0]
    assert (arm.inertia == [[1, 0, 0], [0, 1, 0], [0, 0, 1]]).all()
    assert any("no <inertial>" in w and "'arm'" in w for w in desc.warnings)
    result = run("simulate", tmp_path / "d.sdf", "--duration", "0", "--json")
    assert result.exit_code == 0, result.stderr
    # the joint sits at the link origin (an SDF joint pose is in the child frame), and so does
    # the default 1 kg: no lever, no holding torque
    assert json.loads(result.stdout)["final"]["joints"]["j"]["holding"][0] == 0.0


@pytest.mark.parametrize("inertial, densities, mass", [
    ('<inertial auto="true"><density>6</density></inertial>', ("", ""), 6 * (0.06 + 0.024)),
    ('<inertial auto="true"/>', ("<density>2</density>", ""), 2 * 0.06 + 1000 * 0.024),
    ('<inertial auto="true"><mass>3</mass></inertial>', ("<density>2</density>", ""), 3.0),
])
def test_auto_inertial_integrates_the_collisions(tmp_path, run, inertial, densities, mass):
    """Two boxes: 0.2 x 0.3 x 1 at x = 0.1, 0.2 x 0.2 x 0.6 at x = 0.4 (volumes 0.06, 0.024)."""
    boxes = (BOX.format(k=1, x=0.1, density=densities[0], a=0.2, b=0.3, c=1.0)
             + BOX.format(k=2, x=0.4, density=densities[1], a=0.2, b=0.2, c=0.6))
    (tmp_path / "a.sdf").write_text(model(f'<link name="arm">{inertial}{boxes}</link>',
                                          hinge("j", "arm")))
    rho1 = {"": None, "<density>2</density>": 2.0}[densities[0]]
    m1 = (rho1 or (6.0 if "<density>6" in inertial else 1000.0)) * 0.06
    m2 = (6.0 if "<density>6" in inertial else 1000.0) * 0.024
    scale = mass / (m1 + m2)
    m1, m2 = m1 * scale, m2 * scale
    com = (m1 * 0.1 + m2 * 0.4) / mass
    # about y through the COM: each box's (a² + c²)/12 plus its offset along x squared
    jyy = (m1 * (0.04 + 1.0) / 12 + m1 * (0.1 - com) ** 2
           + m2 * (0.04 + 0.36) / 12 + m2 * (0.4 - com) ** 2)
    arm = describe(tmp_path / "a.sdf").bodies[0]
    assert arm.mass == pytest.approx(mass, rel=1e-12)
    assert arm.com0[0] == pytest.approx(com, rel=1e-12)
    assert arm.inertia[1, 1] == pytest.approx(jyy, rel=1e-12)
    result = run("model", tmp_path / "a.sdf", "--json")
    assert result.exit_code == 0, result.stderr
    row = json.loads(result.stdout.splitlines()[0])
    assert row["status"] == "computed" and row["computed"]["mass"] == pytest.approx(mass)
