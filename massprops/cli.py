"""The ``massprops`` command: parse options, call one library function, render, map errors to exits.

Imports of anything heavier than click happen inside the commands, so that ``inspect --json`` on
a small mesh pays for numpy and the mesh code only (no rich, scipy, trimesh or numba).
"""

from __future__ import annotations

import gc
import json
import sys
from collections.abc import Callable, Iterable
from typing import Any

import click

from massprops import __version__
from massprops.errors import MassPropsError, UsageError, exit_code

UNIT_CHOICES = ("m", "cm", "mm", "um", "in", "ft")
"""The keys of massprops.io.UNITS, written out so that building the CLI does not import the
readers (tests/test_cli.py checks the two agree)."""


def _say_error(message: str) -> None:
    click.echo(f"massprops: error: {message}", err=True)


def _say_warning(name: str, message: str) -> None:
    click.echo(f"massprops: warning: {name}: {message}", err=True)


def _say_note(message: str) -> None:
    """A note on stderr while something slow and one-off happens (never on --json stdout)."""
    click.echo(f"massprops: {message}", err=True)


def _guarded(ctx: click.Context, fn: Callable[[], Any]) -> int:
    """Run ``fn``; turn any exception into one stderr line and the contract's exit code (with
    --debug: its traceback instead of the line, and the same exit code)."""
    try:
        fn()
        return 0
    except KeyboardInterrupt:
        raise
    except Exception as exc:
        if ctx.obj.get("debug"):
            import traceback

            traceback.print_exc()
            return exit_code(exc)
        if isinstance(exc, MassPropsError):
            _say_error(str(exc))
            return exit_code(exc)
        # a bug or an environment failure: say what, not a traceback
        if isinstance(exc, OSError):
            _say_error(f"{exc.filename or ''}: {exc.strerror or exc}".lstrip(": "))
        else:
            _say_error(f"internal error: {type(exc).__name__}: {exc} "
                       "(run with --debug for details)")
        return exit_code(exc)


def _emit_json(obj: dict) -> None:
    # allow_nan=False: a NaN reaching the output is a bug to surface, never a number to print
    click.echo(json.dumps(obj, allow_nan=False))


def _positive(ctx: click.Context, param: click.Parameter, value: float | None) -> float | None:
    import math

    if value is not None and not (math.isfinite(value) and value > 0):
        raise click.BadParameter(f"must be a positive finite number, got {value!r}")
    return value


def mass_options(f: Callable) -> Callable:
    """--density / --mass / --unit / --allow-open / --input-format, shared by inspect and align."""
    for opt in reversed([
        click.option("--density", type=float, callback=_positive,
                     help="Density in kg/m³ (default 1)."),
        click.option("--mass", "total_mass", type=float, callback=_positive,
                     help="Total mass in kg; the density follows from the volume."),
        click.option("--unit", type=click.Choice(UNIT_CHOICES), default="m", show_default=True,
                     help="Unit of the file's coordinates; results are always SI."),
        click.option("--allow-open", is_flag=True,
                     help="Compute an open mesh anyway (the result is then ill-defined; "
                          "warnings say by how much)."),
        click.option("--input-format", default=None,
                     help="Format of the input (required for '-' = standard input)."),
    ]):
        f = opt(f)
    return f


def _check_mass_options(density: float | None, total_mass: float | None) -> None:
    if density is not None and total_mass is not None:
        raise click.UsageError("give --density or --mass, not both")


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="massprops")
@click.option("--debug", is_flag=True, help="Show tracebacks instead of one-line errors.")
@click.pass_context
def cli(ctx: click.Context, debug: bool) -> None:
    """Mass properties and rigid-body dynamics of closed meshes (SI units)."""
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug


