"""Input files are regular files (massprops.files): a named pipe, a socket or a device given
as an input, found in a directory, or named by a scene or a robot description is refused in
one line naming it, exit 1, before it is opened (issue 30: opening a pipe without a writer
waited forever)."""

from __future__ import annotations

import os
import re
import socket

import pytest
from conftest import SAMPLES

from massprops.errors import MeshFileError
from massprops.files import check_input_file, read_input
from massprops.io import read_mesh

pytestmark = [pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="POSIX named pipes"),
              pytest.mark.timeout(30)]  # before the fix these waited for a writer: fail, not hang

FIFO = "is a named pipe (FIFO), not a regular file"


def fifo(path):
    os.mkfifo(path)
    return path


def one_error_line(res, name: str, problem: str) -> None:
    """stderr is exactly one line: the error naming the file, then the problem."""
    lines = res.stderr.splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith(f"massprops: error: {name}: ") and problem in lines[0], lines[0]


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".vf", ".vtx", ".off", ".ply", ".dae"])
def test_read_mesh_refuses_a_named_pipe_of_every_format(suffix, tmp_path):
    path = fifo(tmp_path / f"pipe{suffix}")
    with pytest.raises(MeshFileError) as caught:
        read_mesh(path)
    assert str(caught.value) == f"{path}: {FIFO}; expected a mesh file"


def test_a_socket_and_a_device_are_refused(tmp_path):
    path = tmp_path / "s.obj"
    server = socket.socket(socket.AF_UNIX)
    try:
        server.bind(str(path))
        with pytest.raises(MeshFileError, match="is a socket, not a regular file"):
            read_mesh(path)
    finally:
        server.close()
    with pytest.raises(MeshFileError, match="/dev/null: is a character device, not a regular"):
        read_mesh("/dev/null", format="obj")
    with pytest.raises(MeshFileError, match="is a character device"):
        check_input_file("/dev/null")


def test_read_input_says_what_was_expected(tmp_path):
    path = fifo(tmp_path / "scene.yaml")
    with pytest.raises(MeshFileError, match=re.escape(f"{FIFO}; expected a scene file")):
        read_input(path, what="a scene file")
    assert read_input(SAMPLES / "cube.obj") == (SAMPLES / "cube.obj").read_bytes()


def test_inspect_a_pipe(run, tmp_path):
    path = fifo(tmp_path / "f.obj")
    res = run("inspect", path)
    assert res.exit_code == 1
    assert res.stdout == ""
    one_error_line(res, str(path), f"{FIFO}; expected a mesh file")


def test_inspect_a_directory_holding_a_pipe_reports_it_and_goes_on(run, tmp_path):
    (tmp_path / "a.obj").write_bytes((SAMPLES / "cube.obj").read_bytes())
    pipe = fifo(tmp_path / "b.obj")
    res = run("inspect", "--json", tmp_path)
    assert res.exit_code == 1
    assert res.stdout.count('"file"') == 1 and "a.obj" in res.stdout
    errors = [x for x in res.stderr.splitlines() if x.startswith("massprops: error:")]
    assert errors == [f"massprops: error: {pipe}: {FIFO}; expected a mesh file"]


def test_align_a_pipe_writes_nothing(run, tmp_path):
    path = fifo(tmp_path / "f.obj")
    res = run("align", path, tmp_path / "out.obj")
    assert res.exit_code == 1
    one_error_line(res, str(path), f"{FIFO}; expected a mesh file")
    assert not (tmp_path / "out.obj").exists()


@pytest.mark.parametrize("command", ["simulate", "precision"])
def test_scene_file_that_is_a_pipe(run, tmp_path, command):
    path = fifo(tmp_path / "fifo.yaml")
    res = run(command, path)
    assert res.exit_code == 1
    one_error_line(res, str(path), f"{FIFO}; expected a scene file (YAML)")


@pytest.mark.parametrize("name", ["fifo.urdf", "fifo.xacro", "fifo.sdf"])
def test_robot_description_that_is_a_pipe(run, tmp_path, name):
    path = fifo(tmp_path / name)
    res = run("model", path)
    assert res.exit_code == 1
    one_error_line(res, str(path), f"{FIFO}; expected a robot description file")


def test_simulate_a_robot_description_that_is_a_pipe(run, tmp_path):
    path = fifo(tmp_path / "fifo.urdf")
    res = run("simulate", path)
    assert res.exit_code == 1
    one_error_line(res, str(path), f"{FIFO}; expected a robot description file")


def test_scene_mesh_that_is_a_pipe(run, tmp_path):
    fifo(tmp_path / "f.obj")
    scene = tmp_path / "s.yaml"
    scene.write_text("body: {mesh: f.obj, density: 1}\ntime: {duration: 1}\n")
    res = run("simulate", scene)
    assert res.exit_code == 1
    one_error_line(res, f"{scene}:1", f"body.mesh: {tmp_path / 'f.obj'} {FIFO}")


def test_model_scene_naming_a_pipe(run, tmp_path):
    fifo(tmp_path / "arm.urdf")
    scene = tmp_path / "m.yaml"
    scene.write_text("model: arm.urdf\ntime: {duration: 1}\n")
    res = run("simulate", scene)
    assert res.exit_code == 1
    one_error_line(res, f"{scene}:1", f"model: {tmp_path / 'arm.urdf'} {FIFO}")


def test_robot_mesh_that_is_a_pipe(run, tmp_path):
    fifo(tmp_path / "f.obj")
    urdf = tmp_path / "r.urdf"
    urdf.write_text('<robot name="r"><link name="a"><collision><geometry>'
                    '<mesh filename="f.obj"/></geometry></collision></link></robot>\n')
    res = run("model", "--json", urdf)
    assert res.exit_code == 1
    errors = [x for x in res.stderr.splitlines() if x.startswith("massprops: error:")]
    assert len(errors) == 1 and f"f.obj: {FIFO}" in errors[0], res.stderr


def test_mjcf_include_that_is_a_pipe(run, tmp_path):
    fifo(tmp_path / "part.xml")
    main = tmp_path / "main.xml"
    main.write_text('<mujoco><include file="part.xml"/><worldbody/></mujoco>\n')
    res = run("model", main)
    assert res.exit_code == 1
    one_error_line(res, str(tmp_path / "part.xml"),
                   f"{FIFO}; expected a robot description file")
