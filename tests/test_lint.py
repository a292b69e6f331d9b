"""ruff's rules (pyproject.toml) hold over the whole tree: CI runs them with the tests."""

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
