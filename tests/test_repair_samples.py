"""The repair samples (sample_meshes/overlapping_boxes.obj, open_box.obj) against the closed
forms in sample_meshes/README.md, through the installed command's code path."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import SAMPLES

from massprops.inspection.file import inspect_file
from massprops.repair import RepairOptions


def test_overlapping_boxes_united():
    r = inspect_file(SAMPLES / "overlapping_boxes.obj", repairs=RepairOptions(union=True))
    p = r.properties
    assert p.volume == pytest.approx(15.0, rel=1e-15)
    np.testing.assert_allclose(p.center_of_mass, [1.5, 1.5, 1.5], atol=1e-15)
    np.testing.assert_allclose(p.inertia, 18.5 * np.eye(3) - 4 * (1 - np.eye(3)), atol=1e-13)
    assert r.repairs["union"].as_dict()["counted_twice"] == pytest.approx(1.0, rel=1e-15)
    plain = inspect_file(SAMPLES / "overlapping_boxes.obj")
    assert plain.properties.volume == pytest.approx(16.0, rel=1e-15)
    assert any("--union" in w for w in plain.warnings)


def test_open_box_capped_and_as_a_wall():
    capped = inspect_file(SAMPLES / "open_box.obj",
                          repairs=RepairOptions(fill_holes=True, max_hole=0.25)).properties
    assert capped.volume == 1.0
    np.testing.assert_allclose(capped.inertia, np.eye(3) / 6, atol=1e-15)
    t = 1e-6
    wall = inspect_file(SAMPLES / "open_box.obj", density=7850,
                        repairs=RepairOptions(shell=t)).properties
    assert wall.mass == pytest.approx(7850 * 5 * t, rel=1e-14)
    np.testing.assert_allclose(wall.center_of_mass, [0.5, 0.5, 0.4], atol=1e-9)
