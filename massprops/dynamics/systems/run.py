"""Simulate a system scene: the start on the joints, the run (the method and its error
estimate: `methods`), diagnostics, the trajectory file."""

from __future__ import annotations

import io
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import cast

import numpy as np

from massprops import tolerances
from massprops.dynamics.accuracy import estimate_note
from massprops.dynamics.budget import (
    ENERGY_BLOWUP,
    MAX_STEPS,
    check_fixed_steps,
    sample_times,
    too_fast,
)
from massprops.dynamics.compiled.compiling import prepare as prepare_kernels
from massprops.dynamics.integrators import INTEGRATORS
from massprops.dynamics.integrators.base import check_rtol, ignored_settings
from massprops.dynamics.systems.assemble import build_tree, initial_coordinates, localized
from massprops.dynamics.systems.falling import falling_frame
from massprops.dynamics.systems.integrate import integrate
from massprops.dynamics.systems.methods import (
    REASONS,
    SYSTEM_INTEGRATORS,
    choose,
    error_estimate,
    kernels,
    kind_of,
    start_companions,
)
from massprops.dynamics.systems.model import SystemScene
from massprops.dynamics.systems.outputs import Samples, energies, evaluate, reference
from massprops.dynamics.systems.system import System, UnclosedLoop
from massprops.dynamics.systems.tree import kinematics
from massprops.errors import (
    ComputationError,
    DivergenceError,
    RunBudgetError,
    SceneError,
    UsageError,
    setting_ref,
)
from massprops.parallel import beside
from massprops.rotation import quat_to_matrix

HOLDING_SAID = ("each joint's holding is what its motor adds to the joint's own spring and "
                "drive to keep the final pose at rest (N·m or N per rate coordinate): a "
                "description's joint stiffness carries its share itself")
"""What ``diagnostics.holding`` says where the joints report holding forces."""


@dataclass(frozen=True, eq=False)
class SystemResult:
    """What `massprops simulate` reports for a system (see ``as_dict``)."""

    samples: Samples
    steps: int
    evaluations: int
    rejected: int
    wall_time_s: float
    diagnostics: dict
    scene: SystemScene
    notes: tuple[str, ...] = field(default=())
    holding: list | None = None  # per scene joint: the static forces at the final pose
    integrator: str = "dop853"
    reason: str = REASONS["dop853"]
    interrupted: bool = False  # Ctrl-C stopped the run: the samples end where it got

    def row(self, n: int) -> dict:
        """Sample ``n``'s state as the contract's ``final`` object (the holding forces, which
        are the final pose's, only there)."""
        s, sc = self.samples, self.scene
        last = n in (-1, len(s.t) - 1)
        bodies = {b.name: {"position": s.position[n, i].tolist(),
                           "orientation": s.orientation[n, i].tolist(),
                           "velocity": s.velocity[n, i].tolist(),
                           "angular_velocity": s.angular_velocity[n, i].tolist(),
                           "angular_velocity_body": (quat_to_matrix(s.orientation[n, i]).T
                                                     @ s.angular_velocity[n, i]).tolist()}
                  for i, b in enumerate(sc.bodies)}
        joints = {j.name: {"type": j.kind, "bodies": [_name(sc, j.a), _name(sc, j.b)],
                           "coordinates": s.coordinates[k][n].tolist(),
                           "rates": s.rates[k][n].tolist(),
                           "force": s.force[n, k].tolist(), "torque": s.torque[n, k].tolist(),
                           **({} if self.holding is None or not last else
                              {"holding": self.holding[k].tolist()})}
                  for k, j in enumerate(sc.joints)}
        return {"t": float(s.t[n]), "bodies": bodies, "joints": joints}

    def as_dict(self) -> dict:
        diagnostics = self.diagnostics if self.holding is None else \
            {**self.diagnostics, "holding": HOLDING_SAID}
        return {"integrator": self.integrator,
                "reason": f"system: {self.reason}; projected onto the joints",
                "steps": self.steps, "evaluations": self.evaluations,
                "rejected_steps": self.rejected, "wall_time_s": self.wall_time_s,
                "interrupted": self.interrupted, "final": self.row(-1),
                "diagnostics": diagnostics}


