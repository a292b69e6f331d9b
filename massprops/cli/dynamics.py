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


def method_options(f):
    """--integrator, --rtol, --step: a run's method and its setting, over the scene's."""
    f = click.option("--step", type=float, callback=positive,
                     help="Step of fixed-step methods [s].")(f)
    f = click.option("--rtol", type=float, callback=positive,
                     help="Tolerance of adaptive methods.")(f)
    return click.option("--integrator", type=RegistryChoice(_integrator_names), default=None,
                        help="Overrides the scene's time.integrator.")(f)


@cli.command()
@click.argument("scene_path", metavar="SCENE")
@click.option("--json", "as_json", is_flag=True, help="Print the result as one JSON object.")
@click.option("--output", "output_path", default=None,
              help="Trajectory file (.csv or .npz); overrides the scene's output.file.")
@method_options
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
        from massprops.dynamics import any_scene
        from massprops.dynamics.budget import sampling_interval
        from massprops.dynamics.compiled.compiling import whole_process

        _check_run_outputs(output_path, plot_path, force, [scene_path])
        if plot_path:
            # deferred: matplotlib (the plot extra) loads only for --plot
            from massprops.dynamics.plots import require_matplotlib

            require_matplotlib()
        whole_process()  # numba started lean: this process runs massprops alone
        scene = any_scene.load(scene_path, duration, package_paths=package_paths,
                               xacro_args=xacro_args)
        for source, w in any_scene.warnings(scene, scene_path):
            say_warning(source, w)
        say_notes(scene.notes)  # already placed: "scene.yaml:LINE: ..."
        out = output_path or scene.output.file
        sampling = sampling_interval(scene.time.duration, every or scene.output.every,
                                     bool(out or plot_path))
        protect = [scene_path, *scene.input_files]
        _check_run_outputs(out, plot_path, force, protect)  # now with the scene's files
        progress = _Progress(enabled=not quiet and sys.stderr.isatty())
        try:
            result = any_scene.simulate(scene, integrator=integrator, rtol=rtol, step=step,
                                        every=sampling, progress=progress, notice=say_note,
                                        max_steps=max_steps, interruptible=True)
        except ComputationError as exc:  # keep what was computed, exit 3
            part: Any = exc.partial  # the run's result type, as far as it got
            if out and part is not None and any_scene.sample_count(part):
                any_scene.write_trajectory(part, out, force=force, protect=protect)
            raise
        finally:
            progress.close()
        say_notes(result.notes)
        if out:
            any_scene.write_trajectory(result, out, force=force, protect=protect)
        if plot_path:
            any_scene.plot(result, plot_path, force=force, protect=protect)
        if as_json:
            emit_json(result.as_dict())
        else:
            # deferred: rich loads only for human-readable output
            from massprops.cli.report import print_run

            print_run(scene_path, scene, result)
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
        from massprops.dynamics import any_scene
        from massprops.dynamics.compiled.compiling import whole_process

        _check_run_outputs(None, plot_path, force, [scene_path])
        if plot_path:
            # deferred: matplotlib (the plot extra) loads only for --plot
            from massprops.dynamics.plots import require_matplotlib

            require_matplotlib()
        scene = any_scene.load(scene_path)
        _check_run_outputs(None, plot_path, force, [scene_path, *scene.input_files])
        progress = _Progress(enabled=not quiet and sys.stderr.isatty())
        whole_process()
        try:
            report = any_scene.precision(scene, integrators=[i for i in integrators
                                                             if i != "auto"],
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
