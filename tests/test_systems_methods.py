"""The registry's fixed-step methods on systems (rk4, midpoint, implicit): their orders of
convergence against a DOP853 reference, the loop kept closed (Freudenstein's equation to
round-off), honest error estimates, a stiff joint spring, and the refusals."""

from __future__ import annotations

import math
import threading
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.systems.outputs import distance
from massprops.dynamics.systems.run import simulate_system
from massprops.dynamics.systems.scene import load_system, parse_system, with_time
from massprops.errors import ComputationError, UsageError

SAMPLES = Path(__file__).resolve().parent.parent / "sample_scenes"
ORDERS = {"rk4": 4, "midpoint": 2, "implicit": 5}


def _scene(name: str, duration: float):
    return with_time(load_system(SAMPLES / f"{name}.yaml"), duration=duration)


def _reference(scene):
    return simulate_system(scene, rtol=1e-13, every=scene.time.duration / 10, estimate=False)


@pytest.fixture(scope="module")
def pendulum():
    scene = _scene("double_pendulum", 2.0)
    return scene, _reference(scene)


@pytest.fixture(scope="module")
def four_bar():
    scene = _scene("four_bar", 2.0)
    return scene, _reference(scene)


@pytest.mark.parametrize("method, h", [("rk4", 0.01), ("midpoint", 0.005), ("implicit", 0.02)])
def test_orders(pendulum, method, h):
    """Halving the step divides the error by 2^order (observed order within 0.5 of it)."""
    scene, ref = pendulum
    errors = []
    for step in (h, h / 2):
        run = simulate_system(scene, integrator=method, step=step, every=0.2, estimate=False)
        errors.append(distance(run.samples, ref.samples, scene.size))
    order = math.log2(errors[0] / errors[1])
    assert abs(order - ORDERS[method]) < 0.5, (errors, order)


def _freudenstein(run) -> float:
    """max |K1 cos φ − K2 cos θ + K3 − cos(θ − φ)| over the samples (the sample's header: crank
    a = 1, coupler b = 3, rocker c = 2.5, ground d = 3; θ, φ from the ground line)."""
    a, b, c, d = 1.0, 3.0, 2.5, 3.0
    k1, k2, k3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    crank = run.samples.position[:, 0]  # the crank's centre: (a/2)(cos θ, 0, sin θ)
    rocker = run.samples.position[:, 2]  # the rocker's: D + (c/2)(cos φ, 0, sin φ)
    theta = np.arctan2(crank[:, 2], crank[:, 0])
    phi = np.arctan2(rocker[:, 2], rocker[:, 0] - d)
    return float(np.abs(k1 * np.cos(phi) - k2 * np.cos(theta) + k3 - np.cos(theta - phi)).max())


@pytest.mark.parametrize("method, h", [("rk4", 0.01), ("midpoint", 0.01), ("implicit", 0.02)])
def test_fixed_steps_keep_the_loop_closed(four_bar, method, h):
    """Every step is projected onto the joints: the four-bar's position equation holds to
    round-off whatever the step's truncation error, and the error estimate bounds the error."""
    scene, ref = four_bar
    run = simulate_system(scene, integrator=method, step=h, every=0.2)
    assert run.diagnostics["constraint_residual"]["position"] < 1e-13 * scene.size
    assert _freudenstein(run) < 1e-12
    error = distance(run.samples, ref.samples, scene.size)
    estimate = run.diagnostics["error_estimate"]
    assert error > 1e3 * _freudenstein(run)  # the check above is not the truncation error
    assert estimate / 10 <= error <= 10 * estimate, (error, estimate)


@pytest.mark.parametrize("method, h", [("rk4", 0.02), ("rk4", 0.005), ("implicit", 0.05),
                                       ("implicit", 0.01), ("midpoint", 0.01)])
def test_error_estimates_within_ten_times(pendulum, method, h):
    """Issue 17 §3: the true error within 10x of the estimate (Richardson over 2h and 4h)."""
    scene, ref = pendulum
    run = simulate_system(scene, integrator=method, step=h, every=0.2)
    error = distance(run.samples, ref.samples, scene.size)
    estimate = run.diagnostics["error_estimate"]
    assert estimate / 10 <= error <= 10 * estimate, (error, estimate)