def _name(scene: SystemScene, i: int) -> str:
    return "world" if i < 0 else scene.bodies[i].name


def prepare(scene: SystemScene) -> tuple[System, np.ndarray, list[str]]:
    """The System and its start y0 on the joints (refusals at the scene's lines), notes."""
    scene, origin = localized(scene)  # about the assembly's middle, wherever it sits
    tree = build_tree(scene)
    system = System(scene, tree, origin)
    notes: list[str] = []
    q, u, fixed_q, fixed_u = initial_coordinates(scene, tree, notes)
    _check_speeds(scene, tree, q, u)
    y0 = np.concatenate([q, u])
    if system.m:
        pos, vel = system.residual(y0)
        speed = max(float(np.abs(u).max(initial=0.0)) * tree.size, tree.size
                    / scene.time.duration if scene.time.duration else 0.0)
        bad_pos = pos > tolerances.JOINT_RTOL * tree.size
        bad_vel = vel > tolerances.JOINT_RTOL * speed
        if (bad_pos or bad_vel) and not scene.initial.project:
            what, key = (("positions", "initial.positions") if bad_pos
                         else ("rates", "initial.rates"))
            amount = f"{pos:.3g} m" if bad_pos else f"{vel:.3g} m/s"
            named = [k for k in scene.places if k.startswith(key + ".")]
            place = scene.where(named[0]) if named else scene.where("initial")
            raise SceneError(f"{place}the initial {what} open a closed loop (the joints miss "
                             f"by {amount}); set initial.project_initial: true to keep the named "
                             "coordinates and rates and solve the others")
        before = y0
        try:
            y0, _, _ = system.project(y0, (fixed_q, fixed_u), iterations=50)
        except UnclosedLoop as exc:
            raise _unclosed(scene, exc.residual) from exc
        left = system.residual(y0)[0]
        if left > 1e3 * tolerances.PROJECTION_ATOL_ULPS * tolerances.EPS * tree.size:
            raise _unclosed(scene, left)
        moved = float(np.abs(y0 - before).max())
        if scene.initial.project and moved > 0:
            notes.append(f"{scene.where('initial')}projected onto the joints: coordinates and "
                         f"rates moved by up to {moved:.3g}")
    sol = system.solve(0.0, y0, check=False)
    frame = falling_frame(scene, tree, y0)
    if frame is not None:  # held by nothing: run where it falls (falling.py says why)
        system = System(scene, tree, origin, frame)
        y0 = frame.start(y0, tree.nq)
    system.rank = sol.rank
    return system, y0, notes


def _unclosed(scene: SystemScene, residual: float) -> SceneError:
    """The refusal of a start whose named coordinates (initial.positions, kept by the
    projection) leave the loop open by ``residual`` (m, the largest |Φ| the projection left),
    at the first named one's line."""
    named = [k for k in scene.places if k.startswith("initial.positions.")]
    place = scene.where(named[0]) if named else scene.where("initial")
    given = ", ".join(f"{k} = {', '.join(f'{x:g}' for x in v)}"
                      for k, v in scene.initial.positions.items())
    what = f"the named initial coordinates ({given})" if given else "the assembly pose"
    return SceneError(f"{place}the loop cannot be closed with {what}: the other joints, solved "
                      f"for the closest fit, leave it open by {residual:.3g} m; change them")


