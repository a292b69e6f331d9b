"""The ``massprops`` command: parse options, call one library function, render, map errors to exits.

Imports of anything heavier than click happen inside the commands, so that ``inspect --json`` on
a small mesh pays for numpy and the mesh code only (no rich, scipy, trimesh or numba).
"""

from __future__ import annotations

import contextlib
import gc
import json
import sys
from collections.abc import Callable, Iterator
from typing import Any

import click

from massprops import __version__
from massprops.errors import UsageError, error_message, exit_code

UNIT_CHOICES = ("m", "cm", "mm", "um", "in", "ft")
"""The keys of massprops.io.UNITS, written out so that building the CLI does not import the
readers (tests/test_cli.py checks the two agree)."""

ELEMENT_FORMATS = ("urdf", "sdf", "mjcf")
"""The keys of massprops.robot.elements.WRITERS, written out so that ``inspect`` never imports
the robot package to build its options (tests/test_robot_cli.py checks the two agree)."""

INSPECT_FORMATS = ("table", "json", "csv", *ELEMENT_FORMATS)
"""inspect --format: the human table, one JSON object per line, CSV (massprops.batch.table), the
robot formats' <inertial> elements."""


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
    except Exception as exc:  # ours, a bug or an environment failure: one line, no traceback
        if ctx.obj.get("debug"):
            import traceback

            traceback.print_exc()
            return exit_code(exc)
        _say_error(error_message(exc))
        return exit_code(exc)


def _emit_json(obj: dict) -> None:
    # allow_nan=False: a NaN reaching the output is a bug to surface, never a number to print
    click.echo(json.dumps(obj, allow_nan=False))


def _positive(ctx: click.Context, param: click.Parameter, value: float | None) -> float | None:
    import math

    if value is not None and not (math.isfinite(value) and value > 0):
        raise click.BadParameter(f"must be a positive finite number, got {value!r}")
    return value


def _non_negative(ctx: click.Context, param: click.Parameter,
                  value: float | None) -> float | None:
    import math

    if value is not None and not (math.isfinite(value) and value >= 0):
        raise click.BadParameter(f"must be a finite number >= 0, got {value!r}")
    return value


def _fraction(ctx: click.Context, param: click.Parameter, value: float | None) -> float | None:
    import math

    if value is not None and not (math.isfinite(value) and 0 < value <= 1):
        raise click.BadParameter(f"must be a fraction in (0, 1], got {value!r}")
    return value


def mass_options(f: Callable) -> Callable:
    """--density / --mass / --unit / --allow-open / --input-format and the repairs (--union,
    --shell, --fill-holes, --max-hole), shared by inspect and align."""
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
        click.option("--fill-holes", is_flag=True,
                     help="Cap each hole (boundary loop) with a triangulation that keeps its "
                          "shape; the error bar covers the choice of cap."),
        click.option("--max-hole", type=float, callback=_fraction, metavar="FRACTION",
                     help="With --fill-holes: the largest cap accepted, as a fraction of the "
                          "surface area (default 0.1); larger loops are openings and refused."),
        click.option("--union", is_flag=True,
                     help="Replace overlapping or nested pieces by the solid they occupy "
                          "together (cavities stay empty), instead of counting overlaps twice."),
        click.option("--shell", type=float, callback=_positive, metavar="THICKNESS",
                     help="The surface as a wall of this thickness, in METRES whatever --unit "
                          "says (mid-surface model; open and flat surfaces too)."),
    ]):
        f = opt(f)
    return f


def _check_mass_options(density: float | None, total_mass: float | None) -> None:
    if density is not None and total_mass is not None:
        raise click.UsageError("give --density or --mass, not both")


def _repairs(fill_holes: bool, max_hole: float | None, union: bool, shell: float | None):
    """The library's RepairOptions, or None when no repair is asked (nothing imported then)."""
    if max_hole is not None and not fill_holes:
        raise click.UsageError("--max-hole applies to --fill-holes; add --fill-holes")
    if not (fill_holes or union or shell is not None):
        return None
    from massprops.repair import RepairOptions

    return RepairOptions(union=union, shell=shell, fill_holes=fill_holes, max_hole=max_hole)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="massprops")
@click.option("--debug", is_flag=True, help="Show tracebacks instead of one-line errors.")
@click.pass_context
def cli(ctx: click.Context, debug: bool) -> None:
    """Mass properties and rigid-body dynamics of closed meshes (SI units)."""
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug


_RENAMED = {"total_mass": "mass", "input_format": "format"}
"""CLI option names that differ from inspect_file's keyword arguments; every other shared mesh
option reaches inspect_file (and the batch workers) under its own name."""

_REPAIR_OPTIONS = ("fill_holes", "max_hole", "union", "shell")
"""The mesh options inspect_file takes together, as one ``repairs=RepairOptions``."""


