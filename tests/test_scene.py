"""The scene YAML: a valid scene becomes the right value objects; every invalid one is refused with
``file:line: key.path: problem`` in one line.

Expected lines are not typed in: each invalid scene marks the offending line with ``# <-`` and the
test finds it, so the truth is the text itself.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from massprops.dynamics.model import (
    Drag,
    Gravity,
    InitialState,
    PointForce,
    RigidBody,
    Scene,
    Spring,
    TimeSettings,
    Torque,
)
from massprops.dynamics.scene import (
    FORCE_TYPES,
    OUTPUT_SUFFIXES,
    load_scene,
    parse_scene,
)
from massprops.errors import InputError, SceneError

BODY = "body: {mass: 12.0, inertia: [[8, 0, 0], [0, 13, 0], [0, 0, 13]]}\n"
TIME = "time: {duration: 1.0}\n"
MINIMAL = BODY + TIME


def parse(text: str, base_dir: Path = Path("."), **kwargs) -> Scene:
    return parse_scene(text, source="scene.yaml", base_dir=base_dir, **kwargs)


def marked_line(text: str) -> int:
    """1-based number of the line carrying the ``# <-`` marker."""
    lines = [i for i, line in enumerate(text.splitlines(), start=1) if "# <-" in line]
    assert len(lines) == 1, "a test scene marks exactly one line"
    return lines[0]


def assert_refused(text: str, key_path: str, base_dir: Path = Path("."), **kwargs) -> str:
    """The scene is refused with a one-line message naming the file, the marked line, the key."""
    with pytest.raises(SceneError) as info:
        parse(text, base_dir, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"scene.yaml:{marked_line(text)}:"), message
    assert key_path in message, message
    return message


# --- a valid scene -----------------------------------------------------------------------------
FULL = """\
body:
  mass: 3.0
  inertia: [[2, -1, 0], [-1, 2, 0], [0, 0, 3]]
  center_of_mass: [0.1, -0.2, 0.3]
initial:
  position: [1, 2, 3]
  orientation: [1, 1, 0, 0]
  velocity: [0.5, -0.5, 0.25]
  angular_velocity: [0.1, 0.2, 0.3]
  angular_velocity_frame: body
forces:
  - {type: gravity, g: [0, 0, -9.81]}
  - {type: force, vector: [1, 0, 0], frame: body, point: [0.5, 0, 0], start: 0, end: 0.1}
  - {type: torque, vector: [0, 0, 1], frame: world, start: 0.2, end: 0.3}
  - {type: spring, anchor: [0, 0, 1], point: [0, 0, 0.5], stiffness: 100, rest_length: 0.25,
     damping: 0.5}
  - {type: drag, linear: 0.1, angular: 0.01}
time:
  duration: 10.0
  integrator: dop853
  rtol: 1.0e-8
  step: 1.0e-3
output:
  every: 0.01
  file: trajectory.npz
"""


def test_full_scene_round_trips_into_the_model(tmp_path):
    scene = parse(FULL, tmp_path)
    assert scene.source == "scene.yaml" and scene.body_source == "explicit"
    assert scene.input_files == ()

    body = scene.body
    assert isinstance(body, RigidBody) and body.mass == 3.0
    # [[2,-1,0],[-1,2,0],[0,0,3]] has eigenvalues 2-1, 2+1 and 3 (closed form).
    np.testing.assert_allclose(body.principal_moments, [1, 3, 3], rtol=1e-14)
    np.testing.assert_allclose(body.inertia_body, [[2, -1, 0], [-1, 2, 0], [0, 0, 3]],
                               atol=1e-14)
    np.testing.assert_array_equal(body.center_of_mass, [0.1, -0.2, 0.3])
    assert body.size == pytest.approx(math.sqrt(3 / 3.0))

    initial = scene.initial
    np.testing.assert_array_equal(initial.position, [1, 2, 3])
    np.testing.assert_allclose(initial.orientation, [2**-0.5, 2**-0.5, 0, 0], rtol=1e-15)
    np.testing.assert_array_equal(initial.velocity, [0.5, -0.5, 0.25])
    np.testing.assert_array_equal(initial.angular_velocity, [0.1, 0.2, 0.3])
    assert initial.angular_velocity_frame == "body"

    gravity, force, torque, spring, drag = scene.forces
    assert isinstance(gravity, Gravity)
    np.testing.assert_array_equal(gravity.g, [0, 0, -9.81])
    assert isinstance(force, PointForce)
    np.testing.assert_array_equal(force.vector, [1, 0, 0])
    np.testing.assert_array_equal(force.point, [0.5, 0, 0])
    assert (force.frame, force.start, force.end) == ("body", 0.0, 0.1)
    assert isinstance(torque, Torque)
    np.testing.assert_array_equal(torque.vector, [0, 0, 1])
    assert (torque.frame, torque.start, torque.end) == ("world", 0.2, 0.3)
    assert isinstance(spring, Spring)
    np.testing.assert_array_equal(spring.anchor, [0, 0, 1])
    np.testing.assert_array_equal(spring.point, [0, 0, 0.5])
    assert (spring.stiffness, spring.rest_length, spring.damping) == (100.0, 0.25, 0.5)
    assert isinstance(drag, Drag) and (drag.linear, drag.angular) == (0.1, 0.01)

    assert scene.time == TimeSettings(duration=10.0, integrator="dop853", rtol=1e-8, step=1e-3)
    assert scene.output.every == 0.01
    assert scene.output.file == tmp_path / "trajectory.npz"


