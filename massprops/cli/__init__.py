"""The ``massprops`` command: parse options, call one library function, render, map errors to exits.

One module per command (`inspect`, `align`, `model`, `dynamics` for simulate and precision,
`sweep`, `torques`) on the group of `app`; `common` holds what they share. Importing this package
registers every command.
Imports heavier than click happen inside the commands, so that ``inspect --json`` on a small mesh
pays for numpy and the mesh code only (no rich, scipy, trimesh, numba or manifold3d).
"""

from massprops.cli import align, dynamics, inspect, model, sweep, torques  # noqa: F401  (register the commands)
from massprops.cli.app import cli, main
from massprops.cli.common import ELEMENT_FORMATS, INSPECT_FORMATS, UNIT_CHOICES
from massprops.cli.inspect import RemoteError

__all__ = ["ELEMENT_FORMATS", "INSPECT_FORMATS", "UNIT_CHOICES", "RemoteError", "cli", "main"]