def _check_speeds(scene: SystemScene, tree, q: np.ndarray, u: np.ndarray) -> None:
    """SceneError where a body starts faster than a run can square (`budget.too_fast`), at
    the initial key that gave its speed (its initial.bodies entry, else the first named
    rate)."""
    with np.errstate(all="ignore"):  # a start that overflows here is refused below
        kin = kinematics(tree, q, u)
        omega = kin.V[:, 0:3]
        velocity = kin.V[:, 3:6] + np.cross(omega, kin.com)  # of each centre of mass
    for i, body in enumerate(tree.bodies):
        fast = too_fast(body.mass, float(np.linalg.eigvalsh(body.inertia).max()),
                        velocity[i], omega[i])
        if fast is None:
            continue
        rates = [k for k in scene.places if k.startswith("initial.rates.")]
        key = (f"initial.bodies.{body.name}" if body.name in scene.initial.velocities
               else rates[0] if rates else "initial")
        raise SceneError(f"{scene.where(key)}body {body.name!r}: {fast[1]}")


def _check_steps(scene: SystemScene, name: str, step: float, limit: int) -> None:
    """RunBudgetError (`budget.check_fixed_steps`) where ``name`` at ``step`` (s) would take
    more than ``limit`` steps over the scene's duration, window edges included."""
    check_fixed_steps(name, scene.time.duration, step, len(load_windows(scene)), scene.source,
                      limit)


def error_floors(system: System, duration: float) -> np.ndarray:
    """Smallest error scale per component: 1 rad (or the size for a length) for coordinates,
    those per duration for rates."""
    tree = system.tree
    fq, fu = np.ones(tree.nq), np.full(tree.nv, 1.0 / duration)
    for j in tree.joints:
        if j.kind == "prismatic":
            fq[j.iq], fu[j.iu] = tree.size, tree.size / duration
        elif j.kind == "cylindrical":
            fq[j.iq + 1], fu[j.iu + 1] = tree.size, tree.size / duration
        elif j.kind == "free":
            fq[j.iq:j.iq + 3], fu[j.iu:j.iu + 3] = tree.size, tree.size / duration
    return np.concatenate([fq, fu])


def load_windows(scene: SystemScene) -> np.ndarray:
    """The times (s, sorted, finite) where a force or a joint drive of ``scene`` switches on or
    off: the runs end a segment at each, so that no step straddles a jump of the loads."""
    edges = [f.start for f in scene.forces] + [f.end for f in scene.forces]
    edges += [j.start for j in scene.joints if j.drive] + [j.end for j in scene.joints if j.drive]
    return np.unique([e for e in edges if math.isfinite(e)])


def simulate_system(scene: SystemScene, *, integrator: str | None = None,
                    rtol: float | None = None, step: float | None = None,
                    every: float | None = None, estimate: bool = True, notice=None,
                    max_steps: int | None = None,
                    progress: Callable[[float], None] | None = None,
                    interruptible: bool = False) -> SystemResult:
    """Run ``scene`` with ``integrator`` (SYSTEM_INTEGRATORS; default the scene's) at ``rtol``
    (dop853) or ``step`` (s, the fixed-step ones; default the scene's, else `default_step`);
    ComputationError (exit 3) at a singular pose or a failed step,
    RunBudgetError once a run takes ``max_steps`` steps (default: budget.MAX_STEPS), or up
    front for a fixed step that would take more.
    ``notice(text)``: told once if the step loop's kernel has to be compiled (see
    `compiled.compiling.prepare`). ``progress(fraction)`` is called between the run's compiled
    calls. Ctrl-C there propagates, or with ``interruptible`` returns the samples computed so
    far with ``interrupted`` set (no error estimate; the CLI exits 130)."""

    name = integrator or scene.time.integrator
    if name not in SYSTEM_INTEGRATORS:
        raise UsageError(f"{scene.source}: integrator {name} steps one body's state only; a "
                         f"system runs with {', '.join(SYSTEM_INTEGRATORS)}")
    system, y0, notes = prepare(scene)
    duration = scene.time.duration
    if duration == 0:  # the start pose only (a description's static torques)
        return _static(system, y0, notes)
    limit = max_steps or MAX_STEPS
    given = step if step is not None else scene.time.step
    if name != "auto" and kind_of(name) == "fixed" and given is not None:
        _check_steps(scene, name, given, limit)  # before a kernel is compiled or loaded
    if name == "dop853":  # the same (`methods.choose` checks what auto picks)
        check_rtol(float(rtol if rtol is not None else scene.time.rtol), scene.source)
    # compiled or loaded before the timed run (and before `choose`, whose stiffness probe
    # evaluates the compiled right-hand side); what `auto` picks, once it has picked
    prepare_kernels(kernels(name), notice)
    name, setting, reason = choose(system, y0, name, rtol, step)
    prepare_kernels(kernels(name), notice)
    if kind_of(name) == "fixed":  # a default step too: the run bound, before the run
        _check_steps(scene, name, setting, limit)
    ignored = ignored_settings(INTEGRATORS[name], rtol, step)
    if ignored is not None:
        notes.append(f"{scene.source}: {ignored}")
    t_out = sample_times(duration, every if every is not None else scene.output.every,
                         scene.source)
    floors = error_floors(system, duration)
    start = time.perf_counter()
    side = start_companions(system, y0, t_out, name, setting, floors, load_windows(scene),
                            limit) if estimate else None
    try:  # the companions stop with the run, whatever ends it (a finished one: at once)
        return _finish(scene, system, y0, t_out, name, setting, reason, floors, limit, start,
                       notes, side, progress, interruptible)
    finally:
        if side is not None:
            side.stop()


