"""`massprops torques`: inverse dynamics along a motion against Pinocchio's RNEA at every sample,
the work of the motors against the change of the arm's energy, the spline's error bar against
the true error of a sampled motion, and --check against the description's effort limits."""

from __future__ import annotations

import json

import numpy as np
import pytest
import robot_arms as ra
from conftest import ROOT, json_lines

from massprops.dynamics import any_scene
from massprops.torques import read_motion, torques_along
from massprops.torques.motion import motion_text, trapezoid

T = np.linspace(0.0, 2.0, 401)


def paths(t):
    """q, q̇, q̈ of a smooth motion of the arm's five joints (sines of different rates)."""
    amp = {"yaw": 0.8, "shoulder": 0.5, "elbow": 0.7, "slide": 0.04, "wrist": 1.0}
    rate = {"yaw": 1.0, "shoulder": 2.0, "elbow": 3.0, "slide": 1.5, "wrist": 2.5}
    q = {n: a * np.sin(rate[n] * t) for n, a in amp.items()}
    qd = {n: a * rate[n] * np.cos(rate[n] * t) for n, a in amp.items()}
    qdd = {n: -a * rate[n] ** 2 * np.sin(rate[n] * t) for n, a in amp.items()}
    return q, qd, qdd


def arm(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(ra.urdf())
    return path


def motion_file(tmp_path, exact: bool, t=T):
    q, qd, qdd = paths(t)
    columns = dict(q)
    if exact:
        columns.update({f"{n}.rate": v for n, v in qd.items()})
        columns.update({f"{n}.acc": v for n, v in qdd.items()})
    path = tmp_path / ("exact.csv" if exact else "sampled.csv")
    path.write_text(motion_text(t, columns))
    return path


@pytest.mark.timeout(120)
def test_torques_are_pinocchios_rnea_at_every_sample(tmp_path):
    pin = pytest.importorskip("pinocchio")
    scene = any_scene.load(arm(tmp_path), 0.0)
    result = torques_along(scene, read_motion(motion_file(tmp_path, exact=True)))
    model = pin.buildModelFromXML(ra.urdf())
    data = model.createData()
    names = list(model.names)[1:]
    q, qd, qdd = paths(T)
    worst = 0.0
    for i in range(0, len(T), 20):
        tau = pin.rnea(model, data, np.array([q[n][i] for n in names]),
                       np.array([qd[n][i] for n in names]), np.array([qdd[n][i] for n in names]))
        ours = np.array([result.rows[i]["joints"][n]["torque"][0] for n in names])
        worst = max(worst, float(np.max(np.abs(ours - tau))))
        assert result.rows[i]["bar"] == 0.0  # rates and accelerations given: exact
    assert worst < 1e-11


@pytest.mark.timeout(120)
def test_the_motors_work_is_the_arms_energy_change(tmp_path):
    """∫ Σ τ q̇ dt = ΔE: nothing else does work (no springs, no dampers in this arm)."""
    pin = pytest.importorskip("pinocchio")
    t = np.linspace(0.0, 2.0, 4001)
    scene = any_scene.load(arm(tmp_path), 0.0)
    result = torques_along(scene, read_motion(motion_file(tmp_path, exact=True, t=t)))
    power = np.array([sum(j["power"][0] for j in r["joints"].values()) for r in result.rows])
    work = trapezoid(power, t)
    model = pin.buildModelFromXML(ra.urdf())
    data = model.createData()
    names = list(model.names)[1:]
    q, qd, _ = paths(t)

    def energy(i):
        qi, vi = (np.array([d[n][i] for n in names]) for d in (q, qd))
        return pin.computeKineticEnergy(model, data, qi, vi) + \
            pin.computePotentialEnergy(model, data, qi)

    change = energy(-1) - energy(0)
    # the trapezoid rule's own error at 4001 samples: ~1e-7 of the power's scale
    assert work == pytest.approx(change, abs=1e-6 * max(1.0, abs(change)))
    total = sum(m["energy"][0] for m in result.summary["summary"].values())
    assert total == pytest.approx(work, rel=1e-12)


@pytest.mark.timeout(120)
def test_the_splines_bar_covers_its_true_error(tmp_path):
    scene = any_scene.load(arm(tmp_path), 0.0)
    t = np.linspace(0.0, 2.0, 101)
    exact = torques_along(scene, read_motion(motion_file(tmp_path, exact=True, t=t)))
    sampled = torques_along(scene, read_motion(motion_file(tmp_path, exact=False, t=t)))
    inner = range(10, len(t) - 10)  # the not-a-knot ends err more: they are reported so
    for i in inner:
        true = max(abs(sampled.rows[i]["joints"][n]["torque"][0]
                       - exact.rows[i]["joints"][n]["torque"][0]) for n in exact.rows[i]["joints"])
        bar = sampled.rows[i]["bar"]
        assert true <= 3 * bar + 1e-12  # an estimate, not a bound: within a small factor
        assert bar < 1e-3  # the sampling is fine: the bar is small, not a shrug


@pytest.mark.timeout(120)
def test_check_fails_naming_the_joint_when_a_peak_passes_its_limit(run, tmp_path):
    urdf = ra.urdf()
    shoulder = urdf[urdf.find('<joint name="shoulder"'):]
    shoulder = shoulder[:shoulder.find("</joint>")]
    assert 'effort="50"' in shoulder  # the arm states 50 N·m; the motion needs ~5 N·m there
    limited = urdf.replace(shoulder, shoulder.replace('effort="50"', 'effort="1.0"'))
    path = tmp_path / "limited.urdf"
    path.write_text(limited)
    motion = motion_file(tmp_path, exact=True)
    res = run("torques", path, motion, "--check", "--json")
    assert res.exit_code == 4
    summary = json_lines(res.stdout)[-1]
    assert summary["check"] == "fail" and summary["summary"]["shoulder"]["limit"] == [1.0]
    assert "joint shoulder needs" in res.stderr and "beyond its limit 1" in res.stderr
    ok = run("torques", path, motion, "--json")
    assert ok.exit_code == 0 and json_lines(ok.stdout)[-1]["check"] == "not checked"


def test_a_motion_naming_an_unknown_joint_is_one_line(run, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,knee\n" + "".join(f"{k / 10},{k / 100}\n" for k in range(12)))
    res = run("torques", arm(tmp_path), bad)
    assert res.exit_code == 1
    errors = [line for line in res.stderr.splitlines() if line.startswith("massprops: error")]
    assert len(errors) == 1 and "no joint 'knee'" in errors[0]
    assert "Traceback" not in res.stderr


@pytest.mark.timeout(120)
def test_csv_rows(run, tmp_path):
    res = run("torques", arm(tmp_path), motion_file(tmp_path, exact=True), "--format", "csv")
    assert res.exit_code == 0, res.stderr
    lines = res.stdout.splitlines()
    assert lines[0].startswith("t,yaw.torque,yaw.power,shoulder.torque")
    assert len(lines) == len(T) + 1
    assert json.loads(res.stderr.strip().splitlines()[-1])["samples"] == len(T)


def round_trip(tmp_path, sample_name: str, joint_end: str, drive: float, time_line: str,
               joints: tuple[str, ...]):
    """The sample run by simulate with ``drive`` (N·m) on the first joint ending in
    ``joint_end``, for 2 s at rtol 1e-12 sampled every 4 ms; the named joints' coordinates given
    to `torques` on the sample without the drive: (its result, the run's samples)."""
    sample = (ROOT / "sample_scenes" / sample_name).read_text()
    driven = sample.replace(joint_end, joint_end[:-1] + f", torque: {drive}}}", 1)
    assert driven != sample and time_line in driven
    driven = driven.replace(time_line, "time: {duration: 2.0, rtol: 1e-12}")
    (tmp_path / "driven.yaml").write_text(driven)
    (tmp_path / "free.yaml").write_text(sample)
    s = any_scene.simulate(any_scene.load(tmp_path / "driven.yaml"), every=0.004).samples
    names = [j.name for j in any_scene.load(tmp_path / "free.yaml").joints]
    columns = {n: s.coordinates[names.index(n)][:, 0] for n in joints}
    (tmp_path / "made.csv").write_text(motion_text(s.t, columns))
    return torques_along(any_scene.load(tmp_path / "free.yaml"),
                         read_motion(tmp_path / "made.csv")), s


@pytest.mark.timeout(120)
def test_a_motion_simulate_made_under_a_drive_gives_that_drive_back(tmp_path):
    """The double pendulum driven at its shoulder by 0.5 N·m runs under simulate; the same
    pendulum without the drive, along that motion, needs 0.5 N·m at the shoulder and nothing at
    the elbow: to within the spline's bar plus the data's own error, which the bar does not hold:
    the run's positions (dense output at rtol 1e-12, ~1e-11 rad) twice differentiated over
    h = 4 ms reach the accelerations as ~2e-11 / h² ≈ 1e-6 rad/s², the torques as ~1e-6 N·m."""
    found, _ = round_trip(tmp_path, "double_pendulum.yaml", "axis: [0, 1, 0]}", 0.5,
                          "time: {duration: 10.0}", ("shoulder", "elbow"))
    for row in found.rows[10:-10]:  # the spline's not-a-knot ends err more
        bar = row["bar"]
        assert row["joints"]["shoulder"]["torque"][0] == pytest.approx(0.5, abs=bar + 1e-5)
        assert abs(row["joints"]["elbow"]["torque"][0]) <= bar + 1e-5
    assert max(r["bar"] for r in found.rows[10:-10]) < 1e-4


@pytest.mark.timeout(120)
def test_a_four_bars_crank_drive_comes_back_through_its_loop(tmp_path):
    """The four-bar sample driven at its crank by 3 N·m under simulate; its crank's sampled
    motion given to `torques` on the undriven four-bar: the crank needs 3 N·m (the coupler and
    rocker solved on the loop), the other joints none (they have no motors)."""
    found, s = round_trip(tmp_path, "four_bar.yaml", "point: [0, 0, 0], axis: [0, 1, 0]}",
                          3.0, "time: {duration: 5.0}", ("A",))
    for row in found.rows[10:-10]:
        bar = row["bar"]
        assert row["joints"]["A"]["torque"][0] == pytest.approx(3.0, abs=bar + 1e-4)
        for other in ("B", "C", "D"):
            assert row["joints"][other]["torque"] == [0.0]
    # every joint's reaction is the run's own (its forward dynamics under the drive), to the
    # same accuracy (measured: 6e-4 N); the planar loop is redundant, both take minimum norm
    assert any("minimum-norm" in n for n in found.notes)
    for k in (100, 250, 400):
        for jj, name in enumerate("ABCD"):
            np.testing.assert_allclose(found.rows[k]["joints"][name]["force"], s.force[k, jj],
                                       atol=2e-3)


@pytest.mark.timeout(120)
def test_computed_inertials_ignore_a_wrong_stated_one_and_bars_show_the_spread(run, tmp_path):
    """The test arm's stated inertials are its geometry's (`model --check` passes); with the
    upper arm's stated inertia replaced by a placeholder (its centre of mass at the link origin,
    diag(0.01)), `--inertials computed` gives the original torques back (the stated mass with
    the geometry's distribution), and `--bars` widens each sample's bar to the spread between
    the placeholder's torques and the geometry's."""
    import shutil

    folder = tmp_path / "arm_description"
    shutil.copytree(ROOT / "tests" / "robots" / "arm_description", folder)
    urdf = folder / "urdf" / "arm.urdf"
    text = urdf.read_text()
    stated = ('<origin xyz="0.07 0.01 0.23" rpy="0 0 0"/>\n      <mass value="2.5"/>\n      '
              '<inertia ixx="0.0441667" ixy="0.003" ixz="-0.006" iyy="0.0421667" iyz="0.012" '
              'izz="0.0141667"/>')
    placeholder = ('<origin xyz="0 0 0" rpy="0 0 0"/>\n      <mass value="2.5"/>\n      '
                   '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>')
    assert text.count(stated) == 1
    t = np.linspace(0.0, 1.0, 101)
    motion = tmp_path / "arm.csv"
    motion.write_text(motion_text(t, {"shoulder": 0.4 * np.sin(3 * t),
                                      "elbow": 0.3 + 0.5 * np.sin(2 * t),
                                      "wrist_joint": np.sin(t)}))

    def torques(*extra):
        res = run("torques", urdf, motion, "--json", *extra)
        assert res.exit_code == 0, res.stderr
        return json_lines(res.stdout)[:-1]

    def shoulder(rows):
        return np.array([r["joints"]["shoulder"]["torque"][0] for r in rows])

    original = shoulder(torques())
    urdf.write_text(text.replace(stated, placeholder))
    wrong, from_geometry = torques(), torques("--inertials", "computed")
    # the file states the geometry's inertials rounded to 6 digits (0.0441667): ~1e-7 N·m apart
    np.testing.assert_allclose(shoulder(from_geometry), original, rtol=0, atol=1e-6)
    spread = np.abs(shoulder(wrong) - shoulder(from_geometry))
    assert spread.max() > 0.01  # the upper arm's misplaced mass is felt at the shoulder
    barred = torques("--bars")
    assert all(r["bar"] >= s for r, s in zip(barred, spread))
    np.testing.assert_array_equal(shoulder(barred), shoulder(wrong))  # the stated ones reported


def test_a_motion_the_loop_cannot_follow_is_one_line_exit_1(run, tmp_path):
    """Crank and coupler both driven: the four-bar has one degree of freedom, so the loop
    cannot close once the two disagree (the contract: exit 1, one line)."""
    t = np.linspace(0.0, 1.0, 50)
    motion = tmp_path / "both.csv"
    motion.write_text(motion_text(t, {"A": 0 * t, "B": 6 * t}))
    res = run("torques", ROOT / "sample_scenes" / "four_bar.yaml", motion)
    assert res.exit_code == 1
    errors = [line for line in res.stderr.splitlines() if line.startswith("massprops: error")]
    assert len(errors) == 1 and "the loop cannot close" in errors[0] and "t = " in errors[0]


def test_check_names_a_joint_that_moves_faster_than_its_velocity_limit(run, tmp_path):
    urdf = ra.urdf()
    shoulder = urdf[urdf.find('<joint name="shoulder"'):]
    shoulder = shoulder[:shoulder.find("</joint>")]
    assert 'velocity="5"' in shoulder  # the motion's shoulder turns at up to 1 rad/s
    path = tmp_path / "slow.urdf"
    path.write_text(urdf.replace(shoulder, shoulder.replace('velocity="5"', 'velocity="0.8"')))
    res = run("torques", path, motion_file(tmp_path, exact=True), "--check", "--json")
    assert res.exit_code == 4
    summary = json_lines(res.stdout)[-1]["summary"]["shoulder"]
    assert summary["rate_limit"] == [0.8]
    assert summary["peak_rate"][0] == pytest.approx(0.5 * 2.0)  # amp × rate of its sine
    assert "joint shoulder moves at 1 at t = 0 s, beyond its velocity limit 0.8" in res.stderr
    assert "joint limits are not enforced" not in res.stderr  # nothing is simulated here
