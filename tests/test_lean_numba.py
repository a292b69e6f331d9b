"""The CLI starts numba without its cffi support and BLAS probe (massprops.dynamics.compiled.jit
.start_numba_lean); a library import keeps full numba. Each case runs in a fresh process, the
only place where numba's start can be observed."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from conftest import ROOT

SCENE = ("body: {mass: 2, inertia: [[1,0,0],[0,2,0],[0,0,3]]}\n"
         "initial: {angular_velocity: [0.3, 1.0, 0.2]}\n"
         "forces: [{type: torque, vector: [0, 0.1, 0]}, {type: spring, anchor: [0, 0, 1], "
         "stiffness: 5.0, damping: 0.2}, {type: drag, linear: 0.1, angular: 0.1}]\n"
         "time: {duration: 0.5, step: 1.0e-3, rtol: 1.0e-9}\n")

PROBE = """
import importlib.util, json, sys
import numba.core.typing.cffi_utils as cffi_utils
import numba.np.arraymath as arraymath
hidden = [n for n in ("cffi", "scipy.linalg.cython_blas")
          if n in sys.modules and sys.modules[n] is None]
installed = importlib.util.find_spec("cffi") is not None
if installed:
    import cffi  # importable again once numba has started
print(json.dumps({"cffi_support": cffi_utils.SUPPORTED, "cffi_installed": installed,
                  "blas_probe": arraymath._HAVE_BLAS, "scipy_linalg": "scipy.linalg" in sys.modules,
                  "left_hidden": hidden}), file=sys.stderr)
"""

CLI = """
import sys
from massprops.cli import main
try:
    main(sys.argv[1:])
except SystemExit as exc:
    assert exc.code == 0, exc.code
""" + PROBE

LIBRARY = """
import sys
from massprops.dynamics.scene import load_scene
from massprops.dynamics.simulate import simulate
simulate(load_scene(sys.argv[1]), integrator="dop853")
""" + PROBE


def fresh_process(code: str, *args) -> tuple[str, dict]:
    out = subprocess.run([sys.executable, "-c", code, *map(str, args)], cwd=ROOT,
                         capture_output=True, text=True, check=True)
    return out.stdout, json.loads(out.stderr.strip().splitlines()[-1])


@pytest.mark.parametrize("integrator", ["dop853", "implicit"])
def test_cli_runs_without_cffi_and_blas_and_leaves_imports_working(tmp_path, integrator):
    # implicit: the one kernel with a linear solve (its own LU in loops, no BLAS)
    path = tmp_path / "scene.yaml"
    path.write_text(SCENE, encoding="utf-8")
    stdout, probe = fresh_process(CLI, "simulate", path, "--json", "--quiet",
                                  "--integrator", integrator)
    result = json.loads(stdout)
    assert result["integrator"] == integrator and result["final"]["t"] == 0.5
    assert result["diagnostics"]["error_estimate"] is not None
    assert probe["cffi_support"] is False and probe["blas_probe"] is False
    assert probe["scipy_linalg"] is False and probe["left_hidden"] == []


@pytest.mark.slow
def test_library_use_keeps_numbas_cffi_and_blas(tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text(SCENE, encoding="utf-8")
    _, probe = fresh_process(LIBRARY, path)
    assert probe["cffi_support"] is probe["cffi_installed"]
    assert probe["blas_probe"] is True and probe["left_hidden"] == []
