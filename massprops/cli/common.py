"""What every command shares: the stderr lines, the error boundary, JSON output, option
validators and the mesh options of inspect and align (with their translation into the library's
keyword arguments)."""

from __future__ import annotations

import contextlib
import json
import os
import re
import sys
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import click

from massprops.errors import error_message, exit_code, format_traceback, render_settings

UNIT_CHOICES = ("m", "cm", "mm", "um", "in", "ft")
"""The keys of massprops.io.UNITS, written out so that building the CLI does not import the
readers (tests/test_cli.py checks the two agree)."""


ELEMENT_FORMATS = ("urdf", "sdf", "mjcf", "gltf", "usd")
"""The keys of massprops.robot.elements.WRITERS, written out so that ``inspect`` never imports
the robot package to build its options (tests/test_robot_cli.py checks the two agree)."""


def element_comment(fmt: str, text: str) -> str | None:
    """The line naming the file above a format's element: an XML comment, a usda ``#``
    comment, none for glTF (one JSON object per line, which has no comments)."""
    return {"gltf": None, "usd": f"# {text}"}.get(fmt, f"<!-- {text} -->")


INSPECT_FORMATS = ("table", "json", "csv", *ELEMENT_FORMATS)
"""inspect --format: the human table, one JSON object per line, CSV (massprops.batch.table), the
robot formats' <inertial> elements."""


def flag(name: str) -> str:
    """A setting a library message refers to (`massprops.errors.setting_ref`), as the command
    line says it: an option ``--max-hole``; a scene key with the option that overrides it,
    ``time.rtol (or --rtol)``."""
    if "." in name:
        return f"{name} (or --{name.rpartition('.')[2].replace('_', '-')})"
    return "--" + name.replace("_", "-")


def cli_text(text: str) -> str:
    """A library message with the settings it names said as options (see `flag`)."""
    return render_settings(text, flag)


def say_error(message: str) -> None:
    click.echo(f"massprops: error: {fitted(cli_text(message))}", err=True)


def say_warning(name: str, message: str) -> None:
    click.echo(f"massprops: warning: {name}: {fitted(cli_text(message))}", err=True)


def say_notes(notes) -> None:
    """A run's notes (each already says its file), as warnings."""
    for note in notes:
        click.echo(f"massprops: warning: {fitted(cli_text(note))}", err=True)


SCENE_COMMANDS = ("simulate", "precision")
"""Commands that read a scene file: an inspect option in a message becomes its scene key."""


def command_options(command: click.Command) -> set[str]:
    """The long options (without dashes) a command and the top-level group accept."""
    ctx = click.get_current_context(silent=True)
    group = ctx.find_root().command.params if ctx is not None else []
    return {opt[2:] for p in [*command.params, *group]
            for opt in [*getattr(p, "opts", []), *getattr(p, "secondary_opts", [])]
            if opt.startswith("--")}


def fitted(message: str) -> str:
    """``message`` naming only options the running command has (`messages.fit_message`)."""
    ctx = click.get_current_context(silent=True)
    if ctx is None or "--" not in message:
        return message
    from massprops.cli.messages import fit_message  # only for messages that name options

    return fit_message(message, command_options(ctx.command),
                       scene=ctx.info_name in SCENE_COMMANDS)


def say_traceback(text: str) -> None:
    """--debug: a traceback (`massprops.errors.format_traceback`, or a worker's) on stderr, the
    settings its messages name said as this command's options, as the one-line errors are."""
    click.echo(fitted(cli_text(text)).rstrip("\n"), err=True)


def estimate_said(value: float | None, interrupted: bool, spec: str = ".3g") -> str:
    """A run's error estimate in a table: the number (in the format ``spec``), or why there is
    none (a run stopped by Ctrl-C has no companion runs to compare with; otherwise a companion
    diverged or was cut off by the run bound)."""
    if value is not None:
        return format(value, spec)
    return ("not estimated (interrupted)" if interrupted
            else "not estimated (its companion runs failed or hit the run bound)")


def say_note(message: str) -> None:
    """A note on stderr while something slow and one-off happens (never on --json stdout)."""
    click.echo(f"massprops: {message}", err=True)


def guarded(ctx: click.Context, fn: Callable[[], Any]) -> int:
    """Run ``fn``; turn any exception into one stderr line and the contract's exit code (with
    --debug: its traceback instead of the line, and the same exit code)."""
    try:
        fn()
        return 0
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # ours, a bug or an environment failure: one line, no traceback
        if ctx.obj.get("debug"):
            say_traceback(format_traceback(exc))
            return exit_code(exc)
        say_error(error_message(exc))
        return exit_code(exc)