STIFF = (SAMPLES / "double_pendulum.yaml").read_text().replace(
    "axis: [0, 1, 0]}\ninitial", "axis: [0, 1, 0], stiffness: 1.0e6, damping: 200.0, "
    "rest: -0.5235987755982988}\ninitial")


def test_stiff_spring_implicit_steps_over_it():
    """A stiff elbow spring at rest at the start angle (k = 1e6 N·m/rad on ~0.33 kg·m²: ~1700
    rad/s, damped within ~10 ms): the pendulum swings nearly as one rigid body. Radau IIA at
    h = 5 ms (hλ ≈ 9) follows that slow swing, which DOP853 resolves step by step, with a
    fifth of the evaluations; RK4 at the same step diverges and says so."""
    scene = parse_system(STIFF.replace("duration: 10.0", "duration: 0.5"),
                         source="stiff.yaml", base_dir=SAMPLES)
    assert "stiffness: 1.0e6" in STIFF
    ref = simulate_system(scene, rtol=1e-11, every=0.05, estimate=False)
    run = simulate_system(scene, integrator="implicit", step=0.005, every=0.05, estimate=False)
    shoulder = [s[:, 0] for s in (ref.samples.coordinates[0], run.samples.coordinates[0])]
    assert np.abs(shoulder[0] - shoulder[1]).max() < 1e-9  # measured: 6e-11 rad
    assert run.evaluations < ref.evaluations / 5
    with pytest.raises(ComputationError, match="diverged.*step"):
        simulate_system(scene, integrator="rk4", step=0.005, estimate=False)


@pytest.mark.parametrize("name", ["splitting", "splitting4", "exact"])
def test_one_body_methods_refused(pendulum, name):
    scene, _ = pendulum
    with pytest.raises(UsageError, match="one body"):
        simulate_system(scene, integrator=name)


def test_a_one_body_method_in_a_system_scene_is_the_scene_s_mistake(tmp_path, run):
    """time.integrator naming a one-body method in a system scene: exit 1 at its line (the
    file is wrong); --integrator naming one: exit 2 (the command line is)."""
    path = tmp_path / "dp.yaml"
    path.write_text((SAMPLES / "double_pendulum.yaml").read_text().replace(
        "time: {duration: 10.0}", "time: {duration: 10.0, integrator: splitting6}"))
    in_scene = run("simulate", path)
    assert in_scene.exit_code == 1
    line = next(n for n, text in enumerate(path.read_text().splitlines(), 1)
                if text.startswith("time:"))
    assert in_scene.stderr.strip() == (
        f"massprops: error: {path}:{line}: time.integrator: splitting6 steps one body's state "
        "only; a system runs with auto, dop853, rk4, midpoint, implicit")
    on_line = run("simulate", SAMPLES / "double_pendulum.yaml", "--integrator", "splitting6")
    assert on_line.exit_code == 2 and "one body's state only" in on_line.stderr


def test_cli_fixed_step(tmp_path, run):
    """--integrator rk4 --step on a system: the JSON names the method and its reason."""
    import json

    path = tmp_path / "dp.yaml"
    path.write_text((SAMPLES / "double_pendulum.yaml").read_text().replace("duration: 10.0",
                                                                         "duration: 0.5"))
    result = run("simulate", path, "--integrator", "rk4", "--step", "0.01", "--json")
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["integrator"] == "rk4" and "fixed step" in data["reason"]
    assert data["steps"] == 50 and data["diagnostics"]["error_estimate"] > 0
    refused = run("simulate", path, "--integrator", "splitting")
    assert refused.exit_code == 2 and len(refused.stderr.strip().splitlines()) == 1


def _welded(text: str) -> str:
    """``text`` (the stiff double pendulum) with its elbow welded at the start angle: both rods
    placed bent in the assembly (the lower one turned by shoulder + elbow about y), the elbow a
    fixed joint, the shoulder at 0 there."""
    t1, t2 = 1.0471975511965976, -0.5235987755982988
    s1, c1, s12, c12 = math.sin(t1), math.cos(t1), math.sin(t1 + t2), math.cos(t1 + t2)
    elbow = (-s1, 0.0, -c1)
    lower = (elbow[0] - 0.5 * s12, 0.0, elbow[2] - 0.5 * c12)
    q1 = (math.cos(t1 / 2), 0.0, math.sin(t1 / 2), 0.0)
    q12 = (math.cos((t1 + t2) / 2), 0.0, math.sin((t1 + t2) / 2), 0.0)
    lines = []
    for line in text.splitlines():
        if line.startswith("  upper:"):
            line = line.replace("position: [0.0, 0.0, -0.5]",
                                f"position: [{-0.5 * s1!r}, 0.0, {-0.5 * c1!r}], "
                                f"orientation: {list(q1)}")
        elif line.startswith("  lower:"):
            line = line.replace("position: [0.0, 0.0, -1.5]",
                                f"position: {list(lower)}, orientation: {list(q12)}")
        elif "name: elbow" in line:
            line = f"  - {{name: elbow, type: fixed, bodies: [upper, lower], point: {list(elbow)}}}"
        elif line.startswith("  positions:"):
            continue
        lines.append(line)
    return "\n".join(lines) + "\n"


