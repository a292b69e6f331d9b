"""Every `$ massprops ...` example in README.md and docs/ runs, and prints what the page says it
prints, so that the documents cannot drift from the program again (issue 30 §3).

An example is a line ``$ massprops ARGS`` in a fenced block; the lines after it, up to the next
``$`` line or the block's end, are what it prints (stdout and stderr, as a terminal shows them).
They are compared token by token: words exactly, numbers to the digits the page shows (a few
units in the last digit shown), numbers at round-off level (below 1e-9) to within a factor of
ten, or both below 1e-13, as they differ between CPUs. A ``...`` skips whatever stands there
(rows of a table, keys of an abridged JSON object); a column or row named as a time (``time
[s]``, ``wall time``) holds a measurement, so any number matches there. ``$ echo $?`` shows the
exit code of the example before it, ``> /dev/null`` leaves stderr alone, and ``&& echo ok``
prints ok after a success. The commands run in a scratch folder that holds the samples, the
test robots and the one file a page describes instead of shipping (robots.md's
``robot.urdf``).
"""

from __future__ import annotations

import functools
import math
import re
import shlex
import shutil
from dataclasses import dataclass
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import ROOT

from massprops.cli import cli

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
PUNCTUATION = "{}[](),:\""
TOKEN = re.compile(rf"\.\.\.|{NUMBER.pattern}|[^\s\d.+\-{re.escape(PUNCTUATION)}]+|\S")
TIME_HEADINGS = ("time [s]",)
TIME_LABELS = ("wall time",)
ROUND_OFF = 1e-9
NOISE = 1e-13


@dataclass
class Example:
    page: str
    line: int
    command: str
    expected: list[str]
    exit_code: int | None = None
    """What a following ``$ echo $?`` shows."""

    @property
    def id(self) -> str:
        return f"{self.page}:{self.line}"


def blocks() -> list[list[Example]]:
    """The examples of every fenced block that has any, block by block (the examples of one
    block run in order in one folder: a later one may read what an earlier one wrote)."""
    found: list[list[Example]] = []
    for page in PAGES:
        block: list[Example] | None = None
        for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
            if line.lstrip().startswith("```"):
                if block is None:
                    block = []
                else:
                    found.append(block)
                    block = None
            elif block is not None and line.startswith("$ "):
                block.append(Example(page.relative_to(ROOT).as_posix(), number, line[2:], []))
            elif block:
                block[-1].expected.append(line)
    for block in found:
        for before, after in zip(block, block[1:]):
            if after.command == "echo $?":
                before.exit_code = int(after.expected[0])
    return [kept for block in found
            if (kept := [e for e in block if e.command.startswith("massprops ")])]


BLOCKS = blocks()


ARM = "tests/robots/arm_description/urdf"
"""Where robots.md's robot.urdf is made, beside the arm it changes (its meshes are found from
there), and where the examples naming it run."""


def _placeholder_arm(folder: Path) -> None:
    """robots.md's robot.urdf: the test arm with upper_arm's inertia a placeholder diag 0.01."""
    arm = (folder / ARM / "arm.urdf").read_text(encoding="utf-8")
    link = arm.index('<link name="upper_arm"')
    start = arm.index("<inertia ", link)
    end = arm.index("/>", start) + 2
    placeholder = '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>'
    (folder / ARM / "robot.urdf").write_text(arm[:start] + placeholder + arm[end:],
                                              encoding="utf-8")


@pytest.fixture
def scratch(tmp_path) -> Path:
    folder = tmp_path
    for name in ("sample_meshes", "sample_scenes"):
        shutil.copytree(ROOT / name, folder / name)
    shutil.copytree(ROOT / "tests" / "robots", folder / "tests" / "robots")
    _placeholder_arm(folder)
    return folder


