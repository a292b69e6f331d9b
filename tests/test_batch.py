"""massprops.batch as a library: inputs, order, retries, stopping, the CSV table.

References are independent of the batch machinery: a plain loop over `inspect_file` (itself
tested against closed forms elsewhere), closed forms for a box, and the file system itself.
"""

from __future__ import annotations

import csv
import io
import math
import os
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import pytest
from _batchdata import binary_stl_box, descendants, mixed_batch, torus_obj
from conftest import box_vf, said_by_cli

from massprops.batch import BadInput, expand_inputs, inspect_many, mesh_extensions, plan
from massprops.batch.table import CSV_COLUMNS, csv_header, csv_row
from massprops.errors import error_message, exit_code
from massprops.inspection.file import inspect_file


def reference(path, **options) -> tuple:
    """(JSON object or None, warnings, error line or None, exit code) from a plain call."""
    try:
        r = inspect_file(str(path), **options)
    except Exception as exc:
        return None, (), error_message(exc), exit_code(exc)
    return r.as_dict(), r.warnings, None, 0


def outcome(record) -> tuple:
    error = record.error
    return (record.data, record.warnings, None if error is None else error.message,
            record.exit_code)


# --- inputs ----------------------------------------------------------------------------------
def test_directory_lists_mesh_files_by_name_and_a_vtx_fac_pair_once(tmp_path):
    for name in ("b.obj", "a.STL", "c.vtx", "c.fac", "lone.fac", "notes.txt", "d.ply"):
        (tmp_path / name).write_text("x")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "e.obj").write_text("x")
    got = list(expand_inputs([str(tmp_path)]))
    names = [os.path.relpath(p, tmp_path) for p in got]
    assert names == ["a.STL", "b.obj", "c.vtx", "d.ply", "lone.fac"]
    assert ".ply" in mesh_extensions() and ".txt" not in mesh_extensions()


