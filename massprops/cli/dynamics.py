"""``massprops simulate`` and ``massprops precision``: a scene's run, and error against run time."""

from __future__ import annotations

import sys
from typing import Any

import click

from massprops.cli.app import cli
from massprops.cli.common import (
    RegistryChoice,
    check_outputs,
    emit_json,
    estimate_said,
    guarded,
    positive,
    robot_file_options,
    say_note,
    say_notes,
    say_warning,
)
from massprops.errors import ComputationError


def _integrator_names() -> tuple[str, ...]:
    # deferred: each command imports only what it runs (start-up of the others)
    from massprops.dynamics.integrators import integrator_names

    return integrator_names()


class _Progress:
    """Progress bar on stderr, shown only on a terminal, not with --quiet, and only once a run
    has lasted a second (short runs print nothing)."""

    def __init__(self, enabled: bool) -> None:
        import time

        self.enabled, self.clock, self.start = enabled, time.monotonic, time.monotonic()
        self.bar: Any = None
        self.task: Any = None

    def __call__(self, fraction: float) -> None:
        if not self.enabled:
            return
        if self.bar is None and self.clock() - self.start > 1.0:
            from rich.console import Console
            from rich.progress import Progress

            self.bar = Progress(console=Console(stderr=True), transient=True)
            self.bar.start()
            self.task = self.bar.add_task("integrating", total=1.0)
        if self.bar is not None:
            self.bar.update(self.task, completed=fraction)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.stop()


@cli.command()
@click.argument("scene_path", metavar="SCENE")
@click.option("--json", "as_json", is_flag=True, help="Print the result as one JSON object.")
@click.option("--output", "output_path", default=None,
              help="Trajectory file (.csv or .npz); overrides the scene's output.file.")
@click.option("--integrator", type=RegistryChoice(_integrator_names), default=None,
              help="Overrides the scene's time.integrator.")
@click.option("--rtol", type=float, callback=positive, help="Tolerance of adaptive methods.")
@click.option("--step", type=float, callback=positive, help="Step of fixed-step methods [s].")
@click.option("--every", type=float, callback=positive, help="Sampling interval [s].")
@click.option("--plot", "plot_path", default=None,
              help="PNG of angular velocity, energy and angular-momentum drift over time.")
