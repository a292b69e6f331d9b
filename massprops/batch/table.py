"""``inspect --format csv``: one row per mesh, every number as the JSON has it (repr floats).

Columns (`CSV_COLUMNS`), SI units, inertia about the centre of mass in the mesh's axes
(Jxy = -∫xy dm, as in the JSON's ``inertia``):

- ``file``, ``volume``, ``mass``, ``density``, ``com_x..com_z``,
  ``Jxx, Jyy, Jzz, Jxy, Jxz, Jyz``, ``I1, I2, I3`` (principal moments, ascending),
  ``axisK_x..axisK_z`` (principal axis K = column K of ``principal_axes``);
- ``closed`` (true/false), ``vertices``, ``faces``, ``warnings`` (how many; the texts are on
  stderr), ``error`` (empty, or the message of a file that failed);
- ``<quantity>_err``: the round-off bound (``uncertainty.rounding``) of each number above
  from volume to I3; ``<quantity>_err_input``: what float32 coordinates leave uncertain
  (``uncertainty.input``), empty for a float64 source.

A file that failed has its ``file`` and ``error`` and nothing else. A float prints as Python's
repr, so parsing it with ``float()`` gives the JSON's number exactly (pandas: pass
``float_precision="round_trip"``; its default parser may be off by an ulp).
"""

from __future__ import annotations

import csv
import io
from typing import Any

from massprops.batch.records import MeshResult

_AXES = "xyz"
_J = ("Jxx", "Jyy", "Jzz", "Jxy", "Jxz", "Jyz")
_J_INDEX = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
_VALUES = ("volume", "mass", *(f"com_{a}" for a in _AXES), *_J, "I1", "I2", "I3")
_BARRED = _VALUES  # every quantity with an error bar in the JSON's "uncertainty"

CSV_COLUMNS: tuple[str, ...] = (
    "file", "volume", "mass", "density", *(f"com_{a}" for a in _AXES), *_J, "I1", "I2", "I3",
    *(f"axis{k}_{a}" for k in (1, 2, 3) for a in _AXES),
    "closed", "vertices", "faces", "warnings", "error",
    *(f"{q}_err" for q in _BARRED), *(f"{q}_err_input" for q in _BARRED),
)


def csv_header() -> str:
    """The header line (with its newline)."""
    return _line(CSV_COLUMNS)


def csv_row(result: MeshResult) -> str:
    """The row of one record (with its newline), columns as in `CSV_COLUMNS`."""
    if result.data is None:
        row: list[Any] = [""] * len(CSV_COLUMNS)
        row[0] = result.file
        row[CSV_COLUMNS.index("error")] = result.error.message if result.error else ""
        return _line(row)
    d = result.data
    axes, mesh, bars = d["principal_axes"], d["mesh"], d["uncertainty"]
    volume, mass, *rest = _quantities(d)
    return _line([
        d["file"], volume, mass, d["density"], *rest,
        *(axes[i][k] for k in range(3) for i in range(3)),
        "true" if mesh["closed"] else "false", mesh["vertices"], mesh["faces"],
        len(d["warnings"]), "",
        *_quantities(bars["rounding"]),
        *(_quantities(bars["input"]) if bars["input"] is not None else [""] * len(_BARRED)),
    ])


def _quantities(block: dict[str, Any]) -> list[Any]:
    """volume, mass, COM (3), the six inertia components, the three moments of a JSON block
    (the result itself or one of its ``uncertainty`` blocks)."""
    j = block["inertia"]
    return [block["volume"], block["mass"], *block["center_of_mass"],
            *(j[r][c] for r, c in _J_INDEX), *block["principal_moments"]]


def _line(cells: Any) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(cells)
    return buffer.getvalue()
