"""`massprops inspect` over many files: byte identity with the one-process loop, parallel runs,
inputs from directories, globs and lists, CSV, Ctrl-C, start-up cost."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from _batchdata import descendants, mixed_batch, torus_obj
from conftest import SAMPLES, box_vf, json_lines

from massprops.batch import plan, pool
from massprops.cli.report import print_inspection
from massprops.errors import error_message, exit_code
from massprops.inspection.file import inspect_file


def sequential(paths, out_format="json", **options) -> tuple[str, str, int]:
    """(stdout, stderr, exit code) of the plain loop `inspect` ran before batches existed:
    per file inspect_file, its warning lines, its output; a failure is one error line."""
    out, err, worst = io.StringIO(), [], 0
    for path in map(str, paths):
        try:
            result = inspect_file(path, name=path, **options)
        except Exception as exc:
            err.append(f"massprops: error: {error_message(exc)}\n")
            worst = max(worst, exit_code(exc))
            continue
        err += [f"massprops: warning: {path}: {w}\n" for w in result.warnings]
        if out_format == "json":
            out.write(json.dumps(result.as_dict(), allow_nan=False) + "\n")
        else:
            with contextlib.redirect_stdout(out):
                print_inspection(result.as_dict(), tuple(result.repairs or ()))
    return out.getvalue(), "".join(err), worst


def without_summary(stderr: str) -> str:
    return "".join(line for line in stderr.splitlines(keepends=True)
                   if not line.startswith("massprops: ") or " files in " not in line)


@pytest.fixture
def pool_always(monkeypatch):
    """Force the local pool on the small batches of these tests; count the pools started."""
    started = []
    real = pool.local_pool

    def counting(jobs):
        started.append(jobs)
        return real(jobs)

    monkeypatch.setattr(plan, "POOL_MIN_S", 0.0)
    monkeypatch.setattr(plan, "LOCAL_CHUNK_S", 0.0)  # one file per task
    monkeypatch.setattr(pool, "local_pool", counting)
    return started


# --- --jobs 1 is the old loop; --jobs 2 is --jobs 1 ------------------------------------------
@pytest.mark.parametrize("out_format", ["json", "table"])
def test_jobs_1_prints_what_the_one_process_loop_printed(run, tmp_path, out_format):
    paths = [*mixed_batch(tmp_path, 7), tmp_path / "missing.stl", SAMPLES / "cuboid.stl"]
    flag = ["--json"] if out_format == "json" else []
    res = run("inspect", *flag, "--jobs", "1", "--allow-open", "--density", "2.5", *paths)
    want_out, want_err, want_code = sequential(paths, out_format, allow_open=True, density=2.5)
    assert (res.stdout, res.stderr, res.exit_code) == (want_out, want_err, want_code)
    assert want_code == 1 and want_out.count('"file"' if flag else "principal moments") == 9


@pytest.mark.slow
@pytest.mark.timeout(60)
@pytest.mark.parametrize("out_format", ["json", "csv", "table"])
def test_jobs_2_prints_the_bytes_of_jobs_1(run, tmp_path, pool_always, out_format):
    paths = [*mixed_batch(tmp_path, 12), tmp_path / "missing.obj"]
    args = ["inspect", "--format", out_format, "--unit", "cm", *paths]
    one = run(*args, "--jobs", "1")
    two = run(*args, "--jobs", "2")
    assert pool_always == [2]  # the second run did use worker processes
    assert two.stdout == one.stdout and two.stderr == one.stderr
    assert two.exit_code == one.exit_code == 1


def test_default_jobs_is_the_usable_cores():
    assert pool.default_jobs() == len(os.sched_getaffinity(0))


# --- a bad file in a batch -------------------------------------------------------------------
def test_bad_file_has_its_line_its_row_and_the_worst_exit_code(run, tmp_path):
    paths = mixed_batch(tmp_path, 6)
    res = run("inspect", "--format", "csv", *paths)
    assert res.exit_code == 1
    errors = [line for line in res.stderr.splitlines() if line.startswith("massprops: error: ")]
    assert len(errors) == 2 and "m50_garbage.obj" in errors[0] and "m51_open.obj" in errors[1]
    rows = list(csv.DictReader(io.StringIO(res.stdout)))
    assert [r["file"] for r in rows] == [str(p) for p in paths]
    failed = [r for r in rows if r["error"]]
    assert [r["file"] for r in failed] == [str(paths[3]), str(paths[5])]
    assert all(f"massprops: error: {r['error']}" in errors for r in failed)
    assert all(r["volume"] == "" and r["closed"] == "" for r in failed)


def test_json_and_csv_rows_agree(run, tmp_path):
    paths = mixed_batch(tmp_path, 6)
    objs = json_lines(run("inspect", "--json", "--allow-open", *paths).stdout)
    rows = list(csv.DictReader(io.StringIO(run("inspect", "--format", "csv", "--allow-open",
                                               *paths).stdout)))
    good = [r for r in rows if not r["error"]]
    assert len(good) == len(objs) == len(paths) - 1  # only the garbage file fails
    for row, obj in zip(good, objs):
        assert row["file"] == obj["file"]
        assert float(row["I3"]) == obj["principal_moments"][2]
        assert float(row["Jxz"]) == obj["inertia"][0][2]
        assert int(row["warnings"]) == len(obj["warnings"])


# --- inputs ----------------------------------------------------------------------------------
def test_directory_recursive_and_glob_inputs(run, tmp_path):
    box_vf(tmp_path / "top.vf")
    (tmp_path / "sub").mkdir()
    torus_obj(tmp_path / "sub" / "t.obj")
    (tmp_path / "notes.txt").write_text("not a mesh")
    flat = json_lines(run("inspect", "--json", tmp_path).stdout)
    assert [o["file"] for o in flat] == [str(tmp_path / "top.vf")]
    deep = run("inspect", "--json", "--recursive", tmp_path)
    assert [o["file"] for o in json_lines(deep.stdout)] == [str(tmp_path / "sub" / "t.obj"),
                                                            str(tmp_path / "top.vf")]
    assert deep.exit_code == 0 and "2 files in" in deep.stderr and "2 done, 0 failed" in \
        deep.stderr  # a listing gets a summary line, even on a pipe
    glob = run("inspect", "--json", "-q", str(tmp_path / "**" / "*.obj"))
    assert [o["file"] for o in json_lines(glob.stdout)] == [str(tmp_path / "sub" / "t.obj")]
    assert glob.stderr == ""  # --quiet: no summary
    empty = tmp_path / "empty"
    empty.mkdir()
    res = run("inspect", "--json", empty)
    assert res.exit_code == 1 and "no mesh files" in res.stderr and res.stdout == ""


def test_files_from_stdin_nul_separated(run, tmp_path):
    names = [tmp_path / "a b.vf", tmp_path / "new\nline.vf", tmp_path / "c.vf"]
    for k, p in enumerate(names):
        box_vf(p, size=(1.0 + k, 1.0, 1.0))
    listing = b"\0".join(os.fsencode(p) for p in names) + b"\0"
    res = run("inspect", "--json", "--files-from", "-", "-0", input=listing)
    assert res.exit_code == 0, res.stderr
    assert [o["volume"] for o in json_lines(res.stdout)] == [1.0, 2.0, 3.0]
    lines = tmp_path / "list.txt"
    lines.write_text(f"{names[2]}\n{names[0]}\n")
    res = run("inspect", "--json", "--files-from", lines, SAMPLES / "cube.obj")
    assert [o["volume"] for o in json_lines(res.stdout)] == [1.0, 3.0, 1.0]


@pytest.mark.timeout(60)
def test_find_print0_pipeline(tmp_path):
    for k, name in enumerate(["p q.obj", "r.obj", "s\nt.obj"]):
        torus_obj(tmp_path / name, 8 + k, 6)
    find = subprocess.run(["find", str(tmp_path), "-name", "*.obj", "-print0"],
                          capture_output=True, check=True).stdout
    res = subprocess.run(
        f"find {tmp_path} -name '*.obj' -print0 | {sys.executable} -m massprops inspect "
        "--files-from - -0 --json", shell=True, capture_output=True)
    assert res.returncode == 0, res.stderr
    files = [json.loads(line)["file"] for line in res.stdout.decode().splitlines()]
    assert files == [os.fsdecode(p) for p in find.split(b"\0") if p]  # find's order, kept


@pytest.mark.parametrize("args", [
    ["--json", "--format", "csv", "cube.obj"],
    [],
    ["-0", "cube.obj"],
    ["--input-format", "obj", "-", "--files-from", "-"],
    ["--jobs", "0", "cube.obj"],
    ["--jobs", "2", "--scheduler", "tcp://127.0.0.1:1", "cube.obj"],
], ids=["json-and-csv", "no-input", "null-without-list", "stdin-twice", "jobs-0",
        "jobs-and-scheduler"])
def test_usage_errors_exit_2(run, args):
    res = run("inspect", *args)
    assert res.exit_code == 2 and res.stdout == ""


def test_scheduler_without_dask_says_what_to_install(run, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if not installed
    res = run("inspect", "--scheduler", "tcp://127.0.0.1:8786", SAMPLES / "cube.obj")
    assert res.exit_code == 2 and "pip install 'massprops[dask]'" in res.stderr


# --- Ctrl-C ----------------------------------------------------------------------------------
@pytest.mark.timeout(90)
def test_ctrl_c_exits_130_with_what_finished_and_leaves_no_process(tmp_path):
    mesh = torus_obj(tmp_path / "t.obj", 100, 100)
    paths = []
    for k in range(150):  # one mesh under many names: a long batch without writing it 150 times
        os.link(mesh, tmp_path / f"t{k:03d}.obj")
        paths.append(str(tmp_path / f"t{k:03d}.obj"))
    listing = tmp_path / "list.txt"
    listing.write_text("".join(p + "\n" for p in paths))
    proc = subprocess.Popen(
        [sys.executable, "-m", "massprops", "inspect", "--json", "--jobs", "2", "--files-from",
         str(listing)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
        bufsize=0)  # unbuffered: readline must not keep bytes that communicate() then misses
    first = proc.stdout.readline()  # the batch is running and has printed
    helpers = descendants(proc.pid)
    os.killpg(proc.pid, signal.SIGINT)  # what a terminal's Ctrl-C does: the whole group
    rest, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    objs = [json.loads(line) for line in (first + rest).decode().splitlines()]
    index = [paths.index(o["file"]) for o in objs]
    assert 1 <= len(objs) < len(paths) and index == sorted(set(index))  # in order, once each
    want = inspect_file(str(mesh)).as_dict()
    assert all({**o, "file": None} == {**want, "file": None} for o in objs)
    assert re.search(rf"^massprops: {len(objs)} of \d+\+? files in .* {len(objs)} done, 0 failed$",
                     err.decode(), re.M)  # the summary counts what was written
    assert helpers, "the pool had no processes to check"
    deadline = time.monotonic() + 5
    while [p for p in helpers if Path(f"/proc/{p}").exists() and not _zombie(p)]:
        assert time.monotonic() < deadline, "a child of massprops outlived it"
        time.sleep(0.05)


def _zombie(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


# --- start-up --------------------------------------------------------------------------------
def test_one_small_file_imports_no_pool_and_nothing_heavy():
    heavy = {"rich", "scipy", "trimesh", "numba", "manifold3d", "lxml", "dask", "distributed",
             "meshio", "multiprocessing", "concurrent", "csv"}
    code = (
        "import sys, atexit\n"
        f"atexit.register(lambda: print(sorted({{m.split('.')[0] for m in sys.modules}} & set("
        f"{sorted(heavy)!r})), file=sys.stderr))\n"
        "from massprops.cli import main\n"
        f"sys.argv = ['massprops', 'inspect', '--json', {str(SAMPLES / 'cube.obj')!r}, "
        f"{str(SAMPLES / 'torus.obj')!r}]\n"
        "main()\n")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert res.stderr.strip().splitlines()[-1] == "[]"


@pytest.mark.timeout(60)
def test_closed_stdout_stops_the_batch_quietly(tmp_path):
    mesh = torus_obj(tmp_path / "t.obj", 60, 40)
    for k in range(300):
        os.link(mesh, tmp_path / f"t{k:03d}.obj")
    res = subprocess.run(f"{sys.executable} -m massprops inspect --json -q {tmp_path} | head -n 2"
                         "; echo \"status ${PIPESTATUS[0]}\" >&2", shell=True, executable="bash",
                         capture_output=True, text=True)
    assert len(res.stdout.splitlines()) == 2
    assert res.stderr.strip().splitlines() == ["status 1"]  # no error line per remaining file


def test_standard_input_joins_a_parallel_batch_in_its_place(run, tmp_path, pool_always):
    paths = [str(torus_obj(tmp_path / f"t{k}.obj", 10 + k, 6)) for k in range(4)]
    args = ["inspect", "--json", "--input-format", "obj", paths[0], paths[1], "-", paths[2]]
    text = (SAMPLES / "cuboid.obj").read_text()
    one = run(*args, "--jobs", "1", input=text)
    two = run(*args, "--jobs", "2", input=text)
    assert pool_always == [2] and two.stdout == one.stdout and two.exit_code == 0
    assert [o["file"] for o in json_lines(two.stdout)] == [paths[0], paths[1], "<stdin>",
                                                          paths[2]]


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_progress_bar_and_summary_on_a_terminal_only(tmp_path):
    import pty

    mesh = torus_obj(tmp_path / "t.obj", 100, 100)
    for k in range(80):
        os.link(mesh, tmp_path / f"t{k:02d}.obj")
    leader, follower = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "massprops", "inspect", "--json", "-j", "1",
                             *sorted(map(str, tmp_path.glob("t??.obj")))],
                            stdout=subprocess.DEVNULL, stderr=follower)
    os.close(follower)
    seen = b""
    with contextlib.suppress(OSError):  # EIO once the process has closed the terminal
        while chunk := os.read(leader, 4096):
            seen += chunk
    os.close(leader)
    assert proc.wait(timeout=60) == 0
    text = seen.decode(errors="replace")
    assert re.search(r"inspecting .* \d+/80 files · [\d.]+ files/s · \d+:\d\d left", text)
    assert re.search(r"massprops: 80 files in [\d.]+ s \([\d.e+]+ files/s\): 80 done, 0 failed",
                     text)


def test_debug_raises_the_error_with_its_traceback(run, tmp_path, pool_always):
    from massprops.cli import RemoteError
    from massprops.errors import MeshFormatError

    paths = [torus_obj(tmp_path / "a.obj"), tmp_path / "b.obj", torus_obj(tmp_path / "c.obj")]
    paths[1].write_bytes(b"\x00 not a mesh")
    with pytest.raises(MeshFormatError):  # one process: the exception itself, as before
        run("--debug", "inspect", "--json", "--jobs", "1", *paths)
    with pytest.raises(RemoteError, match=r"(?s)Traceback.*MeshFormatError: .*b\.obj"):
        run("--debug", "inspect", "--json", "--jobs", "2", *paths)  # a worker's, as text


@pytest.mark.timeout(90)
@pytest.mark.parametrize("args", [
    ["--format", "urdf", "--mass", "1.3"],
    ["--format", "mjcf", "--principal"],
    ["--union"],
    ["--fill-holes", "--max-hole", "0.3", "--json"],
    ["--shell", "0.002", "--density", "7850"],
], ids=["urdf", "mjcf-principal", "union-table", "fill-holes-json", "shell-table"])
@pytest.mark.slow
def test_robot_formats_and_repairs_in_workers_print_the_bytes_of_one_process(
        run, pool_always, args):
    """The other inspect options reach the workers unchanged (repairs as one RepairOptions) and
    every renderer works from the records (the repairs table lists what was asked for)."""
    paths = [SAMPLES / n for n in ("overlapping_boxes.obj", "open_box.obj", "cuboid.stl",
                                   "torus.obj", "cube.obj")]
    one = run("inspect", *args, "--jobs", "1", *paths)
    two = run("inspect", *args, "--jobs", "2", *paths)
    assert pool_always == [2]
    assert (two.stdout, two.stderr, two.exit_code) == (one.stdout, one.stderr, one.exit_code)
    assert one.stdout
