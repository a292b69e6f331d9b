"""MJCF elements whose bodies MuJoCo's compiler makes (<composite>, <flexcomp>): massprops does
not expand them; it says so once and simulates the rest, and an equality naming one of their
bodies says where the name would come from."""

from __future__ import annotations

import json

ARM = """<mujoco><worldbody>
  <body name="arm" pos="0 0 0"><joint name="h" type="hinge" axis="0 1 0"/>
    <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.02" density="1000"/></body>
  {extra}
</worldbody>{equality}</mujoco>"""

CABLE = ('<composite type="cable" count="5 1 1" size="1" initial="none">'
         '<geom type="capsule" size=".005" density="100"/></composite>')


def test_a_composite_is_said_and_the_rest_simulated(tmp_path, run):
    (tmp_path / "m.xml").write_text(ARM.format(extra=CABLE, equality=""))
    plain = tmp_path / "plain.xml"
    plain.write_text(ARM.format(extra="", equality=""))
    result = run("simulate", tmp_path / "m.xml", "--duration", "0.3", "--json")
    assert result.exit_code == 0, result.stderr
    said = [line for line in result.stderr.splitlines() if "<composite>" in line]
    assert len(said) == 1 and "not expanded" in said[0]
    alone = run("simulate", plain, "--duration", "0.3", "--json")
    assert json.loads(result.stdout)["final"]["joints"] == json.loads(alone.stdout)["final"][
        "joints"]


def test_a_connect_to_a_generated_body_names_the_composite(tmp_path, run):
    (tmp_path / "m.xml").write_text(ARM.format(
        extra=CABLE, equality='<equality><connect body1="B_last" body2="arm" anchor="0 0 0"/>'
                              '</equality>'))
    result = run("simulate", tmp_path / "m.xml", "--duration", "0.1")
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "'B_last'" in lines[0] and "<composite>" in lines[0], lines
