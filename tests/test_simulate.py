"""simulate end to end: closed forms through the frames, windows, diagnostics, files, exit codes."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import CUBE_QUADS, CUBE_VERTS, json_lines, vf_text

from massprops.dynamics.model import (
    Drag,
    Gravity,
    InitialState,
    OutputSettings,
    PointForce,
    RigidBody,
    Scene,
    Spring,
    TimeSettings,
    Torque,
)
from massprops.dynamics.simulate import simulate
from massprops.errors import DivergenceError
from massprops.rotation import quat_from_axis_angle, quat_to_matrix, rotation_angle_between

BOX = RigidBody.from_inertia(12.0, np.diag([8.0, 13.0, 13.0]))  # the notes' cuboid
ASYM = RigidBody.from_inertia(2.0, np.diag([1.0, 2.0, 3.0]))


def scene(body=BOX, forces=(), duration=1.0, integrator="auto", initial=None, **time):
    return Scene(body=body, initial=initial or InitialState(), forces=tuple(forces),
                 time=TimeSettings(duration=duration, integrator=integrator, **time),
                 output=OutputSettings())


def final(result):
    return result.trajectory.row(-1)


@pytest.mark.parametrize("integrator", ["auto", "exact", "rk4", "dop853"])
def test_free_fall_is_exact(integrator):
    g = np.array([0.0, 0.0, -9.81])
    ini = InitialState(position=np.array([1.0, 2.0, 3.0]), velocity=np.array([0.5, 0.0, 4.0]))
    res = simulate(scene(forces=[Gravity(g)], duration=2.0, integrator=integrator, initial=ini))
    f = final(res)
    assert np.allclose(f["position"], ini.position + 2.0 * ini.velocity + 2.0 * g, rtol=1e-14,
                       atol=1e-13)
    assert np.allclose(f["velocity"], ini.velocity + 2.0 * g, rtol=1e-14, atol=1e-13)
    if integrator == "auto":
        assert res.integrator == "exact"


def test_body_frame_force_equals_world_force_at_t0():
    q = quat_from_axis_angle(np.array([1.0, 2.0, 3.0]) / math.sqrt(14), 0.7)
    f_body = np.array([0.3, -1.0, 2.0])
    f_world = quat_to_matrix(q) @ f_body
    point = np.array([0.5, 0.2, -0.1])
    ini = InitialState(orientation=q)
    short = dict(duration=1e-3, integrator="dop853", rtol=1e-13)
    a = simulate(scene(forces=[PointForce(f_body, "body", point)], initial=ini, **short))
    b = simulate(scene(forces=[PointForce(f_world, "world", point)], initial=ini, **short))
    # identical at t = 0, so equal to O(t²·ω) over a short run
    for key in ("position", "velocity", "angular_velocity"):
        assert np.allclose(final(a)[key], final(b)[key], rtol=1e-6, atol=1e-12)


def test_constant_body_torque_about_principal_axis():
    tau = 2.0
    res = simulate(scene(forces=[Torque(np.array([0.0, 0.0, tau]), "body")], duration=3.0,
                         integrator="dop853", rtol=1e-12))
    f = final(res)
    assert np.allclose(f["angular_velocity"], [0, 0, tau / 13 * 3.0], rtol=1e-11, atol=1e-13)
    angle = tau * 9.0 / (2 * 13)
    assert rotation_angle_between(np.array(f["orientation"]),
                                  quat_from_axis_angle(np.array([0.0, 0, 1]), angle)) < 1e-10


def test_harmonic_spring_period():
    k, m = 100.0, 12.0
    ini = InitialState(position=np.array([0.1, 0.0, 0.0]))
    period = 2 * math.pi * math.sqrt(m / k)
    res = simulate(scene(forces=[Spring(np.zeros(3), k)], duration=period, integrator="dop853",
                         rtol=1e-12, initial=ini))
    assert np.allclose(final(res)["position"], [0.1, 0, 0], atol=1e-10)
    assert res.diagnostics["energy_rel_drift"] < 1e-9
    assert res.diagnostics["angular_momentum_rel_drift"] is not None  # spring at COM: no torque


def test_damped_spring_closed_form():
    k, c, m = 50.0, 3.0, 12.0
    x0 = 0.2
    ini = InitialState(position=np.array([0.0, x0, 0.0]))
    res = simulate(scene(forces=[Spring(np.zeros(3), k, damping=c)], duration=2.0,
                         integrator="dop853", rtol=1e-12, initial=ini))
    zeta_w, wd = c / (2 * m), math.sqrt(k / m - (c / (2 * m)) ** 2)
    x = x0 * math.exp(-zeta_w * 2.0) * (math.cos(wd * 2.0) + zeta_w / wd * math.sin(wd * 2.0))
    assert final(res)["position"][1] == pytest.approx(x, abs=1e-10)
    assert res.diagnostics["energy_rel_drift"] is None  # damping: not conserved, reported null


def test_window_shorter_than_step_is_resolved():
    # 1 N on 12 kg for 1e-4 s inside a run with step 1e-2: impulse 1e-4 N·s exactly
    res = simulate(scene(forces=[PointForce(np.array([1.0, 0, 0]), start=0.5, end=0.5001)],
                         duration=1.0, integrator="rk4", step=1e-2))
    assert final(res)["velocity"][0] == pytest.approx(1e-4 / 12, rel=1e-12)
    assert final(res)["position"][0] == pytest.approx(1e-4 / 12 * (1.0 - 0.50005), rel=1e-9)


def test_torque_free_exact_matches_tight_dop853():
    ini = InitialState(angular_velocity=np.array([1.0, 0.05, 0.3]),
                       angular_velocity_frame="body")
    ex = simulate(scene(body=ASYM, duration=20.0, integrator="exact", initial=ini))
    nu = simulate(scene(body=ASYM, duration=20.0, integrator="dop853", rtol=1e-13, initial=ini))
    assert np.allclose(final(ex)["angular_velocity"], final(nu)["angular_velocity"], atol=1e-9)
    assert rotation_angle_between(np.array(final(ex)["orientation"]),
                                  np.array(final(nu)["orientation"])) < 1e-9
    assert ex.diagnostics["angular_momentum_rel_drift"] < 1e-13


def test_mesh_body_equals_explicit_body(tmp_path):
    mesh = tmp_path / "box.vf"
    mesh.write_text(vf_text((np.array(CUBE_VERTS, float) * [3.0, 2.0, 1.0]).tolist(), CUBE_QUADS))
    yaml_common = ("initial: {angular_velocity: [0.3, 1.0, 0.2], angular_velocity_frame: body}\n"
                   "forces: [{type: torque, vector: [0, 0.1, 0], frame: body}]\n"
                   "time: {duration: 2.0, integrator: dop853, rtol: 1.0e-12}\n")
    (tmp_path / "mesh.yaml").write_text(f"body: {{mesh: box.vf, density: 2.0}}\n{yaml_common}")
    m = 12.0
    j = np.diag([m * (4 + 1), m * (9 + 1), m * (9 + 4)]) / 12
    (tmp_path / "explicit.yaml").write_text(
        f"body: {{mass: {m}, inertia: {j.tolist()}, center_of_mass: [1.5, 1.0, 0.5]}}\n"
        + yaml_common)
    from massprops.dynamics.scene import load_scene

    a = simulate(load_scene(tmp_path / "mesh.yaml"))
    b = simulate(load_scene(tmp_path / "explicit.yaml"))
    for key in ("position", "orientation", "velocity", "angular_velocity"):
        assert np.allclose(final(a)[key], final(b)[key], atol=1e-10)


def test_stiff_explicit_reports_divergence():
    sc = scene(forces=[Spring(np.zeros(3), 1e8)], duration=0.1, integrator="rk4", step=1e-3,
               initial=InitialState(position=np.array([1e-3, 0, 0])))
    with pytest.raises(DivergenceError) as info:
        simulate(sc)
    assert "t = " in str(info.value) and "implicit" in str(info.value)


def test_strong_damper_auto_picks_implicit_and_matches_closed_form():
    # m = 1 (unit body), k = 1e4, c = 1e6: overdamped, fast rate c/m = 1e6 would take ~3.6e6
    # explicit steps over 10 s, so auto must go implicit; the slow root carries the motion
    unit = RigidBody.from_inertia(1.0, np.eye(3))
    k, c, x0, t = 1e4, 1e6, 1e-3, 10.0
    sc = scene(body=unit, forces=[Spring(np.zeros(3), k, damping=c)], duration=t,
               initial=InitialState(position=np.array([x0, 0, 0])))
    res = simulate(sc)
    assert res.integrator == "implicit"
    disc = math.sqrt(c * c - 4 * k)
    slow, fast = (-c + disc) / 2, (-c - disc) / 2
    x = x0 * fast / (fast - slow) * math.exp(slow * t)  # the fast term is e^-1e7: gone
    assert final(res)["position"][0] == pytest.approx(x, rel=1e-6)
    e = res.trajectory.energy
    assert np.all(np.isfinite(e)) and np.all(np.diff(e) <= 1e-12 * e[0])


def test_drag_makes_energy_null_and_decays():
    ini = InitialState(velocity=np.array([1.0, 0, 0]), angular_velocity=np.array([0, 0, 1.0]))
    res = simulate(scene(forces=[Drag(linear=1.2, angular=0.13)], duration=1.0,
                         integrator="dop853", rtol=1e-12, initial=ini))
    assert res.diagnostics["energy_rel_drift"] is None
    assert final(res)["velocity"][0] == pytest.approx(math.exp(-0.1), rel=1e-10)
    assert final(res)["angular_velocity"][2] == pytest.approx(math.exp(-0.01), rel=1e-10)


# --- the command --------------------------------------------------------------------------------
def _write_scene(tmp_path, text, name="scene.yaml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_cli_json_contract_and_trajectory(run, tmp_path):
    sc = _write_scene(tmp_path, "body: {mass: 12.0, inertia: [[8,0,0],[0,13,0],[0,0,13]]}\n"
                                "initial: {velocity: [1, 0, 0]}\n"
                                "forces: [{type: gravity, g: [0, 0, -9.81]}]\n"
                                "time: {duration: 1.0}\n"
                                "output: {every: 0.25, file: traj.csv}\n")
    res = run("simulate", "--json", sc)
    assert res.exit_code == 0, res.stderr
    (out,) = json_lines(res.stdout)
    assert {"integrator", "steps", "wall_time_s", "final", "diagnostics"} <= out.keys()
    assert {"t", "position", "orientation", "velocity", "angular_velocity",
            "angular_velocity_body"} <= out["final"].keys()
    assert {"energy_rel_drift", "angular_momentum_rel_drift", "quaternion_norm_error",
            "error_estimate"} <= out["diagnostics"].keys()
    assert out["final"]["position"] == pytest.approx([1.0, 0, -9.81 / 2], abs=1e-14)
    table = np.loadtxt(tmp_path / "traj.csv", delimiter=",", skiprows=1)
    header = (tmp_path / "traj.csv").read_text().splitlines()[0]
    assert header.startswith("t [s],x [m],y [m],z [m],qw")
    assert np.allclose(table[:, 0], [0, 0.25, 0.5, 0.75, 1.0])
    assert np.allclose(table[:, 3], -9.81 / 2 * table[:, 0] ** 2, atol=1e-14)
    # a second run refuses to replace the trajectory without --force
    again = run("simulate", "--json", sc)
    assert again.exit_code == 1 and "--force" in again.stderr
    assert run("simulate", "--json", "--force", sc).exit_code == 0


@pytest.mark.parametrize("text,needle", [
    ("body: {mass: -1, inertia: [[1,0,0],[0,1,0],[0,0,1]]}\ntime: {duration: 1}\n", "body.mass"),
    ("body: {mass: 1, inertia: [[1,0,0],[0,1,0],[0,0,3]]}\ntime: {duration: 1}\n", "triangle"),
    ("body: {mass: 1, inertia: [[1,0,0],[0,1,0],[0,0,1]]}\ntime: {duraton: 1}\n", "duraton"),
    ("body: {mass: 1, inertia: [[1,0,0],[0,1,0],[0,0,1]]}\n", "duration"),
    ("body: [unclosed\n", "scene.yaml"),
], ids=["negative-mass", "triangle-inequality", "typo", "missing-duration", "yaml-syntax"])
def test_cli_bad_scene_exit_1(run, tmp_path, text, needle):
    res = run("simulate", _write_scene(tmp_path, text))
    assert res.exit_code == 1
    (line,) = res.stderr.strip().splitlines()
    assert needle in line and "scene.yaml" in line


def test_cli_divergence_exit_3(run, tmp_path):
    sc = _write_scene(tmp_path, "body: {mass: 1, inertia: [[1,0,0],[0,1,0],[0,0,1]]}\n"
                                "initial: {position: [0.001, 0, 0]}\n"
                                "forces: [{type: spring, anchor: [0,0,0], stiffness: 1.0e8}]\n"
                                "time: {duration: 0.1, integrator: rk4, step: 1.0e-3}\n")
    res = run("simulate", sc)
    assert res.exit_code == 3
    assert "diverged" in res.stderr and "Traceback" not in res.stderr


def test_cli_unknown_integrator_exit_2(run, tmp_path):
    sc = _write_scene(tmp_path, "body: {mass: 1, inertia: [[1,0,0],[0,1,0],[0,0,1]]}\n"
                                "time: {duration: 1}\n")
    assert run("simulate", "--integrator", "euler", sc).exit_code == 2


def test_ctrl_c_keeps_what_was_computed():
    calls = []

    def interrupt_on_third(fraction):
        calls.append(fraction)
        if len(calls) == 3:
            raise KeyboardInterrupt

    ini = InitialState(angular_velocity=np.array([0.3, 1.0, 0.2]))
    sc = scene(body=ASYM, forces=[Torque(np.array([0.0, 0.1, 0.0]), "body")], duration=10.0,
               integrator="rk4", step=1e-5, initial=ini)
    res = simulate(sc, every=0.01, progress=interrupt_on_third)
    tr = res.trajectory
    assert res.interrupted and 0 < tr.t[-1] < 10.0
    assert np.all(np.isfinite(tr.position)) and np.all(np.isfinite(tr.orientation))
    assert np.all(np.diff(tr.t) > 0) and res.diagnostics["error_estimate"] is None


def test_cli_interrupted_run_writes_and_exits_130(run, tmp_path, monkeypatch):
    import massprops.dynamics.simulate as sim

    real = sim.simulate

    def interrupted(scene, **kw):
        kw["progress"] = _raise_at_second_call()
        return real(scene, **kw)

    monkeypatch.setattr(sim, "simulate", interrupted)
    sc = _write_scene(tmp_path, "body: {mass: 2, inertia: [[1,0,0],[0,2,0],[0,0,3]]}\n"
                                "initial: {angular_velocity: [0.3, 1.0, 0.2]}\n"
                                "forces: [{type: torque, vector: [0, 0.1, 0]}]\n"
                                "time: {duration: 10.0, integrator: rk4, step: 1.0e-5}\n"
                                "output: {every: 0.01, file: out.npz}\n")
    res = run("simulate", "--json", sc)
    assert res.exit_code == 130 and "interrupted" in res.stderr
    with np.load(tmp_path / "out.npz") as data:
        assert 0 < data["t"][-1] < 10.0 and np.all(np.isfinite(data["orientation"]))


def _raise_at_second_call():
    count = [0]

    def progress(fraction):
        count[0] += 1
        if count[0] == 2:
            raise KeyboardInterrupt

    return progress


def test_nan_divergence_names_time_and_stiff_rate():
    # k = 1e10 on 1 kg: rate 1e5/s, rk4's limit 2.8e-5 s; h = 1e-3 overflows to NaN in a few steps
    unit = RigidBody.from_inertia(1.0, np.eye(3))
    sc = scene(body=unit, forces=[Spring(np.zeros(3), 1e10)], duration=1.0, integrator="rk4",
               step=1e-3, initial=InitialState(position=np.array([1e-3, 0, 0])))
    with pytest.raises(DivergenceError) as info:
        simulate(sc)
    message = str(info.value)
    assert "diverged" in message and "t = " in message
    assert "1e+05" in message and "implicit" in message
    partial = info.value.partial
    assert partial is not None and np.all(np.isfinite(partial.trajectory.position))


def test_cache_folders_unused_for_a_month_are_pruned(tmp_path):
    """Every edit or upgrade keys a new numba cache folder (~8 MB): a new one removes the
    others not used for UNUSED_CACHE_DAYS, and never the one in use or a recent one."""
    import os
    import time

    import massprops.dynamics.compiled.cache as dyn

    old = time.time() - (dyn.UNUSED_CACHE_DAYS + 1) * 86400
    for name in ("numba-stale", "numba-recent", "numba-current", "unrelated"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "index.nbi").write_bytes(b"x")
    for name in ("numba-stale", "numba-current", "unrelated"):
        os.utime(tmp_path / name, (old, old))
    dyn._prune_unused(tmp_path, keep=tmp_path / "numba-current")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["numba-current", "numba-recent",
                                                          "unrelated"]


# --- issue 30: absurd settings get the right advice; what a run ignores is said ----------------
SAMPLE_SCENES = Path(__file__).resolve().parent.parent / "sample_scenes"


def _error_line(res) -> str:
    """The one error line of a failed command (a first run's compile notice aside)."""
    (line,) = [ln for ln in res.stderr.strip().splitlines() if "compiling" not in ln]
    return line


def test_one_run_bound_for_one_body_and_systems():
    """budget.MAX_STEPS (2e7, what --max-steps says) is the bound of every run: systems kept a
    bound of their own (2e6), which stopped a one-body rk4 run at a tenth of it."""
    import inspect

    from massprops.dynamics import budget, precision
    from massprops.dynamics.systems import integrate

    assert budget.MAX_STEPS == 20_000_000
    assert inspect.signature(integrate.integrate).parameters["max_steps"].default \
        == budget.MAX_STEPS
    for module in (integrate, precision):
        assert getattr(module, "MAX_STEPS", budget.MAX_STEPS) is budget.MAX_STEPS


def test_a_fixed_step_system_run_beyond_the_bound_is_refused_up_front(run):
    """2.5e7 steps of rk4: refused before it runs, saying the bound and the step that fits
    (a system's run went on until its own bound of 2e6 steps, then stopped)."""
    res = run("simulate", SAMPLE_SCENES / "double_pendulum.yaml", "--integrator", "rk4",
              "--step", "4e-7")
    assert res.exit_code == 3, res.stderr
    line = _error_line(res)
    assert "2.5e+07 steps" in line and "2e+07" in line and "at least 5e-07 s" in line


@pytest.mark.parametrize("duration", ["1e8", "1e12"])
def test_a_duration_beyond_what_float64_resolves_is_said_not_called_stiff(run, duration):
    """The double pendulum (fastest rate ~6/s) over 1e8 s and 1e12 s: dop853's step fell below
    1e-14 of the run at t = 0, which said 'too stiff ... run the implicit method' (and the
    implicit method then failed too): the system is not stiff; the duration is the problem."""
    res = run("simulate", SAMPLE_SCENES / "double_pendulum.yaml", "--duration", duration)
    assert res.exit_code == 3, res.stderr
    line = _error_line(res)
    assert "not stiff" in line and "--duration" in line and "t·eps" in line
    assert "implicit" not in line and "too stiff" not in line


def test_an_implicit_run_whose_resolving_step_cannot_fit_says_so(run):
    res = run("simulate", SAMPLE_SCENES / "double_pendulum.yaml", "--duration", "1e8",
              "--integrator", "implicit")
    assert res.exit_code == 3, res.stderr
    line = _error_line(res)
    assert "Newton" in line and "--duration" in line and "2e+07 steps" in line


@pytest.mark.parametrize("scene_file", ["double_pendulum.yaml", "dzhanibekov.yaml"])
def test_cli_an_rtol_below_what_float64_gives_is_a_usage_error(run, scene_file):
    res = run("simulate", SAMPLE_SCENES / scene_file, "--rtol", "1e-30",
              "--integrator", "dop853")
    assert res.exit_code == 2, res.stderr
    line = _error_line(res)
    assert "--rtol 1e-30" in line and "smallest accepted is 1e-15" in line


@pytest.mark.parametrize("options, said", [
    (("--integrator", "dop853", "--step", "0.001"), "--step 0.001 ignored: dop853 is an adaptive"),
    (("--integrator", "rk4", "--step", "0.01", "--rtol", "1e-6"), "--rtol 1e-06 ignored: rk4"),
    (("--integrator", "exact", "--step", "0.01"), "--step 0.01 ignored: exact is a closed form"),
], ids=["step-with-dop853", "rtol-with-rk4", "step-with-exact"])
def test_cli_a_setting_the_method_does_not_read_is_said(run, tmp_path, options, said):
    sc = _write_scene(tmp_path, "body: {mass: 2, inertia: [[1,0,0],[0,2,0],[0,0,3]]}\n"
                                "initial: {angular_velocity: [0.3, 1.0, 0.2]}\n"
                                "time: {duration: 0.5}\n")
    res = run("simulate", sc, *options)
    assert res.exit_code == 0, res.stderr
    assert f"massprops: warning: {sc}: {said}" in res.stderr


def test_cli_a_system_run_says_what_it_ignores(run):
    res = run("simulate", SAMPLE_SCENES / "double_pendulum.yaml", "--duration", "0.2",
              "--step", "0.001")
    assert res.exit_code == 0, res.stderr
    assert "--step 0.001 ignored: dop853 is an adaptive method" in res.stderr


def test_cli_an_unnormalised_quaternion_is_said(run, tmp_path):
    sc = _write_scene(tmp_path, "body: {mass: 2, inertia: [[1,0,0],[0,2,0],[0,0,3]]}\n"
                                "initial: {orientation: [2, 0, 0, 0]}\n"
                                "time: {duration: 0.5}\n")
    res = run("simulate", sc)
    assert res.exit_code == 0, res.stderr
    assert f"massprops: warning: {sc}:2: initial.orientation: normalised to [1, 0, 0, 0]" \
        in res.stderr


def test_cli_an_interrupted_system_run_is_not_estimated(run, tmp_path, monkeypatch):
    """Ctrl-C on a system: the summary said 'error estimate None'; the JSON keeps null with
    "interrupted": true."""
    from massprops.dynamics.systems import integrate
    from massprops.dynamics.systems import run as system_run

    real = system_run.simulate_system

    def interrupted(scene, **kw):
        return real(scene, **{**kw, "progress": _raise_at_second_call()})

    monkeypatch.setattr(integrate, "CALL_STEPS", 10)
    monkeypatch.setattr(system_run, "simulate_system", interrupted)
    res = run("simulate", SAMPLE_SCENES / "four_bar.yaml")
    assert res.exit_code == 130
    assert "error estimate not estimated (interrupted)" in res.stdout and "None" not in res.stdout
    res = run("simulate", "--json", SAMPLE_SCENES / "four_bar.yaml")
    (out,) = json_lines(res.stdout)
    assert out["interrupted"] is True and out["diagnostics"]["error_estimate"] is None


@pytest.mark.parametrize("sample", ["disk.yaml", "double_pendulum.yaml"],
                         ids=["one body", "system"])
def test_a_written_run_without_an_interval_is_sampled_a_thousand_times(run, tmp_path, sample):
    """No output.every and no --every, one body or a system alike: a written trajectory has
    the run's 1000 equal intervals (`budget.sampling_interval`), t = k × duration / 1000."""
    scene = Path(__file__).resolve().parent.parent / "sample_scenes" / sample
    text = "\n".join(line for line in scene.read_text().splitlines()
                     if not line.strip().startswith("every:"))
    path = tmp_path / sample
    path.write_text(text.replace("duration: 10.0", "duration: 0.5") + "\n")
    res = run("simulate", path, "--output", tmp_path / "traj.csv", "--integrator", "rk4",
              "--step", "1e-3", "-q")
    assert res.exit_code == 0, res.stderr
    t = np.loadtxt(tmp_path / "traj.csv", delimiter=",", skiprows=1)[:, 0]
    np.testing.assert_allclose(t, 0.5 * np.arange(1001) / 1000, rtol=0, atol=1e-15)