def _inspect_kwargs(mesh_options: dict[str, Any]) -> dict[str, Any]:
    """inspect_file's keyword arguments from the shared mesh options (`mass_options`)."""
    options = {_RENAMED.get(k, k): v for k, v in mesh_options.items()
               if k not in _REPAIR_OPTIONS}
    _check_mass_options(options["density"], options["mass"])
    options["repairs"] = _repairs(*(mesh_options[k] for k in _REPAIR_OPTIONS))
    return options


@cli.command()
@click.argument("meshes", nargs=-1)
@mass_options
@click.option("--json", "as_json", is_flag=True,
              help="One JSON object per mesh, one per line (the same as --format json).")
@click.option("--format", "output_format", type=click.Choice(INSPECT_FORMATS), default="table",
              show_default=True,
              help="table: for people; json (= --json): one object per line; csv: a header and "
                   "one row per mesh (columns in the README); urdf/sdf/mjcf: the format's "
                   "<inertial> element per mesh (about the COM, mesh axes, round-trip digits).")
@click.option("--principal", is_flag=True,
              help="With --format mjcf: quat + diaginertia instead of fullinertia.")
@click.option("--jobs", "-j", type=click.IntRange(min=1), default=None,
              help="Worker processes [default: the cores this process may use]. 1: one "
                   "process, as before; a small batch runs in one process anyway.")
@click.option("--recursive", "-r", is_flag=True,
              help="A directory MESH includes its sub-directories.")
@click.option("--files-from", metavar="FILE", default=None,
              help="Also inspect the paths listed in FILE, one per line ('-': standard input).")
@click.option("-0", "--null", is_flag=True,
              help="The --files-from list is NUL-separated (as find -print0 writes it).")
@click.option("--scheduler", metavar="ADDRESS", default=None,
              help="Run on the Dask cluster of this scheduler (pip install 'massprops[dask]'); "
                   "workers must see the same paths.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar and no summary line.")
@click.pass_context
def inspect(ctx: click.Context, meshes: tuple[str, ...], as_json: bool, output_format: str,
            principal: bool, jobs: int | None, recursive: bool, files_from: str | None,
            null: bool, scheduler: str | None, quiet: bool, **mesh_options: Any) -> None:
    """Mass, centre of mass, inertia tensor, principal moments and axes of each MESH.

    MESH is a file (OBJ, STL, .vf/.vtx/.fac, PLY, OFF, ...), '-' for standard input, a
    directory (the mesh files in it; with --recursive, also below), or a quoted glob pattern
    ('parts/**/*.stl'). Results come in input order; a file that fails is reported and the
    others go on; the exit code is the worst.
    """
    options = _inspect_kwargs(mesh_options)
    if as_json and output_format not in ("table", "json"):
        raise click.UsageError(f"--json is --format json; give one of --json and --format "
                               f"{output_format}")
    if principal and output_format != "mjcf":
        raise click.UsageError("--principal goes with --format mjcf (quat + diaginertia)")
    out_format = "json" if as_json else output_format
    if not meshes and files_from is None:
        raise click.UsageError("give MESH arguments or --files-from FILE")
    if "-" in meshes and options["format"] is None:
        raise click.UsageError("reading standard input ('-') needs --input-format")
    if "-" in meshes and files_from == "-":
        raise click.UsageError("'-' and --files-from - both read standard input; give one")
    if null and files_from is None:
        raise click.UsageError("-0/--null describes the --files-from list; give --files-from")
    if scheduler is not None and jobs is not None:
        raise click.UsageError("--jobs and --scheduler contradict: the cluster's workers run "
                               "the batch; give one")
    from massprops.batch import dask_executor, expand_inputs, inspect_many
    from massprops.batch.inputs import stands_for_many

    inputs = expand_inputs(meshes, recursive=recursive, files_from=files_from, null=null)
    if files_from is None:  # the whole list is known: the progress bar can count down
        inputs = list(inputs)
    summary = not quiet and (sys.stderr.isatty() or files_from is not None
                             or any(stands_for_many(m) for m in meshes))
    executor, workers, client = None, None, None
    if scheduler is not None:
        try:
            executor, workers, client = dask_executor(scheduler)
        except UsageError as exc:  # not installed, or not reachable
            _say_error(str(exc))
            ctx.exit(exit_code(exc))
    try:
        batch = inspect_many(inputs, executor, jobs=jobs, workers=workers, **options)
        code = _report_batch(ctx, batch, out_format, summary, quiet, principal)
    finally:
        if client is not None:
            client.close()
        from massprops.batch.pool import end_helper_processes

        end_helper_processes()
    ctx.exit(code)