def test_defaults_of_a_minimal_scene():
    scene = parse(MINIMAL + """\
forces:
  - {type: force, vector: [1, 0, 0]}
  - {type: torque, vector: [0, 0, 1]}
  - {type: spring, anchor: [0, 0, 1], stiffness: 2}
  - {type: drag}
""")
    default = InitialState()
    for name in ("position", "orientation", "velocity", "angular_velocity"):
        np.testing.assert_array_equal(getattr(scene.initial, name), getattr(default, name))
    assert scene.initial.angular_velocity_frame == "world"
    np.testing.assert_array_equal(scene.body.center_of_mass, [0, 0, 0])
    force, torque, spring, drag = scene.forces
    assert (force.frame, force.point, force.start, force.end) == ("world", None, -math.inf,
                                                                  math.inf)
    assert (torque.frame, torque.start, torque.end) == ("world", -math.inf, math.inf)
    assert (spring.point, spring.rest_length, spring.damping) == (None, 0.0, 0.0)
    assert (drag.linear, drag.angular) == (0.0, 0.0)
    assert scene.time == TimeSettings(duration=1.0, integrator="auto", rtol=1e-9, step=None)
    assert (scene.output.every, scene.output.file) == (None, None)


@pytest.mark.parametrize("text", ["initial:\nforces:\noutput:\n", "initial: {}\nforces: []\n"],
                         ids=["null-sections", "empty-sections"])
def test_empty_optional_sections_mean_defaults(text):
    scene = parse(MINIMAL + text)
    assert scene.forces == () and scene.output.file is None
    np.testing.assert_array_equal(scene.initial.orientation, [1, 0, 0, 0])


@pytest.mark.parametrize(("given", "unit"), [
    ([2, 0, 0, 0], [1, 0, 0, 0]),
    ([0, 3, 0, 4], [0, 0.6, 0, 0.8]),
    ([-1, -1, -1, -1], [-0.5, -0.5, -0.5, -0.5]),
], ids=["2-0-0-0", "0-3-0-4", "all-minus-one"])
def test_a_non_unit_quaternion_is_normalised(given, unit):
    scene = parse(MINIMAL + f"initial: {{orientation: {given}}}\n")
    np.testing.assert_allclose(scene.initial.orientation, unit, rtol=0, atol=1e-16)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(allow_nan=False, allow_infinity=False, width=64), min_size=3,
                max_size=3))
def test_numbers_round_trip_exactly_through_their_repr(values):
    # a position: speeds have a largest value a run can square (test_a_start_too_fast_...)
    scene = parse(MINIMAL + f"initial: {{position: [{', '.join(map(repr, values))}]}}\n")
    assert scene.initial.position.tolist() == values


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-1e3, 1e3), min_size=4, max_size=4).filter(
    lambda q: math.fsum(x * x for x in q) > 1e-6))
def test_a_quaternion_is_scaled_to_unit_length_not_turned(q):
    unit = parse(MINIMAL + f"initial: {{orientation: {q}}}\n").initial.orientation
    assert np.linalg.norm(unit) == pytest.approx(1, abs=1e-15)
    np.testing.assert_allclose(unit * np.linalg.norm(q), q, rtol=1e-12, atol=1e-12)


