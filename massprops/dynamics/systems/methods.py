"""Which method a system runs with, its setting, and the run's error estimate.

The methods are the registry's time-stepping ones (`integrators.SYSTEM_METHODS`, `integrate`):
dop853 (adaptive, rtol), rk4, midpoint and implicit (fixed step h). The error estimate is
global, as for one body (`dynamics.accuracy`): companion runs at `accuracy.companion_settings`
(rtol / 20; or 2h and 4h with Richardson's rule, `accuracy.global_estimate`), compared in the
contract's metric over all bodies (`outputs.distance`).
"""

from __future__ import annotations

import math
from typing import cast

import numpy as np

from massprops.dynamics.accuracy import (
    RESOLVES_NOTHING,
    companion_settings,
    global_estimate,
    rotation_floor,
)
from massprops.dynamics.budget import STEP_BUDGET
from massprops.dynamics.budget import default_step as budget_default_step
from massprops.dynamics.integrators import INTEGRATORS, SYSTEM_METHODS
from massprops.dynamics.integrators.base import check_rtol
from massprops.dynamics.systems.integrate import integrate
from massprops.dynamics.systems.model import WORLD
from massprops.dynamics.systems.outputs import Samples, distance, evaluate_states
from massprops.dynamics.systems.stiffness import fastest_rate, unresolved_mode_error
from massprops.dynamics.systems.system import System
from massprops.parallel import CancellableJob

SYSTEM_INTEGRATORS = ("auto", *SYSTEM_METHODS)
"""What a system scene may name: the registry's time-stepping methods (`integrate`); auto picks
one (`choose`). The splitting methods compose one free body's exact rotation and have no system
form; the closed form is one body's."""

REASONS = {"dop853": "adaptive 8th order", "rk4": "fixed step, 4th order",
           "midpoint": "fixed step, implicit midpoint (symplectic)",
           "implicit": "fixed step, Radau IIA (L-stable, for stiff systems)"}
"""The JSON's ``reason`` of each method on a system (every one projects after each step)."""


def choose(system: System, y0: np.ndarray, name: str, rtol: float | None,
           step: float | None) -> tuple[str, float, str]:
    """(method, setting, reason) of a run asked for ``name`` (SYSTEM_INTEGRATORS) with the
    caller's ``rtol`` / ``step`` (None: the scene's). ``auto`` is the one-body rule
    (`dynamics.simulate.choose_integrator`): implicit where an explicit method would need more
    than STEP_BUDGET steps to resolve the fastest rate over the run, else dop853. A system
    without springs or dampers has no such rate and pays nothing to find that out."""

    scene, reason = system.scene, None
    if name == "auto":
        name, reason = "dop853", REASONS["dop853"]
        if _sprung(scene):
            rate = fastest_rate(system, y0)
            explicit = scene.time.duration * rate / 2.8
            if explicit > STEP_BUDGET:
                name, reason = "implicit", (f"stiff: fastest rate {rate:.3g}/s would need "
                                            f"~{explicit:.2g} explicit steps "
                                            f"(> {STEP_BUDGET:.0e})")
    if name == "dop853":
        value = float(rtol if rtol is not None else scene.time.rtol)
        check_rtol(value, scene.source)  # a scene's own is refused at its line already
        return name, value, reason or REASONS[name]
    h = step if step is not None else scene.time.step
    if h is None:
        h = default_step(system, y0, scene.time.duration, stiff=is_stiff(name))
    return name, float(h), reason or REASONS[name]


def kernels(name: str) -> list[str]:
    """The compiled entries (`compiling.SYSTEM_ENTRIES`) a run of ``name`` (SYSTEM_INTEGRATORS)
    uses, to be made ready before it starts: the method's step loop (`auto`: DOP853's, what it
    picks unless the scene is stiff) and the outputs' entry, which also serves the stiffness
    probe (`system.spectral_radius`); and DOP853 where the estimate's unresolved-mode probe
    runs (a stiff method). Only a failure's diagnosis may use more (DOP853 narrowing a singular
    pose): compiled then, on first use."""
    if name == "auto":
        return ["dop853", "outputs"]
    spec = INTEGRATORS[name]
    return [cast(str, spec.kernel), "outputs", *(["dop853"] if spec.stiff else [])]


