"""massprops: exact mass properties of solid parts, and the Newton-Euler dynamics of bodies.

    >>> import massprops
    >>> part = massprops.inspect("part.stl", density=7850)
    >>> part.mass, part.center_of_mass, part.inertia, part.principal_moments

The public API (``__all__``; docs/api.md) is loaded on first use, so ``import massprops`` stays
as light as it was. The library never prints and never exits; the command line lives in
``massprops.cli``.
"""

from __future__ import annotations

__version__ = "0.1.0"

_EXPORTS = {
    # reading and inspecting a part
    "inspect": "massprops.api", "align": "massprops.api",
    "read_mesh": "massprops.io", "write_mesh": "massprops.io",
    "Mesh": "massprops.mesh", "MassProperties": "massprops.mesh.integral",
    "Inspection": "massprops.inspection.file", "Alignment": "massprops.inspection.align",
    "RepairOptions": "massprops.repair",
    # robot models, batches
    "model": "massprops.api", "inspect_many": "massprops.api",
    # dynamics
    "load_scene": "massprops.api", "simulate": "massprops.api", "precision": "massprops.api",
    # errors
    "MassPropsError": "massprops.errors",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'massprops' has no attribute {name!r}")
    import importlib  # deferred: only a front-door name pays for it

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # once found, a plain attribute (no submodule can shadow it later)
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