def test_a_plain_exponent_without_a_dot_is_a_number():
    # YAML 1.1 reads `1e-9` as text; the scene reads it as the number it shows.
    assert parse(BODY + "time: {duration: 1e1, rtol: 1e-7}\n").time == TimeSettings(10.0,
                                                                                   rtol=1e-7)


def test_the_integrator_names_are_a_parameter():
    text = BODY + "time: {duration: 1, integrator: euler}  # <-\n"
    assert parse(text, known_integrators=("euler",)).time.integrator == "euler"
    assert_refused(text, "time.integrator")
    from massprops.dynamics.integrators import integrator_names

    assert set(integrator_names()) >= {"auto", "exact", "rk4", "dop853", "implicit"}


FORCE_EXAMPLES = {
    "gravity": ("{type: gravity, g: [0, 0, -9.81]}", Gravity),
    "force": ("{type: force, vector: [1, 0, 0]}", PointForce),
    "torque": ("{type: torque, vector: [0, 0, 1]}", Torque),
    "spring": ("{type: spring, anchor: [0, 0, 1], stiffness: 1}", Spring),
    "drag": ("{type: drag, linear: 1}", Drag),
}


def test_every_registered_force_type_has_an_example_here():
    assert set(FORCE_TYPES) == set(FORCE_EXAMPLES)


@pytest.mark.parametrize("name", sorted(FORCE_EXAMPLES))
def test_each_force_type_builds_its_model_class(name):
    text, cls = FORCE_EXAMPLES[name]
    (term,) = parse(MINIMAL + f"forces:\n  - {text}\n").forces
    assert type(term) is cls is FORCE_TYPES[name][0]


def test_paths_start_at_the_scene_files_folder(tmp_path):
    folder = tmp_path / "scenes"
    folder.mkdir()
    (folder / "scene.yaml").write_text(MINIMAL + "output: {file: out/traj.csv}\n")
    (folder / "out").mkdir()
    scene = load_scene(folder / "scene.yaml")
    assert scene.output.file == folder / "out" / "traj.csv"
    assert scene.source == str(folder / "scene.yaml")


