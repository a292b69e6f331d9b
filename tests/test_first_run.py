"""The first run on a fresh machine (issue 8 §1): the exact path needs no compiler, and a run
that compiles says so once on stderr, only when numba really compiles (a cache miss), never on
stdout and never when everything loads from the cache. Each case that observes numba's start or
its cache runs in a fresh process with its own empty cache folder (NUMBA_CACHE_DIR)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys

import pytest
from conftest import ROOT

from massprops.dynamics.compiled import compiling

EXACT_SCENE = ("body: {mass: 1, inertia: [[1, 0, 0], [0, 2, 0], [0, 0, 3]]}\n"
               "initial: {angular_velocity: [0.3, 5.0, 0.2]}\n"
               "forces: [{type: gravity, g: [0, 0, -9.81]}]\n"
               "time: {duration: 20.0}\noutput: {every: 0.01}\n")
STEPPED_SCENE = ("body: {mass: 1, inertia: [[1, 0, 0], [0, 2, 0], [0, 0, 3]]}\n"
                 "initial: {angular_velocity: [0.3, 1.0, 0.2]}\n"
                 "forces: [{type: torque, vector: [0, 0.1, 0]}]\n"
                 "time: {duration: 0.5, integrator: splitting, step: 1.0e-3}\n")
"""A one-body scene on a one-body kernel that compiles in seconds (the splitting methods'; the
time-stepping methods run as a system of one body, whose entries take half a minute)."""

CLI = """
import json, sys
from massprops.cli import main
try:
    main(sys.argv[1:])
except SystemExit as exc:
    code = exc.code
import massprops
print(json.dumps({"exit": code, "file": massprops.__file__, "numba": "numba" in sys.modules,
                  "scipy_special": "scipy.special" in sys.modules}), file=sys.stderr)
