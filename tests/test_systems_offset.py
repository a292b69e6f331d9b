"""A system is the same run wherever it sits: the double pendulum and the four-bar moved 1e3,
1e6 and 1e8 m away (along every axis) give the joint coordinates and reactions of the run at the
origin, and positions moved by exactly that much up to the output's rounding.

The only difference allowed is the moved scene's own: its numbers are rounded to eps × d (the
four-bar's 17-digit points, moved, no longer close its loop exactly; its start is projected).
Computed about the world origin, the engine lost (d / size)² × eps instead: 2.6e-9 rad for the
double pendulum at 1e3 m, and at 1e6 m it could not run at all."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.systems.run import simulate_system
from massprops.dynamics.systems.scene import parse_system

SAMPLES = Path(__file__).resolve().parent.parent / "sample_scenes"
EPS = np.finfo(float).eps


def _moved(text: str, d: float) -> str:
    """Every `position:` and `point:` of ``text`` moved by (d, d, d)."""
    def move(match: re.Match) -> str:
        values = [float(v) + d for v in match.group(2).split(",")]
        return f"{match.group(1)}[{', '.join(repr(v) for v in values)}]"

    return re.sub(r"((?:position|point): )\[([^\]]*)\]", move, text)


def _run(text: str):
    scene = parse_system(text, source="moved.yaml", base_dir=SAMPLES)
    return simulate_system(scene, rtol=1e-11, every=0.25, estimate=False)


@pytest.mark.parametrize("name", ["double_pendulum", "four_bar"])
@pytest.mark.parametrize("d", [1e3, 1e6, 1e8])
def test_far_from_the_origin(name, d):
    text = re.sub(r"duration: [0-9.]+", "duration: 1.0", (SAMPLES / f"{name}.yaml").read_text())
    here, there = _run(text), _run(_moved(text, d))
    allowed = max(1e-13, 4 * EPS * d)  # the moved input's rounding, relative to ~1 m parts
    for k in range(len(here.samples.coordinates)):
        assert np.abs(here.samples.coordinates[k] - there.samples.coordinates[k]).max() < allowed
    scale = np.abs(here.samples.force).max()
    assert np.abs(here.samples.force - there.samples.force).max() < allowed * scale
    assert np.abs(here.samples.torque - there.samples.torque).max() < allowed * scale
    gap = np.abs(there.samples.position - d - here.samples.position).max()
    assert gap <= 8 * EPS * d, gap