# --- invalid scenes ----------------------------------------------------------------------------
EXPLICIT = "body:\n  mass: 2\n"
MESH = "body:\n  mesh: part.obj\n"
INVALID = [
    # (id, scene text with the offending line marked, key path in the message)
    ("unknown-top-key", MINIMAL + "outptu: {every: 1}  # <-\n", "outptu"),
    ("unknown-body-key", "body: {mass: 1, inertia: [[1,0,0],[0,1,0],[0,0,1]], cog: [0,0,0]}  # <-\n"
     + TIME, "body.cog"),
    ("unknown-initial-key", MINIMAL + "initial:\n  positon: [0, 0, 0]  # <-\n",
     "initial.positon"),
    ("unknown-force-key", MINIMAL + "forces:\n  - {type: drag, lineer: 1}  # <-\n",
     "forces[0].lineer"),
    ("unknown-time-key", BODY + "time:\n  duration: 1\n  stepp: 0.1  # <-\n", "time.stepp"),
    ("unknown-output-key", MINIMAL + "output:\n  fiel: a.csv  # <-\n", "output.fiel"),
    ("duplicate-key", BODY + "time:\n  duration: 1\n  duration: 2  # <-\n", "time.duration"),
    ("key-not-a-string", MINIMAL + "initial:\n  1: 2  # <-\n", "initial"),
    ("string-for-number", BODY + "time: {duration: ten}  # <-\n", "time.duration"),
    ("quoted-number", BODY + "time: {duration: '10'}  # <-\n", "time.duration"),
    ("bool-for-number", BODY + "time: {duration: true}  # <-\n", "time.duration"),
    ("null-for-number", BODY + "time: {duration: null}  # <-\n", "time.duration"),
    ("list-for-number", BODY + "time: {duration: [1]}  # <-\n", "time.duration"),
    ("vector-too-short", MINIMAL + "initial: {position: [1, 2]}  # <-\n", "initial.position"),
    ("vector-too-long", MINIMAL + "initial: {velocity: [1, 2, 3, 4]}  # <-\n",
     "initial.velocity"),
    ("vector-not-a-list", MINIMAL + "initial: {velocity: 3}  # <-\n", "initial.velocity"),
    ("vector-element-string", MINIMAL + "initial:\n  position:\n    - 1\n    - x  # <-\n    - 3\n",
     "initial.position[1]"),
    ("nan", MINIMAL + "initial: {angular_velocity: [0, .nan, 0]}  # <-\n",
     "initial.angular_velocity[1]"),
    ("inf", MINIMAL + "forces:\n  - {type: gravity, g: [0, 0, -.inf]}  # <-\n", "forces[0].g[2]"),
    ("inf-start", MINIMAL + "forces:\n  - {type: torque, vector: [0, 0, 1], start: .inf}  # <-\n",
     "forces[0].start"),
    ("huge-integer", BODY + "time: {duration: 1" + "0" * 400 + "}  # <-\n", "time.duration"),
    ("zero-mass", "body: {mass: 0, inertia: [[1,0,0],[0,1,0],[0,0,1]]}  # <-\n" + TIME,
     "body.mass"),
    ("negative-mass", "body:\n  mass: -1  # <-\n  inertia: [[1,0,0],[0,1,0],[0,0,1]]\n" + TIME,
     "body.mass"),
    ("inertia-not-a-matrix", EXPLICIT + "  inertia: 1  # <-\n" + TIME, "body.inertia"),
    ("explicit-without-mass", "body: {inertia: [[1,0,0],[0,1,0],[0,0,1]]}  # <-\n" + TIME,
     "body.mass"),
    ("neither-mesh-nor-inertia", "body: {mass: 3}  # <-\n" + TIME, "body"),
    ("inertia-not-symmetric", EXPLICIT + "  inertia: [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]  # <-\n"
     + TIME, "body.inertia"),
    ("inertia-not-positive-definite", EXPLICIT
     + "  inertia: [[1, 0, 0], [0, 1, 0], [0, 0, -1]]  # <-\n" + TIME, "body.inertia"),
    ("inertia-triangle", EXPLICIT + "  inertia: [[1, 0, 0], [0, 1, 0], [0, 0, 3]]  # <-\n" + TIME,
     "body.inertia"),
    ("inertia-zero", EXPLICIT + "  inertia: [[0, 0, 0], [0, 0, 0], [0, 0, 0]]  # <-\n" + TIME,
     "body.inertia"),
    ("inertia-row-too-short", EXPLICIT + "  inertia: [[1, 0, 0], [0, 1], [0, 0, 1]]  # <-\n"
     + TIME, "body.inertia[1]"),
    ("inertia-and-density", EXPLICIT + "  inertia: [[1,0,0],[0,1,0],[0,0,1]]\n  density: 3  # <-\n"
     + TIME, "body.density"),
    ("mesh-and-inertia", MESH + "  inertia: [[1,0,0],[0,1,0],[0,0,1]]  # <-\n" + TIME,
     "body.inertia"),
    ("zero-density", MESH + "  density: 0  # <-\n" + TIME, "body.density"),
    ("negative-density", MESH + "  density: -7850  # <-\n" + TIME, "body.density"),
    ("negative-mesh-mass", MESH + "  mass: -2  # <-\n" + TIME, "body.mass"),
    ("density-and-mass", MESH + "  density: 1\n  mass: 2  # <-\n" + TIME, "body.mass"),
    ("unknown-unit", MESH + "  unit: mmm  # <-\n" + TIME, "body.unit: unknown unit 'mmm'"),
    ("allow-open-not-bool", MESH + "  allow_open: 1  # <-\n" + TIME, "body.allow_open"),
    ("missing-mesh-file", "body:\n  mesh: nowhere.obj  # <-\n" + TIME, "body.mesh"),
    ("mesh-is-a-folder", "body:\n  mesh: folder  # <-\n" + TIME, "body.mesh"),
    ("zero-quaternion", MINIMAL + "initial: {orientation: [0, 0, 0, 0]}  # <-\n",
     "initial.orientation"),
    ("quaternion-of-three", MINIMAL + "initial: {orientation: [1, 0, 0]}  # <-\n",
     "initial.orientation"),
    # A missing key is reported where its mapping starts: here the first key of the file.
    ("missing-body", "# a comment\n" + TIME.rstrip() + "  # <-\n", "body"),
    ("missing-time", BODY.rstrip() + "  # <-\n", "time"),
    ("missing-duration", BODY + "time: {integrator: rk4}  # <-\n", "time.duration"),
    ("zero-duration", BODY + "time: {duration: 0}  # <-\n", "time.duration"),
    ("negative-duration", BODY + "time: {duration: -1.5}  # <-\n", "time.duration"),
    ("unknown-force-type", MINIMAL + "forces:\n  - {type: gravty, g: [0, 0, 1]}  # <-\n",
     "forces[0].type"),
    ("missing-force-type", MINIMAL + "forces:\n  - {g: [0, 0, 1]}  # <-\n", "forces[0].type"),
    ("force-not-a-mapping", MINIMAL + "forces:\n  - gravity  # <-\n", "forces[0]"),
    ("forces-not-a-list", MINIMAL + "forces: {type: gravity, g: [0, 0, 1]}  # <-\n", "forces"),
    ("gravity-without-g", MINIMAL + "forces:\n  - {type: gravity}  # <-\n", "forces[0].g"),
    ("force-frame", MINIMAL + "forces:\n  - {type: force, vector: [1,0,0], frame: wrld}  # <-\n",
     "forces[0].frame"),
    ("torque-frame", MINIMAL + "forces:\n  - {type: torque, vector: [0,0,1], frame: 1}  # <-\n",
     "forces[0].frame"),
    ("torque-has-no-point", MINIMAL
     + "forces:\n  - {type: torque, vector: [0,0,1], point: [1,0,0]}  # <-\n", "forces[0].point"),
    ("spring-stiffness", MINIMAL
     + "forces:\n  - {type: drag}\n  - {type: spring, anchor: [0,0,1], stiffness: -3}  # <-\n",
     "forces[1].stiffness"),
    ("spring-damping", MINIMAL
     + "forces:\n  - {type: spring, anchor: [0,0,1], stiffness: 3, damping: -0.1}  # <-\n",
     "forces[0].damping"),
    ("spring-rest-length", MINIMAL
     + "forces:\n  - {type: spring, anchor: [0,0,1], stiffness: 3, rest_length: -1}  # <-\n",
     "forces[0].rest_length"),
    ("spring-without-stiffness", MINIMAL + "forces:\n  - {type: spring, anchor: [0,0,1]}  # <-\n",
     "forces[0].stiffness"),
    ("drag-linear", MINIMAL + "forces:\n  - {type: drag, linear: -0.1}  # <-\n",
     "forces[0].linear"),
    ("drag-angular", MINIMAL + "forces:\n  - {type: drag, angular: -0.1}  # <-\n",
     "forces[0].angular"),
    ("start-after-end", MINIMAL
     + "forces:\n  - {type: force, vector: [1,0,0], start: 2, end: 1}  # <-\n", "forces[0].end"),
    ("start-equals-end", MINIMAL
     + "forces:\n  - type: torque\n    vector: [0, 0, 1]\n    end: 1  # <-\n    start: 1\n",
     "forces[0].end"),
    ("rtol-zero", BODY + "time: {duration: 1, rtol: 0}  # <-\n", "time.rtol"),
    ("rtol-one", BODY + "time: {duration: 1, rtol: 1}  # <-\n", "time.rtol"),
    ("rtol-negative", BODY + "time: {duration: 1, rtol: -1.0e-9}  # <-\n", "time.rtol"),
    ("step-zero", BODY + "time: {duration: 1, step: 0}  # <-\n", "time.step"),
    ("step-negative", BODY + "time: {duration: 1, step: -0.01}  # <-\n", "time.step"),
    ("integrator-unknown", BODY + "time: {duration: 1, integrator: rk5}  # <-\n",
     "time.integrator"),
    ("every-zero", MINIMAL + "output: {every: 0}  # <-\n", "output.every"),
    ("every-negative", MINIMAL + "output: {every: -0.1}  # <-\n", "output.every"),
    ("output-extension", MINIMAL + "output: {file: traj.txt}  # <-\n", "output.file"),
    ("output-no-extension", MINIMAL + "output: {file: traj}  # <-\n", "output.file"),
    ("output-folder-missing", MINIMAL + "output: {file: nowhere/traj.csv}  # <-\n",
     "output.file"),
    ("angular-velocity-frame", MINIMAL + "initial: {angular_velocity_frame: inertial}  # <-\n",
     "initial.angular_velocity_frame"),
    ("time-not-a-mapping", BODY + "time: 10  # <-\n", "time"),
    ("top-level-list", "- body  # <-\n- time\n", "scene.yaml"),
    ("top-level-scalar", "just text  # <-\n", "scene.yaml"),
    ("merge-key", BODY + "time:\n  <<: {duration: 1}  # <-\n", "time: YAML merge keys (<<)"),
]