def tokens(lines: list[str]) -> list[tuple[str, bool]]:
    """(token, is a measurement) over ``lines``: a number under a time heading or after a time
    label is a measurement."""
    out: list[tuple[str, bool]] = []
    spans: list[tuple[int, int]] = []
    for line in lines:
        lowered = line.lower()
        heads = [(lowered.index(h), lowered.index(h) + len(h)) for h in TIME_HEADINGS
                 if h in lowered]
        if heads:
            spans = heads
        label = any(lowered.lstrip().startswith(t) for t in TIME_LABELS)
        for match in TOKEN.finditer(line):
            text = match.group()
            timed = label or any(match.start() < b + 2 and match.end() > a - 2 for a, b in spans)
            out.append((text, timed and bool(NUMBER.fullmatch(text))))
    return out


def _last_digit(text: str) -> float:
    mantissa, _, exponent = text.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (int(exponent or 0) - decimals)


def same(expected: str, actual: str, timed: bool) -> bool:
    if not NUMBER.fullmatch(expected):
        return expected == actual
    if not NUMBER.fullmatch(actual):
        return False
    if timed:
        return True
    e, a = float(expected), float(actual)
    if abs(e) < ROUND_OFF:
        return abs(e) < NOISE and abs(a) < NOISE or e != 0 and 0.1 <= a / e <= 10
    return math.isclose(a, e, rel_tol=1e-9, abs_tol=5 * _last_digit(expected))


def match(expected: list[tuple[str, bool]], actual: list[str]) -> str | None:
    """None when ``actual`` tokens match ``expected`` (``...`` skips any run), else where not."""
    furthest = [0]

    @functools.cache
    def fails_at(i: int, j: int) -> int | None:
        """Where matching expected[i:] against actual[j:] fails (None: it does not)."""
        while i < len(expected) and expected[i][0] != "...":
            if j >= len(actual) or not same(expected[i][0], actual[j], expected[i][1]):
                furthest[0] = max(furthest[0], i)
                return i
            i, j = i + 1, j + 1
        if i == len(expected):
            return None if j == len(actual) else i
        if i + 1 == len(expected):  # a closing "...": whatever follows
            return None
        if any(fails_at(i + 1, k) is None for k in range(j, len(actual))):
            return None
        return i

    if fails_at(0, 0) is None:
        return None
    failed = furthest[0]
    near = " ".join(t for t, _ in expected[max(0, failed - 6):failed + 6])
    return f"expected token {failed} ({near!r}) not matched"


@pytest.mark.parametrize("block", BLOCKS, ids=lambda block: block[0].id)
def test_documented_examples_print_what_the_page_says(block, scratch, monkeypatch):
    arm = any("robot.urdf" in example.command for example in block)
    monkeypatch.chdir(scratch / ARM if arm else scratch)
    monkeypatch.setenv("COLUMNS", "120")
    for example in block:
        command, then_ok = example.command.split(" #")[0].strip(), False
        if command.endswith("&& echo ok"):
            command, then_ok = command.removesuffix("&& echo ok").strip(), True
        quiet = command.endswith("> /dev/null")
        command = command.removesuffix("> /dev/null").strip()
        result = CliRunner().invoke(cli, shlex.split(command)[1:], catch_exceptions=False)
        where = f"{example.id}: {command}"
        if example.exit_code is not None:
            assert result.exit_code == example.exit_code, f"{where}\n{result.output}"
        elif not example.expected or then_ok:  # nothing shown but success
            assert result.exit_code == 0, f"{where}\n{result.output}"
        output = (result.stderr if quiet else result.output).splitlines()
        output += ["ok"] if then_ok and result.exit_code == 0 else []
        if example.expected:
            problem = match(tokens(example.expected), [t for t, _ in tokens(output)])
            assert problem is None, f"{where}: {problem}\n--- the page:\n" + \
                "\n".join(example.expected) + "\n--- the program:\n" + result.output


def test_the_pages_have_examples_of_every_command():
    shown = {e.command.split()[1] for block in BLOCKS for e in block}
    assert shown >= set(cli.commands)