def kind_of(name: str) -> str:
    """Method ``name``'s kind in the registry (``adaptive``, ``fixed``): which setting it takes."""
    return INTEGRATORS[name].kind


def is_stiff(name: str) -> bool:
    """Method ``name`` is stable far beyond the explicit step limit (the registry's ``stiff``):
    its default step ignores the fast rates."""
    return INTEGRATORS[name].stiff


def _sprung(scene) -> bool:
    """A spring or damper anywhere (between bodies, on a joint, a body's drag): the only stiff
    terms."""
    return bool(scene.springs or scene.drags) or any(j.stiffness or j.damping
                                                      for j in scene.joints)


COMPANION_GROWTH = 3
"""A companion run may take this many times the main run's steps (DOP853's at rtol / 20 takes
~1.45 times, the fixed ones at 2h and 4h fewer): one that needs more has met what the main run
did not resolve, and the estimate is None rather than minutes more of stepping (the fuzzer's
11-link chain: 10 s of main run, then 79 s of a companion running into its bound)."""


class Companions:
    """The error estimate's companion runs (`accuracy.companion_settings`), one after the other
    on a helper thread beside the main run: the compiled calls release the GIL, so on two
    cores the estimate adds little to the main run's wall time. Each run is deterministic in
    its own arrays: the numbers are those of running them after the main run. ``cap`` (set
    once the main run's steps are known) bounds each at COMPANION_GROWTH times as many: one
    that goes beyond stops at its next call (by step counts, so the outcome does not depend on
    the machine)."""

    def __init__(self, system: System, y0: np.ndarray, t_out: np.ndarray, name: str,
                 settings: tuple, floors: np.ndarray, windows: np.ndarray, limit: int) -> None:
        self.cap: int | None = None

        def watch(steps: int) -> None:
            if self.cap is not None and steps > self.cap:
                raise KeyboardInterrupt  # integrate ends the run there (interrupted)

        def runs(report) -> list:
            out = []
            for k, other in enumerate(settings):
                def part(f: float, k: int = k) -> None:
                    report((k + f) / len(settings))

                run = integrate(system, y0, t_out, other, floors, windows, limit, name, part,
                                watch)
                out.append(run)
                if run.interrupted or run.failure is not None:
                    break  # the next could add nothing
            return out

        self.job = CancellableJob(runs)

    @property
    def fraction(self) -> float:
        return self.job.fraction

    def stop(self) -> None:
        self.job.stop()

    def result(self, steps: int, poll) -> list:
        """The runs, each None where it stopped at the cap or failed, once the main run took
        ``steps`` (Ctrl-C while waiting stops them and propagates). A run that already went
        past the cap is judged by it too: the outcome is the one of running them afterwards."""
        self.cap = COMPANION_GROWTH * max(steps, 1000)
        try:
            runs = self.job.result(poll)
        except KeyboardInterrupt:
            self.job.stop()
            raise
        return [None if (r.interrupted or r.failure is not None or r.steps > self.cap) else r
                for r in runs]


def start_companions(system: System, y0: np.ndarray, t_out: np.ndarray, name: str,
                     setting: float, floors: np.ndarray, windows: np.ndarray,
                     limit: int) -> Companions | None:
    """The companion runs of a run of ``name`` at ``setting``, started (None: a method that
    needs none)."""
    settings = companion_settings(INTEGRATORS[name].kind, setting)
    if not settings:
        return None
    return Companions(system, y0, t_out, name, settings, floors, windows, limit)


