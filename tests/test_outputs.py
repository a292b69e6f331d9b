"""One rule for every file a command writes (massprops.io.atomic, issue 30): the extension names
a format the command writes (else exit 2 naming the file, the extension and the accepted
ones); the file is no input, does not exist without --force, and its folder exists and is
writable (exit 1); all checked BEFORE any work, and written atomically."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import ROOT, SAMPLES

from massprops.errors import MeshFileError, OutputExistsError, UsageError
from massprops.io.atomic import OutputKind, check_output

SCENES = ROOT / "sample_scenes"
ARM = ROOT / "tests" / "robots" / "arm_description" / "urdf" / "arm.urdf"


@pytest.fixture
def no_work(monkeypatch):
    """Every command's work fails the test if it starts: the rule must refuse first."""
    def refuse(*args, **kwargs):
        raise AssertionError("the work started before the outputs were checked")

    for target in ("massprops.dynamics.precision.precision",
                   "massprops.dynamics.simulate.simulate",
                   "massprops.dynamics.systems.run.simulate_system",
                   "massprops.robot.analyze.analyze_model",
                   "massprops.inspection.file.inspect_file"):
        monkeypatch.setattr(target, refuse)


def error_line(res) -> str:
    lines = [x for x in res.stderr.splitlines() if x.startswith("massprops: error:")]
    assert len(lines) == 1, res.stderr
    assert "Traceback" not in res.stderr
    return lines[0].removeprefix("massprops: error: ")


def scene(tmp_path, name="disk.yaml", extra="") -> Path:
    path = tmp_path / name
    path.write_text((SCENES / "disk.yaml").read_text() + extra)
    return path


# --- the extension: exit 2, naming the file, its extension and the accepted ones --------------
@pytest.mark.parametrize("args, name, says", [
    (["simulate", "{scene}", "--output", "{dir}/t.json"], "t.json",
     "cannot write a trajectory as '.json' (--output); expected .csv or .npz"),
    (["simulate", "{scene}", "--plot", "{dir}/p.txt"], "p.txt",
     "cannot write a plot as '.txt' (--plot); expected .png"),
    (["precision", "{scene}", "--plot", "{dir}/wp.txt"], "wp.txt",
     "cannot write a plot as '.txt' (--plot); expected .png"),
    (["model", str(ARM), "--write", "{dir}/out.txt"], "out.txt",
     "cannot write the edited description as '.txt' (--write); expected .urdf"),
    (["align", str(SAMPLES / "cube.obj"), "{dir}/out.txt"], "out.txt",
     "cannot write a mesh as '.txt'; expected .fac, .obj, .off, .ply, .stl, .vf or .vtx"),
    (["align", str(SAMPLES / "cube.obj"), "{dir}/out"], "out",
     "cannot write a mesh without an extension; expected .fac, .obj, .off, .ply, .stl, .vf "
     "or .vtx"),
], ids=["simulate-output", "simulate-plot", "precision-plot", "model-write", "align",
        "align-no-extension"])
def test_an_extension_the_command_cannot_write_is_a_usage_error(run, tmp_path, no_work, args,
                                                                 name, says):
    path = scene(tmp_path)
    res = run(*[a.format(scene=path, dir=tmp_path) for a in args])
    assert res.exit_code == 2
    assert error_line(res) == f"{tmp_path / name}: {says}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["disk.yaml"]


def test_model_write_takes_the_descriptions_own_extension(tmp_path):
    from massprops.robot.write.writeback import description_output

    assert description_output("a/arm.urdf").extensions == (".urdf",)
    assert description_output("a/arm.XML").extensions == (".xml",)
    assert description_output("a/arm.urdf.xacro").extensions == (".urdf",)  # its expansion
    assert description_output("base.sdf").extensions == (".sdf",)


# --- the destination, before any work: exit 1 ----------------------------------------------------
def test_precision_plot_into_a_missing_folder_is_refused_before_the_ladder(run, tmp_path,
                                                                            no_work):
    res = run("precision", scene(tmp_path), "--plot", tmp_path / "nodir" / "wp.png")
    assert res.exit_code == 1
    assert error_line(res) == (f"{tmp_path / 'nodir' / 'wp.png'}: the directory "
                               f"{tmp_path / 'nodir'} does not exist; create it first")