def test_auto_picks_implicit_for_a_stiff_system():
    """k = 1e14 N·m/rad at the elbow (fastest rate ~2e7/s: ~7e6 explicit steps over 1 s): auto
    runs Radau IIA, which steps over the stiff mode and moves as the pendulum whose elbow is
    welded (a fixed joint, run by DOP853): the elbow yields ~1e-13 rad under ~10 N·m."""
    text = STIFF.replace("stiffness: 1.0e6, damping: 200.0", "stiffness: 1.0e14, damping: 1e4")
    text = text.replace("duration: 10.0", "duration: 1.0")
    stiff = parse_system(text, source="stiff.yaml", base_dir=SAMPLES)
    run = simulate_system(stiff, every=0.1, estimate=False)
    assert run.as_dict()["integrator"] == "implicit" and "stiff" in run.as_dict()["reason"]
    rigid = simulate_system(parse_system(_welded(text), source="welded.yaml", base_dir=SAMPLES),
                            rtol=1e-12, every=0.1, estimate=False)
    assert rigid.as_dict()["integrator"] == "dop853"
    gap = np.abs(run.samples.position - rigid.samples.position).max()
    assert gap < 1e-10, gap  # measured: 4e-13 m


def test_a_coarse_step_that_jumps_a_loop_says_so(four_bar):
    """RK4 at 0.5 s moves the crank ~1 rad a step: one step lands the loop beyond a dead point
    that the crank-rocker never reaches (Grashof: its crank turns all the way round). A fine run
    of that stretch passes, so the step is blamed, not the mechanism."""
    scene, _ = four_bar
    with pytest.raises(ComputationError, match="jumped the loop.*step") as info:
        simulate_system(scene, integrator="rk4", step=0.5, estimate=False)
    assert "\n" not in str(info.value)


def test_an_unresolved_fast_mode_is_in_the_estimate():
    """An undamped k = 1e8 N·m/rad elbow (ρ ~ 1.7e4/s) under Radau at h = 1 ms: the elbow's
    small fast swing is damped out by the run and by both companions alike, which alone put the
    error at 1e-11 while it is 1.9e-4; the probe against a resolving run (systems.stiffness)
    brings the estimate up to the error."""
    text = STIFF.replace("stiffness: 1.0e6, damping: 200.0", "stiffness: 1.0e8, damping: 0.0")
    scene = parse_system(text.replace("duration: 10.0", "duration: 1.0"), source="s.yaml",
                         base_dir=SAMPLES)
    ref = simulate_system(scene, rtol=1e-12, every=0.01, estimate=False)
    run = simulate_system(scene, integrator="implicit", step=0.001, every=0.01)
    error, estimate = distance(run.samples, ref.samples, scene.size), \
        run.diagnostics["error_estimate"]
    assert error > 1e-5 and estimate / 10 <= error <= 10 * estimate, (error, estimate)


def test_orders_hold_across_a_load_window():
    """The slider-crank's drive torque ends at t = 1 s, a segment edge. Loads are judged at each
    segment's middle, so the Radau stage on the edge sees the drive that acts over the whole
    step: the run converges at order 5 (it fell to order 1, 8e-3 wrong at h = 4 ms, when that
    stage saw the drive already off)."""
    scene = load_system(SAMPLES / "slider_crank.yaml")
    assert any(math.isfinite(j.end) and j.drive for j in scene.joints)
    ref = simulate_system(scene, rtol=1e-13, every=0.2, estimate=False)
    errors = [distance(simulate_system(scene, integrator="implicit", step=h, every=0.2,
                                       estimate=False).samples, ref.samples, scene.size)
              for h in (0.002, 0.001)]
    assert math.log2(errors[0] / errors[1]) > 4.5, errors