@pytest.mark.parametrize(("text", "key_path"), [case[1:] for case in INVALID],
                         ids=[case[0] for case in INVALID])
def test_an_invalid_scene_is_refused_at_its_line_and_key(tmp_path, text, key_path):
    (tmp_path / "part.obj").write_text("not read: every check here fails before the mesh is\n")
    (tmp_path / "folder").mkdir()
    assert_refused(text, key_path, tmp_path)


@pytest.mark.parametrize(("text", "suggestion"), [
    (MINIMAL + "forces:\n  - {type: spring, anchor: [0,0,1], stifness: 3}\n", "'stiffness'"),
    (MINIMAL + "forces:\n  - {type: gravty}\n", "'gravity'"),
    ("body: {msh: part.obj}\n" + TIME, "'mesh'"),
    (BODY + "time: {duration: 1, integrator: dop835}\n", "'dop853'"),
    (MINIMAL + "initial: {angular_velocity_frame: bdy}\n", "'body'"),
], ids=["key", "force-type", "body-key", "integrator", "frame"])
def test_a_typo_gets_the_closest_known_name(text, suggestion):
    with pytest.raises(SceneError, match=f"did you mean {suggestion}"):
        parse(text)


def test_an_unknown_force_type_lists_the_known_ones():
    with pytest.raises(SceneError) as info:
        parse(MINIMAL + "forces:\n  - {type: magnet}\n")
    assert all(name in str(info.value) for name in FORCE_TYPES)


