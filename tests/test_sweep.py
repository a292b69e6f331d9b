"""`massprops sweep`: each sample against its own closed form, the Monte Carlo spread against the
delta method, the same rows whatever runs them, every drawn inertial valid, the exit codes.

Truth here is independent of the program: the small-amplitude compound pendulum
θ(t) = θ0 cos(ω t), ω² = m g l / (I + m l²); the torque-free symmetric body's body-frame
precession at Ω = (C − A) / A ω3; the invariance of motion under gravity when mass and inertia
scale together; the validity tests of the inertia doctor.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import json_lines

from massprops.robot.doctor.bounds import bounds_of
from massprops.robot.doctor.validity import judge
from massprops.sweep import prepare, run_sweep, summarize
from massprops.sweep.inertials import stretched

G = 9.81
M, L_ROD, W = 2.0, 1.0, 0.02
I_ROD = M * (L_ROD ** 2 + W ** 2) / 12  # across the rod, about its centre
THETA0 = 1e-3
DURATION = 2.0


def pendulum(tmp_path, hinge_z: float = 0.3):
    """A rod hanging on a hinge about y at the world origin, its centre ``hinge_z`` below it."""
    text = f"""
bodies:
  rod: {{mass: {M}, inertia: [[{I_ROD}, 0, 0], [0, {I_ROD}, 0], [0, 0, 1e-4]],
        position: [0, 0, {-hinge_z}]}}
joints:
  - {{name: hinge, type: revolute, bodies: [world, rod], point: [0, 0, 0], axis: [0, 1, 0]}}
initial:
  positions: {{hinge: {THETA0}}}
forces:
  - {{type: gravity, g: [0, 0, {-G}]}}
time: {{duration: {DURATION}, rtol: 1e-11}}
"""
    path = tmp_path / "pendulum.yaml"
    path.write_text(text)
    return path


def theta(arm: float, t: float = DURATION) -> float:
    """The hinge angle at t of the small-amplitude pendulum with its centre ``arm`` below the
    hinge, Lindstedt-Poincaré to third order: τ = ω (1 − θ0²/16) t,
    θ = θ0 cos τ + θ0³/192 (cos τ − cos 3τ) (what is left is O(θ0⁵) ~ 1e-15 here)."""
    tau = math.sqrt(M * G * arm / (I_ROD + M * arm * arm)) * (1 - THETA0 ** 2 / 16) * t
    return THETA0 * math.cos(tau) + THETA0 ** 3 / 192 * (math.cos(tau) - math.cos(3 * tau))


def rows_of(prepared, **kw):
    return list(run_sweep(prepared, **kw))


OUT = "final.joints.hinge.coordinates"


@pytest.mark.timeout(120)
def test_each_sample_is_the_pendulum_of_its_own_drawn_length(tmp_path):
    # the rod's centre moves: the drawn value is the arm in the closed form
    prepared = prepare(pendulum(tmp_path), ["bodies.rod.position[2]=uniform:-0.5:-0.2"],
                       samples=12, seed=3, outputs=[OUT], options={"estimate": False})
    for row in rows_of(prepared):
        arm = -row.values["bodies.rod.position[2]"]
        assert 0.2 <= arm <= 0.5
        assert row.outputs[OUT][0] == pytest.approx(theta(arm), abs=1e-8 * THETA0)


@pytest.mark.timeout(120)
def test_the_spread_and_the_slope_are_the_delta_method(tmp_path):
    l0, sd = 0.3, 0.002
    n = 200
    prepared = prepare(pendulum(tmp_path, l0), [f"bodies.rod.position[2]=normal:{-l0}:{sd}"],
                       samples=n, seed=11, outputs=[OUT], options={"estimate": False})
    rows = rows_of(prepared)
    result = summarize(rows, [OUT], ["bodies.rod.position[2]"])
    h = 1e-6
    slope = -(theta(l0 + h) - theta(l0 - h)) / (2 * h)  # d θ / d position_z = -d θ / d l
    stats = result["summary"][OUT]
    # the sd of an sd from n normal samples is sd / sqrt(2 (n - 1)): 5 % here, 4 of them allowed
    assert stats["sd"][0] == pytest.approx(abs(slope) * sd, rel=4 / math.sqrt(2 * (n - 1)))
    assert stats["mean"][0] == pytest.approx(theta(l0), abs=5 * abs(slope) * sd / math.sqrt(n))
    # the regression's slope: within a few percent (the curvature over ±3 sd is smaller still)
    assert result["sensitivity"][OUT]["bodies.rod.position[2]"][0] == pytest.approx(slope,
                                                                                    rel=0.03)
    lo, mid, hi = stats["p05"][0], stats["p50"][0], stats["p95"][0]
    assert lo < mid < hi
    assert hi - lo == pytest.approx(2 * 1.6449 * abs(slope) * sd, rel=0.2)


@pytest.mark.timeout(120)
def test_a_mass_that_carries_its_inertia_leaves_the_motion_under_gravity_unchanged(tmp_path):
    prepared = prepare(pendulum(tmp_path), ["bodies.rod.mass=values:0.5,2,8"], samples=None,
                       outputs=[OUT, "final.joints.hinge.force"], options={"estimate": False})
    rows = rows_of(prepared)
    assert [r.values["bodies.rod.mass"] for r in rows] == [0.5, 2.0, 8.0]
    angles = [r.outputs[OUT][0] for r in rows]
    assert angles == pytest.approx([theta(0.3)] * 3, abs=1e-8 * THETA0)
    forces = np.array([r.outputs["final.joints.hinge.force"] for r in rows])
    # the hinge carries the weight (and the tiny centripetal part): it scales with the mass
    for force, mass in zip(forces, (0.5, 2.0, 8.0)):
        np.testing.assert_allclose(force / mass, forces[1] / 2.0, rtol=1e-9, atol=1e-12)


def symmetric_body(tmp_path):
    a, c = 2.0, 3.0
    text = f"""
