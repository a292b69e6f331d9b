"""``massprops sweep``: a scene run once per sample with named values varied (`massprops.sweep`)."""

from __future__ import annotations

import json
import sys
from typing import Any

import click

from massprops.cli.app import cli
from massprops.cli.common import CtrlC, emit_json, guarded, say_note
from massprops.cli.dynamics import method_options

_ROWS_EXTENSIONS = {"csv": (".csv",), "json": (".jsonl", ".json")}


class _Counter:
    """Samples done, on stderr: a bar on a terminal (not with --quiet), else nothing."""

    def __init__(self, total: int, enabled: bool) -> None:
        self.bar: Any = None
        if enabled:
            # deferred: rich loads only for a bar on a terminal
            from rich.console import Console
            from rich.progress import Progress

            self.bar = Progress(console=Console(stderr=True), transient=True)
            self.bar.start()
            self.task = self.bar.add_task("sampling", total=total)

    def step(self) -> None:
        if self.bar is not None:
            self.bar.advance(self.task)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.stop()


@cli.command()
@click.argument("scene_path", metavar="SCENE")
@click.option("--vary", "varies", multiple=True, metavar="KEY=SPEC",
              help="A scene value and how it varies (repeatable): KEY a path such as "
                   "body.mass, bodies.upper.inertia, body.center_of_mass[2], "
                   "forces[0].stiffness, initial.angular_velocity[1]; SPEC normal:MEAN:SD, "
                   "uniform:LOW:HIGH, lognormal:MEDIAN:FACTOR, relative:P (e.g. relative:5%) "
                   "or values:A,B,C.")
@click.option("--samples", type=click.IntRange(min=1), default=None,
              help="Draws (per grid point); not needed when every value is a grid.")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True,
              help="Sample i's draws depend on the seed and i only.")
@click.option("--bars", "use_bars", is_flag=True,
              help="Draw every mesh body's mass, centre of mass and inertia within the error "
                   "bars inspect reports for its mesh (each bar a bound: uniform within it).")
@click.option("--bars-scale", type=float, default=None, metavar="K",
              help="Widen --bars K times (e.g. to a density or machining tolerance); "
                   "default 1.")
@click.option("--jobs", "-j", type=click.IntRange(min=1), default=None,
              help="Local worker processes (default, for a sweep of more than a few seconds: "
                   "one per core, or per two cores with the error estimate; else this process).")
@click.option("--scheduler", metavar="ADDRESS", default=None,
              help="Run on the Dask cluster of this scheduler (pip install 'massprops[dask]').")
@click.option("--outputs", "outputs", default=None, metavar="NAME,...",
              help="What each row reports, names into simulate's JSON (default: every body's "
                   "final position and angular velocity, every joint's final coordinates and "
                   "reaction force).")
@click.option("--json", "as_json", is_flag=True, help="JSON lines: the rows, then the summary.")
@click.option("--format", "out_format", type=click.Choice(["csv", "json"]), default=None,
              help="The rows as CSV (the summary then on stderr) or JSON lines.")
@click.option("--output", "output_path", default=None,
              help="Write the rows to this file (.csv, or .jsonl for JSON) instead of stdout.")
@method_options
@click.option("--plot", "plot_path", default=None,
              help="PNG of the outputs over time: the samples' median and 25-75 % and "
                   "5-95 % bands (pip install 'massprops[plot]').")
@click.option("--linear", is_flag=True,
              help="Add each output's derivative by each drawn value at the draws' centres, by "
                   "central differences of the engine's own runs, with its accuracy, and the "
                   "spread the delta method predicts from them.")
@click.option("--no-estimate", is_flag=True,
              help="Leave out each run's error estimate (about half the time).")