def test_cli_precision_on_a_robot_description(run):
    """`precision ROBOT.urdf` runs the description as `simulate ROBOT` does (1 s from the zero
    pose); it was read as a YAML scene and refused with the file's whole text."""
    import json

    result = run("precision", SAMPLES / "robot_arm.urdf", "--integrator", "dop853", "--json")
    assert result.exit_code == 0, result.stderr
    runs = json.loads(result.stdout)["runs"]
    assert {r["integrator"] for r in runs} == {"dop853"} and len(runs) >= 4
    assert runs[-1]["error"] < 1e-3 * runs[0]["error"]  # the ladder converges


def _rod(mass: float, moment: float, z: float, load: str, duration: float,
         gravity: bool = True) -> str:
    """A rod on a hinge about y at the origin, its centre at (0, 0, z), starting at 1 rad/s."""
    return (f"bodies:\n  rod: {{mass: {mass}, inertia: [[{moment}, 0, 0], [0, {moment}, 0], "
            f"[0, 0, {moment / 100}]], position: [0, 0, {z}]}}\njoints:\n  - {{name: A, type: "
            f"revolute, bodies: [world, rod], point: [0, 0, 0], axis: [0, 1, 0], {load}}}\n"
            "initial: {rates: {A: 1.0}}\n"
            + ("forces: [{type: gravity, g: [0, 0, -9.81]}]\n" if gravity else "")
            + f"time: {{duration: {duration}}}\n")


@pytest.mark.parametrize("z, gravity", [(-0.5, False), (-0.1, True)])
def test_a_diverged_run_is_not_a_result(z, gravity):
    """RK4 at h ρ ~ 2000 on a stiff hinge (found by benchmarks/fuzz_systems.py): its angles grew
    to 4e34 rad and the run was reported as a result (the first case), or it ended saying the
    mass matrix was not positive definite. Now either is a one-line divergence that says what
    to do: the energy of a system that cannot gain any grew, or the state went wild."""
    scene = parse_system(_rod(1e-3, 1e-4, z, "stiffness: 1.0e9", 1.0, gravity),
                         source="rod.yaml", base_dir=SAMPLES)
    with pytest.raises(ComputationError, match="rk4 run diverged.*implicit") as info:
        simulate_system(scene, integrator="rk4", step=1e-3, estimate=False)
    assert "\n" not in str(info.value)


def test_an_unmeasurable_fast_mode_leaves_no_estimate():
    """A hinge damper at c / I ~ 1e11/s under Radau at 1 ms (fuzz_systems): the probe's
    resolving run cannot be made within its bound, so the estimate is unknown (None), not inf
    (which the JSON writer refused: an internal error)."""
    import json

    scene = parse_system(_rod(1.0, 1e-3, -0.1, "damping: 1.0e9", 1.0), source="rod.yaml",
                         base_dir=SAMPLES)
    run = simulate_system(scene, integrator="implicit", step=1e-3)
    assert run.diagnostics["error_estimate"] is None
    json.dumps(run.as_dict(), allow_nan=False)


@pytest.mark.slow  # ~7 s: the stiff reference and the bounded dop853 rung
def test_precision_on_a_stiff_system_ends():
    """A damper with a ~1e-13 s time constant over 2 ms (fuzz_systems): precision ran for
    hours; now its reference is Radau at a fine step (as for one body) and a rung that hits the
    run bound ends its ladder."""
    from massprops.dynamics.systems.precision import precision_system

    scene = parse_system(_rod(1e-6, 1e-12, -0.001, "damping: 0.1", 0.002), source="rod.yaml",
                         base_dir=SAMPLES)
    report = precision_system(scene).as_dict()
    assert report["reference"]["integrator"] == "implicit"
    dop853 = [r for r in report["runs"] if r["integrator"] == "dop853"]
    assert len(dop853) == 1 and "run bound" in dop853[0]["reason"]
    assert any(r["integrator"] == "implicit" and r["error"] is not None for r in report["runs"])