def test_the_output_suffixes_are_csv_and_npz():
    assert set(OUTPUT_SUFFIXES) == {".csv", ".npz"}


@pytest.mark.parametrize("text", ["", "\n\n", "# only a comment\n", "---\n"],
                         ids=["empty", "blank-lines", "comment", "document-marker"])
def test_an_empty_file_is_refused(text):
    with pytest.raises(SceneError, match=r"^scene\.yaml:1: .*empty"):
        parse(text)


@pytest.mark.parametrize(("text", "line", "column"), [
    ("body: {mass: 1\ntime: 2\n", 2, 5),  # a flow mapping never closed: ':' where ',' or '}'
    ("time:\n\tduration: 1\n", 2, 1),  # a tab cannot indent
    ("time: {duration: 1}\n  body: x: y\n", 2, 3),
], ids=["unclosed-flow-mapping", "tab-indent", "bad-indent"])
def test_a_yaml_syntax_error_gives_yamls_line_and_column(text, line, column):
    with pytest.raises(SceneError, match=rf"^scene\.yaml:{line}:{column}: invalid YAML: "):
        parse(text)


def test_a_forbidden_character_is_reported_at_its_line():
    with pytest.raises(SceneError, match=r"^scene\.yaml:2: invalid YAML"):
        parse(BODY + "time: {duration: 1}\x07\n")


@pytest.mark.parametrize("tagged", [
    "!!python/object/apply:os.mkdir ['{marker}']",
    "!!python/object:pathlib.Path {{}}",
    "!!python/name:os.system",
    "!custom 3",
    "!!binary aGVsbG8=",
], ids=["python-apply", "python-object", "python-name", "local-tag", "binary"])
def test_yaml_tags_are_refused_and_never_constructed(tmp_path, tagged):
    marker = tmp_path / "constructed"
    text = MINIMAL + "initial:\n  position: " + tagged.format(marker=marker) + "  # <-\n"
    message = assert_refused(text, "initial.position: unsupported YAML tag", tmp_path)
    assert tagged.split()[0].split(":")[0] in message
    assert not marker.exists()


def test_a_cyclic_alias_is_refused_without_recursing():
    text = MINIMAL + "initial:\n  position: &a [1, *a, 3]  # <-\n"
    assert_refused(text, "initial.position[1]")


def test_a_missing_scene_file_is_a_scene_error(tmp_path):
    with pytest.raises(SceneError, match="not found"):
        load_scene(tmp_path / "absent.yaml")


