"""What the file says about its parts besides geometry: STEP material designations (name and
density, the density used unless an option says otherwise) and IGES entity names reported;
an IGES part without a name numbered like any other, not named after its shape type."""

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
    # applied: each solid takes its material's density from the file, and says so
    assert by_name["pin"]["density"] == pytest.approx(7850.0)
    assert by_name["pin"]["material"] == {"name": "Steel", "density": pytest.approx(7850.0),
                                          "source": "file"}
    assert by_name["plug"]["material"] == {"name": None, "density": 1.0, "source": "default"}
    volume, _, _ = cp.closed_forms("cylinder", 2.0)
    assert by_name["pin"]["mass"] == pytest.approx(7850.0 * volume * 1e-9, rel=1e-12)


def test_options_override_the_files_density(tmp_path):
    """--density-map for the solids it names, --density for the rest: the file's density is
    the fallback, and each solid says which one it took."""
    path = tmp_path / "named.step"
    cp.write_named(PARTS, path, "step")
    records = inspect_cad(path, density=1000.0, density_map=[("pin", 8000.0)]).as_dicts()
    by_name = {r["solid"]: r for r in records if not r.get("total")}
    assert by_name["pin"]["material"] == {"name": "Steel", "density": 8000.0,
                                          "source": "--density-map"}
    assert by_name["bracket"]["material"] == {"name": "Aluminium 6061-T6", "density": 1000.0,
                                              "source": "--density"}
    assert by_name["plug"]["material"]["source"] == "--density"
    mapped = {r["solid"]: r for r in inspect_cad(path, density_map=[("plug", 500.0)]).as_dicts()
              if not r.get("total")}
    assert mapped["bracket"]["material"]["source"] == "file"
    assert mapped["bracket"]["density"] == pytest.approx(2700.0)
    assert mapped["plug"]["material"] == {"name": None, "density": 500.0,
                                          "source": "--density-map"}
    total = inspect_cad(path, mass=2.0).as_dicts()
    assert {r["material"]["source"] for r in total if not r.get("total")} == {"--mass"}


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
