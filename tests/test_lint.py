"""ruff's rules hold over the whole tree, and the package type-checks under mypy (both
configured in pyproject.toml): CI runs them with the tests."""

from __future__ import annotations

import subprocess
import sys

import pytest
from conftest import ROOT


def test_ruff_check_is_clean():
    pytest.importorskip("ruff", reason="ruff comes with the test extra")
    out = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "."], cwd=ROOT,
                         capture_output=True, text=True, timeout=100)
    assert out.returncode == 0, out.stdout + out.stderr


@pytest.mark.timeout(300)
def test_mypy_finds_no_type_errors():
    pytest.importorskip("mypy", reason="mypy comes with the test extra")
    out = subprocess.run([sys.executable, "-m", "mypy"], cwd=ROOT, capture_output=True,
                         text=True, timeout=280)
    assert out.returncode == 0, out.stdout + out.stderr