def test_a_scene_file_that_is_not_utf8_is_refused(tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_bytes(MINIMAL.encode() + b"# caf\xe9\n")
    with pytest.raises(SceneError, match="UTF-8"):
        load_scene(path)


# --- mesh bodies: these need massprops.io, massprops.mesh.health and massprops.mesh.integral ---
def cuboid_vf(sides, offset, omit: tuple[int, ...] = ()) -> str:
    """A .vf box [0, a] x [0, b] x [0, c] + offset: quads counter-clockwise seen from outside,
    in the order z=0, z=c, y=0, y=b, x=0, x=a; those numbered in ``omit`` are left out (open)."""
    a, b, c = sides
    corners = [(i * a + offset[0], j * b + offset[1], k * c + offset[2])
               for k in (0, 1) for j in (0, 1) for i in (0, 1)]  # index i + 2 j + 4 k
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    quads = [quad for i, quad in enumerate(quads) if i not in omit]
    lines = ["# a cuboid", str(len(corners)), *(f"{x!r} {y!r} {z!r}" for x, y, z in corners),
             str(len(quads)), *(" ".join(str(v + 1) for v in quad) for quad in quads)]
    return "\n".join(lines) + "\n"


SIDES, OFFSET = (2.0, 3.0, 4.0), (1.0, -2.0, 0.5)


def cuboid_truth(sides, offset, mass):
    """Closed forms: COM at the box centre; J = m/12 diag(b²+c², a²+c², a²+b²) in the box axes."""
    a, b, c = sides
    com = np.add(offset, np.divide(sides, 2))
    inertia = mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    return com, inertia


@pytest.mark.parametrize(("amount", "unit", "scale", "mass"), [
    ("density: 7850", "m", 1.0, 7850 * 24.0),
    ("mass: 2.5", "m", 1.0, 2.5),
    ("density: 1000", "mm", 1e-3, 1000 * 24e-9),
], ids=["density", "mass", "millimetres"])
def test_mesh_body_of_a_cuboid_has_its_closed_form_properties(tmp_path, amount, unit, scale, mass):
    (tmp_path / "box.vf").write_text(cuboid_vf(SIDES, OFFSET))
    (tmp_path / "scene.yaml").write_text(f"body: {{mesh: box.vf, {amount}, unit: {unit}}}\n"
                                         + TIME)
    scene = load_scene(tmp_path / "scene.yaml")
    body = scene.body
    com, inertia = cuboid_truth(np.multiply(SIDES, scale), np.multiply(OFFSET, scale), mass)
    assert scene.body_source == str(tmp_path / "box.vf")
    assert scene.input_files == (tmp_path / "box.vf",)
    assert body.mass == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(body.center_of_mass, com, rtol=1e-12, atol=1e-15 * scale)
    np.testing.assert_allclose(body.inertia_body, inertia, rtol=1e-12,
                               atol=1e-12 * float(inertia.max()))
    np.testing.assert_allclose(np.sort(body.principal_moments), np.sort(np.diag(inertia)),
                               rtol=1e-12)
    axes = body.principal_axes
    np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-12)
    assert np.linalg.det(axes) == pytest.approx(1.0, abs=1e-12)
    # size: the larger of the half diagonal (the farthest corner) and the radius of gyration.
    half_diagonal = scale * math.hypot(*SIDES) / 2
    assert body.size == pytest.approx(max(half_diagonal, math.sqrt(inertia.max() / mass)),
                                      rel=1e-12)


def test_mesh_body_errors_keep_their_class_and_gain_the_scene_place(tmp_path):
    (tmp_path / "open.vf").write_text(cuboid_vf(SIDES, OFFSET, omit=(1,)))
    scene = "body:\n  density: 3\n  mesh: open.vf  # <-\n" + TIME
    (tmp_path / "scene.yaml").write_text(scene)
    with pytest.raises(InputError) as info:
        load_scene(tmp_path / "scene.yaml")
    message = str(info.value)
    assert message.startswith(f"{tmp_path / 'scene.yaml'}:{marked_line(scene)}: body.mesh: ")
    assert "open.vf" in message and "\n" not in message
    assert "--allow-open" not in message  # the fix is worded as the scene key, not the option


def test_mesh_body_allow_open_computes_anyway(tmp_path):
    # The missing face x=0 lies in a plane through the origin, where the usual surface integrals
    # vanish, so the open box still has physical mass properties; its mass is the one given.
    (tmp_path / "open.vf").write_text(cuboid_vf(SIDES, (0, 0, 0), omit=(4,)))
    (tmp_path / "scene.yaml").write_text("body: {mesh: open.vf, mass: 2, allow_open: true}\n"
                                         + TIME)
    assert load_scene(tmp_path / "scene.yaml").body.mass == 2.0