@cli.command()
@click.argument("meshes", nargs=-1, required=True)
@mass_options
@click.option("--json", "as_json", is_flag=True, help="One JSON object per mesh, one per line.")
@click.pass_context
def inspect(ctx: click.Context, meshes: tuple[str, ...], density: float | None,
            total_mass: float | None, unit: str, allow_open: bool, input_format: str | None,
            as_json: bool) -> None:
    """Mass, centre of mass, inertia tensor, principal moments and axes of each MESH.

    MESH is a file (OBJ, STL, .vf/.vtx/.fac, PLY, OFF, ...) or '-' for standard input.
    """
    _check_mass_options(density, total_mass)
    if "-" in meshes and input_format is None:
        raise click.UsageError("reading standard input ('-') needs --input-format")
    from massprops.analysis import inspect_file

    def one(path: str) -> None:
        source = sys.stdin.buffer if path == "-" else path
        result = inspect_file(source, format=input_format, unit=unit,
                              name="<stdin>" if path == "-" else path,
                              density=density, mass=total_mass, allow_open=allow_open)
        for w in result.warnings:
            _say_warning(result.mesh.name, w)
        if as_json:
            _emit_json(result.as_dict())
        else:
            from massprops.report import print_inspection

            print_inspection(result)

    ctx.exit(_worst(ctx, meshes, one))


@cli.command()
@click.argument("input_path", metavar="IN")
@click.argument("output_path", metavar="OUT")
@mass_options
@click.option("--force", is_flag=True, help="Replace OUT if it exists (never IN).")
@click.option("--json", "as_json", is_flag=True, help="Print the applied map as JSON.")
@click.pass_context
def align(ctx: click.Context, input_path: str, output_path: str, density: float | None,
          total_mass: float | None, unit: str, allow_open: bool, input_format: str | None,
          force: bool, as_json: bool) -> None:
    """Write OUT: the mesh IN moved into its principal frame (COM at the origin, axes along the
    principal axes, ascending moments). Faces and winding are unchanged."""
    _check_mass_options(density, total_mass)

    def run() -> None:
        from massprops.align import align_mesh
        from massprops.analysis import inspect_file
        from massprops.io import write_mesh

        result = inspect_file(input_path, format=input_format, unit=unit, density=density,
                              mass=total_mass, allow_open=allow_open)
        for w in result.warnings:
            _say_warning(result.mesh.name, w)
        aligned = align_mesh(result.mesh, result.properties)
        write_mesh(aligned.mesh, output_path, force=force, protect=(input_path,))
        if as_json:
            _emit_json({"input": input_path, "output": output_path, **aligned.as_dict()})
        else:
            from massprops.report import print_alignment

            print_alignment(input_path, output_path, aligned)

    ctx.exit(_guarded(ctx, run))


class RegistryChoice(click.ParamType):
    """A choice whose values come from a registry, loaded on first use, so that building the
    command line never imports what only one command needs (numba for the integrators)."""

    name = "choice"

    def __init__(self, loader: Callable[[], tuple[str, ...]]) -> None:
        self.loader = loader

    def get_metavar(self, *args: Any, **kwargs: Any) -> str:
        return "[" + "|".join(self.loader()) + "]"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> str:
        choices = self.loader()
        if value not in choices:
            self.fail(f"{value!r} is not one of {', '.join(choices)}", param, ctx)
        return value


def _integrator_names() -> tuple[str, ...]:
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
@click.option("--rtol", type=float, callback=_positive, help="Tolerance of adaptive methods.")
@click.option("--step", type=float, callback=_positive, help="Step of fixed-step methods [s].")
@click.option("--every", type=float, callback=_positive, help="Sampling interval [s].")
@click.option("--plot", "plot_path", default=None,
              help="PNG of angular velocity, energy and angular-momentum drift over time.")
