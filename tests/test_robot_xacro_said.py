"""xacro prints its warnings to stderr itself; massprops says them as its own warning lines
(one line each, naming the file), and a file of macros only (no links) is said, not shown as an
empty table without a word."""

from __future__ import annotations

import pytest

MACROS = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="pi" value="3.14159"/>
  <xacro:macro name="arm"><link name="a"/></xacro:macro>
</robot>
"""


def test_xacro_warnings_become_one_line_each(tmp_path, run):
    pytest.importorskip("xacro")
    (tmp_path / "m.urdf.xacro").write_text(MACROS)
    result = run("model", tmp_path / "m.urdf.xacro")
    assert result.exit_code == 0, result.stderr
    lines = result.stderr.strip().splitlines()
    assert all(line.startswith("massprops: warning: ") and "m.urdf.xacro" in line
               for line in lines), result.stderr
    assert any("xacro: redefining global symbol: pi" in line for line in lines)
    assert any("no links" in line and "macros only" in line for line in lines)
    assert "when processing file" not in result.stderr
