"""The compiled systems kernels (dynamics/compiled/systems_*) against the numpy System they
replace in the step loop: the same right-hand side and the same projection at random states, for
every joint kind, loads of every kind, a floating base and loops (the numpy objects are the
independent reference: written separately, with numpy's LAPACK where the kernels use loops)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.compiled.systems_step import project, rhs, workspace
from massprops.dynamics.systems import tree as tr
from massprops.dynamics.systems.run import prepare
from massprops.dynamics.systems.scene import load_system, parse_system

SAMPLES = Path(__file__).resolve().parents[1] / "sample_scenes"
BOX = "[[0.02, 0, 0], [0, 0.03, 0], [0, 0, 0.04]]"

EVERY_KIND = f"""bodies:
  a: {{mass: 1.0, inertia: {BOX}, position: [0, 0, -0.5]}}
  b: {{mass: 1.2, inertia: {BOX}, position: [0.1, 0, -1.0]}}
  c: {{mass: 0.8, inertia: {BOX}, position: [0.2, 0.1, -1.5]}}
  d: {{mass: 0.5, inertia: {BOX}, position: [0.3, 0.1, -2.0]}}
  e: {{mass: 0.7, inertia: {BOX}, position: [1.0, 0, -0.5]}}
  f: {{mass: 0.3, inertia: {BOX}, position: [3.0, 1.0, 0.0]}}
joints:
  - {{name: s, type: spherical, bodies: [world, a], point: [0, 0, 0]}}
  - {{name: u, type: universal, bodies: [a, b], point: [0.05, 0, -0.8],
     axes: [[1, 0, 0], [0, 1, 0]]}}
  - {{name: c, type: cylindrical, bodies: [c, b], point: [0.15, 0, -1.2], axis: [0, 0, 1]}}
  - {{name: p, type: prismatic, bodies: [c, d], point: [0.25, 0.1, -1.8], axis: [0.6, 0, 0.8]}}
  - {{name: r, type: revolute, bodies: [world, e], point: [1.0, 0, 0], axis: [0, 1, 0],
     stiffness: 2.0, damping: 0.3, torque: 0.4, start: 0.1, end: 0.5}}
  - {{name: tie, type: distance, bodies: [d, e], points: [[0.3, 0.1, -2.0], [1.0, 0, -0.5]]}}
initial:
  rates: {{s: [0.3, -0.2, 0.5], u: [0.4, -0.1], r: 0.7}}
  project_initial: true
forces:
  - {{type: gravity, g: [0, 0, -9.81]}}
  - {{type: force, body: b, vector: [0.5, 0.2, 0], frame: body,
     point: [0.1, 0, -1.0]}}
  - {{type: torque, body: c, vector: [0, 0, 0.3], start: 0.0, end: 0.2}}
  - {{type: spring, bodies: [a, world], points: [[0, 0, -0.5], [0, 0.5, 0]], stiffness: 5.0,
     rest_length: 0.4, damping: 0.2}}
  - {{type: spring, bodies: [d, f], points: [[0.3, 0.1, -2.0], [3.0, 1.0, 0.0]],
     stiffness: 1.0, damping: 0.1}}
  - {{type: drag, body: e, linear: 0.4, angular: 0.05}}
  - {{type: drag, linear: 0.01}}
time: {{duration: 1.0}}
"""

THROWN_DRAG = f"""bodies:
  a: {{mass: 1.0, inertia: {BOX}, position: [0, 0, 0]}}
  b: {{mass: 0.6, inertia: {BOX}, position: [0.4, 0, 0.1]}}
joints:
  - {{name: h, type: revolute, bodies: [a, b], point: [0.2, 0, 0], axis: [0, 1, 0]}}
initial:
  bodies: {{a: {{velocity: [3, 0, 2], angular_velocity: [0.2, 0.5, -0.1]}}}}
  rates: {{h: 0.8}}
forces:
  - {{type: gravity, g: [0, 0, -9.81]}}
  - {{type: drag, body: b, linear: 0.3, angular: 0.02}}
time: {{duration: 1.0}}
"""

FLOATING = """bodies:
  a: {mass: 1.5, inertia: [[0.3, 0.02, -0.01], [0.02, 0.2, 0.03], [-0.01, 0.03, 0.15]],
      position: [0.2, -0.1, 0.3], orientation: [0.9, 0.3, -0.2, 0.1]}
  b: {mass: 0.4, inertia: [[0.02, 0, 0], [0, 0.05, 0], [0, 0, 0.06]], position: [2.0, 1.0, -0.5]}
initial:
  bodies: {a: {velocity: [1, -2, 0.5], angular_velocity: [3.0, -1.0, 2.0]},
           b: {velocity: [0, 0.3, 0], angular_velocity: [0.1, 0.2, -0.4]}}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
  - {type: force, body: a, vector: [0.5, 0.2, -0.3], frame: body, point: [0.1, 0.05, -0.2]}
  - {type: spring, bodies: [a, b], points: [[0.25, 0, 0.3], [1.9, 1.0, -0.4]], stiffness: 4.0,
     rest_length: 1.0, damping: 0.3}