def test_precision_refuses_at_once_a_reference_beyond_its_bound(monkeypatch):
    """A reference that would need more than MAX_REFERENCE_STEPS is refused at the pace of
    its first 1/PILOT_SHARE of the duration, not after stepping into the bound (the fuzzer's
    case: 2.5 minutes of stepping, then the same refusal); only the pilot runs."""
    from massprops.dynamics.systems import precision

    scene = parse_system(_rod(1.0, 1e-3, -0.5, "stiffness: 1.0e4", 5.0), source="rod.yaml",
                         base_dir=SAMPLES)
    monkeypatch.setattr(precision, "MAX_REFERENCE_STEPS", 2000)
    calls = []

    def counted(*args, **kwargs):
        calls.append(kwargs["max_steps"])
        return simulate_system(*args, **kwargs)

    monkeypatch.setattr(precision, "simulate_system", counted)
    with pytest.raises(ComputationError, match=r"rod\.yaml: the reference run \(dop853 at "
                       r"rtol 1e-13\) needs more than 2000 steps \(the pace of its first 0\.1 s"):
        precision.precision_system(scene)
    assert calls == [2 * 2000 // precision.PILOT_SHARE]


def test_a_rank_drop_at_a_wild_state_is_divergence(recwarn):
    """The kernel reports a rank drop at a state gone wild (a slider 1e200 m out, fuzzer case):
    the numpy solve that names the joints then fails on the mass matrix itself. That is the
    run going wild, said in one line; it was an internal LinAlgError and numpy's overflow
    warnings on stderr."""
    from massprops.dynamics.compiled.systems_loops import SINGULAR
    from massprops.dynamics.systems.integrate import _failure
    from massprops.dynamics.systems.run import prepare

    system, y0, _ = prepare(load_system(SAMPLES / "slider_crank.yaml"))
    y = y0.copy()
    for j in system.tree.joints:
        if j.kind == "prismatic":
            y[j.iq] = 1e200
    fstats = np.array([0.0, 0.0, 1.0, 0.5, 0.0, 0.0, 1.0])
    failure = _failure(system, SINGULAR, fstats, y, 1000, "dop853")
    assert isinstance(failure, ArithmeticError)
    assert "slider_crank.yaml: the dop853 run went wild (its mass matrix lost positive " \
           "definiteness) at t = 0.5 s" in str(failure)
    assert not recwarn.list


@pytest.mark.parametrize("scene, step", [("double_pendulum.yaml", "0.2"),
                                         ("heavy_top.yaml", "0.05")])
def test_a_run_that_does_not_follow_the_motion_says_so(run, scene, step):
    """A fixed step far too long for the motion (a system and one body): the run is still
    reported (exit 0, its JSON), with one warning that its error estimate, 0.1 or more of the
    size, a radian or the speeds, makes its numbers no results, naming the option to change.
    The fuzzers found such runs reported with estimates of 2.6 to 21 and no word."""
    import json

    result = run("simulate", SAMPLES / scene, "--integrator", "rk4", "--step", step, "--json")
    assert result.exit_code == 0
    estimate = json.loads(result.stdout)["diagnostics"]["error_estimate"]
    assert estimate >= 0.1
    warned = [line for line in result.stderr.splitlines() if "error estimate" in line]
    assert warned == [f"massprops: warning: {SAMPLES / scene}: the rk4 run's error estimate is "
                      f"{estimate:.2g} (a fraction of the size, of a radian, of the speeds): it "
                      "did not follow the motion, its numbers are not to be trusted; shorten "
                      "--step"]


STIFF_UNSEEN = """bodies:
  a: {mass: 1.0, inertia: [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.2]], position: [0, 0, 0]}
  b: {mass: 1.0e-6, inertia: [[1.0e-9, 0, 0], [0, 1.0e-9, 0], [0, 0, 1.0e-9]],
      position: [0.05, 0, 0]}
joints:
  - {name: h, type: revolute, bodies: [a, b], point: [0, 0, 0], axis: [0, 0, 1],
     stiffness: 10.0}
forces:
  - {type: force, body: b, vector: [0, 1.0e-9, 0]}
time: {duration: 0.01}
"""


def test_a_first_step_far_beyond_stability_is_rejected_not_fatal():
    """A floating pair with a 5e4 rad/s hinge mode that nothing excites at the start: DOP853's
    first trial step (Hairer's HINIT sees only the weak force) is ~1e4 times the mode's
    period, its stages fly off until M about the origin is lost to round-off. That is a
    rejected step, as an infinite error is: the run goes on (it used to end "went wild") and
    agrees with a tight run within its error estimate."""
    scene = parse_system(STIFF_UNSEEN, source="stiff.yaml", base_dir=SAMPLES)
    run = simulate_system(scene, estimate=True)
    tight = simulate_system(scene, rtol=1e-12, estimate=False)
    assert run.rejected >= 1
    error = distance(run.samples, tight.samples, scene.size)
    assert error <= max(10 * run.diagnostics["error_estimate"], 1e-12)
    swing = np.abs(tight.samples.coordinates[0][:, 0]).max()
    assert swing > 0  # the hinge is loaded: the pair really moves


@pytest.mark.parametrize("method", ["rk4", "implicit"])
def test_a_fixed_step_run_cut_into_calls_is_the_same_run(four_bar, monkeypatch, method):
    four_bar = four_bar[0]
    """Compiled calls end every CALL_STEPS steps (Ctrl-C and the progress bar are served
    between them); a fixed-step run resumes on its own grid, so cut into calls of 7 steps it
    is the uncut run to round-off (a resumed call evaluates f at its start afresh, where the
    uncut one reused the projection's factors), and the progress it reports rises to 1."""
    from massprops.dynamics.systems import integrate

    whole = simulate_system(four_bar, integrator=method, step=0.01, estimate=False)
    monkeypatch.setattr(integrate, "CALL_STEPS", 7)
    seen: list[float] = []
    cut = simulate_system(four_bar, integrator=method, step=0.01, estimate=False,
                          progress=seen.append)
    assert cut.steps == whole.steps and len(seen) > whole.steps // 7 - 2
    assert np.allclose(cut.samples.coordinates[0], whole.samples.coordinates[0], rtol=0,
                       atol=1e-13)
    scale = np.abs(whole.samples.force).max()
    assert np.abs(cut.samples.force - whole.samples.force).max() < 1e-12 * scale
    assert seen == sorted(seen) and seen[-1] == 1.0


def test_dop853_cut_into_calls_stays_within_its_estimate(pendulum, monkeypatch):
    pendulum = pendulum[0]
    """DOP853 resumed after each call starts with a fresh first step: another step sequence,
    the same solution within the error estimate."""
    from massprops.dynamics.systems import integrate

    whole = simulate_system(pendulum, rtol=1e-8)
    monkeypatch.setattr(integrate, "CALL_STEPS", 5)
    cut = simulate_system(pendulum, rtol=1e-8, estimate=False)
    size = pendulum.size
    assert distance(cut.samples, whole.samples, size) < 2 * whole.diagnostics["error_estimate"]
    assert cut.steps > whole.steps  # each call's first step is small again


def test_ctrl_c_keeps_what_was_computed(four_bar, monkeypatch):
    four_bar = four_bar[0]
    """Ctrl-C between compiled calls ends the run with its samples up to where it got (for a
    caller that asks, as the CLI; else it propagates): the result says interrupted, has no
    error estimate, and its samples are the motion's (the uncut run's, to its error)."""
    from massprops.dynamics.systems import integrate

    monkeypatch.setattr(integrate, "CALL_STEPS", 10)
    calls = []

    def progress(fraction: float) -> None:
        calls.append(fraction)
        if len(calls) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):  # a library caller that keeps nothing partial
        simulate_system(four_bar, rtol=1e-9, every=0.01, progress=progress)
    calls.clear()
    part = simulate_system(four_bar, rtol=1e-9, every=0.01, progress=progress,
                           interruptible=True)
    assert part.interrupted and part.as_dict()["interrupted"] is True
    assert part.diagnostics["error_estimate"] is None
    reached = part.samples.t[-1]
    assert 0 < reached < four_bar.time.duration and np.all(np.diff(part.samples.t) > 0)
    assert np.isfinite(part.samples.position).all()
    whole = simulate_system(four_bar, rtol=1e-9, every=0.01, estimate=False)
    at = np.searchsorted(whole.samples.t, part.samples.t[-2])
    assert np.abs(part.samples.coordinates[0][-2] - whole.samples.coordinates[0][at]).max() < 1e-6


