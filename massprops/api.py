"""The library's front door: what ``import massprops`` offers (docs/api.md shows each at work).

Each function is one call into the layer that does the work; values are SI (m, kg, s, rad),
inertia about the centre of mass in the mesh's axes, J = -∫ s̃ s̃ dm. Errors are
`massprops.errors.MassPropsError` subclasses; the library never prints or exits.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any, BinaryIO

if TYPE_CHECKING:  # the real imports are deferred into each function: start-up stays as it was
    from massprops.batch.runner import Batch
    from massprops.dynamics.model import Scene
    from massprops.dynamics.precision import PrecisionReport
    from massprops.dynamics.simulate import SimulationResult
    from massprops.dynamics.systems.model import SystemScene
    from massprops.dynamics.systems.run import SystemResult
    from massprops.inspection.align import Alignment
    from massprops.inspection.file import Inspection
    from massprops.repair import RepairOptions
    from massprops.robot.analyze import ModelReport

PathLike = str | os.PathLike


def inspect(source: PathLike | BinaryIO, *, density: float | None = None,
            mass: float | None = None, unit: str = "m", format: str | None = None,
            allow_open: bool = False, repairs: RepairOptions | None = None) -> Inspection:
    """Read a mesh file and integrate it exactly: an `Inspection` whose ``mass`` (kg),
    ``center_of_mass`` (3,) m, ``inertia`` (3, 3) kg·m² (about the COM, mesh axes),
    ``principal_moments`` (3,) ascending, ``principal_axes`` (3, 3) columns, and
    ``uncertainty`` (error bars: ``rounding``, ``input``, ``repair``) are read as attributes;
    ``as_dict()`` is the ``inspect --json`` object.

    density kg/m³ (default 1) or mass kg (total); unit of the file's coordinates (m, cm, mm, um,
    in, ft); format names the reader for a stream; allow_open computes an open mesh anyway
    (with warnings); repairs: `RepairOptions` (fill holes, union, shell)."""
    from massprops.inspection.file import inspect_file  # deferred: start-up of `import massprops`

    return inspect_file(source, format=format, unit=unit, density=density, mass=mass,
                        allow_open=allow_open, repairs=repairs)


def align(source: PathLike, output: PathLike | None = None, *, force: bool = False,
          **options: Any) -> Alignment:
    """The part at ``source`` moved into its principal frame (v ↦ Rᵀ(v − c)): an `Alignment`
    with ``rotation``, ``translation``, ``principal_moments`` and the moved ``mesh``. With
    ``output``, the moved mesh is also written there (format from the extension; atomically,
    never over ``source``, nor over an existing file unless ``force``). ``options`` as for
    `inspect`."""
    # deferred: start-up of `import massprops`
    from massprops.inspection.align import align_mesh
    from massprops.io import write_mesh

    result = inspect(source, **options)
    aligned = align_mesh(result.mesh, result.properties)
    if output is not None:
        write_mesh(aligned.mesh, output, force=force, protect=(source,))
    return aligned


def model(path: PathLike, *, source: str = "collision", density: float | None = None,
          package_paths: Iterable[PathLike] = (), allow_open: bool = False) -> ModelReport:
    """Every link of a URDF, SDF or MJCF robot description: its inertial computed from its
    geometry (``source``: "collision" or "visual") beside the one the file states."""
    from massprops.robot.analyze import analyze_model  # deferred: start-up of `import massprops`

    return analyze_model(path, source=source, density=density,
                         package_paths=tuple(package_paths), allow_open=allow_open)


def inspect_many(paths: Iterable, *, jobs: int | None = None, executor: Any = None,
                 **options: Any) -> Batch:
    """Inspect many files, ``jobs`` processes side by side (or on a Dask ``executor``);
    iterate the result for one record per input, in input order (``record.data`` is the
    ``inspect --json`` object, ``record.error`` the failure). ``options`` as for `inspect`."""
    from massprops.batch import inspect_many as run  # deferred: start-up of `import massprops`

    return run(paths, executor, jobs=jobs, **options)


def load_scene(path: PathLike) -> Scene | SystemScene:
    """Read and validate a scene file (YAML; the keys of docs/interface.md): a `Scene`, or for
    a scene with ``bodies:`` or ``model:`` (a system, docs/systems.md) a `SystemScene`; a robot
    description (``.urdf``, ``.sdf``, ``.xml``) gives the scene ``massprops simulate ROBOT``
    runs (its stated inertials and base, gravity, 1 s from the zero pose at rest)."""
    from massprops.dynamics.any_scene import load  # deferred: start-up

    return load(path)


def simulate(scene: Scene | SystemScene | PathLike,
             **options: Any) -> SimulationResult | SystemResult:
    """Integrate the Newton-Euler equations of a scene (a `Scene` or its file): a
    `SimulationResult` (``final``, ``diagnostics``, ``trajectory``; ``as_dict()`` is the
    ``simulate --json`` object). ``options``: integrator, rtol, step, every, max_steps. A
    system (a `SystemScene`) gives a `SystemResult` (the same keys, per body and joint),
    with the same ``options``."""
    from massprops.dynamics import any_scene  # deferred: start-up

    return any_scene.simulate(_scene(scene), **options)


def precision(scene: Scene | SystemScene | PathLike, **options: Any) -> PrecisionReport:
    """Error against run time, integrator by integrator, over ladders of tolerances or steps;
    ``options``: integrators (names)."""
    from massprops.dynamics import any_scene  # deferred: start-up

    return any_scene.precision(_scene(scene), **options)


def _scene(value: Scene | SystemScene | PathLike) -> Scene | SystemScene:
    """A scene given as itself or by its file."""
    return load_scene(value) if isinstance(value, str | os.PathLike) else value
