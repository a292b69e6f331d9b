"""Human-readable output (rich): the inspect table in the spirit of the notes' slide 14.

Only the CLI imports this module; the library never prints. Numbers are shown with the digits
their error bar justifies (at most 15 significant), so an exact 12 prints as 12 and a round-off
residue below its bound prints as 0. --json output is never rounded.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable
from typing import Any, cast

import numpy as np
from rich.console import Console, Group
from rich.table import Table
from rich.text import Text

from massprops.cli.common import cli_text, estimate_said

# a pipe gets no colour (rich's own check) and a fixed width wide enough for the tables, rather
# than wrapping at 80 columns where no one will resize a window
_console = Console(highlight=False, width=None if sys.stdout.isatty() else 120)


def _print_table(table: Table) -> None:
    """``table`` whole: a pipe's fixed width must not cut a number to "…" (a robot's long link
    names made pr2's mass column "0.…"), so a wider table gets the width it needs there."""
    if _console.is_terminal:
        _console.print(table)
        return
    need = _console.measure(table, options=_console.options.update_width(10_000)).maximum
    if need <= _console.width:
        _console.print(table)
    else:
        Console(highlight=False, width=need, file=_console.file).print(table)


def _row(table: Table, *cells) -> None:
    """Add a row of plain text: units like "[m³]" must not be read as rich markup tags."""
    table.add_row(*(Text(c) if isinstance(c, str) else c for c in cells))


def fmt(value: float, error: float = 0.0) -> str:
    """``value`` with the significant digits that ``error`` (an absolute bound) leaves certain."""
    if not math.isfinite(value):
        return str(value)
    if value == 0 or abs(value) <= error:
        return "0"
    digits = 15
    if error > 0:
        digits = max(1, min(15, 1 + int(math.floor(math.log10(abs(value) / error)))))
    return f"{value:.{digits}g}"


def _matrix(m: np.ndarray, err: np.ndarray | float, title: str) -> Group:
    """A heading line, then the matrix (a table is too narrow to carry a long title)."""
    err = np.broadcast_to(np.asarray(err, dtype=float), m.shape)
    t = Table(show_header=False, box=None, padding=(0, 2))
    for i in range(m.shape[0]):
        _row(t, *(fmt(float(m[i, j]), float(err[i, j])) for j in range(m.shape[1])))
    return Group(Text(title, style="bold"), t)


def _vector(v: np.ndarray, err: np.ndarray | float) -> str:
    err = np.broadcast_to(np.asarray(err, dtype=float), v.shape)
    return "(" + ", ".join(fmt(float(x), float(e)) for x, e in zip(v, err)) + ")"


def _bar(e: np.ndarray | float) -> str:
    return f"± {float(np.max(e)):.1e}"


def inspection_renderable(data: dict, repaired: Iterable[str] | None = None) -> Group:
    """A rich renderable for one inspection, given as its JSON object
    (`massprops.inspection.file.Inspection.as_dict`, or a batch record's ``data``).
    ``repaired``: the keys of ``data["repairs"]`` to list (the repairs that were asked for;
    default: all)."""
    bars = [b for b in (data["uncertainty"]["rounding"], data["uncertainty"]["input"],
                        data["uncertainty"].get("repair")) if b is not None]

    def value(name: str) -> np.ndarray:
        return np.asarray(data[name], dtype=float)

    def bound(name: str) -> np.ndarray:  # an array: the round-off bar is always there
        return cast(np.ndarray, sum(np.asarray(b[name], dtype=float) for b in bars))

    kinds = ["round-off"] + (["float32 input"] if data["uncertainty"]["input"] is not None
                             else []) + (["repair"] if "repair" in data["uncertainty"] else [])

    head = Table(show_header=True, header_style="bold", box=None, padding=(0, 2),
                 title=Text(data["file"], style="bold"), title_justify="left")
    head.add_column("quantity")
    head.add_column("value")
    head.add_column("error bar" + (f" ({' + '.join(kinds)})" if len(kinds) > 1 else ""))
    _row(head, "volume [m³]", fmt(data["volume"], float(bound("volume"))), _bar(bound("volume")))
    _row(head, "mass [kg]", fmt(data["mass"], float(bound("mass"))), _bar(bound("mass")))
    _row(head, "density [kg/m³]", fmt(data["density"]), "")
    _row(head, "centre of mass [m]", _vector(value("center_of_mass"), bound("center_of_mass")),
                 _bar(bound("center_of_mass")))
    _row(head, "principal moments [kg·m²]",
                 _vector(value("principal_moments"), bound("principal_moments")),
                 _bar(bound("principal_moments")))

    j = _matrix(value("inertia"), bound("inertia"),
                f"inertia tensor about the centre of mass [kg·m²]  {_bar(bound('inertia'))}")
    axes = _matrix(value("principal_axes"), 0.0, "principal axes (columns, mesh frame)")

    mesh = Table(show_header=False, box=None, padding=(0, 2), title="mesh",
                 title_justify="left")
    for key, item in data["mesh"].items():
        if isinstance(item, (list, tuple)):
            item = ", ".join(fmt(float(v)) if isinstance(v, float) else str(v) for v in item)
        _row(mesh, key, str(item))

    parts: list[Any] = [head, Text(""), j, Text(""), axes, Text(""), mesh]
    repairs = data.get("repairs") or {}
    shown = {k: repairs[k] for k in (repairs if repaired is None else repaired)}
    if shown:
        parts += [Text(""), _repairs_table(shown)]
    if data["warnings"]:
        parts.append(Text(""))
        parts.extend(Text(f"warning: {cli_text(w)}", style="yellow") for w in data["warnings"])
    return Group(*parts, Text(""))