time: {duration: 1.0}
"""
"""Two floating bodies, no joint: two floating roots (`systems_mass._floating_root`), the second
away from the point positions are measured from."""


def _numpy_rhs(system, t, y):
    sol = system.solve(t, y, check=False, full=False)
    return np.concatenate([tr.qdot(system.tree, y[:system.nq], y[system.nq:]), sol.udot])


def _states(system, y0, rng, count=4, spread=0.05):
    out = [y0]
    for _ in range(count):
        y = y0 + spread * rng.standard_normal(y0.size)
        tr.normalize(system.tree, y[:system.nq])
        out.append(y)
    return out


def _turned_four_bar() -> str:
    """The four-bar sample turned so that its hinges lie along (1, 1, 1)/√3: its redundant
    rows are no longer zero rows of G but combinations of the others (the planar motion's
    point rows in world x, y, z have rank 2), which the kernel's pivoted QR must find."""
    import yaml

    axis = np.ones(3) / np.sqrt(3.0)
    turn = np.cross([0.0, 1.0, 0.0], axis)
    angle = np.arcsin(np.linalg.norm(turn))
    k = turn / np.linalg.norm(turn)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    rot = np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx  # y -> axis
    data = yaml.safe_load((SAMPLES / "four_bar.yaml").read_text())
    for body in data["bodies"].values():
        body["position"] = (rot @ body["position"]).tolist()
        body["inertia"] = (rot @ np.array(body["inertia"]) @ rot.T).tolist()
    for joint in data["joints"]:
        joint["point"] = (rot @ joint["point"]).tolist()
        joint["axis"] = (rot @ joint["axis"]).tolist()
    return yaml.safe_dump(data)


@pytest.mark.parametrize("scene", ["every_kind", "thrown_drag", "floating", "four_bar",
                                   "four_bar_turned", "chain10", "andrews", "slider_crank",
                                   "double_pendulum"])
def test_compiled_right_hand_side_and_projection_equal_numpy(scene):
    if scene == "every_kind":
        loaded = parse_system(EVERY_KIND, source="k.yaml", base_dir=SAMPLES)
    elif scene == "thrown_drag":  # a floating base with drag: it runs in the world frame
        loaded = parse_system(THROWN_DRAG, source="f.yaml", base_dir=SAMPLES)
        assert prepare(loaded)[0].falling is None
    elif scene == "floating":
        loaded = parse_system(FLOATING, source="f.yaml", base_dir=SAMPLES)
    elif scene == "four_bar_turned":
        loaded = parse_system(_turned_four_bar(), source="t.yaml", base_dir=SAMPLES)
        assert (loaded.bodies and prepare(loaded)[0].rank) == 2
    else:
        loaded = load_system(SAMPLES / f"{scene}.yaml")
    system, y0, _ = prepare(loaded)
    ws = workspace(system.program)
    rng = np.random.default_rng(7)
    for t in (0.15, 0.7):  # inside and outside the load windows
        for y in _states(system, y0, rng):
            want = _numpy_rhs(system, t, y)
            got = np.zeros_like(y)
            status = rhs(system.program, ws, t, y, got, -1)
            assert status == 0
            scale = max(1.0, float(np.abs(want).max()))
            assert np.abs(got - want).max() <= 1e-11 * scale
            if system.m:
                want_y, dq, du = system.project(y)
                got_y, moved = y.copy(), np.zeros(3)
                assert project(system.program, ws, got_y, 12, moved) == 0
                assert np.abs(got_y - want_y).max() <= 1e-11
                assert moved[0] == pytest.approx(dq, rel=1e-6, abs=1e-13)
                assert moved[1] == pytest.approx(du, rel=1e-6, abs=1e-13)


def test_max_steps_bounds_a_system_run():
    """max_steps (the CLI's --max-steps) stops a system run like a one-body run: RunBudgetError
    (exit 3) naming the bound, where the step count reached it."""
    from massprops.dynamics.systems.run import simulate_system
    from massprops.errors import RunBudgetError, settings_in

    scene = load_system(SAMPLES / "four_bar.yaml")
    with pytest.raises(RunBudgetError) as info:
        simulate_system(scene, rtol=1e-10, max_steps=5, estimate=False)
    assert "took 5 steps" in str(info.value) and "max_steps" in settings_in(info.value.args[0])
    assert simulate_system(scene, rtol=1e-6, max_steps=10_000, estimate=False).steps < 10_000


