"""A library must not change its host process or write files on import (issue 19 §3): every
massprops module is imported in a fresh process, with and without a NUMBA_CACHE_DIR of the
process's own; the environment, numba's config and the disk stay as they were. The kernels
still cache where massprops keeps them once one is used."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from conftest import ROOT

PROBE = """
import importlib, json, os, pkgutil, sys
import numba
before_env = dict(os.environ)
before = {k: repr(getattr(numba.config, k)) for k in dir(numba.config) if k.isupper()}
import massprops
names = [m.name for m in pkgutil.walk_packages(massprops.__path__, "massprops.")
         if not m.name.endswith("__main__")]
for name in names:
    importlib.import_module(name)
after = {k: repr(getattr(numba.config, k)) for k in dir(numba.config) if k.isupper()}
changed = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
env = sorted(k for k in set(before_env) | set(os.environ)
             if before_env.get(k) != os.environ.get(k))
print(json.dumps({"modules": len(names), "config": changed, "env": env}))
"""


def _files(folder) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.mark.slow
@pytest.mark.slow
@pytest.mark.parametrize("own_cache", [False, True],
                         ids=["no NUMBA_CACHE_DIR", "own NUMBA_CACHE_DIR"])
def test_importing_every_module_changes_nothing(tmp_path, own_cache):
    home, work = tmp_path / "home", tmp_path / "work"
    home.mkdir()
    work.mkdir()
    env = dict(os.environ, HOME=str(home), XDG_CACHE_HOME=str(home / ".cache"),
               PYTHONPATH=str(ROOT), PYTHONDONTWRITEBYTECODE="1")
    env.pop("NUMBA_CACHE_DIR", None)
    if own_cache:
        env["NUMBA_CACHE_DIR"] = str(tmp_path / "numba")
    out = subprocess.run([sys.executable, "-c", PROBE], cwd=work, env=env, capture_output=True,
                         text=True, timeout=100)
    assert out.returncode == 0, out.stderr
    probe = json.loads(out.stdout)
    assert probe["modules"] > 100
    assert probe["config"] == [] and probe["env"] == []
    assert _files(home) == [] and _files(work) == []
    assert not (tmp_path / "numba").exists()


@pytest.mark.slow
def test_a_kernel_used_caches_in_massprops_folder_and_nowhere_else(tmp_path):
    home = tmp_path / "home"
    env = dict(os.environ, HOME=str(home), XDG_CACHE_HOME=str(home / ".cache"),
               PYTHONPATH=str(ROOT))
    env.pop("NUMBA_CACHE_DIR", None)
    code = ("import os, numba, numpy as np\n"
            "from massprops.dynamics.compiled.cache import planned_root\n"
            "from massprops.dynamics.compiled.compiling import warm_up\n"
            "warm_up('splitting')\n"
            "print(planned_root(), repr(numba.config.CACHE_DIR),\n"
            "      'NUMBA_CACHE_DIR' in os.environ)\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, out.stderr
    root, config_dir, env_set = out.stdout.split()
    assert config_dir == "''" and env_set == "False"
    cached = list((home / ".cache" / "massprops").rglob("*.nbi"))
    assert cached and all(str(p).startswith(root) for p in cached)
