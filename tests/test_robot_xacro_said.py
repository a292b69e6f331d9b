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


# --- the settings a description's messages name exist where the message is read (issue 30) ----
ARG_ARM = ARM.replace('<xacro:property name="reach" value="0.4"/>',
                      '<xacro:arg name="unused" default="0"/>').replace(
    "${reach/2}", "$(arg half)").replace("${reach}", "0.4")


def _one_error(result) -> str:
    lines = result.stderr.strip().splitlines()
    errors = [x for x in lines if x.startswith("massprops: error: ")]
    assert len(errors) == 1 and "Traceback" not in result.stderr, result.stderr
    return errors[0].removeprefix("massprops: error: ")


def test_simulate_takes_xacro_arg_as_its_message_says(tmp_path, run):
    pytest.importorskip("xacro")
    path = tmp_path / "arm.urdf.xacro"
    path.write_text(ARG_ARM)
    result = run("simulate", path, "--duration", "0", "--json")
    assert result.exit_code == 1
    assert _one_error(result) == (f"{path}: xacro failed: Undefined substitution argument half; "
                                  "give its value with --xacro-arg half:=VALUE")
    result = run("simulate", path, "--duration", "0", "--json", "--xacro-arg", "half:=0.2")
    assert result.exit_code == 0, result.stderr
    held = json.loads(result.stdout)["final"]["joints"]["j"]["holding"][0]
    assert held == pytest.approx(-9.81 * 2 * 0.2, rel=1e-12)


def test_a_model_scene_takes_xacro_args_as_its_message_says(tmp_path, run):
    pytest.importorskip("xacro")
    (tmp_path / "arm.urdf.xacro").write_text(ARG_ARM)
    scene = tmp_path / "arm.yaml"
    scene.write_text("model: arm.urdf.xacro\ntime: {duration: 1}\n")
    result = run("simulate", scene, "--duration", "0")
    assert result.exit_code == 1
    assert _one_error(result) == (
        f"{scene}:1: model: {tmp_path / 'arm.urdf.xacro'}: xacro failed: Undefined "
        "substitution argument half; give its value with an entry of the scene key "
        "xacro_args: half:=VALUE")
    scene.write_text("model: arm.urdf.xacro\nxacro_args: [half:=0.2]\ntime: {duration: 1}\n"
                     "forces: [{type: gravity, g: [0, 0, -9.81]}]\n")
    result = run("simulate", scene, "--duration", "0", "--json")
    assert result.exit_code == 0, result.stderr
    held = json.loads(result.stdout)["final"]["joints"]["j"]["holding"][0]
    assert held == pytest.approx(-9.81 * 2 * 0.2, rel=1e-12)
    scene.write_text("model: arm.urdf.xacro\nxacro_args: [half]\ntime: {duration: 1}\n")
    assert _one_error(run("simulate", scene)) == (
        f"{scene}:2: xacro_args[0]: expected NAME:=VALUE, got 'half'")


def test_an_undefined_property_is_said_as_such_not_as_an_argument(tmp_path, run):
    pytest.importorskip("xacro")
    path = tmp_path / "arm.urdf.xacro"
    path.write_text(ARM.replace('<xacro:property name="reach" value="0.4"/>', ""))
    result = run("model", path)
    assert result.exit_code == 1
    line = _one_error(result)
    assert line.startswith(f"{path}: xacro failed: name 'reach' is not defined")
    assert line.endswith("; the property 'reach' is not defined in arm.urdf.xacro nor in the "
                         "files it includes: define it there (<xacro:property name=\"reach\" "
                         "value=\"...\"/>) or fix the expression")
    assert "--xacro-arg" not in line


PACKAGED = """<robot name="r">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="0.2 0 0"/><mass value="2"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.03"/></inertial>
    <collision><origin xyz="-0.3 -0.5 -0.5"/>
      <geometry><mesh filename="package://mypkg/meshes/cube.obj"/></geometry></collision></link>
  <joint name="j" type="continuous"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 1 0"/></joint>
</robot>
"""