def _repairs_table(repairs: dict) -> Table:
    """What each repair did: one row per key of its JSON record."""
    t = Table(show_header=False, box=None, padding=(0, 2), title="repairs", title_justify="left")
    for name, record in repairs.items():
        for key, value in record.items():
            if isinstance(value, float):
                value = fmt(value)
            elif isinstance(value, list):
                value = "; ".join(str(v) for v in value) or "none"
            _row(t, f"{name}.{key}", str(value))
    return t


def print_inspection(data: dict, repaired: Iterable[str] | None = None) -> None:
    """Print one inspection (its JSON object) as the human table."""
    _console.print(inspection_renderable(data, repaired))


def print_alignment(input_path: str, output_path: str, alignment, repairs: dict | None = None
                    ) -> None:
    """Summary of `massprops align`: the map written and the moments that are now diagonal (and
    what a repair did to the mesh that was written)."""
    t = Table(show_header=False, box=None, padding=(0, 2),
              title=Text(f"{input_path} → {output_path}", style="bold"), title_justify="left")
    _row(t, "map", "v ↦ rotation · v + translation")
    _row(t, "translation [m]", _vector(alignment.translation, 0.0))
    _row(t, "principal moments [kg·m²]", _vector(alignment.principal_moments, 0.0))
    _print_table(t)
    _console.print(_matrix(alignment.rotation, 0.0, "rotation (rows: principal axes)"))
    if repairs:
        _console.print(_repairs_table({k: r.as_dict() for k, r in repairs.items()}))


def print_run(name: str, scene, result) -> None:
    """Summary of `massprops simulate` of the scene the user named ``name``: a system's
    (`print_system_run`) or one body's (`print_simulation`)."""
    # deferred: the scene kinds, decided where they were loaded
    from massprops.dynamics.any_scene import is_system

    if is_system(scene):
        print_system_run(name, scene, result)
    else:
        print_simulation(scene, result)


def print_system_run(name: str, scene, result) -> None:
    """A system run in a few lines: its size, where and how it ended, each scene joint's
    coordinates and reaction (the JSON's ``final``)."""
    data = result.as_dict()
    diag = data["diagnostics"]
    static = scene.time.duration == 0  # the start pose's reactions: nothing was integrated
    said = ("none (the start pose: no motion integrated)" if static
            else estimate_said(diag["error_estimate"], result.interrupted, ""))
    print(f"{name}: {len(scene.bodies)} bodies, {len(scene.joints)} joints, "
          f"{diag['degrees_of_freedom']} degrees of freedom; t = {data['final']['t']:g} s "
          f"in {data['steps']} steps; error estimate {said}")
    for joint_name, joint in data["final"]["joints"].items():
        held = f", holding {joint['holding']}" if "holding" in joint else ""
        print(f"  {joint_name} ({joint['type']}): q = {joint['coordinates']}, "
              f"force {joint['force']} N, torque {joint['torque']} N·m{held}")