def test_recursive_walks_depth_first_in_name_order_without_following_dir_links(tmp_path):
    for rel in ("a/z.obj", "a/b/y.obj", "c.obj", "a0.obj"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text("x")
    os.symlink(tmp_path / "a", tmp_path / "loop")  # a cycle if followed
    got = [os.path.relpath(p, tmp_path) for p in expand_inputs([str(tmp_path)], recursive=True)]
    assert got == ["a/b/y.obj", "a/z.obj", "a0.obj", "c.obj"]
    flat = [os.path.relpath(p, tmp_path) for p in expand_inputs([str(tmp_path)])]
    assert flat == ["a0.obj", "c.obj"]


def test_directory_without_meshes_is_one_bad_input(tmp_path):
    (tmp_path / "readme.txt").write_text("x")
    (bad,) = expand_inputs([str(tmp_path)])
    assert isinstance(bad, BadInput) and bad.name == str(tmp_path)
    assert exit_code(bad.error) == 1 and "recursive" in bad.error.settings


def test_globs_expand_sorted_and_an_unmatched_pattern_stays_a_path(tmp_path):
    for rel in ("p/2.stl", "p/1.stl", "p/q/3.stl", "p/x.obj"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text("x")
    got = list(expand_inputs([str(tmp_path / "p" / "*.stl"), str(tmp_path / "p/**/*.stl"),
                              str(tmp_path / "nothing*.obj")]))
    rel = [os.path.relpath(p, tmp_path) for p in got[:-1]]
    assert rel == ["p/1.stl", "p/2.stl", "p/1.stl", "p/2.stl", "p/q/3.stl"]
    assert got[-1] == str(tmp_path / "nothing*.obj")  # then fails as a missing file
    literal = tmp_path / "odd[1].obj"  # an existing name with glob characters is a name
    literal.write_text("x")
    assert list(expand_inputs([str(literal)])) == [str(literal)]


def test_files_from_lines_and_nul_separated(tmp_path):
    names = ["a b.obj", "new\nline.obj", "ünï.stl", "-"]
    nul = tmp_path / "list0"
    nul.write_bytes(b"\0".join(n.encode() for n in names) + b"\0\0")
    got = list(expand_inputs([], files_from=str(nul), null=True))
    assert got == ["a b.obj", "new\nline.obj", "ünï.stl", os.path.join(".", "-")]
    lines = tmp_path / "list"
    lines.write_bytes(b"first.obj\r\n\nsecond.obj\nno-newline.obj")
    assert list(expand_inputs(["x.obj"], files_from=str(lines))) == [
        "x.obj", "first.obj", "second.obj", "no-newline.obj"]
    (bad,) = expand_inputs([], files_from=str(tmp_path / "missing.txt"))
    assert isinstance(bad, BadInput) and "cannot read the list" in str(bad.error)


@pytest.mark.timeout(20)
def test_files_from_yields_each_entry_as_it_arrives():
    """A slow producer (find on a big tree): the first path is available before the list ends."""
    read_fd, write_fd = os.pipe()
    release = threading.Event()

    def producer():
        os.write(write_fd, b"one.obj\0")
        release.wait(10)
        os.write(write_fd, b"two.obj\0")
        os.close(write_fd)

    threading.Thread(target=producer, daemon=True).start()
    with open(read_fd, "rb") as stream:
        entries = expand_inputs([], files_from="-", null=True, stdin=stream)
        assert next(entries) == "one.obj"  # would block here if it waited for a full block
        release.set()
        assert list(entries) == ["two.obj"]


# --- inspect_many ----------------------------------------------------------------------------
def test_one_process_is_a_plain_loop(tmp_path):
    paths = mixed_batch(tmp_path)
    batch = inspect_many([str(p) for p in paths], jobs=1, density=7.5)
    got = [outcome(r) for r in batch]
    assert got == [reference(p, density=7.5) for p in paths]
    assert batch.parallel is False and batch.total == len(paths)
    assert [r[3] for r in got].count(1) == 2  # the garbage file and the open mesh


def test_small_batch_never_starts_a_pool(tmp_path):
    paths = [str(box_vf(tmp_path / f"b{k}.vf")) for k in range(3)]
    batch = inspect_many(paths, jobs=4)
    assert [r.data["volume"] for r in batch] == [1.0, 1.0, 1.0]
    assert batch.parallel is False


class DelayedExecutor(ThreadPoolExecutor):
    """Threads where the task submitted first finishes last (it sleeps longest), recording the
    order in which tasks finish."""

    def __init__(self, tasks: int):
        super().__init__(max_workers=tasks)
        self.finished: list[int] = []
        self.submitted = 0
        self.tasks = tasks

    def submit(self, fn, *args, **kwargs):
        delay = 0.02 * max(0, self.tasks - self.submitted)
        self.submitted += 1

        def slow():
            time.sleep(delay)
            out = fn(*args, **kwargs)
            self.finished.append(args[-1])  # the chunk's index
            return out

        return super().submit(slow)


@pytest.mark.timeout(30)
def test_results_in_input_order_whatever_the_completion_order(tmp_path):
    paths = [str(p) for p in mixed_batch(tmp_path, 9)]
    with DelayedExecutor(len(paths)) as executor:
        records = list(inspect_many(paths, executor, workers=len(paths), chunk_s=0.0))
    assert executor.finished != sorted(executor.finished)  # they did finish out of order
    assert [outcome(r) for r in records] == [reference(p) for p in paths]


class FlakyExecutor(ThreadPoolExecutor):
    """A task that holds ``victim`` fails (as when the worker running it dies) the first
    ``failures`` times it is submitted; records how many other tasks were in flight then."""

    def __init__(self, victim: str, failures: int):
        super().__init__(max_workers=3)
        self.victim, self.failures = victim, failures
        self.in_flight: set = set()
        self.company: list[int] = []  # tasks in flight beside each single-victim submission

    def submit(self, fn, *args, **kwargs):
        paths = args[1]
        if self.victim in paths:
            if len(paths) == 1:
                self.company.append(len([f for f in self.in_flight if not f.done()]))
            if self.failures > 0:
                self.failures -= 1
                future = Future()
                future.set_exception(RuntimeError("worker died"))
                return future
        future = super().submit(fn, *args, **kwargs)
        self.in_flight.add(future)
        return future


@pytest.mark.timeout(30)
@pytest.mark.parametrize("failures", [1, 2, 99], ids=["transient", "twice", "always"])
def test_a_lost_task_is_split_then_retried_alone_and_every_file_reported_once(tmp_path, failures):
    paths = [str(p) for p in mixed_batch(tmp_path, 12)]
    victim = paths[4]
    with FlakyExecutor(victim, failures) as executor:
        records = list(inspect_many(paths, executor, workers=3, chunk_s=1.0))  # all in 1 task
    want = [reference(p) for p in paths]
    got = [outcome(r) for r in records]
    assert [r.file for r in records] == paths
    for k, (g, w) in enumerate(zip(got, want)):
        if k != 4 or failures < 3:
            assert g == w
    if failures >= 3:  # split, failed as a single file, then alone: given up, exit 3
        assert got[4][3] == 3 and got[4][0] is None
        assert victim in got[4][2] and "--jobs 1" in said_by_cli(got[4][2])
    if failures >= 2:  # its run as a suspect had nothing else in flight
        assert executor.company[-1] == 0


def _pool_batch(paths, monkeypatch, **kwargs):
    monkeypatch.setattr(plan, "POOL_MIN_S", 0.0)  # these batches are small: force the pool
    return inspect_many(paths, jobs=2, **kwargs)


@pytest.mark.slow
@pytest.mark.timeout(60)
def test_local_pool_gives_the_records_of_one_process(tmp_path, monkeypatch):
    paths = [str(p) for p in mixed_batch(tmp_path, 14)]
    monkeypatch.chdir(tmp_path)  # relative paths: workers resolve them where the caller is
    rel = [os.path.relpath(p, tmp_path) for p in paths]
    with _pool_batch(rel, monkeypatch, chunk_s=0.002, unit="mm", allow_open=True) as batch:
        records = list(batch)
        assert batch.parallel is True
    assert [outcome(r) for r in records] == [reference(p, unit="mm", allow_open=True)
                                             for p in rel]


@pytest.mark.slow
@pytest.mark.timeout(90)
def test_killed_local_worker_is_replaced_and_every_file_reported_once(tmp_path, monkeypatch):
    mesh = torus_obj(tmp_path / "t.obj", 100, 100)
    paths = []
    for k in range(30):  # one mesh under many names: a long batch, written once
        os.link(mesh, tmp_path / f"t{k:03d}.obj")
        paths.append(str(tmp_path / f"t{k:03d}.obj"))
    with _pool_batch(paths, monkeypatch, chunk_s=0.0) as batch:
        records = [next(batch)]
        workers = {p for p in descendants(os.getpid()) if _is_pool_worker(p)}
        os.kill(min(workers), signal.SIGKILL)
        seen = set()
        for record in batch:
            records.append(record)
            seen |= {p for p in descendants(os.getpid()) if _is_pool_worker(p)}
    assert seen - workers, "no replacement worker: the kill missed the batch"
    assert [outcome(r) for r in records] == [reference(p) for p in paths]


def _is_pool_worker(pid: int) -> bool:
    """A fork-server child (the pool's worker), not the fork server or the resource tracker."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            parent = int(f.read().rsplit(")", 1)[1].split()[1])
        with open(f"/proc/{parent}/cmdline", "rb") as f:
            return b"forkserver" in f.read()
    except OSError:
        return False


@pytest.mark.timeout(60)
def test_interrupt_returns_what_finished_in_order_and_stops_the_workers(tmp_path, monkeypatch):
    mesh = torus_obj(tmp_path / "t.obj", 80, 40)
    paths = []
    for k in range(60):
        os.link(mesh, tmp_path / f"t{k:03d}.obj")
        paths.append(str(tmp_path / f"t{k:03d}.obj"))
    batch = _pool_batch(paths, monkeypatch, chunk_s=0.0)
    first = next(batch)
    time.sleep(0.3)
    rest = batch.interrupt()
    got = [first, *rest]
    files = [r.file for r in got]
    assert files == sorted(files) and len(set(files)) == len(files)  # in order, once each
    assert len(got) < len(paths)  # it stopped early
    want = {p: reference(p) for p in files}
    assert all(outcome(r) == want[r.file] for r in got)
    deadline = time.monotonic() + 10
    while any(_is_pool_worker(p) for p in descendants(os.getpid())):
        assert time.monotonic() < deadline, "pool workers outlived interrupt()"
        time.sleep(0.05)
    assert list(batch) == []


def test_unknown_option_and_bad_jobs_are_refused():
    with pytest.raises(TypeError, match="densty"):
        next(inspect_many(["a.obj"], densty=2.0))
    with pytest.raises(ValueError, match="at least 1"):
        inspect_many(["a.obj"], jobs=0)


def test_bad_input_records_keep_their_place(tmp_path):
    good = str(box_vf(tmp_path / "ok.vf"))
    inputs = [good, BadInput("dir", expand_inputs.__globals__["MeshFileError"]("dir: empty")),
              good]
    got = [(r.file, r.exit_code) for r in inspect_many(inputs, jobs=1)]
    assert got == [(good, 0), ("dir", 1), (good, 0)]


# --- CSV -------------------------------------------------------------------------------------
def _rows(records) -> list[dict]:
    text = csv_header() + "".join(csv_row(r) for r in records)
    return list(csv.DictReader(io.StringIO(text)))


def test_csv_has_the_contract_columns():
    contract = ("file, volume, mass, com_x, com_y, com_z, Jxx, Jyy, Jzz, Jxy, Jxz, Jyz, I1, I2, "
                "I3, closed, warnings").split(", ")
    assert set(contract) <= set(CSV_COLUMNS) and len(set(CSV_COLUMNS)) == len(CSV_COLUMNS)
    assert csv_header().rstrip("\n").split(",") == list(CSV_COLUMNS)


def test_csv_cells_parse_back_to_the_json_values_exactly(tmp_path):
    paths = [str(p) for p in mixed_batch(tmp_path, 6)]
    records = list(inspect_many(paths, jobs=1, allow_open=True, density=1234.5))
    for row, record in zip(_rows(records), records):
        d = record.data
        assert row["file"] == record.file
        if d is None:
            assert row["error"] == record.error.message
            assert all(row[c] == "" for c in CSV_COLUMNS if c not in ("file", "error"))
            continue
        u, ui = d["uncertainty"]["rounding"], d["uncertainty"]["input"]
        pairs = [("volume", d["volume"]), ("mass", d["mass"]), ("density", d["density"])]
        for block, suffix in ((d, ""), (u, "_err"), (ui, "_err_input")):
            if block is None:
                assert all(row[c] == "" for c in CSV_COLUMNS if c.endswith("_err_input"))
                continue
            pairs += [("volume" + suffix, block["volume"]), ("mass" + suffix, block["mass"])]
            pairs += [(f"com_{a}{suffix}", block["center_of_mass"][i])
                      for i, a in enumerate("xyz")]
            pairs += [(f"J{'xyz'[i]}{'xyz'[j]}{suffix}", block["inertia"][i][j])
                      for i, j in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))]
            pairs += [(f"I{k + 1}{suffix}", block["principal_moments"][k]) for k in range(3)]
        pairs += [(f"axis{k + 1}_{'xyz'[i]}", d["principal_axes"][i][k])
                  for k in range(3) for i in range(3)]
        for column, value in pairs:  # repr compares the bits (-0.0 too)
            assert repr(float(row[column])) == repr(value), column
        assert row["closed"] == ("true" if d["mesh"]["closed"] else "false")
        assert int(row["vertices"]) == d["mesh"]["vertices"]
        assert int(row["faces"]) == d["mesh"]["faces"]
        assert int(row["warnings"]) == len(d["warnings"]) and row["error"] == ""


def test_csv_row_of_a_box_is_its_closed_form(tmp_path):
    a, b, c, rho = 2.0, 3.0, 5.0, 7.0
    path = box_vf(tmp_path / "box.vf", size=(a, b, c), offset=(10.0, -20.0, 30.0))
    (row,) = _rows(inspect_many([str(path)], jobs=1, density=rho))
    m = rho * a * b * c
    exact = {"volume": a * b * c, "mass": m, "com_x": 11.0, "com_y": -18.5, "com_z": 32.5,
             "Jxx": m * (b * b + c * c) / 12, "Jyy": m * (a * a + c * c) / 12,
             "Jzz": m * (a * a + b * b) / 12, "Jxy": 0.0, "Jxz": 0.0, "Jyz": 0.0,
             "I1": m * (a * a + b * b) / 12, "I2": m * (a * a + c * c) / 12,
             "I3": m * (b * b + c * c) / 12}  # ascending
    for column, value in exact.items():
        err = float(row[column + "_err"])
        assert abs(float(row[column]) - value) <= err + 1e-300, column
    assert row["volume_err_input"] == ""  # float64 source: no input error bar


def test_csv_float32_source_has_input_error_bars(tmp_path):
    (row,) = _rows(inspect_many([str(binary_stl_box(tmp_path / "b.stl"))], jobs=1))
    assert float(row["volume_err_input"]) > 0 and math.isfinite(float(row["I3_err_input"]))
    assert np.isclose(float(row["volume"]), 6.0, rtol=1e-6)


class RecordingExecutor(ThreadPoolExecutor):
    """One thread; records the batch index of each task in the order it was handed out."""

    def __init__(self):
        super().__init__(max_workers=1)
        self.order: list[int] = []

    def submit(self, fn, *args, **kwargs):
        self.order.append(args[-1])
        return super().submit(fn, *args, **kwargs)


def test_a_large_file_goes_out_first_and_its_record_still_in_place(tmp_path):
    small = [str(box_vf(tmp_path / f"b{k:02d}.vf", size=(1.0 + k, 1.0, 1.0))) for k in range(12)]
    large = str(torus_obj(tmp_path / "large.obj", 120, 60))  # costs > 4 tasks of small files
    paths = [*small, large]
    with RecordingExecutor() as executor:
        records = list(inspect_many(paths, executor, workers=1,
                                    chunk_s=5 * plan.estimate(small[0])))  # 5 small per task
    assert executor.order[0] == len(small)  # the large file was handed out first ...
    assert [outcome(r) for r in records] == [reference(p) for p in paths]  # ... printed last


@pytest.mark.timeout(120)
def test_a_pool_whose_workers_cannot_start_falls_back_to_this_process(tmp_path):
    """A program read from stdin has no file the fork server's children can import as their
    __main__ (multiprocessing's rule): every worker dies at start. The batch must still end,
    with every record, computed here."""
    mesh = torus_obj(tmp_path / "t.obj", 12, 8)
    script = (
        "from massprops.batch import inspect_many, plan\n"
        "plan.POOL_MIN_S = 0.0\n"
        f"records = list(inspect_many([{str(mesh)!r}] * 60, jobs=2, chunk_s=0.0))\n"
        "print(len(records), sum(r.error is None for r in records))\n")
    res = subprocess.run([sys.executable, "-"], input=script, capture_output=True, text=True,
                         cwd=tmp_path, timeout=100)
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.split() == ["60", "60"]
