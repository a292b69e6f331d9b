"""xacro prints its warnings to stderr itself; massprops says them as its own warning lines
(one line each, naming the file), and a file of macros only (no links) is said, not shown as an
empty table without a word."""

from __future__ import annotations

import json

import pytest

MACROS = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="pi" value="3.14159"/>
  <xacro:macro name="arm"><link name="a"/></xacro:macro>
</robot>
"""


def test_xacro_warnings_become_one_line_each(tmp_path, run):
    pytest.importorskip("xacro")
    (tmp_path / "m.urdf.xacro").write_text(MACROS)
    result = run("model", tmp_path / "m.urdf.xacro")
    assert result.exit_code == 0, result.stderr
    lines = result.stderr.strip().splitlines()
    assert all(line.startswith("massprops: warning: ") and "m.urdf.xacro" in line
               for line in lines), result.stderr
    assert any("xacro: redefining global symbol: pi" in line for line in lines)
    assert any("no links" in line and "macros only" in line for line in lines)
    assert "when processing file" not in result.stderr


ARM = """<?xml version="1.0"?>
<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="reach" value="0.4"/>
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="${reach/2} 0 0"/><mass value="2"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.03"/></inertial></link>
  <joint name="j" type="continuous"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 ${reach}"/><axis xyz="0 1 0"/></joint>
</robot>
"""


def test_simulate_reads_the_expanded_xacro(tmp_path, run):
    """The mechanism comes from xacro's output, not the raw file's ${...} (the holding torque
    of 2 kg at 0.2 m)."""
    pytest.importorskip("xacro")
    (tmp_path / "arm.urdf.xacro").write_text(ARM)
    result = run("simulate", tmp_path / "arm.urdf.xacro", "--duration", "0", "--json")
    assert result.exit_code == 0, result.stderr
    held = json.loads(result.stdout)["final"]["joints"]["j"]["holding"][0]
    assert held == pytest.approx(-9.81 * 2 * 0.2, rel=1e-12)