def _report_batch(ctx: click.Context, batch: Any, out_format: str, summary: bool,
                  quiet: bool, principal: bool) -> int:
    """Print every record of ``batch`` as it comes; the worst exit code. Ctrl-C: print what
    was finished, the summary, and let main() exit 130."""
    import time

    progress = None
    if not quiet and sys.stderr.isatty():
        from massprops.report import BatchProgress

        progress = BatchProgress()
    start = time.monotonic()
    counts = {"done": 0, "failed": 0, "worst": 0}

    def show(record: Any) -> None:
        code = _show_record(ctx, record, out_format, principal)
        counts["failed" if code else "done"] += 1
        counts["worst"] = max(counts["worst"], code)

    def say_summary(interrupted: bool) -> None:
        if progress is not None:
            progress.close()
        n = counts["done"] + counts["failed"]
        if not summary or (n < 2 and not interrupted):  # one file: its own lines say it all
            return
        elapsed = time.monotonic() - start
        rate = f"{n / elapsed:.3g} files/s" if elapsed > 0 else "-"
        of = f" of {batch.total}" if interrupted and batch.total is not None else (
            f" of {batch.seen}+" if interrupted else "")
        click.echo(f"massprops: {n}{of} files in {elapsed:.3g} s ({rate}): "
                   f"{counts['done']} done, {counts['failed']} failed", err=True)

    ctrl_c = _CtrlC()
    try:
        with ctrl_c.deferred():
            if out_format == "csv":
                from massprops.batch.table import csv_header

                _to_stdout(lambda: _echo_text(csv_header()))
        for record in batch:  # Ctrl-C lands here, while waiting for the next record
            with ctrl_c.deferred():  # ... never half-way through printing one
                show(record)
                if progress is not None:
                    progress.update(counts["done"], counts["failed"], batch.total)
    except _StdoutClosed:
        batch.interrupt()
        _silence_stdout()
        say_summary(interrupted=True)
        return max(counts["worst"], 1)  # the output could not be written
    except KeyboardInterrupt:
        with ctrl_c.deferred():  # a second Ctrl-C waits until the workers are stopped
            for record in batch.interrupt():
                show(record)
            say_summary(interrupted=True)
        raise
    finally:
        batch.close()
        ctrl_c.restore()
        if progress is not None:
            progress.close()
    say_summary(interrupted=False)
    return counts["worst"]


class _CtrlC:
    """Ctrl-C (SIGINT) as KeyboardInterrupt, except inside ``deferred()`` blocks, where it is
    held until the block ends: a record is printed and counted whole or not taken at all."""

    def __init__(self) -> None:
        import signal
        import threading

        self.held = self.holding = False
        self.previous = None
        if threading.current_thread() is threading.main_thread():
            self.previous = signal.signal(signal.SIGINT, self._handler)

    def _handler(self, signum: int, frame: Any) -> None:
        if self.holding:
            self.held = True
        else:
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def deferred(self) -> Iterator[None]:
        self.holding = True
        try:
            yield
        finally:
            self.holding = False
        if self.held:
            self.held = False
            raise KeyboardInterrupt

    def restore(self) -> None:
        if self.previous is not None:
            import signal

            signal.signal(signal.SIGINT, self.previous)
            self.previous = None


class RemoteError(Exception):
    """--debug: an input failed in a worker process; the message is the worker's traceback."""


def _show_record(ctx: click.Context, record: Any, out_format: str, principal: bool) -> int:
    """Print one record (warnings and errors on stderr); its exit code."""
    error = record.error
    if error is not None:
        if ctx.obj.get("debug"):
            raise error.exception or RemoteError(error.traceback or error.message)
        _say_error(error.message)
        if out_format == "csv":
            from massprops.batch.table import csv_row

            _to_stdout(lambda: _echo_text(csv_row(record)))
        return error.exit_code

    def emit() -> None:
        for w in record.warnings:
            _say_warning(record.file, w)
        if out_format == "json":
            _to_stdout(lambda: _emit_json(record.data))
        elif out_format == "csv":
            from massprops.batch.table import csv_row

            _to_stdout(lambda: _echo_text(csv_row(record)))
        elif out_format in ELEMENT_FORMATS:
            from massprops.robot.elements import WRITERS

            d = record.data
            _to_stdout(lambda: click.echo(f"<!-- {record.file} -->"))
            element = WRITERS[out_format](d["mass"], d["center_of_mass"], d["inertia"],
                                          principal=principal)
            _to_stdout(lambda: click.echo(element))
        else:
            from massprops.report import print_inspection

            _to_stdout(lambda: print_inspection(record.data, record.repaired))

    return _guarded(ctx, emit)


class _StdoutClosed(BaseException):
    """Standard output was closed by its reader (``... | head``): the batch stops (no error
    line per remaining file, no work for nobody). A BaseException, so _guarded lets it by."""


def _to_stdout(write: Callable[[], None]) -> None:
    try:
        write()
    except BrokenPipeError as exc:
        raise _StdoutClosed from exc


