"""A motion to follow: joint coordinates over time from a CSV file, with their rates and
accelerations.

The file: a header ``t,<coordinate>...`` (a one-axis joint by its name), optional
``<coordinate>.rate`` and ``<coordinate>.acc`` columns; SI units (s, rad, m); times strictly
increasing. Where a coordinate's rates or accelerations are not given, they are the derivatives
of its interpolating spline of order 5 (quintic, scipy's not-a-knot ends; at least 6 samples),
and the spline's own error is estimated from the sampling: the same spline through every other
sample, whose acceleration error is 2⁴ = 16 times larger (a quintic's second derivative errs
as h⁴), so the full spline's is about |a_h − a_2h| / 15 (Richardson). Given columns are exact:
their bar is 0. The bar is the sampling's error, not the data's: positions known to ε reach the
accelerations as ~ε/h², which no spline can tell from motion.
"""

from __future__ import annotations

import csv
import io
import os
from dataclasses import dataclass

import numpy as np

from massprops.errors import InputError, SceneError

SPLINE_ORDER = 5
RICHARDSON = 2 ** (SPLINE_ORDER - 1) - 1
"""|a_h − a_2h| / RICHARDSON estimates the acceleration error of the spline through every
sample (the module's rule)."""


@dataclass(frozen=True, eq=False)
class Motion:
    """t (n,) s; per named coordinate (file order): q, rate, acc (n,) each; ``acc_bar`` (n,)
    the spline's acceleration error estimate (0 where the file gives the accelerations);
    ``coarse`` the accelerations of the spline through every other sample (None where given)."""

    t: np.ndarray
    names: tuple[str, ...]
    q: dict[str, np.ndarray]
    rate: dict[str, np.ndarray]
    acc: dict[str, np.ndarray]
    coarse: dict[str, np.ndarray | None]
    source: str


def read_motion(path: str | os.PathLike) -> Motion:
    """The motion in the CSV at ``path``; SceneError (exit 1) naming the file and the problem."""
    source = os.fspath(path)
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            rows = list(csv.reader(fh))
    except FileNotFoundError:
        raise InputError(f"{source}: motion file not found; check the path") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{source}: cannot read the motion ({exc})") from None
    return parse_motion(rows, source)


def parse_motion(rows: list[list[str]], source: str) -> Motion:
    """The motion of CSV ``rows`` (header first)."""
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if len(rows) < 2:
        raise SceneError(f"{source}: a motion needs a header t,<joint>... and at least one row")
    header = [h.strip() for h in rows[0]]
    if header[0] != "t":
        raise SceneError(f"{source}:1: the first column must be t (seconds), got {header[0]!r}")
    if len(set(header)) < len(header):
        raise SceneError(f"{source}:1: a column is named twice")
    data = np.empty((len(rows) - 1, len(header)))
    for i, row in enumerate(rows[1:]):
        if len(row) != len(header):
            raise SceneError(f"{source}:{i + 2}: {len(row)} values, the header has "
                             f"{len(header)}")
        try:
            data[i] = [float(c) for c in row]
        except ValueError:
            raise SceneError(f"{source}:{i + 2}: not a number in {row}") from None
    if not np.isfinite(data).all():
        raise SceneError(f"{source}: the motion holds a value that is not finite")
    t = data[:, 0]
    if np.any(np.diff(t) <= 0):
        raise SceneError(f"{source}: the times must increase strictly")
    columns = dict(zip(header, data.T))
    names = tuple(h for h in header[1:] if not h.endswith((".rate", ".acc")))
    for h in header[1:]:
        base = h.rsplit(".", 1)[0]
        if h.endswith((".rate", ".acc")) and base not in names:
            raise SceneError(f"{source}:1: column {h} names no coordinate column {base}")
    q: dict[str, np.ndarray] = {}
    rate: dict[str, np.ndarray] = {}
    acc: dict[str, np.ndarray] = {}
    coarse: dict[str, np.ndarray | None] = {}
    for name in names:
        q[name] = columns[name]
        given_rate, given_acc = columns.get(f"{name}.rate"), columns.get(f"{name}.acc")
        if given_rate is not None and given_acc is not None:
            rate[name], acc[name], coarse[name] = given_rate, given_acc, None
            continue
        if len(t) < SPLINE_ORDER + 1 or len(t[::2]) < SPLINE_ORDER + 1:
            raise SceneError(f"{source}: {name}: {len(t)} samples; its rates and accelerations "
                             f"come from a spline of order {SPLINE_ORDER}, which needs at "
                             f"least {2 * SPLINE_ORDER + 1} (or give {name}.rate and "
                             f"{name}.acc columns)")
        fine = _spline(t, q[name])
        rate[name] = given_rate if given_rate is not None else fine.derivative(1)(t)
        acc[name] = given_acc if given_acc is not None else fine.derivative(2)(t)
        half = _spline(t[::2], q[name][::2])
        coarse[name] = half.derivative(2)(t)
    return Motion(t, names, q, rate, acc, coarse, source)


def _spline(t: np.ndarray, q: np.ndarray):
    from scipy.interpolate import make_interp_spline  # deferred: scipy, only for a motion

    return make_interp_spline(t, q, k=SPLINE_ORDER)


def motion_text(t: np.ndarray, columns: dict[str, np.ndarray]) -> str:
    """A motion CSV of ``columns`` at times ``t`` (the reader's format; repr digits)."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["t", *columns])
    for i in range(len(t)):
        w.writerow([repr(float(t[i])), *(repr(float(c[i])) for c in columns.values())])
    return out.getvalue()


def trapezoid(y: np.ndarray, t: np.ndarray) -> float:
    """∫ y dt by the trapezoid rule (the samples' own resolution)."""
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(t))) if len(t) > 1 else 0.0