@click.option("--force", is_flag=True, help="Replace existing output files.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
@click.option("--max-steps", type=click.IntRange(min=1), default=None,
              help="Steps a run may take (default 2e7); beyond it the run is refused or "
                   "stopped, keeping what it computed.")
@click.pass_context
def simulate(ctx: click.Context, scene_path: str, as_json: bool, output_path: str | None,
             integrator: str | None, rtol: float | None, step: float | None,
             every: float | None, plot_path: str | None, force: bool, quiet: bool,
             max_steps: int | None) -> None:
    """Integrate the Newton-Euler equations of the one body in SCENE (YAML, SI units)."""
    interrupted = []

    def run() -> None:
        from massprops.dynamics.compiling import whole_process
        from massprops.dynamics.scene import load_scene
        from massprops.dynamics.simulate import simulate as run_scene
        from massprops.errors import DivergenceError, RunBudgetError

        if plot_path:
            from massprops.dynamics.plots import require_matplotlib

            require_matplotlib()
        scene = load_scene(scene_path)
        for w in scene.warnings:
            _say_warning(scene.body_source, w)
        out = output_path or scene.output.file
        sampling = every or scene.output.every
        if sampling is None and (out or plot_path):
            sampling = scene.time.duration / 1000
        protect = [scene_path, *scene.input_files]
        progress = _Progress(enabled=not quiet and sys.stderr.isatty())
        whole_process()
        try:
            result = run_scene(scene, integrator=integrator, rtol=rtol, step=step,
                               every=sampling, progress=progress, notice=_say_note,
                               max_steps=max_steps)
        except (DivergenceError, RunBudgetError) as exc:  # keep what was computed, exit 3
            if out and exc.partial is not None:
                _save(exc.partial, out, None, force, protect)
            raise
        finally:
            progress.close()
        _save(result, out, plot_path, force, protect)
        if as_json:
            _emit_json(result.as_dict())
        else:
            from massprops.report import print_simulation

            print_simulation(scene, result)
        if result.interrupted:
            interrupted.append(True)

    code = _guarded(ctx, run)
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
        from massprops.dynamics.compiling import whole_process
        from massprops.dynamics.precision import precision as run_ladders
        from massprops.dynamics.scene import load_scene

        if plot_path:
            from massprops.dynamics.plots import require_matplotlib

            require_matplotlib()
        scene = load_scene(scene_path)
        progress = _Progress(enabled=not quiet and sys.stderr.isatty())
        whole_process()
        try:
            report = run_ladders(scene, integrators=[i for i in integrators if i != "auto"],
                                 progress=progress, notice=_say_note)
        finally:
            progress.close()
        if plot_path:
            from massprops.dynamics.plots import plot_precision

            plot_precision(report, plot_path, title=scene_path, force=force,
                           protect=[scene_path, *scene.input_files])
        if as_json:
            _emit_json(report.as_dict())
        else:
            from massprops.report import print_precision

            print_precision(scene_path, report)

    ctx.exit(_guarded(ctx, run))


def _save(result: Any, trajectory_path: Any, plot_path: str | None, force: bool,
          protect: list) -> None:
    if trajectory_path:
        from massprops.dynamics.trajectory import write_trajectory

        write_trajectory(result.trajectory, trajectory_path, force=force, protect=protect)
    if plot_path:
        from massprops.dynamics.plots import plot_simulation

        plot_simulation(result, plot_path, force=force, protect=protect)


def _worst(ctx: click.Context, items: Iterable[str], fn: Callable[[str], None]) -> int:
    """Run ``fn`` on each item, reporting each failure; the exit code is the worst one."""
    worst = 0
    for item in items:
        worst = max(worst, _guarded(ctx, lambda item=item: fn(item)))
    return worst


def main(argv: list[str] | None = None) -> None:
    """Entry point: click's own usage errors exit 2; Ctrl-C exits 130 without a traceback."""
    try:
        # non-standalone: click returns ctx.exit's code instead of exiting itself
        code = cli.main(args=argv, prog_name="massprops", standalone_mode=False)
    except click.ClickException as exc:
        exc.show()
        sys.exit(exc.exit_code)
    except click.exceptions.Abort:
        sys.exit(130)
    except KeyboardInterrupt:
        click.echo("massprops: interrupted", err=True)
        sys.exit(130)
    except UsageError as exc:
        _say_error(str(exc))
        sys.exit(2)
    # The process ends here: freeze what the command left (after simulate, numba's ~10^6
    # typing and compiled-code objects) so the interpreter's teardown does not collect them one
    # cycle at a time: ~0.25 s of a ~0.7 s simulate, ~0.03 s frozen. Files are closed already
    # and stdout is still flushed at exit; the OS takes the memory back.
    gc.freeze()
    sys.exit(code if isinstance(code, int) else 0)