"""


def fresh_process(cache, *args, env=None, cwd=ROOT) -> tuple[str, list[str], dict]:
    """(stdout, stderr lines but the probe's, probe) of the CLI in a new process."""
    env = env or dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    out = subprocess.run([sys.executable, "-c", CLI, *map(str, args)], cwd=cwd, env=env,
                         capture_output=True, text=True, timeout=300)
    lines = out.stderr.strip().splitlines()
    return out.stdout, lines[:-1], json.loads(lines[-1])


def test_an_exact_run_imports_neither_numba_nor_scipy_special(tmp_path):
    path = tmp_path / "free.yaml"
    path.write_text(EXACT_SCENE)
    stdout, errors, probe = fresh_process(tmp_path / "cache", "simulate", path, "--json", "-q")
    assert probe | {"file": None} == {"exit": 0, "file": None, "numba": False,
                                      "scipy_special": False}
    assert errors == []  # nothing compiled, nothing said
    result = json.loads(stdout)
    assert result["integrator"] == "exact" and result["steps"] == 0
    assert not (tmp_path / "cache").exists() or not any((tmp_path / "cache").iterdir())


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_the_compile_notice_is_one_stderr_line_on_a_cache_miss_only(tmp_path):
    path = tmp_path / "torqued.yaml"
    path.write_text(STEPPED_SCENE)
    cache = tmp_path / "cache"
    stdout, errors, probe = fresh_process(cache, "simulate", path, "--json", "-q")
    assert probe["exit"] == 0 and probe["numba"] is True
    (line,) = errors
    assert line.startswith("massprops: compiling the splitting kernel once for this machine")
    assert "later runs load it from the cache" in line
    assert json.loads(stdout)["integrator"] == "splitting"  # stdout is the JSON alone
    again, errors, probe = fresh_process(cache, "simulate", path, "--json", "-q")
    assert probe["exit"] == 0 and errors == []  # loaded from the cache: silent
    assert json.loads(again)["final"] == json.loads(stdout)["final"]


def test_kernels_behind_integrator_names():
    """The splitting methods share one kernel, and so do the fixed-step ones; DOP853 has its
    own; the systems' other entries are named as themselves; the closed form has none."""
    assert compiling.compiled_names(["exact", "splitting6", "splitting", "dop853", "implicit"]) \
        == ["splitting", "dop853", "fixed"]
    assert compiling.compiled_names(["rk4", "midpoint", "outputs", "rhs"]) \
        == ["fixed", "outputs", "rhs"]
    assert compiling.compiled_names(["exact"]) == []
    assert set(compiling.SYSTEM_ENTRIES) <= set(compiling.COMPILE_SECONDS)


def test_prepare_of_the_closed_form_does_nothing():
    heard = []
    assert compiling.prepare(["exact"], heard.append) == 0.0
    assert heard == []


def test_the_first_compile_says_so_once_and_shares_the_rest_with_a_helper(monkeypatch):
    """The listener's reaction to numba's compile event, without compiling: one notice naming
    what is still to do, and in a CLI process a helper for the kernels the second core takes."""
    spawned, heard = [], []
    monkeypatch.setattr(compiling, "_whole_process", True)
    monkeypatch.setattr(compiling, "_spawn", lambda kernels: spawned.append(kernels))
    watch = compiling._Watch(["implicit", "dop853", "rk4"], heard.append)
    watch.done.append("implicit")  # already loaded from the cache: not compiled, not named
    watch.on_start()
    watch.on_start()  # later compiles of the batch: silent
    assert spawned == [["rk4"]]  # dop853 is compiling here now; the helper takes the other
    (text,) = heard
    assert text.startswith("compiling the dop853, rk4 kernels once for this machine (~")
    assert "later runs load them from the cache" in text


def test_a_library_process_never_starts_a_helper(monkeypatch):
    spawned = []
    monkeypatch.setattr(compiling, "_whole_process", False)
    monkeypatch.setattr(compiling, "_spawn", lambda kernels: spawned.append(kernels))
    watch = compiling._Watch(["implicit", "dop853"], None)
    watch.on_start()
    assert spawned == [] and watch.helper is None


def test_a_held_body_in_closed_form_needs_no_compiler(tmp_path):
    """A Lagrange top moves in closed form, and its reactions evaluate the force law with numpy
    over the samples: nothing compiled, numba not even imported, nothing said."""
    stdout, errors, probe = fresh_process(tmp_path / "cache", "simulate",
                                          ROOT / "sample_scenes" / "heavy_top.yaml", "--json", "-q")
    assert probe | {"file": None} == {"exit": 0, "file": None, "numba": False,
                                      "scipy_special": False}, errors
    assert errors == []
    result = json.loads(stdout)
    assert result["integrator"] == "exact" and len(result["final"]["joints"]) == 1


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_kernels_built_with_the_package_load_without_compiling_wherever_it_is_installed(
        tmp_path, run):
    """What setup.py does to a wheel: the kernels compiled in the build folder (into the
    builder's cache), then the package moved to another absolute path (site-packages), and a
    first run with massprops' own cache folder in a fresh home: it loads them (numba compiles
    nothing, so nothing is said) and gives the same motion as this process's own kernel."""
    ignore = shutil.ignore_patterns("__pycache__", "_prebuilt")
    shutil.copytree(ROOT / "massprops", tmp_path / "build" / "massprops", ignore=ignore)
    env = dict(os.environ, PYTHONPATH=str(tmp_path / "build"),
               XDG_CACHE_HOME=str(tmp_path / "builder"))
    env.pop("NUMBA_CACHE_DIR", None)
    subprocess.run([sys.executable, "-m", "massprops.dynamics.compiled.build", "--only",
                    "splitting"],
                   cwd=tmp_path, env=env, check=True, capture_output=True, timeout=240)
    shutil.copytree(tmp_path / "build" / "massprops", tmp_path / "site" / "massprops")
    scene = tmp_path / "torqued.yaml"
    scene.write_text(STEPPED_SCENE)

    env = dict(os.environ, PYTHONPATH=str(tmp_path / "site"), XDG_CACHE_HOME=str(tmp_path / "home"))
    env.pop("NUMBA_CACHE_DIR", None)
    stdout, errors, probe = fresh_process(None, "simulate", scene, "--json", "-q", env=env,
                                          cwd=tmp_path)
    assert probe["file"].startswith(str(tmp_path / "site"))
    assert probe["exit"] == 0 and probe["numba"] is True
    assert errors == []  # loaded: numba compiled nothing
    (cache,) = (tmp_path / "home" / "massprops").iterdir()
    assert (cache / ".prebuilt-seeded").exists()
    here = run("simulate", scene, "--json", "-q")
    assert json.loads(stdout)["final"] == json.loads(here.stdout)["final"]
    # a second copy of the same sources (another venv, a checkout) in the same home shares the
    # seeded kernels: nothing compiled, nothing more copied
    files = sorted(cache.rglob("*"))
    shutil.copytree(tmp_path / "build" / "massprops", tmp_path / "site2" / "massprops",
                    ignore=ignore)
    env["PYTHONPATH"] = str(tmp_path / "site2")
    stdout2, errors2, probe2 = fresh_process(None, "simulate", scene, "--json", "-q", env=env,
                                             cwd=tmp_path)
    assert probe2["file"].startswith(str(tmp_path / "site2")) and probe2["exit"] == 0
    assert errors2 == []  # loaded: numba compiled nothing
    assert sorted(cache.rglob("*")) == files
    assert json.loads(stdout2)["final"] == json.loads(stdout)["final"]


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_building_the_same_sources_again_loads_the_kernels_from_the_builders_cache(tmp_path):
    """A second build of the same sources (the test extra's install after the plain one) takes
    its kernels from the builder's cache: numba compiles nothing the second time."""
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "builder"))
    env.pop("NUMBA_CACHE_DIR", None)
    counts = []
    for build in ("first", "second"):
        ignore = shutil.ignore_patterns("__pycache__", "_prebuilt")
        shutil.copytree(ROOT / "massprops", tmp_path / build / "massprops", ignore=ignore)
        env["PYTHONPATH"] = str(tmp_path / build)
        code = ("from massprops.dynamics.compiled.compiling import ready_side_by_side\n"
                "print(ready_side_by_side(['splitting'], jobs=1))")
        out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, check=True,
                             capture_output=True, text=True, timeout=240)
        counts.append(int(out.stdout.split()[-1]))
    assert counts[0] > 0 and counts[1] == 0


