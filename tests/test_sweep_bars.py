"""`massprops sweep --bars` and the centre-of-mass keys: the draws against the bars' own law,
each pendulum against its closed form with its own drawn arm, every draw a valid inertial, the
same rows whatever runs them, the refusals.

Truth here is independent of the program: a box's mass, centre and inertia (ρ a b c, its
centre, m (b² + c²)/12); the small-amplitude compound pendulum θ(t) = θ0 cos(ω t),
ω² = m g l / (I + m l²) (`test_sweep.theta`, Lindstedt-Poincaré to third order); a rectangular
law's moments (sd = half-width / √3); the validity tests of the inertia doctor.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import box_vf, json_lines
from test_sweep import I_ROD, OUT, THETA0, G, M, pendulum, rows_of, theta

from massprops.inspection.file import inspect_file
from massprops.robot.doctor.bounds import bounds_of
from massprops.robot.doctor.validity import judge
from massprops.sweep import prepare, summarize

SIZE = (3.0, 2.0, 2.0)
MASS = 12.0  # ρ a b c at ρ = 1
CENTRE = np.array([1.5, 1.0, 1.0])  # box_vf's box spans [0, size]
BOX_BOUNDS = bounds_of(np.array([[x, y, z] for x in (0, 3.0) for y in (0, 2.0)
                                 for z in (0, 2.0)]))


def box_scene(tmp_path, system: bool = False):
    box_vf(tmp_path / "box.vf", size=SIZE)
    path = tmp_path / "box.yaml"
    if system:
        path.write_text("bodies:\n  box: {mesh: box.vf, density: 1.0}\n"
                        "initial: {bodies: {box: {angular_velocity: [0.1, 2.0, 0.1]}}}\n"
                        "time: {duration: 0.2}\n")
    else:
        path.write_text("body: {mesh: box.vf, density: 1.0}\n"
                        "initial: {angular_velocity: [0.1, 2.0, 0.1]}\n"
                        "time: {duration: 0.2, integrator: dop853}\n")
    return path


def bar(quantity: str, tmp_path) -> np.ndarray:
    """inspect's bar (rounding + input, each a bound) of the box."""
    u = inspect_file(tmp_path / "box.vf").uncertainty
    return sum(np.asarray(getattr(part, quantity)) for part in (u.rounding, u.input)
               if part is not None)


@pytest.mark.timeout(180)
def test_the_box_masses_spread_as_its_widened_bar_and_every_draw_is_valid(tmp_path):
    path = box_scene(tmp_path)
    mass_bar, com_bar = float(bar("mass", tmp_path)), bar("center_of_mass", tmp_path)
    assert mass_bar < 1e-12 * MASS and np.all(com_bar < 1e-12)  # a box's bars: round-off
    scale = 0.01 * MASS / mass_bar  # ± 1 % of the mass
    n = 200
    prepared = prepare(path, [], samples=n, seed=4, bars=scale,
                       outputs=["final.angular_velocity"], options={"estimate": False})
    rows = rows_of(prepared)
    assert all(r.status == "ok" for r in rows)
    masses = np.array([r.values["body.mass"] for r in rows])
    half = scale * mass_bar
    assert np.all(np.abs(masses - MASS) <= half)
    # a rectangular law over ± half: mean MASS, sd half / √3 (the sd of n such draws' sd is
    # about 0.45 sd / √n, 3 % here: 5 of them allowed)
    assert masses.mean() == pytest.approx(MASS, abs=4 * half / math.sqrt(3 * n))
    assert masses.std(ddof=1) == pytest.approx(half / math.sqrt(3), rel=0.16)
    coms = np.array([r.values["body.center_of_mass"] for r in rows])
    assert np.all(np.abs(coms - CENTRE) <= scale * com_bar * (1 + 1e-12) + 1e-15)
    for r in rows:
        m, j, c = r.values["body.mass"], np.array(r.values["body.inertia"]), \
            np.array(r.values["body.center_of_mass"])
        assert judge(m, c, j, BOX_BOUNDS).ok
    # the inertia moves with the mass, then by about its own bar: J / m stays the box's to
    # within the stretch (its bar is round-off too, so ~1 % here)
    box = np.diag([SIZE[1] ** 2 + SIZE[2] ** 2, SIZE[0] ** 2 + SIZE[2] ** 2,
                   SIZE[0] ** 2 + SIZE[1] ** 2]) / 12
    for r in rows[:20]:
        np.testing.assert_allclose(np.array(r.values["body.inertia"]) / r.values["body.mass"],
                                   box, atol=0.1 * box.max())
    result = summarize(rows, prepared.plan.outputs, [k for k, _ in prepared.plan.value_keys])
    assert result["samples"] == n and result["failed"] == 0
    assert "body.mass" in result["sensitivity"]["final.angular_velocity"]


@pytest.mark.timeout(180)
def test_a_system_pendulum_swings_with_its_own_drawn_centre_of_mass(tmp_path):
    # the rod's centre moves along it, the hinge stays: the arm is 0.3 - c_z, I about the
    # centre unchanged
    key = "bodies.rod.center_of_mass[2]"
    prepared = prepare(pendulum(tmp_path, 0.3), [f"{key}=uniform:-0.15:0.15"], samples=8,
                       seed=2, outputs=[OUT], options={"estimate": False})
    for row in rows_of(prepared):
        arm = 0.3 - row.values[key]
        assert row.outputs[OUT][0] == pytest.approx(theta(arm), abs=1e-8 * THETA0)