def test_mesh_body_from_a_vtx_fac_pair_reads_and_protects_both_files(tmp_path):
    # The .vf text split in two: the vertex block (count + lines) and the face block.
    lines = cuboid_vf(SIDES, OFFSET).splitlines()[1:]  # without the comment line
    (tmp_path / "box.vtx").write_text("\n".join(lines[:9]) + "\n")
    (tmp_path / "box.fac").write_text("\n".join(lines[9:]) + "\n")
    (tmp_path / "scene.yaml").write_text("body: {mesh: box.fac, mass: 6}\n" + TIME)
    scene = load_scene(tmp_path / "scene.yaml")
    assert scene.input_files == (tmp_path / "box.fac", tmp_path / "box.vtx")
    np.testing.assert_allclose(scene.body.center_of_mass, cuboid_truth(SIDES, OFFSET, 6)[0],
                               rtol=1e-12)


# --- issue 30: values a run cannot use, said before it starts --------------------------------
def test_a_start_too_fast_to_square_is_refused_with_its_limit():
    """ω = 1e300 rad/s: a run squares it (|ω|², ½ ω·Jω, |J ω|²) and multiplies the energy by
    the divergence test's 1e6, all beyond float64: refused at its key, with the limit
    √(float max / 1e6) / J_max for J_max ≥ 2 (the body's largest moment is 13)."""
    text = MINIMAL + "initial: {angular_velocity: [1.0e300, 1, 1]}  # <-\n"
    message = assert_refused(text, "initial.angular_velocity")
    limit = math.sqrt(np.finfo(float).max / 1e6) / 13.0
    assert f"{limit:.3g} rad/s at most" in message
    below = MINIMAL + f"initial: {{angular_velocity: [{0.99 * limit!r}, 0, 0]}}\n"
    assert parse(below).initial.angular_velocity[0] == pytest.approx(0.99 * limit)
    text = MINIMAL + "initial: {velocity: [0, 1.0e300, 0]}  # <-\n"
    assert "m/s at most" in assert_refused(text, "initial.velocity")


def test_cli_a_start_too_fast_to_square_is_exit_1_without_warnings(run, tmp_path):
    """The issue's scene printed numpy RuntimeWarnings with package paths, then failed."""
    path = tmp_path / "fast.yaml"
    path.write_text(MINIMAL + "initial: {angular_velocity: [1.0e300, 1, 1]}\n")
    for integrator in ("auto", "rk4", "dop853", "splitting"):
        res = run("simulate", str(path), "--integrator", integrator)
        assert res.exit_code == 1, res.stderr
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and "fast.yaml:3: initial.angular_velocity" in lines[0]
        assert "Warning" not in res.stderr


@pytest.mark.parametrize("rtol", ["1.0e-30", "1.0e-16"])
def test_an_rtol_below_what_float64_gives_is_refused_saying_the_smallest(rtol):
    message = assert_refused(BODY + f"time: {{duration: 1, rtol: {rtol}}}  # <-\n", "time.rtol")
    assert "smallest rtol accepted is 1e-15" in message
    assert parse(BODY + "time: {duration: 1, rtol: 1.0e-15}\n").time.rtol == 1e-15


def test_an_unknown_top_level_key_names_every_kind_of_scene():
    """A scene's top level is one body's (body:), a system's (bodies:) or a robot
    description's (model:): a typo there is told all three, not one body's keys alone."""
    message = assert_refused(MINIMAL + "bodys: {}  # <-\n", "bodys")
    assert all(key in message for key in ("bodies:", "model:", "body:", "joints"))


@pytest.mark.parametrize(("given", "said"), [
    ("[2, 0, 0, 0]", "norm was 2"), ("[0, 3, 0, 4]", "norm was 5"),
    ("[0.7071067812, 0.7071067812, 0, 0]", None),  # typed from cos/sin with 10 digits
    ("[1, 0, 0, 0]", None),
])
def test_a_quaternion_that_is_not_unit_is_normalised_and_said(given, said):
    scene = parse(MINIMAL + f"initial: {{orientation: {given}}}\n")
    if said is None:
        assert scene.notes == ()
        return
    (note,) = scene.notes
    assert note.startswith("scene.yaml:3: initial.orientation: normalised") and said in note