@click.option("--force", is_flag=True, help="Replace existing output files.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
@click.option("--max-steps", type=click.IntRange(min=1), default=None,
              help="Steps a run may take (default 2e7); beyond it the run is refused or "
                   "stopped, keeping what it computed.")
@click.option("--duration", type=click.FloatRange(min=0), default=None,
              help="Seconds to run (overrides time.duration; 0, for a system or a robot "
                   "description: the start pose's reactions and holding torques).")
@robot_file_options
@click.pass_context
def simulate(ctx: click.Context, scene_path: str, as_json: bool, output_path: str | None,
             integrator: str | None, rtol: float | None, step: float | None,
             every: float | None, plot_path: str | None, force: bool, quiet: bool,
             max_steps: int | None, duration: float | None, package_paths: tuple[str, ...],
             xacro_args: dict[str, str]) -> None:
    """Integrate the Newton-Euler equations of the one body in SCENE (YAML, SI units), of a
    system of bodies, or of a robot description (ROBOT.urdf|.sdf|.xml|.xacro) under gravity."""
    interrupted = []

    def run() -> None:
        # deferred: each command imports only what it runs (start-up of the others)
        from massprops.dynamics.compiled.compiling import whole_process
        from massprops.dynamics.systems.robot_scene import check_description_settings

        check_description_settings(scene_path, package_paths, xacro_args)
        _check_run_outputs(output_path, plot_path, force, [scene_path])
        if plot_path:
            # deferred: matplotlib (the plot extra) loads only for --plot
            from massprops.dynamics.plots import require_matplotlib

            require_matplotlib()
        if _is_system(scene_path):  # `bodies:`, `model:` or a description: the systems package
            whole_process()  # numba started lean: this process runs massprops alone
            if _simulate_system(scene_path, as_json, output_path, integrator, rtol, step, every,
                                force, plot_path, duration, max_steps, quiet,
                                {"package_paths": package_paths, "xacro_args": xacro_args}):
                interrupted.append(True)
            return
        # deferred: the one-body run's modules, not a system's
        from massprops.dynamics.budget import sampling_interval
        from massprops.dynamics.scene import load_scene
        from massprops.dynamics.simulate import simulate as run_scene
        from massprops.errors import DivergenceError, RunBudgetError

        scene = load_scene(scene_path)
        if duration is not None:
            scene = _one_body_duration(scene, scene_path, duration)
        for w in scene.warnings:
            say_warning(scene.body_source, w)
        say_notes(scene.notes)  # already placed: "scene.yaml:LINE: ..."
        out = output_path or scene.output.file
        sampling = sampling_interval(scene.time.duration, every or scene.output.every,
                                     bool(out or plot_path))
        protect = [scene_path, *scene.input_files]
        _check_run_outputs(out, plot_path, force, protect)  # now with the scene's files
        progress = _Progress(enabled=not quiet and sys.stderr.isatty())
        whole_process()
        try:
            result = run_scene(scene, integrator=integrator, rtol=rtol, step=step,
                               every=sampling, progress=progress, notice=say_note,
                               max_steps=max_steps)
        except (DivergenceError, RunBudgetError) as exc:  # keep what was computed, exit 3
            if out and exc.partial is not None:
                _save(exc.partial, out, None, force, protect)
            raise
        finally:
            progress.close()
        _save(result, out, plot_path, force, protect)
        say_notes(result.notes)
        if as_json:
            emit_json(result.as_dict())
        else:
            # deferred: rich loads only for human-readable output
            from massprops.cli.report import print_simulation

            print_simulation(scene, result)
        if result.interrupted:
            interrupted.append(True)

    code = guarded(ctx, run)
    if interrupted and code == 0:
        click.echo("massprops: interrupted; wrote what was computed", err=True)
        code = 130
    ctx.exit(code)


@cli.command()
@click.argument("scene_path", metavar="SCENE")
@click.option("--json", "as_json", is_flag=True,
              help="One JSON object: the reference and every run.")
@click.option("--plot", "plot_path", default=None,
              help="Work-precision diagram (PNG): error against run time per integrator.")
@click.option("--integrator", "integrators", multiple=True,
              type=RegistryChoice(_integrator_names),
              help="Only these integrators (repeatable); default: every applicable one.")
@click.option("--force", is_flag=True, help="Replace an existing plot file.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
@click.pass_context
def precision(ctx: click.Context, scene_path: str, as_json: bool, plot_path: str | None,
              integrators: tuple[str, ...], force: bool, quiet: bool) -> None:
    """Error against run time: each applicable integrator over a ladder of tolerances or steps,
    measured against the exact solution or a much tighter, checked reference run."""

    def run() -> None:
        # deferred: each command imports only what it runs (start-up of the others)
        from massprops.dynamics.compiled.compiling import whole_process
        from massprops.dynamics.precision import precision as run_ladders
        from massprops.dynamics.scene import load_scene

        _check_run_outputs(None, plot_path, force, [scene_path])
        if plot_path:
            # deferred: matplotlib (the plot extra) loads only for --plot
            from massprops.dynamics.plots import require_matplotlib

            require_matplotlib()
        if _is_system(scene_path):  # a `bodies:` scene: the systems package's own ladders
            # deferred: only a system scene needs them
            from massprops.dynamics.systems.precision import precision_system as run_ladders
            from massprops.dynamics.systems.robot_scene import load_any_system

            scene = load_any_system(scene_path)
        else:
            scene = load_scene(scene_path)
        _check_run_outputs(None, plot_path, force, [scene_path, *scene.input_files])
        progress = _Progress(enabled=not quiet and sys.stderr.isatty())
        whole_process()
        try:
            report = run_ladders(scene, integrators=[i for i in integrators if i != "auto"],
                                 progress=progress, notice=say_note)
        finally:
            progress.close()
        _emit_precision(report, scene_path, plot_path, as_json, force, scene.input_files)

    ctx.exit(guarded(ctx, run))


def _check_run_outputs(trajectory_path: Any, plot_path: str | None, force: bool,
                       inputs: list) -> None:
    """The output rule for a run's trajectory and plot, before the run (`check_outputs`)."""
    # deferred: the outputs' kinds, only where the run writes files
    from massprops.dynamics.plots import plot_output
    from massprops.dynamics.trajectory import trajectory_output

    check_outputs([(trajectory_path and str(trajectory_path), trajectory_output()),
                   (plot_path, plot_output())], force=force, inputs=[str(p) for p in inputs])


def _save(result: Any, trajectory_path: Any, plot_path: str | None, force: bool,
          protect: list) -> None:
    if trajectory_path:
        # deferred: each command imports only what it runs (start-up of the others)
        from massprops.dynamics.trajectory import write_trajectory

        write_trajectory(result.trajectory, trajectory_path, force=force, protect=protect)
    if plot_path:
        # deferred: matplotlib (the plot extra) loads only for --plot
        from massprops.dynamics.plots import plot_simulation

        plot_simulation(result, plot_path, force=force, protect=protect)


def _one_body_duration(scene: Any, scene_path: str, duration: float) -> Any:
    """``scene`` run for ``duration`` s instead of its time.duration."""
    import dataclasses  # deferred: only with --duration

    if duration <= 0:
        # deferred: rare path
        from massprops.errors import UsageError, setting_ref

        raise UsageError(f"{scene_path}: {setting_ref('duration')} 0 gives a system's start "
                         "pose reactions; a one-body scene needs a duration > 0")
    return dataclasses.replace(scene, time=dataclasses.replace(scene.time, duration=duration))


def _is_system(scene_path: str) -> bool:
    # deferred: start-up cost
    from massprops.dynamics.systems.robot_scene import is_system_file

    return is_system_file(scene_path)


def _simulate_system(scene_path: str, as_json: bool, output_path: str | None,
                     integrator: str | None, rtol: float | None, step: float | None,
                     every: float | None, force: bool, plot_path: str | None = None,
                     duration: float | None = None, max_steps: int | None = None,
                     quiet: bool = False, description: dict | None = None) -> bool:
    """A system scene or a robot description (``description``: its package_paths and
    xacro_args): run, write the trajectory, print JSON or a short summary; True when Ctrl-C
    stopped the run (what it computed is written and printed)."""
    # deferred, as the one-body path's imports: only a system scene needs them
    from massprops.dynamics.budget import sampling_interval
    from massprops.dynamics.systems.robot_scene import load_any_system
    from massprops.dynamics.systems.run import simulate_system, write_system_trajectory

    scene = load_any_system(scene_path, duration, **(description or {}))
    for w in scene.warnings:
        say_warning(scene_path, w)
    say_notes(scene.notes)  # already placed: "scene.yaml:LINE: ..."
    out = output_path or scene.output.file
    sampling = sampling_interval(scene.time.duration, every or scene.output.every,
                                 bool(out or plot_path))
    progress = _Progress(enabled=not quiet and sys.stderr.isatty())
    protect = [scene_path, *scene.input_files]
    _check_run_outputs(out, plot_path, force, protect)  # now with the scene's files
    try:
        result = simulate_system(scene, integrator=integrator, rtol=rtol, step=step,
                                 every=sampling, notice=say_note, max_steps=max_steps,
                                 progress=progress, interruptible=True)
    except ComputationError as exc:  # keep what was computed, exit 3
        if out and exc.partial is not None and len(exc.partial.samples.t):
            write_system_trajectory(exc.partial, out, force=force, protect=protect)
        raise
    finally:
        progress.close()
    say_notes(result.notes)
    if out:
        write_system_trajectory(result, out, force=force, protect=protect)
    if plot_path:
        from massprops.dynamics.systems.plots import plot_system  # matplotlib: --plot only

        plot_system(result, plot_path, force=force, protect=[scene_path, *scene.input_files])
    data = result.as_dict()
    if as_json:
        emit_json(data)
        return result.interrupted
    diag = data["diagnostics"]
    click.echo(f"{scene_path}: {len(scene.bodies)} bodies, {len(scene.joints)} joints, "
               f"{diag['degrees_of_freedom']} degrees of freedom; t = {data['final']['t']:g} s "
               f"in {data['steps']} steps; error estimate "
               f"{estimate_said(diag['error_estimate'], result.interrupted, '')}")
    for name, joint in data["final"]["joints"].items():
        held = f", holding {joint['holding']}" if "holding" in joint else ""
        click.echo(f"  {name} ({joint['type']}): q = {joint['coordinates']}, "
                   f"force {joint['force']} N, torque {joint['torque']} N·m{held}")
    return result.interrupted


def _emit_precision(report: Any, scene_path: str, plot_path: str | None, as_json: bool,
                    force: bool, inputs: Any) -> None:
    """A precision report: the plot, then JSON or the table."""
    if plot_path:
        # deferred: matplotlib (the plot extra) loads only for --plot
        from massprops.dynamics.plots import plot_precision

        plot_precision(report, plot_path, title=scene_path, force=force,
                       protect=[scene_path, *inputs])
    if as_json:
        emit_json(report.as_dict())
    else:
        # deferred: rich loads only for human-readable output
        from massprops.cli.report import print_precision

        print_precision(scene_path, report)
