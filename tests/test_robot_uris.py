"""Mesh references as written in the wild (package://, package:///, model://, file://, plain
paths) and SDF ``<include>`` of ``model://`` folders found through --package-path or the
environment."""

from __future__ import annotations

from pathlib import Path

import pytest

from massprops.errors import RobotModelError, settings_in
from massprops.robot.analyze import analyze_model
from massprops.robot.formats.uris import resolve_uri

WEDGE = Path(__file__).resolve().parent / "robots" / "split" / "meshes" / "wedge.obj"


@pytest.fixture
def tree(tmp_path):
    """tmp/ws/pkg/urdf/r.urdf, tmp/ws/pkg/meshes/m.obj, tmp/other/gz/cube/..."""
    (tmp_path / "ws" / "pkg" / "urdf").mkdir(parents=True)
    (tmp_path / "ws" / "pkg" / "meshes").mkdir()
    (tmp_path / "ws" / "pkg" / "meshes" / "m.obj").write_bytes(WEDGE.read_bytes())
    return tmp_path


@pytest.mark.parametrize("uri", ["package://pkg/meshes/m.obj", "package:///pkg/meshes/m.obj",
                                 "model://pkg/meshes/m.obj", "../meshes/m.obj",
                                 "file://../meshes/m.obj", "package://pkg/meshes/%6D.obj"])
def test_uri_forms_reach_the_same_file(tree, uri):
    description = tree / "ws" / "pkg" / "urdf" / "r.urdf"
    path, problem = resolve_uri(uri, description.parent, description)
    assert problem is None
    assert path.resolve() == (tree / "ws" / "pkg" / "meshes" / "m.obj").resolve()


def test_file_uri_absolute_and_localhost(tree):
    target = tree / "ws" / "pkg" / "meshes" / "m.obj"
    d = tree / "r.urdf"
    for uri in (f"file://{target}", f"file://localhost{target}", str(target)):
        assert resolve_uri(uri, d.parent, d)[0] == target


def test_package_path_then_environment(tree, monkeypatch):
    elsewhere = tree / "elsewhere" / "r.urdf"
    uri = "package:///pkg/meshes/m.obj"
    path, problem = resolve_uri(uri, elsewhere.parent, elsewhere)
    assert path is None and "package_path" in settings_in(problem)
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tree / "ws"))
    assert resolve_uri(uri, elsewhere.parent, elsewhere)[0].is_file()


def _cube_model(folder: Path) -> None:
    """A model folder whose model.config names two SDF versions (the highest is used)."""
    (folder / "cube" / "meshes").mkdir(parents=True)
    (folder / "cube" / "meshes" / "w.obj").write_bytes(WEDGE.read_bytes())
    (folder / "cube" / "model.config").write_text(
        '<?xml version="1.0"?><model><name>cube</name><sdf version="1.6">missing.sdf</sdf>'
        '<sdf version="1.10">cube.sdf</sdf></model>')
    (folder / "cube" / "cube.sdf").write_text(
        '<sdf version="1.10"><model name="cube"><link name="body"><inertial><mass>3</mass>'
        '<inertia><ixx>1</ixx><iyy>1</iyy><izz>1</izz><ixy>0</ixy><ixz>0</ixz><iyz>0</iyz>'
        '</inertia></inertial><collision name="c"><geometry><mesh><uri>meshes/w.obj</uri>'
        '<scale>0.1 0.2 0.3</scale></mesh></geometry></collision></link></model></sdf>')


@pytest.mark.parametrize("how", ["option", "GZ_SIM_RESOURCE_PATH", "SDF_PATH"])
def test_sdf_include_of_model_uri(tmp_path, monkeypatch, how):
    """The wedge (legs 1, 2, height 3) scaled by (0.1, 0.2, 0.3): V = 0.1·0.2·0.3·3 = 0.018,
    centroid (1/3·0.1, 2/3·0.2, 1.5·0.3); included twice, at the top and nested (renamed)."""
    models = tmp_path / "models"
    _cube_model(models)
    world = tmp_path / "w" / "world.sdf"
    world.parent.mkdir()
    world.write_text('<sdf version="1.10"><world name="w"><include><uri>model://cube</uri>'
                     '</include><model name="outer"><include><uri>model://cube</uri>'
                     '<name>inner</name></include></model></world></sdf>')
    for var in ("GZ_SIM_RESOURCE_PATH", "SDF_PATH", "GAZEBO_MODEL_PATH", "ROS_PACKAGE_PATH"):
        monkeypatch.delenv(var, raising=False)
    kw = {}
    if how == "option":
        kw["package_paths"] = [models]
    else:
        monkeypatch.setenv(how, str(models))
    r = {x.name: x for x in analyze_model(world, **kw).links}
    assert list(r) == ["body", "outer::inner::body"]
    for x in r.values():
        assert x.status == "computed"
        assert x.computed.volume == pytest.approx(0.018, rel=1e-14)
        assert x.computed.mass == 3.0
        assert x.computed.center_of_mass == pytest.approx([0.1 / 3, 0.4 / 3, 0.45], rel=1e-14)


def test_sdf_include_not_found_names_the_options(tmp_path, monkeypatch):
    for var in ("GZ_SIM_RESOURCE_PATH", "SDF_PATH", "GAZEBO_MODEL_PATH", "ROS_PACKAGE_PATH"):
        monkeypatch.delenv(var, raising=False)
    world = tmp_path / "world.sdf"
    world.write_text('<sdf version="1.10"><world name="w">\n<include><uri>model://nope</uri>'
                     '</include></world></sdf>')
    with pytest.raises(RobotModelError, match=r"world\.sdf:2: <include>: ") as err:
        analyze_model(world)
    assert "package_path" in err.value.settings


def test_a_missing_mesh_in_a_format_we_cannot_read_is_said_missing(tmp_path):
    """example-robot-data's romeo_laas_small.urdf names file:///usr/Romeo/.../Torso.mesh (Ogre
    meshes on its author's machine): that the file is not there is the problem to say."""
    gone = tmp_path / "not-here" / "Torso.mesh"
    (tmp_path / "r.urdf").write_text(
        '<robot name="r"><link name="torso"><inertial><mass value="1"/><inertia ixx="1" ixy="0" '
        f'ixz="0" iyy="1" iyz="0" izz="1"/></inertial><visual><geometry><mesh filename="file://'
        f'{gone}"/></geometry></visual></link></robot>')
    r, = analyze_model(tmp_path / "r.urdf").links
    assert r.status == "skipped" and r.error
    assert f"{gone}: no such file" in r.reason and "extension" not in r.reason