def _finish(scene, system, y0, t_out, name, setting, reason, floors, limit, start, notes, side,
            progress, interruptible) -> SystemResult:
    """`simulate_system` from the main run on, its companions running beside it (``side``)."""
    run = integrate(system, y0, t_out, setting, floors, load_windows(scene), limit, name,
                    None if progress is None else beside(progress, side))
    wall = time.perf_counter() - start
    system.margin = run.margin
    if run.interrupted and not interruptible:
        raise KeyboardInterrupt
    if run.interrupted:
        t_out = _reached(run, t_out)
    if run.failure is not None:  # the samples it reached go with the error, to be written
        part = _partial(system, t_out, run, wall, notes, name, reason)
        if isinstance(run.failure, RunBudgetError):
            raise RunBudgetError(run.failure.template, partial=part) from run.failure
        raise ComputationError(str(run.failure).splitlines()[0], partial=part) \
            from run.failure
    energy = None
    if system.cannot_gain_energy():
        with np.errstate(all="ignore"):  # a diverged run's energy may overflow: said below
            energy = energies(system, run.y_out)
        try:
            _check_energy(system, t_out, energy, name)
        except DivergenceError as exc:  # with the samples, to be written
            exc.partial = _partial(system, t_out, run, wall, notes, name, reason)
            raise
    conservative = system.conservative()
    samples = evaluate(system, t_out, run.y_out, energy if conservative else None)
    residual = cast(np.ndarray, samples.residual)  # every evaluation measures it
    diagnostics = {
        "energy_rel_drift": None, "error_estimate": None,
        "constraint_residual": {"position": float(residual[:, 0].max()),
                                "velocity": float(residual[:, 1].max())},
        "degrees_of_freedom": system.nv - system.rank,
        "redundant_constraints": system.m - system.rank,
        "projection": {"position": run.moved_q, "velocity": run.moved_u},
        "singularity_margin": run.margin if system.m else None,
        "reactions": ("unique" if system.m == system.rank else
                      "minimum-norm multipliers: the redundant constraints' reactions are not "
                      "unique; the smallest set of loop forces is reported"),
    }
    if conservative:
        e = cast(np.ndarray, samples.energy)  # asked for: the system conserves energy
        scale = max(abs(e[0]), _energy_scale(system), 1e-300)
        diagnostics["energy_rel_drift"] = float(np.max(np.abs(e - e[0])) / scale)
    if system.nv == system.rank and system.m:
        notes.append(f"{scene.source}: the mechanism is locked: 0 degrees of freedom (joints "
                     f"{', '.join(scene.joints[k].name for k in system.tree.cut)} close it)")
    if system.m > system.rank:
        notes.append(f"{scene.source}: {system.m - system.rank} redundant constraint(s): the "
                     "reactions reported are the minimum-norm choice, not unique")
    if side is not None and not run.interrupted:  # estimate asked (and a method with companions)
        try:
            diagnostics["error_estimate"] = error_estimate(
                system, y0, t_out, name, setting, floors, load_windows(scene), samples, 2 * limit,
                run.steps, side, progress, run.short_err)
        except KeyboardInterrupt:  # Ctrl-C while the companions ran: the run itself stands
            if not interruptible:
                raise
        note = estimate_note(scene.source, diagnostics["error_estimate"], name, kind_of(name))
        if note is not None:
            notes.append(note)
    held = _holding(system, run.y_out[-1], notes)
    return SystemResult(samples, run.steps, run.nfev, run.rejected, wall, diagnostics, scene,
                        tuple(notes), held, name, reason, run.interrupted)


