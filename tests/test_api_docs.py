"""The front door (issue 19 §2): docs/api.md's examples run as written, from the repository's
root, and every name in ``massprops.__all__`` resolves without making ``import massprops``
heavier."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest
from conftest import ROOT

import massprops

EXAMPLES = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "api.md").read_text(), re.S)


@pytest.mark.slow
@pytest.mark.parametrize("code", EXAMPLES, ids=[f"example{i}" for i in range(len(EXAMPLES))])
def test_api_examples_run(code, monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    exec(compile(code, "docs/api.md", "exec"), {"__name__": "__docs__"})


def test_there_are_examples_of_every_kind():
    text = "".join(EXAMPLES)
    for name in ("inspect", "align", "RepairOptions", "model", "inspect_many", "load_scene",
                 "simulate", "precision"):
        assert f"massprops.{name}(" in text, name


@pytest.mark.parametrize("name", massprops.__all__)
def test_every_public_name_resolves(name):
    assert getattr(massprops, name) is not None
    assert name in dir(massprops)


def test_import_massprops_loads_nothing_else():
    code = ("import sys, massprops\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'massprops'))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)), timeout=60, check=True)
    assert out.stdout.strip() == "['massprops']"