def print_simulation(scene, result) -> None:
    """Summary of `massprops simulate`: method and why, cost, final state, diagnostics."""
    head = Table(show_header=False, box=None, padding=(0, 2), title_justify="left",
                 title=Text(scene.source, style="bold"))
    _row(head, "integrator", f"{result.integrator} ({result.reason})")
    _row(head, "steps / evaluations", f"{result.steps} / {result.evaluations}"
                 + (f" ({result.rejected} rejected)" if result.rejected else ""))
    _row(head, "wall time [s]", f"{result.wall_time_s:.3g} (+ {result.warmup_time_s:.3g} "
                 "compile/load)")
    final = result.trajectory.row(-1)
    _row(head, "t [s]", fmt(final["t"]))
    for key, unit in (("position", "m"), ("orientation", "w, x, y, z"),
                      ("velocity", "m/s"), ("angular_velocity", "rad/s, world"),
                      ("angular_velocity_body", "rad/s, body")):
        _row(head, f"{key.replace('_', ' ')} [{unit}]",
                     "(" + ", ".join(f"{x:.10g}" for x in final[key]) + ")")
    for k, joint in enumerate(final.get("joints", ())):
        _row(head, f"joint {k} ({joint['type']}) force on body [N, world]",
             "(" + ", ".join(f"{x:.6g}" for x in joint["force_world"]) + ")")
        if joint["torque_world"] is not None:
            _row(head, f"joint {k} torque on body [N·m, world]",
                 "(" + ", ".join(f"{x:.6g}" for x in joint["torque_world"]) + ")")
    for key, value in result.diagnostics.items():
        said = (estimate_said(value, result.interrupted) if key == "error_estimate"
                else "n/a (no joints)" if value is None and key == "constraint_drift"
                else "n/a (not conserved in this scene)" if value is None else f"{value:.3g}")
        _row(head, key.replace("_", " "), said)
    if result.interrupted:
        _row(head, "interrupted", "yes: the results stop at the time above")
    _print_table(head)


def print_precision(name: str, report) -> None:
    """The ladders as one table per integrator block: setting, time, error, estimate, steps."""
    ref = report.reference
    t = Table(title=Text(f"{name}: error against run time", style="bold"), title_justify="left",
              box=None, padding=(0, 2), header_style="bold")
    for col in ("integrator", "rtol | h [s]", "time [s]", "error", "estimate", "steps",
                "evals"):
        t.add_column(Text(col), justify="left" if col == "integrator" else "right", no_wrap=True)
    previous = None
    failed = []
    for r in report.runs:
        label = r.integrator if r.integrator != previous else ""
        previous = r.integrator
        setting = f"{r.setting:.3g}" if r.setting_name != "none" else ""
        if r.reason is not None:
            failed.append(f"{r.integrator} {setting}: {cli_text(r.reason)}")
        _row(t, label, setting, "—" if r.wall_time_s is None else f"{r.wall_time_s:.2e}",
                  f"failed ({len(failed)})" if r.error is None else f"{r.error:.2e}",
                  "—" if r.estimate is None else f"{r.estimate:.2e}", str(r.steps),
                  str(r.evaluations))
    _print_table(t)
    for k, why in enumerate(failed, 1):
        _console.print(Text(f"({k}) {why}"))
    acc = ref.get("accuracy")
    _console.print(f"reference: {ref['kind']} ({ref['checked']}); its accuracy ~ "
                   f"{acc:.1e}" if acc is not None else f"reference: {ref['kind']}")


def print_model(report, rtol: float | None = None) -> None:
    """`massprops model`: one row per link, stated against computed (rtol marks the failures)."""
    t = Table(title=Text(f"{report.name} ({report.model.format})", style="bold"),
              title_justify="left", box=None, padding=(0, 2), header_style="bold")
    for col in ("link", "mass [kg]", "mass off", "COM off [m]", "of size", "inertia off",
                "axes [°]", "valid", "check"):
        t.add_column(Text(col), justify="left" if col == "link" else "right", no_wrap=True)
    notes = []
    for r in report.links:
        if r.computed is None:
            _row(t, r.name, "", "", "", "", "", "", "", r.status)
            notes.append(f"{r.name}: {cli_text(r.reason)}")
            continue
        c, cmp = r.computed, r.comparison
        if cmp is None:
            _row(t, r.name, f"{c.mass:.6g}", "", "", "", "", "", "", "not stated")
        else:
            angle = "" if cmp.axes_angle is None else f"{math.degrees(cmp.axes_angle):.3g}"
            verdict = "" if rtol is None else ("ok" if cmp.passes(rtol) else "FAIL")
            _row(t, r.name, f"{c.mass:.6g}", f"{cmp.mass_rel:.2%}", f"{cmp.com_offset:.3g}",
                 f"{cmp.com_rel:.2%}", f"{cmp.inertia_rel:.2%}", angle,
                 "yes" if not cmp.problems else "NO", verdict)
            notes.extend(f"{r.name}: stated {p}" for p in cmp.problems)
            if r.diagnosis is not None:
                notes.append(f"{r.name}: diagnosis: {cli_text(r.diagnosis.detail)}")
        notes.extend(f"{r.name}: {cli_text(w)}" for w in r.warnings)
        notes.extend(f"{r.name}: {mesh}: repaired ({', '.join(rec)})"
                     for mesh, rec in (r.repairs or {}).items())
    _print_table(t)
    for n in notes:
        _console.print(Text(n, style="yellow"))