def _partial(system: System, t_out: np.ndarray, run, wall: float, notes: list, name: str,
             reason: str) -> SystemResult:
    """What a failed ``run`` computed: its samples up to the first one it did not reach (the
    kernels fill them in order and stop at a state that is not finite), no estimate."""
    filled = np.isfinite(run.y_out).all(axis=1)
    n = len(filled) if filled.all() else int(np.argmin(filled))
    samples = evaluate(system, t_out[:n], run.y_out[:n])
    diagnostics = {"energy_rel_drift": None, "error_estimate": None}
    return SystemResult(samples, run.steps, run.nfev, run.rejected, wall, diagnostics,
                        system.scene, tuple(notes), None, name, reason)


def _reached(run, t_out: np.ndarray) -> np.ndarray:
    """The output times an interrupted ``run`` reached, its samples cut to them, and its last
    state appended where that falls between two (as a one-body run's)."""
    keep = t_out <= run.t_reached
    t_kept, y_kept = t_out[keep], run.y_out[keep]
    if not len(t_kept) or t_kept[-1] < run.t_reached:
        t_kept = np.append(t_kept, run.t_reached)
        y_kept = np.vstack([y_kept, run.y_last])
    run.y_out = y_kept
    return t_kept


def _holding(system: System, y: np.ndarray, notes: list[str]) -> list | None:
    """A description's holding forces at the final state (holding.py), else None; with loops
    a note says which split of the load it reports."""
    if system.scene.robot is None:
        return None
    # deferred: only a description reports it
    from massprops.dynamics.systems.holding import LOOP_RULE, holding

    if system.tree.prims:  # a coupling alone leaves no choice (holding.py): nothing to say
        notes.append(f"{system.scene.source}: holding forces with closed loops: {LOOP_RULE}")
    if system.falling is not None:  # holding is against the weight: the world frame's system
        system = System(system.scene, system.tree, system.origin)
    return holding(system, system.scene.time.duration, y)


def _static(system: System, y0: np.ndarray, notes: list[str]) -> SystemResult:
    """Duration 0: the start state's outputs and reactions, no integration (one sample: the
    numpy outputs, without loading the compiled kernel)."""
    samples = reference(system, np.zeros(1), y0[None, :])
    pos, vel = system.residual(y0)
    rank = cast(int, system.rank)  # found by `prepare`
    diagnostics = {"energy_rel_drift": None, "error_estimate": None,
                   "constraint_residual": {"position": pos, "velocity": vel},
                   "degrees_of_freedom": system.nv - rank,
                   "redundant_constraints": system.m - rank,
                   "projection": {"position": 0.0, "velocity": 0.0},
                   "singularity_margin": None, "reactions": "unique" if system.m == rank
                   else "minimum-norm multipliers"}
    held = _holding(system, y0, notes)
    return SystemResult(samples, 0, 1, 0, 0.0, diagnostics, system.scene, tuple(notes), held)


