"""The error-estimate companion runs on a helper thread beside the main run: the same numbers as
running the two one after the other, and clean ends (Ctrl-C during either run, a diverging main
run) with no thread left behind. Also `CancellableJob` itself. The one-body kernels' companions
serve the splitting methods (the time-stepping ones run as a system of one body, whose
companions `tests/test_systems_methods.py` tests)."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from massprops.dynamics import budget
from massprops.dynamics import simulate as sim
from massprops.dynamics.accuracy import companion_settings
from massprops.dynamics.integrators import INTEGRATORS
from massprops.dynamics.model import (
    Drag,
    InitialState,
    OutputSettings,
    RigidBody,
    Scene,
    Spring,
    TimeSettings,
    Torque,
)
from massprops.dynamics.program import compile_forces
from massprops.errors import DivergenceError
from massprops.parallel import CancellableJob

ASYM = RigidBody.from_inertia(2.0, np.diag([1.0, 2.0, 3.0]))
SPIN = InitialState(angular_velocity=np.array([0.3, 1.0, 0.2]))
# a torque window (three segments), a damped spring and drag: every code path of the walker
TORQUED = (Torque(np.array([0.0, 0.1, 0.05]), "body", start=0.3, end=0.9),
           Spring(np.array([0.0, 0.0, 1.0]), 5.0, damping=0.2), Drag(0.1, 0.05))


def scene(forces=TORQUED, duration=1.5, integrator="dop853", **time) -> Scene:
    return Scene(body=ASYM, initial=SPIN, forces=tuple(forces),
                 time=TimeSettings(duration=duration, integrator=integrator, **time),
                 output=OutputSettings())


def helpers_alive() -> int:
    return threading.active_count()


# --- same numbers as one run after the other ---------------------------------------------------
@pytest.mark.parametrize("name, settings", [
    ("splitting", {"step": 2e-3}), ("splitting4", {"step": 5e-3}),
], ids=["splitting", "splitting4"])
def test_concurrent_companion_gives_the_sequential_numbers(name, settings):
    sc = scene(integrator=name, **settings)
    result = sim.simulate(sc)
    # the same two runs, one after the other, on this thread
    program = compile_forces(sc)
    spec = INTEGRATORS[name]
    setting = settings.get("rtol", settings.get("step"))
    t_out = budget.sample_times(sc.time.duration, None)
    main = sim.run_once(sc, program, spec, setting, t_out)
    others = [sim.run_once(sc, program, spec, s, t_out)
              for s in companion_settings(spec.kind, setting)]
    traj = sim.to_world(sc, main.t, main.y, program, with_energy=True)
    expected = sim._error_estimate(sc, program, spec, setting, traj, others, main.short_err,
                                   int(main.stats[0]))
    assert result.diagnostics["error_estimate"] == expected  # bit for bit
    assert np.array_equal(result.trajectory.orientation, traj.orientation)
    assert np.array_equal(result.trajectory.position, traj.position)
    assert result.evaluations == int(main.stats[1])


# --- clean ends ---------------------------------------------------------------------------------
def test_ctrl_c_in_the_main_run_stops_the_companion_too():
    before = helpers_alive()
    calls = []

    def interrupt_on_second(fraction):
        calls.append(fraction)
        if len(calls) == 2:
            raise KeyboardInterrupt

    res = sim.simulate(scene(integrator="rk4", step=1e-5, duration=3.0),
                       progress=interrupt_on_second)
    assert res.interrupted and res.diagnostics["error_estimate"] is None
    assert 0 < res.trajectory.t[-1] < 3.0
    assert helpers_alive() == before


def test_ctrl_c_while_waiting_for_the_companion_keeps_the_result(monkeypatch):
    """Ctrl-C after the main run finished, while the companion still runs: the result stands
    without an estimate (as when the companion ran after the main run and was interrupted)."""
    real = sim.run_once
    main_done, pressed = threading.Event(), threading.Event()

    def run_once(scene, program, spec, setting, t_out, progress=None, max_steps=None):
        if setting != 5e-3:  # a companion: hold it until Ctrl-C was pressed while waiting
            main_done.wait(30)  # bounded: a broken hand-off fails the test, never hangs it
            pressed.wait(30)
            return real(scene, program, spec, setting, t_out, progress, max_steps)
        out = real(scene, program, spec, setting, t_out, progress, max_steps)
        main_done.set()
        return out

    def progress(fraction):
        if main_done.is_set():  # called while waiting for the companion
            pressed.set()
            raise KeyboardInterrupt

    monkeypatch.setattr(sim, "run_once", run_once)
    before = helpers_alive()
    res = sim.simulate(scene(integrator="splitting", step=5e-3), progress=progress)
    assert pressed.is_set() and not res.interrupted
    assert res.diagnostics["error_estimate"] is None
    assert res.trajectory.t[-1] == 1.5 and np.all(np.isfinite(res.trajectory.position))
    assert helpers_alive() == before


def test_ctrl_c_while_the_kernel_loads_does_not_wait_for_the_companion(monkeypatch):
    """Ctrl-C before the main run's chunks (numba compiling: seconds) ends simulate at once; the
    companion, busy compiling too, is only told to stop."""
    release, finished = threading.Event(), threading.Event()

    def run_once(scene, program, spec, setting, t_out, progress=None, max_steps=None):
        if setting == 5e-3:  # the main run, interrupted in its warm-up
            raise KeyboardInterrupt
        release.wait(30)  # the companion, still compiling
        finished.set()
        return sim.RawRun(t_out[:1], np.zeros((1, 13)), np.zeros(5, np.int64), 0.0, 0.0, None,
                          True)

    monkeypatch.setattr(sim, "run_once", run_once)
    before = helpers_alive()
    with pytest.raises(KeyboardInterrupt):
        sim.simulate(scene(integrator="splitting", step=5e-3))
    assert not finished.is_set()  # simulate did not wait for it
    release.set()
    finished.wait(30)
    while helpers_alive() > before:  # the helper ends right after
        threading.Event().wait(0.01)


def test_divergence_is_raised_and_the_companion_stopped():
    # k = 1e10 on 1 kg: rate 1e5/s, far beyond rk4's limit at h = 1e-3 (NaN within a few steps)
    unit = RigidBody.from_inertia(1.0, np.eye(3))
    sc = Scene(body=unit, initial=InitialState(position=np.array([1e-3, 0.0, 0.0])),
               forces=(Spring(np.zeros(3), 1e10),),
               time=TimeSettings(duration=1.0, integrator="rk4", step=1e-3),
               output=OutputSettings())
    before = helpers_alive()
    with pytest.raises(DivergenceError) as info:
        sim.simulate(sc)
    assert info.value.partial is not None
    assert helpers_alive() == before


@pytest.mark.slow
def test_progress_is_monotonic_and_ends_at_one():
    seen = []
    sim.simulate(scene(integrator="rk4", step=1e-5, duration=3.0), progress=seen.append)
    assert seen and all(0.0 <= f <= 1.0 for f in seen)
    assert all(b >= a for a, b in zip(seen, seen[1:]))


# --- CancellableJob -----------------------------------------------------------------------------
def test_job_returns_its_result_and_reports_progress():
    job = CancellableJob(lambda report: (report(0.25), "done")[1])
    assert job.result() == "done" and job.fraction == 0.25


def test_job_reraises_its_exception_in_the_waiting_thread():
    def fail(report):
        raise ValueError("inside")

    with pytest.raises(ValueError, match="inside"):
        CancellableJob(fail).result()


def test_cancel_stops_the_job_at_its_next_report():
    cancelled = threading.Event()

    def chunks(report):
        for k in range(100):
            try:
                report(k / 100)
            except KeyboardInterrupt:
                return k
            cancelled.wait(30)  # hold after each chunk until the test has cancelled
        return None

    job = CancellableJob(chunks)
    job.cancel()
    cancelled.set()
    assert job.result() in (0, 1)  # stopped at the report before or after cancel() came


def test_stop_drops_the_jobs_exception_and_waits_for_its_thread():
    before = helpers_alive()

    def fail(report):
        raise ValueError("nobody asked")

    job = CancellableJob(fail)
    job.stop()  # no exception here
    assert helpers_alive() == before


def test_result_polls_while_waiting():
    release, polls = threading.Event(), []

    def wait_for_release(report):
        release.wait(30)
        return 7

    job = CancellableJob(wait_for_release)

    def poll():
        polls.append(1)
        release.set()

    assert job.result(poll, every=0.01) == 7 and polls