def test_cli_ctrl_c_on_a_system_writes_what_was_computed_and_exits_130(run, tmp_path,
                                                                       monkeypatch):
    from massprops.dynamics.systems import integrate
    from massprops.dynamics.systems import run as system_run

    real, count = system_run.simulate_system, [0]

    def progress(fraction: float) -> None:
        count[0] += 1
        if count[0] == 2:
            raise KeyboardInterrupt

    def interrupted(scene, **kw):
        return real(scene, **{**kw, "progress": progress})

    monkeypatch.setattr(integrate, "CALL_STEPS", 10)
    monkeypatch.setattr(system_run, "simulate_system", interrupted)
    out = tmp_path / "out.csv"
    res = run("simulate", "--json", str(SAMPLES / "four_bar.yaml"), "--rtol", "1e-9",
              "--output", str(out))
    assert res.exit_code == 130 and "interrupted" in res.stderr
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert 0 < data[-1, 0] < 5.0 and np.isfinite(data).all()


def test_cli_a_failed_system_run_writes_what_it_reached(run, tmp_path):
    """A system run stopped by the run bound (exit 3) still writes the samples it reached, as a
    one-body run does; the error carries them (ComputationError.partial)."""
    from massprops.errors import RunBudgetError

    scene = _scene("four_bar", 5.0)
    with pytest.raises(RunBudgetError) as info:
        simulate_system(scene, rtol=1e-10, every=0.01, max_steps=60, estimate=False)
    part = info.value.partial
    assert 0 < part.samples.t[-1] < 5.0 and np.isfinite(part.samples.force).all()
    whole = simulate_system(scene, rtol=1e-10, every=0.01, estimate=False)
    n = len(part.samples.t)
    assert np.abs(part.samples.coordinates[0] - whole.samples.coordinates[0][:n]).max() < 1e-6
    out = tmp_path / "out.csv"
    res = run("simulate", str(SAMPLES / "four_bar.yaml"), "--rtol", "1e-10", "--every", "0.01",
              "--max-steps", "60", "--output", str(out))
    assert res.exit_code == 3 and "max_steps" in res.stderr.replace("-", "_")
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert len(data) == n and np.isfinite(data).all()