def test_a_model_scene_takes_package_path_as_its_message_says(tmp_path, run):
    """inertials: computed reads the package:// mesh: a unit cube of the stated 2 kg whose
    centre is 0.2 m out along x (the holding torque of 2 kg at 0.2 m)."""
    from conftest import SAMPLES

    (tmp_path / "ros" / "mypkg" / "meshes").mkdir(parents=True)
    (tmp_path / "ros" / "mypkg" / "meshes" / "cube.obj").write_bytes(
        (SAMPLES / "cube.obj").read_bytes())
    (tmp_path / "robot").mkdir()
    (tmp_path / "robot" / "arm.urdf").write_text(PACKAGED)
    scene = tmp_path / "robot" / "arm.yaml"
    scene.write_text("model: arm.urdf\ninertials: computed\ntime: {duration: 1}\n")
    line = _one_error(run("simulate", scene, "--duration", "0"))
    assert line.startswith(f"{scene}:1: model: ")
    assert line.endswith("give the scene key package_path: DIR (the folder holding mypkg/) or "
                         "set ROS_PACKAGE_PATH")
    scene.write_text("model: arm.urdf\npackage_path: ../ros\ninertials: computed\n"
                     "time: {duration: 1}\nforces: [{type: gravity, g: [0, 0, -9.81]}]\n")
    result = run("simulate", scene, "--duration", "0", "--json")
    assert result.exit_code == 0, result.stderr
    held = json.loads(result.stdout)["final"]["joints"]["j"]["holding"][0]
    assert held == pytest.approx(-9.81 * 2 * 0.2, rel=1e-12)
    result = run("simulate", scene, "--package-path", tmp_path / "ros")
    assert result.exit_code == 2
    assert _one_error(result) == (
        f"{scene}: --package-path applies to a robot description given directly; a scene "
        "with model: names its own (the keys package_path and xacro_args)")


def test_simulate_takes_package_path_for_xacro_find(tmp_path, run):
    pytest.importorskip("xacro")
    (tmp_path / "ros" / "mypkg").mkdir(parents=True)
    path = tmp_path / "robot" / "arm.urdf.xacro"
    path.parent.mkdir()
    path.write_text(ARM.replace('<link name="base"/>',
                                '<link name="base"><visual><geometry><mesh filename='
                                '"$(find mypkg)/base.obj"/></geometry></visual></link>'))
    line = _one_error(run("simulate", path, "--duration", "0"))
    assert line.startswith(f"{path}: $(find mypkg): cannot find package 'mypkg'")
    assert line.endswith("give --package-path DIR (the folder holding mypkg/) or set "
                         "ROS_PACKAGE_PATH")
    result = run("simulate", path, "--duration", "0", "--json", "--package-path",
                 tmp_path / "ros")
    assert result.exit_code == 0, result.stderr


def test_an_include_by_package_uri_says_to_write_find(tmp_path, run):
    """example-robot-data's hector_description/robots/quadrotor_base.xacro includes
    "package://example-robot-data/robots/hector_description/urdf/quadrotor_base.urdf.xacro":
    xacro takes that for a relative path and finds nothing."""
    pytest.importorskip("xacro")
    path = tmp_path / "robots" / "q.xacro"
    path.parent.mkdir()
    path.write_text('<robot name="q" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                    '<xacro:include filename="package://mypkg/urdf/base.urdf.xacro"/></robot>')
    result = run("model", path)
    assert result.exit_code == 1
    line = _one_error(result)
    assert line.startswith(f"{path}: xacro failed: No such file or directory")
    assert line.endswith("; xacro:include takes a path, not a URI: write "
                         "$(find mypkg)/urdf/base.urdf.xacro for "
                         "package://mypkg/urdf/base.urdf.xacro")
