"""``massprops inspect``: one mesh or a batch of many (local processes or a Dask cluster), printed
in input order as table, JSON, CSV or a robot format's inertial element."""

from __future__ import annotations

import functools
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import click

from massprops.cli.app import cli
from massprops.cli.common import (
    ELEMENT_FORMATS,
    INSPECT_FORMATS,
    CtrlC,
    StdoutClosed,
    cli_text,
    element_comment,
    emit_json,
    guarded,
    inspect_kwargs,
    mass_options,
    say_error,
    say_warning,
    silence_stdout,
    to_stdout,
)
from massprops.errors import UsageError, error_message, exit_code


@cli.command()
@click.argument("meshes", nargs=-1)
@mass_options
@click.option("--json", "as_json", is_flag=True,
              help="One JSON object per mesh, one per line (the same as --format json).")
@click.option("--format", "output_format", type=click.Choice(INSPECT_FORMATS), default="table",
              show_default=True,
              help="table: for people; json (= --json): one object per line; csv: a header and "
                   "one row per mesh (columns in the README); urdf/sdf/mjcf: the format's "
                   "<inertial> element per mesh (about the COM, mesh axes, round-trip digits); "
                   "gltf: the KHR_physics_rigid_bodies motion per mesh (JSON lines); usd: a "
                   "usda prim with PhysicsMassAPI per mesh (both principal moments and axes).")
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
@click.option("--density-map", metavar="FILE.yaml", default=None,
              help="CAD files: solid names or glob patterns to densities in kg/m³ (first "
                   "match in file order; others take --density).")
@click.option("--write-physics", metavar="OUT", default=None,
              help="MESH is one glTF asset (.glb/.gltf): write a copy to OUT (same extension) "
                   "with the KHR_physics_rigid_bodies motion on each mesh node, in the node's "
                   "space; --mass is the asset's total. Prints one motion per node.")
@click.option("--force", is_flag=True, help="With --write-physics: replace OUT if it exists "
                                             "(never MESH).")
@click.pass_context
def inspect(ctx: click.Context, meshes: tuple[str, ...], as_json: bool, output_format: str,
            principal: bool, jobs: int | None, recursive: bool, files_from: str | None,
            null: bool, scheduler: str | None, quiet: bool, density_map: str | None,
            write_physics: str | None, force: bool, **mesh_options: Any) -> None:
    """Mass, centre of mass, inertia tensor, principal moments and axes of each MESH.

    MESH is a file (OBJ, STL, .vf/.vtx/.fac, PLY, OFF, ...), '-' for standard input, a
    directory (the mesh files in it; with --recursive, also below), or a quoted glob pattern
    ('parts/**/*.stl'). Results come in input order; a file that fails is reported and the
    others go on; the exit code is the worst.
    """
    options = inspect_kwargs(mesh_options)
    if as_json and output_format not in ("table", "json"):
        raise click.UsageError(f"--json is --format json; give one of --json and --format "
                               f"{output_format}")
    if principal and output_format != "mjcf":
        raise click.UsageError("--principal goes with --format mjcf (quat + diaginertia)")
    out_format = "json" if as_json else output_format
    if not meshes and files_from is None:
        raise click.UsageError("give MESH arguments or --files-from FILE")
    if write_physics is not None:
        ctx.exit(_write_physics(ctx, meshes, write_physics, force, out_format, options,
                                files_from=files_from, jobs=jobs, scheduler=scheduler,
                                recursive=recursive, density_map=density_map))
    if force:
        raise click.UsageError("--force goes with --write-physics (replace OUT)")
    from massprops.cad import is_cad_path  # no OpenCASCADE: extensions only

    cad_files = [m for m in meshes if is_cad_path(m)]
    if cad_files:
        if len(cad_files) < len(meshes) or files_from is not None:
            raise click.UsageError("give CAD files (.step .stp .iges .igs .brep) and meshes "
                                   "in separate commands")
        from massprops.cli.cad import inspect_cad_files  # the CAD branch, named files only

        ctx.exit(inspect_cad_files(ctx, meshes, out_format, principal, options, density_map))
    if density_map is not None:
        raise click.UsageError("--density-map applies to CAD files (.step .stp .iges .igs "
                               ".brep)")
    if "-" in meshes and options["format"] is None:
        raise click.UsageError("reading standard input ('-') needs --input-format")
    if "-" in meshes and files_from == "-":
        raise click.UsageError("'-' and --files-from - both read standard input; give one")
    if null and files_from is None:
        raise click.UsageError("-0/--null describes the --files-from list; give --files-from")
    if scheduler is not None and jobs is not None:
        raise click.UsageError("--jobs and --scheduler contradict: the cluster's workers run "
                               "the batch; give one")
    # deferred: each command imports only what it runs (start-up of the others)
    from massprops.batch import dask_executor, expand_inputs, inspect_many
    from massprops.batch.inputs import stands_for_many

    inputs: Iterable[Any] = expand_inputs(meshes, recursive=recursive, files_from=files_from,
                                          null=null)
    if files_from is None:  # the whole list is known: the progress bar can count down
        inputs = list(inputs)
    summary = not quiet and (sys.stderr.isatty() or files_from is not None
                             or any(stands_for_many(m) for m in meshes))
    executor, workers, client = None, None, None
    if scheduler is not None:
        try:
            executor, workers, client = dask_executor(scheduler)
        except UsageError as exc:  # not installed, or not reachable
            say_error(error_message(exc))
            ctx.exit(exit_code(exc))
    try:
        batch = inspect_many(inputs, executor, jobs=jobs, workers=workers, **options)
        code = _report_batch(ctx, batch, out_format, summary, quiet, principal)
    finally:
        if client is not None:
            client.close()
        # deferred: each command imports only what it runs (start-up of the others)
        from massprops.batch.pool import end_helper_processes

        end_helper_processes()
    ctx.exit(code)


