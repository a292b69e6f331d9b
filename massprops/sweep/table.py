"""A sweep's rows as CSV: ``sample, status, error, <KEY>..., <OUTPUT>[_x|_y|_z or _i]...,
error_estimate`` (the contract). A 3-vector's components are _x, _y, _z, other lists' _0, _1,
...; a drawn inertia tensor's six _xx, _yy, _zz, _xy, _xz, _yz; a failed sample's outputs are
empty cells."""

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


def _is_tensor_key(prepared: Prepared, key: str) -> bool:
    return any(v.key == key and v.mass is not None and v.mass.what == "inertia"
               for v in prepared.plan.varies)


def header(prepared: Prepared) -> list[str]:
    """The CSV header of ``prepared``'s rows."""
    cols = ["sample", "status", "error"]
    for v in prepared.plan.varies:
        cols += [v.key + s for s, _, _ in _TENSOR] if _is_tensor_key(prepared, v.key) \
            else [v.key]
    for name in prepared.plan.outputs:
        cols += [name + s for s in _suffixes(prepared.nominal[name])]
    return [*cols, "error_estimate"]


def cells(prepared: Prepared, row: Row) -> list[Any]:
    """One row's cells, as `header` names them."""
    out: list[Any] = [row.sample, row.status, row.error or ""]
    for v in prepared.plan.varies:
        value = row.values.get(v.key)
        if _is_tensor_key(prepared, v.key):
            out += [repr(value[i][j]) if value is not None else "" for _, i, j in _TENSOR]
        else:
            out.append(repr(value) if value is not None else "")
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