@pytest.mark.parametrize("scene", ["every_kind", "andrews"])
def test_accelerations_on_made_kinematics_are_the_same_numbers(scene):
    """`tree.with_accelerations` (the outputs' second pass) gives bit for bit the A of a full
    `tree.kinematics` pass with the same u̇, at random states of every joint kind."""
    loaded = (parse_system(EVERY_KIND, source="k.yaml", base_dir=SAMPLES) if scene == "every_kind"
              else load_system(SAMPLES / f"{scene}.yaml"))
    system, y0, _ = prepare(loaded)
    rng = np.random.default_rng(11)
    for y in _states(system, y0, rng, spread=0.2):
        q, u = y[:system.nq], y[system.nq:]
        udot = rng.standard_normal(system.nv)
        full = tr.kinematics(system.tree, q, u, udot).A
        assert np.array_equal(tr.with_accelerations(system.tree, tr.kinematics(system.tree, q, u),
                                                    udot).A, full)


def test_program_and_workspace_hold_what_their_slot_names_say():
    """Each named slot (`compiled.systems_layout`) holds the array its name stands for, checked
    against the numpy System: the program's bodies, joints, sizes and tolerances, and every
    workspace slot's shape (the workspace is built in order, so a slot out of place shows)."""
    from massprops import tolerances
    from massprops.dynamics.compiled import systems_layout as L
    from massprops.dynamics.compiled.systems_tree import INERTIA_SIZE

    system, _, _ = prepare(parse_system(EVERY_KIND, source="e.yaml", base_dir=SAMPLES))
    prog, tree = system.program, system.tree
    assert len(prog) == L.PROGRAM_SLOTS
    nq, nv, m, n, nj = (int(prog[L.P_DIMS][k]) for k in
                        (L.D_NQ, L.D_NV, L.D_M, L.D_BODIES, L.D_JOINTS))
    assert (nq, nv, m, n, nj) == (tree.nq, tree.nv, system.m, len(tree.bodies), len(tree.joints))
    assert m > 0 and nq > nv  # a loop, and quaternions: every size tells
    assert prog[L.P_MASS].tolist() == [b.mass for b in tree.bodies]
    assert np.array_equal(prog[L.P_COM0], [b.com0 for b in tree.bodies])
    assert prog[L.P_JOINTS][:, 2].tolist() == [j.child for j in tree.joints]
    assert prog[L.P_TOLERANCES][L.T_RANK_RTOL] == tolerances.CONSTRAINT_RANK_RTOL
    assert prog[L.P_TOLERANCES][L.T_SINGULAR_MARGIN] == tolerances.NEAR_SINGULAR_MARGIN
    assert prog[L.P_LOADED].tolist() == list(tree.loaded)
    assert prog[L.P_SCENE_JOINTS].shape == (len(system.scene.joints), 2)
    p, kk, i6 = max(m, nv), min(m, nv), INERTIA_SIZE
    shapes = {
        "W_ROT": (n, 3, 3), "W_COM": (n, 3), "W_VEL": (n, 6), "W_ACC": (n, 6),
        "W_INERTIA": (n, i6), "W_MOTION": (6, nv), "W_JOINT_POINTS": (nj, 3), "W_BIAS": (n, 6),
        "W_M3": (4, 3, 3), "W_V3": (16, 3), "W_M6": (6, 6), "W_LOADS": (n, 6), "W_TAU": (nv,),
        "W_ART_INERTIA": (n, 6, 6), "W_ART_BIAS": (n, 6), "W_ABA_U": (nv,),
        "W_ABA_DINV": (nj, 6, 6), "W_ABA_UMAT": (nj, 6, 6), "W_M6_PAIR": (2, 6, 6),
        "W_PHI": (m,), "W_GDOT": (m,), "W_ROW_B": (m, 6), "W_ROW_A": (m, 6), "W_G": (m, nv),
        "W_MASS": (nv, nv), "W_CHOL": (nv, nv), "W_B": (m, nv), "W_QR": (p, p),
        "W_SVD_WORK": (p, p), "W_SINGULAR": (p,), "W_KEEP": (1 + p,), "W_SVD_U": (m, kk),
        "W_SVD_V": (nv, kk), "W_COLUMN": (nv,), "W_Q": (0,), "W_H": (nv,), "W_ROWS": (m,),
        "W_DELTA": (nq,), "W_ORDER": (1 + p,), "W_REFLECTORS": (p,), "W_COMPOSITE": (n, i6),
        "W_Z": (kk, kk), "W_REFERENCE": (3,)}
    names = {k: v for k, v in vars(L).items() if k.startswith("W_")}
    assert set(names) == set(shapes) and sorted(names.values()) == list(range(L.WORKSPACE_SLOTS))
    ws = workspace(prog)
    assert len(ws) == L.WORKSPACE_SLOTS
    assert {k: ws[names[k]].shape for k in shapes} == shapes
    assert ws[L.W_KEEP].dtype == ws[L.W_ORDER].dtype == np.int64