def emit_json(obj: dict) -> None:
    # allow_nan=False: a NaN reaching the output is a bug to surface, never a number to print
    text = json.dumps(obj, allow_nan=False)
    if "\\u001f" in text:  # a message of the library's naming a setting (see `flag`)
        text = re.sub(r"\\u001f([a-z_.]+)\\u001f", lambda m: flag(m[1]), text)
    click.echo(text)


class RegistryChoice(click.ParamType):
    """A choice whose values come from a registry, loaded on first use, so that building the
    command line never imports what only one command needs (numba for the integrators, the
    readers for the formats). ``normalize`` turns a value into the registry's key (formats:
    case-insensitive, a leading dot allowed). A value not in the registry is a usage error
    (exit 2) listing the registry's values."""

    name = "choice"

    def __init__(self, loader: Callable[[], Sequence[str]],
                 normalize: Callable[[str], str] | None = None) -> None:
        self.loader, self.normalize = loader, normalize

    def get_metavar(self, *args: Any, **kwargs: Any) -> str:
        return "[" + "|".join(self.loader()) + "]"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> str:
        choices = self.loader()
        key = value if self.normalize is None else self.normalize(value)
        if key not in choices:
            self.fail(f"{value!r} is not one of {', '.join(choices)}", param, ctx)
        return key


def _input_formats() -> list[str]:
    # deferred: the readers' registry, only when --input-format is given
    from massprops.io import input_formats

    return input_formats()


def _format_key(name: str) -> str:
    # deferred: the readers' registry, only when --input-format is given
    from massprops.io.registry import format_key

    return format_key(name)


def check_outputs(outputs: Sequence[tuple[str | None, Any]], *, force: bool,
                  inputs: Sequence[str]) -> None:
    """The output rule (`massprops.io.atomic`: an extension the command can write, no input,
    not existing without --force, a writable folder) for every (path, `OutputKind`) a command
    will write, before any work; a path None is not asked for. No output may be another."""
    # deferred: only a command that writes files needs the rule
    from massprops.io.atomic import check_output

    written: list[str] = []
    for path, kind in outputs:
        if path:
            check_output(path, kind, force=force, protect=[*inputs, *written])
            written.append(path)


def positive(ctx: click.Context, param: click.Parameter, value: float | None) -> float | None:
    import math

    if value is not None and not (math.isfinite(value) and value > 0):
        raise click.BadParameter(f"must be a positive finite number, got {value!r}")
    return value


def non_negative(ctx: click.Context, param: click.Parameter,
                  value: float | None) -> float | None:
    import math

    if value is not None and not (math.isfinite(value) and value >= 0):
        raise click.BadParameter(f"must be a finite number >= 0, got {value!r}")
    return value


def fraction(ctx: click.Context, param: click.Parameter, value: float | None) -> float | None:
    import math

    if value is not None and not (math.isfinite(value) and 0 < value <= 1):
        raise click.BadParameter(f"must be a fraction in (0, 1], got {value!r}")
    return value


def mass_options(f: Callable) -> Callable:
    """--density / --mass / --unit / --allow-open / --input-format and the repairs (--union,
    --shell, --fill-holes, --max-hole), shared by inspect and align."""
    for opt in reversed([
        click.option("--density", type=float, callback=positive,
                     help="Density in kg/m³ (default 1)."),
        click.option("--mass", "total_mass", type=float, callback=positive,
                     help="Total mass in kg; the density follows from the volume."),
        click.option("--unit", type=click.Choice(UNIT_CHOICES), default="m", show_default=True,
                     help="Unit of the file's coordinates; results are always SI."),
        click.option("--allow-open", is_flag=True,
                     help="Compute an open mesh anyway (the result is then ill-defined; "
                          "warnings say by how much)."),
        click.option("--input-format", default=None, metavar="FORMAT",
                     type=RegistryChoice(_input_formats, _format_key),
                     help="Format of the input, a name of the formats massprops reads (obj, "
                          "stl, ply, ...; required for '-' = standard input)."),
        *_repair_flags(),
    ]):
        f = opt(f)
    return f


