"""What the file says about its parts besides geometry: STEP material designations (name and
density) and IGES entity names reported; an IGES part without a name numbered like any other,
not named after its shape type."""

from __future__ import annotations

import pytest

pytest.importorskip("OCP")

import cadparts as cp  # noqa: E402

from massprops.cad.inspect import inspect_cad  # noqa: E402
from massprops.cad.write import align_cad  # noqa: E402

PARTS = [("bracket", cp.make("box", 10.0), ("Aluminium 6061-T6", 2700.0)),
         ("pin", cp.moved(cp.make("cylinder", 2.0), (100.0, 0.0, 0.0)), ("Steel", 7850.0)),
         ("plug", cp.moved(cp.make("sphere", 3.0), (0.0, 100.0, 0.0)), None)]


def test_step_materials_are_reported(tmp_path):
    path = tmp_path / "named.step"
    cp.write_named(PARTS, path, "step")
    records = inspect_cad(path).as_dicts()
    by_name = {r["solid"]: r for r in records if not r.get("total")}
    assert set(by_name) == {"bracket", "pin", "plug"}
    assert by_name["bracket"]["cad"]["material"] == {"name": "Aluminium 6061-T6",
                                                     "density": pytest.approx(2700.0)}
    assert by_name["pin"]["cad"]["material"]["density"] == pytest.approx(7850.0)
    assert "material" not in by_name["plug"]["cad"]
    # reported, not applied: the density is the option's (default 1 kg/m³)
    assert by_name["pin"]["density"] == 1.0


def test_iges_entity_names_are_the_solids_names(tmp_path):
    path = tmp_path / "named.igs"
    cp.write_named(PARTS, path, "iges")
    result = inspect_cad(path)
    assert [r.solid.name for r in result.solids] == ["bracket", "pin", "plug"]
    volume, _, _ = cp.closed_forms("box", 10.0)
    assert result.solids[0].properties.volume == pytest.approx(volume * 1e-9, rel=1e-9)


def test_unnamed_iges_parts_are_numbered_not_called_compound(tmp_path):
    path = tmp_path / "named.step"
    cp.write_named(PARTS, path, "step")
    align_cad(inspect_cad(path), tmp_path / "aligned.igs")  # our writer names nothing
    names = [r.solid.name for r in inspect_cad(tmp_path / "aligned.igs").solids]
    assert names == ["solid1", "solid2", "solid3"]