body: {{mass: 1.0, inertia: [[{a}, 0, 0], [0, {a}, 0], [0, 0, {c}]]}}
initial: {{angular_velocity: [0.4, 0.0, 5.0]}}
time: {{duration: 3.0, integrator: dop853, rtol: 1e-12}}
"""
    path = tmp_path / "top.yaml"
    path.write_text(text)
    return path, a, c


@pytest.mark.timeout(120)
def test_each_torque_free_sample_precesses_at_its_own_rate(tmp_path):
    path, a, c = symmetric_body(tmp_path)
    prepared = prepare(path, ["initial.angular_velocity[2]=normal:5:1",
                              "body.mass=lognormal:1:2"], samples=8, seed=5,
                       outputs=["final.angular_velocity_body"], options={"estimate": False})
    for row in rows_of(prepared):
        w3 = row.values["initial.angular_velocity[2]"]
        rate = (c - a) / a * w3  # ω1 + i ω2 = 0.4 exp(i Ω t) in the body frame
        want = [0.4 * math.cos(rate * 3.0), 0.4 * math.sin(rate * 3.0), w3]
        np.testing.assert_allclose(row.outputs["final.angular_velocity_body"], want, atol=1e-9)


def test_stretched_inertials_are_valid_and_spread_as_said():
    rng = np.random.default_rng(0)
    disk = np.diag([1.0, 1.0, 2.0])  # a flat disk: on the triangle inequality's edge
    rod = np.diag([1.0, 1.0, 1e-6])
    for base in (np.diag([1.0, 2.0, 2.5]), disk, rod):
        draws = [stretched(rng, base, 0.05) for _ in range(400)]
        assert all(judge(1.0, np.zeros(3), j, None).ok for j in draws)
    moments = np.array([np.linalg.eigvalsh(stretched(rng, np.eye(3), 0.05))
                        for _ in range(2000)])
    sd = np.std(moments / 1.0, axis=0)
    assert np.all((0.6 * 0.05 < sd) & (sd < 1.1 * 0.05))  # between 0.7 P and P, with MC slack


@pytest.mark.timeout(120)
def test_a_mesh_bodys_drawn_inertia_fits_its_shape(tmp_path):
    from conftest import box_vf

    mesh = box_vf(tmp_path / "box.vf", size=(3.0, 2.0, 2.0))
    scene = tmp_path / "box.yaml"
    scene.write_text(f"body: {{mesh: {mesh.name}, density: 1.0}}\n"
                     "initial: {angular_velocity: [0.1, 2.0, 0.1]}\n"
                     "time: {duration: 0.5, integrator: dop853}\n")
    # a solid box leaves its bounding ellipsoid's test much slack (tr(S⁻¹Σ) = m/3 of m): only
    # a wide spread reaches it
    prepared = prepare(scene, ["body.inertia=relative:150%"], samples=40, seed=1,
                       outputs=["final.angular_velocity"], options={"estimate": False})
    rows = rows_of(prepared)
    result = summarize(rows, prepared.plan.outputs, ["body.inertia"])
    assert result["redrawn"] > 0
    bounds = bounds_of(np.array([[x, y, z] for x in (-1.5, 1.5) for y in (-1, 1)
                                 for z in (-1, 1)]))
    for row in rows:
        assert row.status == "ok"
        j = np.array(row.values["body.inertia"])
        assert judge(12.0, np.zeros(3), j, bounds).ok


@pytest.mark.timeout(120)
def test_the_same_rows_from_one_process_two_workers_and_a_dask_cluster(tmp_path):
    distributed = pytest.importorskip("distributed")
    path, _, _ = symmetric_body(tmp_path)
    prepared = prepare(path, ["initial.angular_velocity[0]=normal:0.4:0.1",
                              "body.inertia=relative:5%"], samples=10, seed=7,
                       options={"estimate": False})
    here = [r.as_dict() for r in rows_of(prepared)]
    for row in here:
        row.pop("wall_time_s")
    pooled = [r.as_dict() for r in rows_of(prepared, jobs=2)]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster, set_as_default=False) as client:
        clustered = [r.as_dict() for r in rows_of(prepared, executor=client.get_executor(),
                                                  workers=2)]
    for rows in (pooled, clustered):
        for row in rows:
            row.pop("wall_time_s")
        assert rows == here


# --- the command ------------------------------------------------------------------------------
@pytest.mark.timeout(120)
def test_json_lines_then_the_summary(run, tmp_path):
    path, _, _ = symmetric_body(tmp_path)
    res = run("sweep", path, "--vary", "body.mass=uniform:1:2", "--samples", "3", "--json",
              "--no-estimate")
    assert res.exit_code == 0, res.stderr
    lines = json_lines(res.stdout)
    assert [r["sample"] for r in lines[:3]] == [0, 1, 2]
    assert set(lines[0]) == {"sample", "values", "status", "error", "outputs",
                             "error_estimate", "wall_time_s"}
    assert set(lines[3]) == {"summary", "sensitivity", "samples", "failed", "redrawn"}
    assert lines[3]["samples"] == 3 and lines[3]["failed"] == 0


@pytest.mark.timeout(120)
def test_csv_rows_to_a_file_and_failed_samples_exit_3(run, tmp_path):
    path, _, _ = symmetric_body(tmp_path)
    out = tmp_path / "rows.csv"
    res = run("sweep", path, "--vary", "time.duration=uniform:-1:1", "--samples", "6",
              "--seed", "2", "--format", "csv", "--output", out, "--no-estimate")
    text = out.read_text().splitlines()
    assert text[0].startswith("sample,status,error,time.duration,final.position_x")
    statuses = [line.split(",")[1] for line in text[1:]]
    assert len(statuses) == 6 and "failed" in statuses and "ok" in statuses
    assert res.exit_code == 3
    assert json.loads(res.stderr.strip().splitlines()[-1])["failed"] == statuses.count("failed")


@pytest.mark.parametrize("vary, code, said", [
    ("forces[0].stiffness=normal:1:0.1", 1, "the scene has no forces"),
    ("body.mass=gauss:1:2", 2, "expected one of normal"),
    ("body.inertia=normal:1:0.1", 2, "relative:P only"),
    ("body.mass", 2, "expected KEY=SPEC"),
])
def test_a_bad_key_or_spec_is_one_line(run, tmp_path, vary, code, said):
    path, _, _ = symmetric_body(tmp_path)
    res = run("sweep", path, "--vary", vary, "--samples", "2")
    assert res.exit_code == code
    assert said in res.stderr and len(res.stderr.strip().splitlines()) == 1
    assert "Traceback" not in res.stderr


@pytest.mark.timeout(120)
def test_linear_derivatives_are_the_closed_forms_within_their_own_accuracy(tmp_path):
    from massprops.sweep.linear import linearize

    l0, sd = 0.3, 0.002
    key = "bodies.rod.position[2]"
    prepared = prepare(pendulum(tmp_path, l0), [f"{key}=normal:{-l0}:{sd}",
                                                "bodies.rod.mass=relative:3%"],
                       samples=2, outputs=[OUT], options={"estimate": False})
    found = linearize(prepared.plan)[OUT]
    h = 1e-6
    slope = -(theta(l0 + h) - theta(l0 - h)) / (2 * h)
    got, accuracy = found["derivative"][key][0], found["accuracy"][key][0]
    assert abs(got - slope) <= max(accuracy, 1e-9 * abs(slope))
    assert accuracy < 1e-3 * abs(slope)  # the bar is tight, not a shrug
    # the mass carries its inertia: the motion does not depend on it
    assert abs(found["derivative"]["bodies.rod.mass"][0]) <= \
        found["accuracy"]["bodies.rod.mass"][0] + 1e-12
    assert found["sd"][0] == pytest.approx(abs(slope) * sd, rel=1e-3)


@pytest.mark.timeout(120)
def test_linear_in_the_json_summary(run, tmp_path):
    res = run("sweep", pendulum(tmp_path), "--vary", "bodies.rod.position[2]=normal:-0.3:0.002",
              "--samples", "4", "--json", "--linear", "--no-estimate", "--outputs", OUT)
    assert res.exit_code == 0, res.stderr
    summary = json_lines(res.stdout)[-1]
    assert set(summary["linear"][OUT]) == {"derivative", "accuracy", "sd"}


@pytest.mark.timeout(120)
def test_each_samples_series_is_its_pendulum_at_every_time(tmp_path):
    prepared = prepare(pendulum(tmp_path), ["bodies.rod.position[2]=uniform:-0.5:-0.2"],
                       samples=4, seed=8, outputs=[OUT], options={"estimate": False},
                       series=True)
    for row in rows_of(prepared):
        arm = -row.values["bodies.rod.position[2]"]
        assert row.times[0] == 0.0 and row.times[-1] == pytest.approx(DURATION)
        angles = [v[0] for v in row.series[OUT]]
        want = [theta(arm, t) for t in row.times]
        np.testing.assert_allclose(angles, want, rtol=0, atol=1e-8 * THETA0)
        assert row.series[OUT][-1] == row.outputs[OUT]


@pytest.mark.timeout(120)
def test_plot_writes_a_png_and_never_over_the_scene(run, tmp_path):
    pytest.importorskip("matplotlib")
    scene = pendulum(tmp_path)
    png = tmp_path / "bands.png"
    res = run("sweep", scene, "--vary", "bodies.rod.position[2]=uniform:-0.5:-0.2",
              "--samples", "5", "--no-estimate", "--plot", png, "--outputs", OUT)
    assert res.exit_code == 0, res.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    again = run("sweep", scene, "--vary", "bodies.rod.position[2]=uniform:-0.5:-0.2",
                "--samples", "5", "--plot", png)
    assert again.exit_code == 1 and "exists" in again.stderr  # checked before any run


@pytest.mark.timeout(90)
def test_ctrl_c_keeps_the_rows_done_and_leaves_no_process(tmp_path):
    """A terminal's Ctrl-C mid-sweep (the whole process group): exit 130, the rows done are
    printed in sample order with their summary, and no worker outlives the command."""
    import os
    import signal
    import subprocess
    import sys
    import time

    from _batchdata import descendants

    proc = subprocess.Popen(
        [sys.executable, "-m", "massprops", "sweep", str(pendulum(tmp_path)), "--vary",
         "bodies.rod.position[2]=uniform:-0.5:-0.2", "--samples", "100000", "--json",
         "--jobs", "2", "--no-estimate"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        start_new_session=True, bufsize=0)
    first = proc.stdout.readline()  # the sweep is running and has printed a row
    helpers = descendants(proc.pid)
    os.killpg(proc.pid, signal.SIGINT)
    rest, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    lines = [json.loads(line) for line in (first + rest).decode().splitlines()]
    rows, summary = lines[:-1], lines[-1]
    assert [r["sample"] for r in rows] == list(range(len(rows))) and 1 <= len(rows) < 100000
    assert summary["samples"] == len(rows) and summary["failed"] == 0
    assert "interrupted" in err.decode()
    deadline = time.monotonic() + 5
    while [p for p in helpers if os.path.exists(f"/proc/{p}")
           and open(f"/proc/{p}/stat").read().rsplit(")", 1)[1].split()[0] != "Z"]:
        assert time.monotonic() < deadline, "a worker outlived the sweep"
        time.sleep(0.05)