def error_estimate(system: System, y0: np.ndarray, t_out: np.ndarray, name: str,
                   setting: float, floors: np.ndarray, windows: np.ndarray, samples: Samples,
                   limit: int, steps: int, side: Companions | None = None,
                   progress=None, short_err: float = 0.0) -> float | None:
    """The run's global error estimate from its companion runs (`accuracy.companion_settings`
    and `global_estimate`, in the systems' metric `outputs.distance`), and for a stiff method
    at a step that does not resolve the fastest rate at least
    `stiffness.unresolved_mode_error`; None where the first companion failed. A method whose
    order can fall on stiff modes (``estimate_order``: Radau IIA to its stage order 3) is
    credited its full order where the step resolves the start's fastest rate (h ρ < 1): there
    is no stiff mode to reduce it, and the reduced credit overstated the four-bar's error
    18-fold at h = 20 ms. ``limit``: the probe's run bound; ``steps``: the main run's (its
    companions are bounded at COMPANION_GROWTH times as many); ``side``: the companions
    started beside the main run (`start_companions`; None: started here);
    ``progress(fraction)`` moved meanwhile, from ½ to 1; ``short_err``: the main run's error on
    its segments of one or two steps, which the companions cannot see (`integrate.Run`), added
    in the metric's units as one body's is: its component unknown, divided by the smallest
    scale (an angle's error of a quaternion component δ is about 2δ). Never below what the
    method does to the rotations its steps take (`accuracy.rotation_floor`, `turn_per_step`):
    where those steps resolve nothing, the estimate is RESOLVES_NOTHING whatever the companions
    say (they can agree by chance there) or whether they ran."""
    spec, size = INTEGRATORS[name], system.scene.size
    floor = rotation_floor(spec.tableau, turn_per_step(system, samples, steps), steps)
    if floor >= RESOLVES_NOTHING:
        return floor
    if side is None:
        side = start_companions(system, y0, t_out, name, setting, floors, windows, limit // 2)
    if side is None:
        return None
    poll = None if progress is None else (lambda: progress(0.5 + 0.5 * side.fraction))
    found = []
    for run in side.result(steps, poll):
        if run is None:
            break
        found.append(evaluate_states(system, t_out, run.y_out))
    if not found:
        return None
    d_run = distance(samples, found[0], size)
    d_companions = distance(found[0], found[1], size) if len(found) > 1 else None
    credit = spec.estimate_order
    if credit is not None and setting * fastest_rate(system, y0) < 1.0:
        credit = spec.order
    estimate = global_estimate(spec.kind, spec.order, d_run, d_companions, credit)
    duration = float(t_out[-1])
    estimate += short_err * max(2.0, 1.0 / size, duration / size, duration)
    if spec.stiff:  # a fast mode all three runs damp or alias alike: measured apart
        probe = unresolved_mode_error(system, y0, name, setting, floors, windows, t_out,
                                      samples, limit)
        if not math.isfinite(probe):  # the resolving run could not be made: size unknown
            return None
        estimate = max(estimate, probe)
    return max(estimate, floor) if math.isfinite(estimate) else None


def turn_per_step(system: System, samples: Samples, steps: int) -> float:
    """rad: the largest turn per step, on average over a run of ``steps`` steps sampled at
    ``samples``, of a rotation the steps integrate as a quaternion: a ball or free joint's
    (its second body's angular velocity relative to its first's, ∫ |ω_rel| dt by the
    trapezoid rule over the samples, / ``steps``). A hinge's or a slider's coordinate is an
    angle or a length, which every method steps as a number (a hinge turning at a constant
    rate is integrated exactly); what its rate does to the dynamics the companions see."""
    w, worst = samples.angular_velocity, 0.0
    with np.errstate(over="ignore", invalid="ignore"):  # a run-away run's: inf, said as such
        for j in system.tree.joints:
            if j.kind not in ("spherical", "free"):
                continue
            rel = w[:, j.child] - (0.0 if j.parent == WORLD else w[:, j.parent])
            speed = np.linalg.norm(rel, axis=1)
            turned = float(np.sum(0.5 * (speed[1:] + speed[:-1]) * np.diff(samples.t)))
            worst = max(worst, turned / max(steps, 1))
    return worst


def default_step(system: System, y0: np.ndarray, duration: float, *, stiff: bool) -> float:
    """A fixed step the scene does not give (s), `budget.default_step`'s rule: for an explicit
    method the fastest rate is ρ, the spectral radius of ∂ẏ/∂y at the start (forward
    differences of the compiled right-hand side, `stiffness.fastest_rate`). A stiff method
    steps over the fast rates: that is its point."""
    return budget_default_step(duration, 0.0 if stiff else fastest_rate(system, y0))