_PHYSICS_FORMATS = ("table", "json", "gltf")
"""What --write-physics prints per mesh node: a line, a JSON object with the node, the motion."""


def _write_physics(ctx: click.Context, meshes: tuple[str, ...], out: str, force: bool,
                   out_format: str, options: dict[str, Any], **batch: Any) -> int:
    """--write-physics: one glTF asset in, its copy with motions out; the exit code."""
    used = [f"--{k.replace('_', '-')}" for k, v in batch.items() if v not in (None, False)]
    used += [flag for key, flag in (("format", "--input-format"), ("unit", "--unit"))
             if options[key] not in (None, "m")]
    if len(meshes) != 1 or meshes[0] == "-" or used:
        why = f"not {', '.join(used)}" if used else "one MESH file"
        raise click.UsageError(f"--write-physics reads one glTF file (.glb/.gltf, metres): {why}")
    if out_format not in _PHYSICS_FORMATS:
        raise click.UsageError(f"--write-physics prints {', '.join(_PHYSICS_FORMATS)}, not "
                               f"--format {out_format}")
    # deferred: only --write-physics reads and writes glTF assets
    from massprops.robot.write.physics import write_physics

    def run() -> None:
        motions = write_physics(meshes[0], out, density=options["density"],
                                mass=options["mass"], allow_open=options["allow_open"],
                                repairs=options["repairs"], force=force)
        for done in motions:
            for w in done.warnings:
                say_warning(f"{meshes[0]}: mesh {done.mesh}", w)
            if out_format == "json":
                obj = {"file": meshes[0], "output": out, **done.as_dict()}
                to_stdout(functools.partial(emit_json, obj))
            elif out_format == "gltf":
                to_stdout(functools.partial(emit_json, done.motion))
            else:
                name = "" if done.name is None else f" {done.name!r}"
                com = ", ".join(f"{x:.6g}" for x in done.motion["centerOfMass"])
                line = (f"{out}: node {done.node}{name} (mesh {done.mesh}): mass "
                        f"{done.motion['mass']:.6g} kg, centre of mass [{com}] m")
                to_stdout(functools.partial(click.echo, line))

    return guarded(ctx, run)


def _report_batch(ctx: click.Context, batch: Any, out_format: str, summary: bool,
                  quiet: bool, principal: bool) -> int:
    """Print every record of ``batch`` as it comes; the worst exit code. Ctrl-C: print what
    was finished, the summary, and let main() exit 130."""
    import time

    progress = None
    if not quiet and sys.stderr.isatty():
        # deferred: rich loads only for human-readable output
        from massprops.cli.report import BatchProgress

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

    ctrl_c = CtrlC()
    try:
        with ctrl_c.deferred():
            if out_format == "csv":
                # deferred: csv loads only for --format csv
                from massprops.batch.table import csv_header

                to_stdout(lambda: _echo_text(csv_header()))
        for record in batch:  # Ctrl-C lands here, while waiting for the next record
            with ctrl_c.deferred():  # ... never half-way through printing one
                show(record)
                if progress is not None:
                    progress.update(counts["done"], counts["failed"], batch.total)
    except StdoutClosed:
        batch.interrupt()
        silence_stdout()
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


class RemoteError(Exception):
    """--debug: an input failed in a worker process; the message is the worker's traceback."""


def _show_record(ctx: click.Context, record: Any, out_format: str, principal: bool) -> int:
    """Print one record (warnings and errors on stderr); its exit code."""
    error = record.error
    if error is not None:
        if ctx.obj.get("debug"):
            raise error.exception or RemoteError(error.traceback or error.message)
        say_error(error.message)
        if out_format == "csv":
            # deferred: csv loads only for --format csv
            from massprops.batch.table import csv_row

            to_stdout(lambda: _echo_text(csv_row(record)))
        return error.exit_code

    def emit() -> None:
        for w in record.warnings:
            say_warning(record.file, w)
        if out_format == "json":
            to_stdout(lambda: emit_json(record.data))
        elif out_format == "csv":
            # deferred: csv loads only for --format csv
            from massprops.batch.table import csv_row

            to_stdout(lambda: _echo_text(csv_row(record)))
        elif out_format in ELEMENT_FORMATS:
            # deferred: only --format urdf|sdf|mjcf writes elements
            from massprops.robot.write.elements import WRITERS

            d = record.data
            comment = element_comment(out_format, str(record.file))
            if comment is not None:
                to_stdout(lambda: click.echo(comment))
            named = {"name": Path(str(record.file)).stem} if out_format == "usd" else {}
            element = WRITERS[out_format](d["mass"], d["center_of_mass"], d["inertia"],
                                          principal=principal, **named)
            to_stdout(lambda: click.echo(element))
        else:
            # deferred: rich loads only for human-readable output
            from massprops.cli.report import print_inspection

            to_stdout(lambda: print_inspection(record.data, record.repaired))

    return guarded(ctx, emit)


def _echo_text(text: str) -> None:
    """Text to stdout as is; a file name that is not valid UTF-8 (decoded with surrogate
    escapes) goes out as its original bytes. Settings the library names are said as options."""
    text = cli_text(text)
    try:
        click.echo(text, nl=False)
    except UnicodeEncodeError:
        click.echo(text.encode("utf-8", "surrogateescape"), nl=False)