def one_body_pendulum(tmp_path, hinge: float = 0.3):
    """The same rod as one body: its hinge at body point (0, 0, hinge), on the world y axis,
    turned θ0 about y (its start derived from the joint)."""
    q = [math.cos(THETA0 / 2), 0.0, math.sin(THETA0 / 2), 0.0]
    text = f"""
body: {{mass: {M}, inertia: [[{I_ROD}, 0, 0], [0, {I_ROD}, 0], [0, 0, 1e-4]]}}
joints:
  - {{type: revolute, point: [0, 0, {hinge}], axis: [0, 1, 0], anchor: [0, 0, 0],
     world_axis: [0, 1, 0]}}
initial: {{orientation: {q}}}
forces:
  - {{type: gravity, g: [0, 0, {-G}]}}
time: {{duration: 2.0, rtol: 1e-11, integrator: dop853}}
"""
    path = tmp_path / "rod.yaml"
    path.write_text(text)
    return path


@pytest.mark.timeout(180)
def test_a_one_body_pendulum_swings_with_its_own_drawn_centre_of_mass(tmp_path):
    key = "body.center_of_mass[2]"
    prepared = prepare(one_body_pendulum(tmp_path), [f"{key}=uniform:-0.15:0.15"],
                       samples=6, seed=9, outputs=["final.orientation"],
                       options={"estimate": False})
    for row in rows_of(prepared):
        arm = 0.3 - row.values[key]
        w, _, y, _ = row.outputs["final.orientation"]
        assert 2 * math.atan2(y, w) == pytest.approx(theta(arm), abs=1e-8 * THETA0)


@pytest.mark.timeout(180)
def test_a_mesh_bodys_drawn_centre_stays_realizable_in_its_shape(tmp_path):
    path = box_scene(tmp_path)
    key = "body.center_of_mass[0]"
    # the box spans x in [0, 3]; a centre near a wall cannot keep the box's inertia
    prepared = prepare(path, [f"{key}=normal:1.5:1.0"], samples=30, seed=3,
                       outputs=["final.angular_velocity"], options={"estimate": False})
    rows = rows_of(prepared)
    result = summarize(rows, prepared.plan.outputs, [key])
    assert result["redrawn"] > 0
    j = np.diag([8.0, 13.0, 13.0])  # m (b² + c²)/12 and so on, m = 12
    for row in rows:
        assert row.status == "ok"
        c = CENTRE.copy()
        c[0] = row.values[key]
        assert judge(MASS, c, j, BOX_BOUNDS).ok


@pytest.mark.timeout(180)
def test_the_same_bars_rows_from_one_process_and_two_workers(tmp_path):
    path = box_scene(tmp_path, system=True)
    prepared = prepare(path, [], samples=6,
                       seed=5, bars=1e10, options={"estimate": False})
    assert prepared.plan.bar_bodies == ("box",)
    here, pooled = ([r.as_dict() for r in rows_of(prepared, jobs=jobs)] for jobs in (1, 2))
    for rows in (here, pooled):
        for row in rows:
            row.pop("wall_time_s")
    assert here == pooled
    assert set(here[0]["values"]) == {"bodies.box.mass", "bodies.box.center_of_mass",
                                      "bodies.box.inertia"}


@pytest.mark.timeout(180)
def test_bars_in_the_csv_columns(run, tmp_path):
    res = run("sweep", box_scene(tmp_path), "--bars", "--bars-scale", "1e9", "--samples", "2",
              "--format", "csv", "--no-estimate", "--outputs", "final.position")
    assert res.exit_code == 0, res.stderr
    head = res.stdout.splitlines()[0].split(",")
    assert head[3:13] == ["body.mass", "body.center_of_mass_x", "body.center_of_mass_y",
                          "body.center_of_mass_z", "body.inertia_xx", "body.inertia_yy",
                          "body.inertia_zz", "body.inertia_xy", "body.inertia_xz",
                          "body.inertia_yz"]


@pytest.mark.timeout(180)
def test_bars_json_rows(run, tmp_path):
    res = run("sweep", box_scene(tmp_path), "--bars", "--samples", "2", "--json",
              "--no-estimate")
    assert res.exit_code == 0, res.stderr
    lines = json_lines(res.stdout)
    assert lines[0]["values"]["body.mass"] == pytest.approx(MASS, rel=1e-12)
    assert set(lines[-1]) == {"summary", "sensitivity", "samples", "failed", "redrawn"}


@pytest.mark.parametrize("args, said", [
    (["--bars"], "has no mesh body"),
    (["--bars-scale", "3", "--vary", "body.mass=relative:1%"], "give --bars too"),
    (["--vary", "body.center_of_mass=normal:0:1"], "varies by component"),
    (["--vary", "body.center_of_mass[3]=normal:0:1"], "varies by component"),
    ([], "--bars"),
])
def test_a_bad_bars_or_centre_option_is_one_line(run, tmp_path, args, said):
    from test_sweep import symmetric_body

    path, _, _ = symmetric_body(tmp_path)
    res = run("sweep", path, *args, "--samples", "2")
    assert res.exit_code == 2
    assert said in res.stderr and len(res.stderr.strip().splitlines()) == 1


def test_bars_and_a_vary_of_the_same_body_contradict(run, tmp_path):
    res = run("sweep", box_scene(tmp_path), "--bars", "--vary", "body.mass=relative:1%",
              "--samples", "2")
    assert res.exit_code == 2
    assert "draw them twice" in res.stderr and len(res.stderr.strip().splitlines()) == 1
