"""``inspect --format urdf|sdf|mjcf`` against the notes' cuboid (closed form), the exit code of a
failed check, and what each command path imports."""

from __future__ import annotations

import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from conftest import SAMPLES, rot_z

from massprops.errors import CheckFailedError, RobotModelError, exit_code

R30 = rot_z(30.0)
CUBOID_J = R30 @ np.diag([8.0, 13.0, 13.0]) @ R30.T   # the notes' cuboid, mass 12


def _floats(text: str) -> list[float]:
    return [float(t) for t in text.split()]


def _element(stdout: str, index: int = 0) -> ET.Element:
    blocks = [b for b in stdout.split("<!--") if b.strip()]
    return ET.fromstring(blocks[index].split("-->", 1)[1])


def test_urdf_element(run):
    res = run("inspect", "--format", "urdf", SAMPLES / "cuboid.obj")
    assert res.exit_code == 0, res.stderr
    el = _element(res.stdout)
    assert el.tag == "inertial"
    assert np.allclose(_floats(el.find("origin").get("xyz")), 0, atol=1e-15)
    assert el.find("origin").get("rpy") == "0 0 0"
    assert abs(float(el.find("mass").get("value")) - 12) < 1e-13
    i = el.find("inertia")
    j = np.array([[float(i.get("ixx")), float(i.get("ixy")), float(i.get("ixz"))],
                  [float(i.get("ixy")), float(i.get("iyy")), float(i.get("iyz"))],
                  [float(i.get("ixz")), float(i.get("iyz")), float(i.get("izz"))]])
    assert np.max(np.abs(j - CUBOID_J)) < 13e-14
    assert j[0, 1] < 0  # J_xy = -∫xy dm of a cuboid turned +30°: the sign is the convention


def test_sdf_element_and_round_trip_digits(run):
    res = run("inspect", "--format", "sdf", "--mass", "1.3", SAMPLES / "cuboid.obj")
    el = _element(res.stdout)
    j = {k: float(el.find("inertia").find(k).text) for k in
         ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    assert abs(j["ixy"] - CUBOID_J[0, 1] * 1.3 / 12) < 1e-14
    assert float(el.find("mass").text) == 1.3
    assert _floats(el.find("pose").text)[3:] == [0, 0, 0]
    (js,) = [__import__("json").loads(line) for line in
             run("inspect", "--json", "--mass", "1.3", SAMPLES / "cuboid.obj").stdout.splitlines()]
    assert j["ixy"] == js["inertia"][0][1]  # repr digits: the same float64 comes back


@pytest.mark.parametrize("principal", [False, True], ids=["fullinertia", "principal"])
def test_mjcf_element(run, principal):
    args = ["inspect", "--format", "mjcf", SAMPLES / "cuboid.obj"]
    res = run(*args, *(["--principal"] if principal else []))
    assert res.exit_code == 0, res.stderr
    el = _element(res.stdout)
    assert abs(float(el.get("mass")) - 12) < 1e-13
    if principal:
        from massprops.rotation import quat_to_matrix

        q = _floats(el.get("quat"))
        a = quat_to_matrix(np.array(q))
        j = a @ np.diag(_floats(el.get("diaginertia"))) @ a.T
        assert q[0] >= 0 and np.allclose(_floats(el.get("diaginertia")), [8, 13, 13],
                                         rtol=1e-14)
    else:
        f = _floats(el.get("fullinertia"))  # Ixx Iyy Izz Ixy Ixz Iyz
        j = np.array([[f[0], f[3], f[4]], [f[3], f[1], f[5]], [f[4], f[5], f[2]]])
    assert np.max(np.abs(j - CUBOID_J)) < 13e-14


def test_one_element_per_mesh_and_json_unchanged(run):
    res = run("inspect", "--format", "urdf", SAMPLES / "cube.obj", SAMPLES / "cuboid.obj")
    assert res.stdout.count("<inertial>") == 2 and "cube.obj" in res.stdout
    a = run("inspect", "--json", SAMPLES / "cube.obj").stdout
    assert run("inspect", "--format", "json", SAMPLES / "cube.obj").stdout == a


@pytest.mark.parametrize("args", [["--format", "urdf", "--principal"],
                                  ["--format", "sdf", "--json"], ["--format", "step"],
                                  ["--principal"]])
def test_format_usage_errors_exit_2(run, args):
    res = run("inspect", *args, SAMPLES / "cube.obj")
    assert res.exit_code == 2 and res.stdout == ""


def test_cli_choices_are_the_writers():
    from massprops.cli import ELEMENT_FORMATS
    from massprops.robot.write.elements import WRITERS

    assert tuple(WRITERS) == ELEMENT_FORMATS


@pytest.mark.parametrize("exc,code", [(CheckFailedError("x"), 4), (RobotModelError("x"), 1)])
def test_exit_codes(exc, code):
    assert exit_code(exc) == code


def _imported(args: list[str]) -> set[str]:
    code = ("import sys; from massprops.cli import main\n"
            "try:\n    main(sys.argv[1:])\nexcept SystemExit:\n    pass\n"
            "print(' '.join(sorted(sys.modules)), file=sys.stderr)")
    out = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True)
    return set(out.stderr.split())


def test_inspect_json_imports_no_robot_code_and_no_xml():
    mods = _imported(["inspect", "--json", str(SAMPLES / "cube.obj")])
    assert "massprops.inspection.file" in mods
    assert not {m for m in mods if m.startswith(("massprops.robot", "xml", "pyexpat", "lxml"))}


def test_inspect_format_urdf_imports_only_the_writers():
    mods = _imported(["inspect", "--format", "urdf", str(SAMPLES / "cube.obj")])
    robot = {m for m in mods if m.startswith("massprops.robot")}
    # the package, the writers' sub-package (a docstring) and the writers: no parser, no mesh code
    assert robot == {"massprops.robot", "massprops.robot.write", "massprops.robot.write.elements"}
    assert not {m for m in mods if m.startswith(("xml", "pyexpat", "lxml", "rich"))}


@pytest.mark.parametrize("args", [["--check", "-1"], ["--check", "nan"], ["--density", "0"],
                                  ["--from", "both"]])
def test_model_usage_errors_exit_2(run, args):
    from test_robot_models import ARM

    res = run("model", *args, ARM)
    assert res.exit_code == 2 and res.stdout == ""


def test_model_table_through_a_pipe_keeps_every_number_and_unit(tmp_path, run):
    """Piped, the table's width is fixed; a link name of 70 characters (real descriptions have
    them) must widen the table, not cut the numbers to "…"; the headers keep their units."""
    src = Path(__file__).parent / "robots" / "arm_description"
    copy = tmp_path / "arm_description"
    shutil.copytree(src, copy)
    urdf = copy / "urdf" / "arm.urdf"
    urdf.write_text(urdf.read_text().replace('"upper_arm"', '"upper_arm_' + "x" * 60 + '"'))
    short, wide = run("model", src / "urdf" / "arm.urdf"), run("model", urdf)
    assert short.exit_code == wide.exit_code == 0, wide.stderr
    assert "…" not in wide.stdout and "mass [kg]" in wide.stdout and "COM off [m]" in wide.stdout

    def rows(out: str) -> list[list[str]]:
        return [line.split()[1:] for line in out.splitlines()[2:] if line.strip()]

    assert rows(wide.stdout) == rows(short.stdout)