def _repair_flags() -> list:
    return [
        click.option("--fill-holes", is_flag=True,
                     help="Cap each hole (boundary loop) with a triangulation that keeps its "
                          "shape; the error bar covers the choice of cap."),
        click.option("--max-hole", type=float, callback=fraction, metavar="FRACTION",
                     help="With --fill-holes: the largest cap accepted, as a fraction of the "
                          "surface area (default 0.1); larger loops are openings and refused."),
        click.option("--union", is_flag=True,
                     help="Replace overlapping or nested pieces by the solid they occupy "
                          "together (cavities stay empty), instead of counting overlaps twice."),
        click.option("--shell", type=float, callback=positive, metavar="THICKNESS",
                     help="The surface as a wall of this thickness, in METRES whatever --unit "
                          "says (mid-surface model; open and flat surfaces too)."),
    ]


def robot_file_options(f: Callable) -> Callable:
    """--package-path / --xacro-arg: how a robot description's references resolve, shared by
    model and simulate (a description given directly; a `model:` scene has the keys
    package_path and xacro_args). --xacro-arg arrives as a dict NAME -> VALUE."""
    for opt in reversed([
        click.option("--package-path", "package_paths", multiple=True, metavar="DIR",
                     help="Folder holding packages for package:// and model:// (repeatable; "
                          "ROS_PACKAGE_PATH is searched too)."),
        click.option("--xacro-arg", "xacro_args", multiple=True, metavar="NAME:=VALUE",
                     callback=_xacro_args,
                     help="An argument for a .xacro FILE (repeatable), as `xacro FILE "
                          "NAME:=VALUE`: the value of $(arg NAME)."),
    ]):
        f = opt(f)
    return f


def _xacro_args(ctx: click.Context, param: click.Parameter,
                values: tuple[str, ...]) -> dict[str, str]:
    if not values:
        return {}
    # deferred: the xacro rules load only when an argument is given
    from massprops.robot.formats.xacro_run import parse_xacro_arg

    out = {}
    for text in values:
        try:
            name, value = parse_xacro_arg(text)
        except ValueError as exc:
            raise click.BadParameter(str(exc)) from exc
        out[name] = value
    return out


def repair_flags(f: Callable) -> Callable:
    """--fill-holes / --max-hole / --union / --shell alone (``model`` applies them per mesh)."""
    for opt in reversed(_repair_flags()):
        f = opt(f)
    return f


def check_mass_options(density: float | None, total_mass: float | None) -> None:
    if density is not None and total_mass is not None:
        raise click.UsageError("give --density or --mass, not both")


def repair_options(fill_holes: bool, max_hole: float | None, union: bool, shell: float | None):
    """The library's RepairOptions, or None when no repair is asked (nothing imported then)."""
    if max_hole is not None and not fill_holes:
        raise click.UsageError("--max-hole applies to --fill-holes; add --fill-holes")
    if not (fill_holes or union or shell is not None):
        return None
    # deferred: each command imports only what it runs (start-up of the others)
    from massprops.repair import RepairOptions

    return RepairOptions(union=union, shell=shell, fill_holes=fill_holes, max_hole=max_hole)


_RENAMED = {"total_mass": "mass", "input_format": "format"}
"""CLI option names that differ from inspect_file's keyword arguments; every other shared mesh
option reaches inspect_file (and the batch workers) under its own name."""


_REPAIR_OPTIONS = ("fill_holes", "max_hole", "union", "shell")
"""The mesh options inspect_file takes together, as one ``repairs=RepairOptions``."""


def inspect_kwargs(mesh_options: dict[str, Any]) -> dict[str, Any]:
    """inspect_file's keyword arguments from the shared mesh options (`mass_options`)."""
    options = {_RENAMED.get(k, k): v for k, v in mesh_options.items()
               if k not in _REPAIR_OPTIONS}
    check_mass_options(options["density"], options["mass"])
    options["repairs"] = repair_options(*(mesh_options[k] for k in _REPAIR_OPTIONS))
    return options


# --- standard output closed by its reader (``... | head``) ---
class StdoutClosed(BaseException):
    """Standard output was closed by its reader (``... | head``): the batch stops (no error
    line per remaining file, no work for nobody). A BaseException, so guarded lets it by."""


def to_stdout(write: Callable[[], None]) -> None:
    try:
        write()
    except BrokenPipeError as exc:
        raise StdoutClosed from exc


def silence_stdout() -> None:
    """Point the closed stdout at /dev/null, so that the flush at exit does not fail again."""
    with contextlib.suppress(OSError, ValueError, AttributeError):  # no real descriptor
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


class CtrlC:
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