@pytest.mark.parametrize("args", [
    ["precision", "{scene}", "--plot", "{out}.png"],
    ["simulate", "{scene}", "--plot", "{out}.png"],
    ["simulate", "{scene}", "--output", "{out}.csv"],
    ["model", str(ARM), "--write", "{out}.urdf"],
    ["align", str(SAMPLES / "cube.obj"), "{out}.obj"],
], ids=["precision-plot", "simulate-plot", "simulate-output", "model-write", "align"])
def test_an_existing_output_without_force_is_refused_before_any_work(run, tmp_path, no_work,
                                                                      args):
    path = scene(tmp_path)
    out = tmp_path / "out"
    args = [a.format(scene=path, out=out) for a in args]
    Path(args[-1]).write_text("keep me")
    res = run(*args)
    assert res.exit_code == 1
    assert error_line(res) == f"{args[-1]}: already exists; use --force to overwrite it"
    assert Path(args[-1]).read_text() == "keep me"


def test_the_scenes_own_output_file_is_checked_before_the_run(run, tmp_path, no_work):
    (tmp_path / "traj.csv").write_text("keep me")
    path = scene(tmp_path, extra="  file: traj.csv\n")  # under output: (the file's last key)
    res = run("simulate", path)
    assert res.exit_code == 1
    assert error_line(res) == (f"{tmp_path / 'traj.csv'}: already exists; use --force to "
                               "overwrite it")


@pytest.mark.parametrize("args, out", [
    (["simulate", "{scene}", "--output", "{scene}"], "{scene}"),
    (["model", str(ARM), "--write", str(ARM), "--force"], str(ARM)),
    (["align", "--force", str(SAMPLES / "cube.obj"), str(SAMPLES / "cube.obj")],
     str(SAMPLES / "cube.obj")),
], ids=["simulate", "model", "align"])
def test_an_input_is_never_an_output(run, tmp_path, no_work, args, out):
    path = scene(tmp_path, name="disk.csv")  # a scene whose name a trajectory could have
    before = Path(out.format(scene=path)).read_bytes()
    res = run(*[a.format(scene=path) for a in args])
    assert res.exit_code == 1
    assert "is an input of this command" in error_line(res)
    assert Path(out.format(scene=path)).read_bytes() == before


def test_two_outputs_of_one_run_may_not_be_one_file(run, tmp_path, no_work):
    res = run("simulate", scene(tmp_path), "--output", tmp_path / "a.npz", "--plot",
              tmp_path / "a.npz")
    assert res.exit_code == 2  # the plot's extension is wrong first
    res = run("simulate", scene(tmp_path), "--output", tmp_path / "a.csv", "--plot",
              tmp_path / "a.csv", "--force")
    assert res.exit_code == 2


def test_a_folder_that_is_not_writable_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr("massprops.io.atomic.os.access", lambda path, mode: False)
    with pytest.raises(MeshFileError, match="is not writable"):
        check_output(tmp_path / "t.csv", OutputKind("a trajectory", (".csv",)), force=False)


def test_the_library_writers_keep_the_rule(tmp_path):
    from massprops.dynamics.trajectory import write_trajectory
    from massprops.io import read_mesh, write_mesh

    with pytest.raises(UsageError, match=r"t.json: cannot write a trajectory as '.json' "
                                         r"\(output\); expected .csv or .npz"):
        write_trajectory(None, tmp_path / "t.json")
    with pytest.raises(UsageError, match="cannot write a mesh as '.vtk'"):
        write_mesh(read_mesh(SAMPLES / "cube.obj"), tmp_path / "a.vtk")
    plot = OutputKind("a plot", (".png",))
    assert check_output(tmp_path / "x.PNG", plot, force=False) == tmp_path / "x.PNG"
    (tmp_path / "x.png").write_bytes(b"old")
    with pytest.raises(OutputExistsError):
        check_output(tmp_path / "x.png", plot, force=False)
    assert check_output(tmp_path / "x.png", plot, force=True) == tmp_path / "x.png"
    assert list(tmp_path.iterdir()) == [tmp_path / "x.png"]


def test_a_plot_is_a_png_whatever_writes_it(tmp_path):
    pytest.importorskip("matplotlib")
    from massprops.dynamics.plots import _pyplot, save_figure

    fig = _pyplot().figure()
    with pytest.raises(UsageError, match=r"wp.txt: cannot write a plot as '.txt'"):
        save_figure(fig, tmp_path / "wp.txt")
    save_figure(fig, tmp_path / "wp.png")
    assert (tmp_path / "wp.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["wp.png"]
