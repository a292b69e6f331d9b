"""Human-readable output (rich): the inspect table in the spirit of the notes' slide 14.

Only the CLI imports this module; the library never prints. Numbers are shown with the digits
their error bar justifies (at most 15 significant), so an exact 12 prints as 12 and a round-off
residue below its bound prints as 0. --json output is never rounded.
"""

from __future__ import annotations

import math
import sys

import numpy as np
from rich.console import Console, Group
from rich.table import Table
from rich.text import Text

# a pipe gets no colour (rich's own check) and a fixed width wide enough for the tables, rather
# than wrapping at 80 columns where no one will resize a window
_console = Console(highlight=False, width=None if sys.stdout.isatty() else 120)


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


def inspection_renderable(result) -> Group:
    """A rich renderable for one `massprops.analysis.Inspection`."""
    p, h = result.properties, result.health
    rnd, inp = p.uncertainty.rounding, p.uncertainty.input

    def bound(name: str) -> np.ndarray:
        b = np.asarray(getattr(rnd, name), dtype=float)
        return b + np.asarray(getattr(inp, name), dtype=float) if inp is not None else b

    head = Table(show_header=True, header_style="bold", box=None, padding=(0, 2),
                 title=Text(result.mesh.name, style="bold"), title_justify="left")
    head.add_column("quantity")
    head.add_column("value")
    head.add_column("error bar" + (" (round-off + float32 input)" if inp is not None else ""))
    _row(head, "volume [m³]", fmt(p.volume, float(bound("volume"))), _bar(bound("volume")))
    _row(head, "mass [kg]", fmt(p.mass, float(bound("mass"))), _bar(bound("mass")))
    _row(head, "density [kg/m³]", fmt(p.density), "")
    _row(head, "centre of mass [m]", _vector(p.center_of_mass, bound("center_of_mass")),
                 _bar(bound("center_of_mass")))
    _row(head, "principal moments [kg·m²]",
                 _vector(p.principal_moments, bound("principal_moments")),
                 _bar(bound("principal_moments")))

    j = _matrix(p.inertia, bound("inertia"),
                f"inertia tensor about the centre of mass [kg·m²]  {_bar(bound('inertia'))}")
    axes = _matrix(p.principal_axes, 0.0, "principal axes (columns, mesh frame)")

    mesh = Table(show_header=False, box=None, padding=(0, 2), title="mesh",
                 title_justify="left")
    for key, value in h.as_dict().items():
        if isinstance(value, (list, tuple)):
            value = ", ".join(fmt(float(v)) if isinstance(v, float) else str(v) for v in value)
        _row(mesh, key, str(value))

    parts = [head, Text(""), j, Text(""), axes, Text(""), mesh]
    if result.warnings:
        parts.append(Text(""))
        parts.extend(Text(f"warning: {w}", style="yellow") for w in result.warnings)
    return Group(*parts, Text(""))


def print_inspection(result) -> None:
    _console.print(inspection_renderable(result))


def print_alignment(input_path: str, output_path: str, alignment) -> None:
    """Summary of `massprops align`: the map written and the moments that are now diagonal."""
    t = Table(show_header=False, box=None, padding=(0, 2),
              title=Text(f"{input_path} → {output_path}", style="bold"), title_justify="left")
    _row(t, "map", "v ↦ rotation · v + translation")
    _row(t, "translation [m]", _vector(alignment.translation, 0.0))
    _row(t, "principal moments [kg·m²]", _vector(alignment.principal_moments, 0.0))
    _console.print(t)
    _console.print(_matrix(alignment.rotation, 0.0, "rotation (rows: principal axes)"))


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
    why_none = {"error_estimate": "n/a (run interrupted, or its companion run diverged)"}
    for key, value in result.diagnostics.items():
        _row(head, key.replace("_", " "), f"{value:.3g}" if value is not None
             else why_none.get(key, "n/a (not conserved in this scene)"))
    if result.interrupted:
        _row(head, "interrupted", "yes: the results stop at the time above")
    _console.print(head)


def print_precision(name: str, report) -> None:
    """The ladders as one table per integrator block: setting, time, error, estimate, steps."""
    ref = report.reference
    t = Table(title=Text(f"{name}: error against run time", style="bold"), title_justify="left",
              box=None, padding=(0, 2), header_style="bold")
    for col in ("integrator", "rtol | h [s]", "time [s]", "error", "estimate", "steps",
                "evals"):
        t.add_column(col, justify="left" if col == "integrator" else "right", no_wrap=True)
    previous = None
    failed = []
    for r in report.runs:
        label = r.integrator if r.integrator != previous else ""
        previous = r.integrator
        setting = f"{r.setting:.3g}" if r.setting_name != "none" else ""
        if r.reason is not None:
            failed.append(f"{r.integrator} {setting}: {r.reason}")
        _row(t, label, setting, "—" if r.wall_time_s is None else f"{r.wall_time_s:.2e}",
                  f"failed ({len(failed)})" if r.error is None else f"{r.error:.2e}",
                  "—" if r.estimate is None else f"{r.estimate:.2e}", str(r.steps),
                  str(r.evaluations))
    _console.print(t)
    for k, why in enumerate(failed, 1):
        _console.print(Text(f"({k}) {why}"))
    acc = ref.get("accuracy")
    _console.print(f"reference: {ref['kind']} ({ref['checked']}); its accuracy ~ "
                   f"{acc:.1e}" if acc is not None else f"reference: {ref['kind']}")
