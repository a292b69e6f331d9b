"""A Dask cluster runs a batch: the same bytes as one process, and a lost worker loses nothing.

The clusters are started here, in the test process (two single-thread workers; their HTTP
servers on free ports, so that nothing clashes on 8787).
"""

from __future__ import annotations

import os
import signal

import pytest
from _batchdata import mixed_batch, torus_obj

from massprops.batch import inspect_many
from massprops.inspection.file import inspect_file

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def threads_cluster():
    """Workers as threads of this process: quick to start, enough for equal bytes."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster:
        yield cluster


@pytest.mark.timeout(90)
@pytest.mark.parametrize("out_format", ["csv", "json"])
def test_cluster_run_prints_the_bytes_of_one_process(run, tmp_path, threads_cluster,
                                                      out_format, monkeypatch):
    paths = [*mixed_batch(tmp_path / "parts", 10), tmp_path / "missing.vf"]
    monkeypatch.chdir(tmp_path)  # relative paths: the client resolves them for the cluster
    rel = [os.path.relpath(p, tmp_path) for p in paths]
    args = ["inspect", "--format", out_format, "--allow-open", "--density", "3", *rel]
    local = run(*args, "--jobs", "1")
    cluster = run(*args, "--scheduler", threads_cluster.scheduler_address)
    assert cluster.stdout == local.stdout and cluster.stderr == local.stderr
    assert cluster.exit_code == local.exit_code == 1


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_lost_worker_mid_batch_still_reports_every_file_once(tmp_path):
    paths = [str(torus_obj(tmp_path / f"t{k:02d}.obj", 100, 80, shift=(0, k, 0)))
             for k in range(24)]
    want = [inspect_file(p).as_dict() for p in paths]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        before = client.run(os.getpid)
        batch = inspect_many(paths, client.get_executor(pure=False), workers=2, chunk_s=0.0)
        got = [next(batch)]
        os.kill(max(before.values()), signal.SIGKILL)  # one worker process dies mid-batch
        got += list(batch)
        after = client.run(os.getpid)
    assert max(before.values()) not in after.values()  # it was lost (the nanny started anew)
    assert len(got) == len(paths)
    assert [r.data for r in got] == want  # every file once, in order, with the same numbers
