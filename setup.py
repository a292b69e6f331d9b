"""Build step of massprops (the metadata is in pyproject.toml): after the sources are copied into
the build folder, the dynamics kernels are compiled there and shipped in the wheel, so that the
first `massprops simulate` on this machine loads them instead of compiling for minutes
(massprops/dynamics/compiled/prebuilt.py says how and why it stays correct on another machine).
They compile into the builder's kernel cache (~/.cache/massprops/numba-<hash>, as a first run
would), so building the same sources again loads them in seconds.

MASSPROPS_PREBUILD=0 skips it; an editable install and a failed compile skip it too (the kernels
are then compiled on first use, as numba does by default).
"""

import os
import shutil
import subprocess
import sys

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildWithKernels(build_py):
    def run(self):
        super().run()
        build_lib = os.path.abspath(self.build_lib)
        # never ship kernels of an earlier build left in the reused build folder
        shutil.rmtree(os.path.join(build_lib, "massprops", "dynamics", "compiled", "_prebuilt"),
                      ignore_errors=True)
        if self.editable_mode or os.environ.get("MASSPROPS_PREBUILD") == "0":
            return
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            p for p in (build_lib, os.environ.get("PYTHONPATH")) if p))
        try:
            subprocess.run([sys.executable, "-m", "massprops.dynamics.compiled.build"],
                           env=env, cwd=build_lib, check=True, timeout=1800)
        except (OSError, subprocess.SubprocessError) as exc:
            print(f"massprops: kernels not prebuilt ({exc}); the first run compiles them",
                  file=sys.stderr)


setup(cmdclass={"build_py": BuildWithKernels})
