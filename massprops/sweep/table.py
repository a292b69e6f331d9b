"""A sweep's rows as CSV: ``sample, status, error, <KEY>..., <OUTPUT>[_x|_y|_z or _i]...,
error_estimate`` (the contract). A 3-vector's components are _x, _y, _z, other lists' _0, _1,
...; a drawn inertia tensor's six _xx, _yy, _zz, _xy, _xz, _yz, a ``--bars`` centre of mass's
_x, _y, _z; a failed sample's outputs are empty cells."""

from __future__ import annotations

import csv
import io
from typing import Any

import numpy as np

from massprops.sweep.run import Prepared
from massprops.sweep.sample import Row

_AXES = ("_x", "_y", "_z")
_TENSOR = (("_xx", 0, 0), ("_yy", 1, 1), ("_zz", 2, 2), ("_xy", 0, 1), ("_xz", 0, 2),
           ("_yz", 1, 2))


def _suffixes(value: Any) -> list[str]:
    if not isinstance(value, list):
        return [""]
    flat = np.ravel(np.asarray(value, dtype=object))
    return list(_AXES) if len(flat) == 3 else [f"_{i}" for i in range(len(flat))]


def header(prepared: Prepared) -> list[str]:
    """The CSV header of ``prepared``'s rows."""
    cols = ["sample", "status", "error"]
    for key, shape in prepared.plan.value_keys:
        cols += [key + s for s in _value_suffixes(shape)]
    for name in prepared.plan.outputs:
        cols += [name + s for s in _suffixes(prepared.nominal[name])]
    return [*cols, "error_estimate"]


def _value_suffixes(shape: str) -> list[str]:
    return {"scalar": [""], "vector": list(_AXES), "tensor": [s for s, _, _ in _TENSOR]}[shape]


def _value_cells(shape: str, value: Any) -> list[str]:
    if value is None:
        return [""] * len(_value_suffixes(shape))
    if shape == "tensor":
        return [repr(value[i][j]) for _, i, j in _TENSOR]
    return [repr(x) for x in value] if shape == "vector" else [repr(value)]


def cells(prepared: Prepared, row: Row) -> list[Any]:
    """One row's cells, as `header` names them."""
    out: list[Any] = [row.sample, row.status, row.error or ""]
    for key, shape in prepared.plan.value_keys:
        out += _value_cells(shape, row.values.get(key))
    for name in prepared.plan.outputs:
        width = len(_suffixes(prepared.nominal[name]))
        value = None if row.outputs is None else row.outputs.get(name)
        flat = [""] * width if value is None else list(np.ravel(np.asarray(value, dtype=object)))
        out += ["" if x is None else repr(x) if isinstance(x, float) else x for x in flat]
    return [*out, "" if row.error_estimate is None else repr(row.error_estimate)]


def csv_line(values: list[Any]) -> str:
    """``values`` as one CSV line (no line end)."""
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="").writerow(values)
    return buffer.getvalue()