def _check_energy(system: System, t: np.ndarray, energy: np.ndarray, name: str) -> None:
    """DivergenceError (exit 3) when a system that cannot gain energy
    (`System.cannot_gain_energy`), its energies ``energy`` (J) at the samples ``t``, ends a
    sample with more than ENERGY_BLOWUP times its energy scale above its start: a step beyond
    the method's stability whose state grew without becoming NaN (RK4 at h ρ = 2000 reached
    angles of 4e34 rad)."""

    scale = max(abs(energy[0]), _energy_scale(system))
    with np.errstate(invalid="ignore"):
        grown = ~(energy - energy[0] <= ENERGY_BLOWUP * scale)  # NaN counts as grown
    if grown.any():
        at = float(t[int(np.argmax(grown))])
        fix = ("run the implicit method" if name != "implicit" else "shorten the step")
        raise DivergenceError(f"{system.scene.source}: the {name} run diverged by t = {at:.6g} "
                              f"s: the energy of a system that cannot gain any grew more than "
                              f"{ENERGY_BLOWUP:.0e} times its scale; {fix} "
                              f"({setting_ref('integrator')}, {setting_ref('step')}, "
                              f"{setting_ref('rtol')})")


def _energy_scale(system: System) -> float:
    """J: Σ m |g| × size and the springs' k × size², a floor for the relative energy drift."""
    size = system.tree.size
    weight = sum(b.mass for b in system.tree.bodies) * float(np.linalg.norm(
        system.scene.gravity)) * size  # the scene's weight, also in the falling frame
    springs = sum(s.stiffness for s in system.scene.springs) * size * size
    return weight + springs + sum(j.stiffness for j in system.scene.joints)


# --- the trajectory file ------------------------------------------------------------------------
def trajectory_table(result: SystemResult) -> tuple[list[str], np.ndarray]:
    """The contract's columns: t, per body x y z qw qx qy qz vx vy vz wx wy wz, per joint q/u
    (q0.. u0.. for several) and fx fy fz tx ty tz."""
    s, sc = result.samples, result.scene
    names, cols = ["t"], [s.t[:, None]]
    for i, b in enumerate(sc.bodies):
        names += [f"{b.name}.{c}" for c in ("x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy",
                                            "vz", "wx", "wy", "wz")]
        cols += [s.position[:, i], s.orientation[:, i], s.velocity[:, i],
                 s.angular_velocity[:, i]]
    for k, j in enumerate(sc.joints):
        nq, nu = s.coordinates[k].shape[1], s.rates[k].shape[1]
        names += [f"{j.name}.q"] if nq == 1 else [f"{j.name}.q{c}" for c in range(nq)]
        names += [f"{j.name}.u"] if nu == 1 else [f"{j.name}.u{c}" for c in range(nu)]
        names += [f"{j.name}.{c}" for c in ("fx", "fy", "fz", "tx", "ty", "tz")]
        cols += [s.coordinates[k], s.rates[k], s.force[:, k], s.torque[:, k]]
    return names, np.hstack(cols)


def write_system_trajectory(result: SystemResult, path: str | Path, *, force: bool = False,
                            protect=()) -> None:
    """CSV (header, full precision) or NPZ (``columns`` and ``table``), atomically."""
    # deferred: only when a file is written
    from massprops.dynamics.trajectory import trajectory_output
    from massprops.io.atomic import atomic_write_bytes, check_output

    path = check_output(path, trajectory_output(), force=force, protect=protect)
    names, table = trajectory_table(result)
    buf = io.BytesIO()
    if path.suffix.lower() == ".csv":
        np.savetxt(buf, table, delimiter=",", fmt="%.17g", header=",".join(names), comments="")
    else:
        np.savez(buf, columns=np.array(names), table=table)
    atomic_write_bytes(path, buf.getvalue(), force=force, protect=protect)