@click.option("--force", is_flag=True, help="Replace an existing --output file.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar.")
@click.pass_context
def sweep(ctx: click.Context, scene_path: str, varies: tuple[str, ...], samples: int | None,
          seed: int, use_bars: bool, bars_scale: float | None, jobs: int | None,
          scheduler: str | None, outputs: str | None,
          as_json: bool, out_format: str | None, output_path: str | None,
          integrator: str | None, rtol: float | None, step: float | None,
          plot_path: str | None, linear: bool,
          no_estimate: bool, force: bool, quiet: bool) -> None:
    """Run SCENE once per sample with the --vary values drawn; print one row per sample and
    a summary: each output's spread and its sensitivity to each value."""
    if as_json and out_format == "csv":
        raise click.UsageError("--json and --format csv contradict; give one")
    if scheduler is not None and jobs is not None:
        raise click.UsageError("--jobs and --scheduler contradict: the cluster's workers run "
                               "the sweep; give one")
    bars = (1.0 if bars_scale is None else bars_scale) if use_bars else None
    fmt = "json" if as_json else out_format
    state: dict[str, Any] = {"failed": False, "interrupted": False}

    def run() -> None:
        # deferred: each command imports only what it runs (start-up of the others)
        from massprops.batch.pool import end_helper_processes
        from massprops.dynamics.compiled.compiling import whole_process
        from massprops.errors import UsageError
        from massprops.io.atomic import OutputKind, atomic_write_bytes, check_output
        from massprops.sweep.session import Sweep

        if bars_scale is not None and not use_bars:  # one line, as the library's refusals
            raise UsageError("--bars-scale widens --bars; give --bars too")
        rows_format = fmt or ("json" if output_path and output_path.endswith((".json",
                                                                              ".jsonl"))
                              else "csv")
        kind = OutputKind("the rows", _ROWS_EXTENSIONS[rows_format], "output")
        if output_path:
            check_output(output_path, kind, force=force, protect=[scene_path])
        protect = [scene_path, *([output_path] if output_path else [])]
        if plot_path:
            # deferred: matplotlib (the plot extra) loads only for --plot
            from massprops.dynamics.plots import plot_output, require_matplotlib

            require_matplotlib()
            check_output(plot_path, plot_output(), force=force, protect=protect)
        whole_process()
        options: dict[str, Any] = {"estimate": not no_estimate}
        options.update({k: v for k, v in (("integrator", integrator), ("rtol", rtol),
                                          ("step", step)) if v is not None})
        try:
            with Sweep(scene_path, varies, samples=samples, seed=seed,
                       outputs=outputs.split(",") if outputs else None, options=options,
                       bars=bars, series=plot_path is not None, jobs=jobs,
                       scheduler=scheduler, notice=say_note) as sweeping:
                rows, lines, interrupted = _rows(sweeping, rows_format,
                                                 fmt is not None and not output_path, quiet)
        finally:
            end_helper_processes()
        state["interrupted"] = interrupted
        prepared = sweeping.prepared
        result = sweeping.summary(rows, linear=linear and not interrupted)
        if plot_path:
            sweeping.plot(rows, plot_path, force=force, protect=protect)
        # the summary: after JSON rows, in their stream; on stderr beside CSV rows; as a table
        # when no format was asked for (the rows then only in --output)
        if output_path:
            text = "\n".join(lines) + "\n"
            if rows_format == "json":
                text += _json_line(result) + "\n"
            atomic_write_bytes(output_path, text.encode(), force=force,  # type: ignore[arg-type]
                               protect=[scene_path])
        if fmt == "json" and not output_path:
            emit_json(result)
        elif fmt == "csv":
            click.echo(_json_line(result), err=True)
        elif fmt is None:
            # deferred: rich loads only for human-readable output
            from massprops.cli.report import print_sweep

            print_sweep(scene_path, prepared, result)
        state["failed"] = result["failed"] > 0

    code = guarded(ctx, run)
    if state["interrupted"] and code == 0:
        click.echo("massprops: interrupted; the rows done are kept", err=True)
        code = 130
    elif state["failed"] and code == 0:
        code = 3
    ctx.exit(code)


def _rows(sweeping: Any, rows_format: str, echo: bool,
          quiet: bool) -> tuple[list, list[str], bool]:
    """Run ``sweeping``: (the rows taken, their lines in ``rows_format``, whether Ctrl-C stopped
    it); each line printed as its row comes where ``echo``. A row is taken whole or not at all:
    Ctrl-C waits while one is printed and counted (`CtrlC`), so the summary counts exactly the
    rows shown."""
    from massprops.sweep import table as csv_table  # deferred: with the command's imports

    prepared = sweeping.prepared
    rows: list = []
    lines = [csv_table.csv_line(csv_table.header(prepared))] if rows_format == "csv" else []
    if echo and lines:
        click.echo(lines[0])
    counter = _Counter(prepared.plan.count, not quiet and sys.stderr.isatty())
    ctrl_c = CtrlC()
    taking = sweeping.rows()
    interrupted = False
    try:
        try:
            for row in taking:
                with ctrl_c.deferred():
                    line = (csv_table.csv_line(csv_table.cells(prepared, row))
                            if rows_format == "csv" else _json_line(row.as_dict()))
                    if echo:
                        click.echo(line)
                    lines.append(line)
                    rows.append(row)
                    counter.step()
        except KeyboardInterrupt:
            interrupted = True
        finally:
            try:
                with ctrl_c.deferred():  # a second Ctrl-C waits until the workers are stopped
                    taking.close()
                    counter.close()
            except KeyboardInterrupt:
                interrupted = True
    finally:
        ctrl_c.restore()
    return rows, lines, interrupted


def _json_line(obj: dict) -> str:
    return json.dumps(obj, allow_nan=False)