class BatchProgress:
    """``inspect`` over many files: done/total, files per second, time left and failures, on
    stderr. The CLI creates it only when stderr is a terminal; it appears once the batch has run
    ``delay`` seconds (short batches print nothing) and leaves no trace when closed. Output lines
    go above the bar: stderr's always, stdout's when it is the terminal too (a redirected stdout
    is never touched)."""

    def __init__(self, delay: float = 1.0) -> None:
        import time

        self.clock = time.monotonic
        self.start = self.clock()
        self.delay = delay
        self.bar: Any = None
        self.task: Any = None

    def update(self, done: int, failed: int, total: int | None) -> None:
        elapsed = self.clock() - self.start
        if self.bar is None:
            if elapsed < self.delay:
                return
            from rich.progress import BarColumn, Progress, TextColumn

            self.bar = Progress(TextColumn("inspecting"), BarColumn(),
                                TextColumn("{task.fields[text]}"),
                                console=Console(stderr=True), transient=True,
                                redirect_stdout=sys.stdout.isatty(), redirect_stderr=True)
            self.bar.start()
            self.task = self.bar.add_task("inspect", total=None, text="")
        rate = done / elapsed if elapsed > 0 else 0.0
        left = "" if total is None or rate <= 0 else f" · {_duration((total - done) / rate)} left"
        text = (f"{done}/{'?' if total is None else total} files · {rate:.3g} files/s{left}"
                + (f" · {failed} failed" if failed else ""))
        self.bar.update(self.task, completed=done, total=total, text=text)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.stop()
            self.bar = None


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def print_sweep(name: str, prepared, result: dict) -> None:
    """A sweep's summary: one line per output component (mean ± its uncertainty, sd, the 5-95 %
    range) and the largest sensitivities."""
    _console.print(f"{cli_text(name)}: {result['samples']} samples, {result['failed']} failed"
                   + (f", {result['redrawn']} mass-property draws redrawn"
                      if result["redrawn"] else ""))
    t = Table(box=None, padding=(0, 2), header_style="bold")
    for col in ("output", "mean", "± (mean)", "sd", "5 %", "50 %", "95 %"):
        t.add_column(Text(col), justify="left" if col == "output" else "right", no_wrap=True)
    for output, stats in result["summary"].items():
        if stats is None:
            _row(t, output, "none ran", "", "", "", "", "")
            continue
        mean = np.ravel(np.asarray(stats["mean"], dtype=float))
        suffixes = ("x", "y", "z") if len(mean) == 3 else tuple(map(str, range(len(mean))))
        for i in range(len(mean)):
            label = output if len(mean) == 1 else f"{output}[{suffixes[i]}]"
            u = float(np.ravel(stats["mean_uncertainty"])[i])
            _row(t, label, fmt(float(mean[i]), u if math.isfinite(u) else 0.0), f"{u:.2g}",
                 *(f"{float(np.ravel(stats[k])[i]):.6g}" for k in ("sd", "p05", "p50", "p95")))
    _print_table(t)
    for output, lin in (result.get("linear") or {}).items():
        for key, d in lin["derivative"].items():
            if d is not None:
                acc = np.ravel(np.asarray(lin["accuracy"][key], dtype=float))
                shown = ", ".join(f"{x:.6g} ± {a:.2g}" for x, a in
                                  zip(np.ravel(np.asarray(d, dtype=float)), acc))
                _console.print(f"d {output} / d {key} = {shown}", soft_wrap=True)
        if lin["sd"] is not None:
            sd = ", ".join(f"{x:.6g}" for x in np.ravel(np.asarray(lin["sd"], dtype=float)))
            _console.print(f"{output}: the delta method's sd {sd}", soft_wrap=True)


def print_torques(robot: str, motion: str, result) -> None:
    """`massprops torques`: one row per motor (peak and when, RMS, peak power, energy, limit)."""
    s = result.summary
    t = Table(title=Text(f"{robot} along {motion}: {s['samples']} samples", style="bold"),
              title_justify="left", box=None, padding=(0, 2), header_style="bold")
    for col in ("joint", "peak", "at t [s]", "RMS", "peak power [W]", "energy [J]", "limit",
                "margin"):
        t.add_column(Text(col), justify="left" if col == "joint" else "right", no_wrap=True)
    for name, m in s["summary"].items():
        limit, margin = m["limit"][0], m["margin"][0]
        _row(t, name, f"{m['peak'][0]:.6g}", f"{m['peak_t'][0]:.6g}", f"{m['rms'][0]:.6g}",
             f"{m['peak_power'][0]:.6g}", f"{m['energy'][0]:.6g}",
             "" if limit is None else f"{limit:.6g}",
             "" if margin is None else f"{margin:+.1%}")
    _print_table(t)
    bar = max((r["bar"] for r in result.rows), default=0.0)
    _console.print(f"the motion's sampling: torques within ± {bar:.2g} (N·m or N)"
                   + ("" if s["check"] == "not checked" else f"; check: {s['check']}"))