COUNT_COMPILES = """
from numba.core import event
from massprops.dynamics.integrators._subflows import drift_work
with event.install_recorder("numba:compile") as seen:
    drift_work()
print(sum(ev.is_start for _, ev in seen.buffer))
"""


def test_a_kernel_built_for_the_portable_cpu_loads_on_this_one(tmp_path):
    """The wheel's kernels are built for a generic CPU of this architecture (`build` sets
    NUMBA_CPU_NAME to `cache.PORTABLE_CPU`): a process on this CPU, which numba alone would
    have compile its own, loads them and compiles nothing."""
    from massprops.dynamics.compiled import build, cache

    def compiles(settings: dict) -> int:
        env = {k: v for k, v in os.environ.items()
               if k not in ("NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES")}
        env.update(NUMBA_CACHE_DIR=str(tmp_path), **settings)
        out = subprocess.run([sys.executable, "-c", COUNT_COMPILES], cwd=ROOT, env=env,
                             capture_output=True, text=True, timeout=120, check=True)
        return int(out.stdout.split()[-1])

    assert build.PORTABLE_ENV["NUMBA_CPU_NAME"] == cache.PORTABLE_CPU
    assert compiles(build.PORTABLE_ENV) > 0  # the build's process: compiled, generic
    assert compiles({}) == 0  # this CPU's process: loaded