@pytest.mark.parametrize("method", ["rk4", "midpoint"])
def test_a_load_window_shorter_than_the_step_is_in_the_estimate(method):
    """A force acting for 0.49 ms (shorter than every step) is stepped alike by the run and its
    2h and 4h companions: Richardson's rule cannot see that step's error. The segment is
    stepped again in halves (`integrate._short_error`) and its difference is in the estimate:
    the true error stays within it (before: rk4 at 5 ms 15 times over, midpoint 12 times)."""
    from massprops.dynamics.scene import load_scene
    from massprops.dynamics.systems.one_body import as_system

    scene = as_system(load_scene(SAMPLES / "short_window.yaml"))
    ref = simulate_system(scene, rtol=1e-13, estimate=False)
    for h in (0.01, 0.005):
        run = simulate_system(scene, integrator=method, step=h)
        error = distance(run.samples, ref.samples, scene.size)
        assert error <= run.diagnostics["error_estimate"], (h, error)


# --- the companions beside the main run ----------------------------------------------------------
class _AfterTheMainRun:
    """Stands for `methods.Companions` and starts the real ones only when the run asks for their
    result, i.e. once the main run is done: the sequential order, the truth the concurrent one
    must give."""

    fraction = 0.0

    def __init__(self, start, args) -> None:
        self._start, self._args, self._real = start, args, None

    def stop(self) -> None:
        if self._real is not None:
            self._real.stop()

    def result(self, steps, poll):
        self._real = self._start(*self._args)
        return self._real.result(steps, poll)


@pytest.mark.parametrize("integrator, step", [("dop853", None), ("rk4", 0.01),
                                              ("implicit", 0.01)])
def test_companions_beside_the_main_run_give_the_sequential_numbers_and_no_thread_stays(
        integrator, step, monkeypatch):
    from massprops.dynamics.systems import run as run_module

    scene = with_time(load_system(SAMPLES / "double_pendulum.yaml"), duration=2.0)
    threads = threading.active_count()
    beside = simulate_system(scene, integrator=integrator, step=step)
    assert threading.active_count() == threads  # the helper thread has ended with the run
    real, made = run_module.start_companions, []
    monkeypatch.setattr(run_module, "start_companions",
                        lambda *args: made.append(_AfterTheMainRun(real, args)) or made[-1])
    after = simulate_system(scene, integrator=integrator, step=step)
    assert threading.active_count() == threads
    assert len(made) == 1 and made[0]._real is not None  # they did run, after the main run
    estimate = beside.diagnostics["error_estimate"]
    assert estimate is not None and estimate == after.diagnostics["error_estimate"]
    assert np.array_equal(beside.samples.position, after.samples.position)