def _silence_stdout() -> None:
    """Point the closed stdout at /dev/null, so that the flush at exit does not fail again."""
    import os

    with contextlib.suppress(OSError, ValueError, AttributeError):  # no real descriptor
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _echo_text(text: str) -> None:
    """Text to stdout as is; a file name that is not valid UTF-8 (decoded with surrogate
    escapes) goes out as its original bytes."""
    try:
        click.echo(text, nl=False)
    except UnicodeEncodeError:
        click.echo(text.encode("utf-8", "surrogateescape"), nl=False)


@cli.command()
@click.argument("description", metavar="FILE")
@click.option("--json", "as_json", is_flag=True, help="One JSON object per link, one per line.")
@click.option("--check", "rtol", type=float, default=None, metavar="RTOL",
              callback=_non_negative,
              help="Exit 4 if any link's stated inertial differs from its geometry by more than "
                   "RTOL (mass, COM / link size, inertia in the 2-norm; all relative).")
@click.option("--write", "output_path", default=None, metavar="OUT",
              help="Write the description with the computed inertials (never over FILE).")
@click.option("--force", is_flag=True, help="Replace OUT if it exists (never FILE).")
@click.option("--from", "source", type=click.Choice(("collision", "visual")),
              default="collision", show_default=True, help="Which geometry makes the link.")
@click.option("--density", type=float, callback=_positive,
              help="Density in kg/m³ for every geometry (default: keep each stated mass).")
@click.option("--package-path", "package_paths", multiple=True, metavar="DIR",
              help="Folder holding packages for package:// and model:// (repeatable; "
                   "ROS_PACKAGE_PATH is searched too).")
@click.option("--allow-open", is_flag=True, help="Compute open meshes anyway (with warnings).")
@click.pass_context
def model(ctx: click.Context, description: str, as_json: bool, rtol: float | None,
          output_path: str | None, force: bool, source: str, density: float | None,
          package_paths: tuple[str, ...], allow_open: bool) -> None:
    """Inertials of every link of a robot description (URDF, SDF or MJCF FILE) from its meshes
    and primitives, against the inertials it states."""
    link_errors = []

    def run() -> None:
        from massprops.robot.analyze import analyze_model

        report = analyze_model(description, source=source, density=density,
                               package_paths=package_paths, allow_open=allow_open)
        for w in report.model.warnings:
            _say_warning(description, w)
        for line in report.errors:
            _say_error(line)
        link_errors.extend(report.errors)
        if as_json:
            for r in report.links:
                _emit_json(r.as_dict(description))
        else:
            from massprops.report import print_model

            print_model(report, rtol)
        if output_path is not None:
            report.write(output_path, force=force)
        if rtol is not None:
            report.require_agreement(rtol)

    code = _guarded(ctx, run)
    ctx.exit(max(code, 1 if link_errors else 0))


@cli.command()
@click.argument("input_path", metavar="IN")
@click.argument("output_path", metavar="OUT")
@mass_options
@click.option("--force", is_flag=True, help="Replace OUT if it exists (never IN).")
@click.option("--json", "as_json", is_flag=True, help="Print the applied map as JSON.")
@click.pass_context
def align(ctx: click.Context, input_path: str, output_path: str, density: float | None,
          total_mass: float | None, unit: str, allow_open: bool, input_format: str | None,
          fill_holes: bool, max_hole: float | None, union: bool, shell: float | None,
          force: bool, as_json: bool) -> None:
    """Write OUT: the mesh IN moved into its principal frame (COM at the origin, axes along the
    principal axes, ascending moments). Faces and winding are unchanged; with --union OUT is
    the united mesh, with --fill-holes the capped one."""
    _check_mass_options(density, total_mass)
    repairs = _repairs(fill_holes, max_hole, union, shell)

    def run() -> None:
        from massprops.align import align_mesh
        from massprops.analysis import inspect_file
        from massprops.io import write_mesh

        result = inspect_file(input_path, format=input_format, unit=unit, density=density,
                              mass=total_mass, allow_open=allow_open, repairs=repairs)
        for w in result.warnings:
            _say_warning(result.mesh.name, w)
        aligned = align_mesh(result.mesh, result.properties)
        write_mesh(aligned.mesh, output_path, force=force, protect=(input_path,))
        if as_json:
            extra = {} if result.repairs is None else {
                "repairs": {key: record.as_dict() for key, record in result.repairs.items()}}
            _emit_json({"input": input_path, "output": output_path, **aligned.as_dict(), **extra})
        else:
            from massprops.report import print_alignment

            print_alignment(input_path, output_path, aligned, result.repairs)

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
        for note in scene.notes:  # already placed: "scene.yaml:LINE: ..."
            click.echo(f"massprops: warning: {note}", err=True)
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
