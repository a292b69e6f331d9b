"""The exception hierarchy: one root, one branch per exit code of the contract.

The mapping to exit codes lives in exactly one place, ``EXIT_CODES`` below, and the CLI is its only
reader. Subclasses also inherit the builtin a Python caller would expect (``OSError`` for files,
``ValueError`` for bad data), so ``except ValueError`` keeps working for library users.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator

_SETTING = re.compile("\x1f([a-z_.]+)\x1f")


def setting_ref(name: str) -> str:
    """A reference to one of the caller's settings inside a message: ``name`` is the library's
    keyword (``fill_holes``, ``allow_open``, ``rtol``). The message carries the name as data and
    whoever shows it says it in its own terms (`render_settings`): the CLI as its flag
    (``--fill-holes``), a scene as its key (``fill_holes: true``), the library as the keyword."""
    return f"\x1f{name}\x1f"  # a control character: never part of a file name or a number


def settings_in(text: str) -> tuple[str, ...]:
    """The settings a message refers to, in order (see `setting_ref`)."""
    return tuple(_SETTING.findall(text))


def render_settings(text: str, say: Callable[[str], str] = str) -> str:
    """``text`` with each `setting_ref` reference said by ``say(name)`` (default: the name)."""
    return _SETTING.sub(lambda m: say(m[1]), text)


class MassPropsError(Exception):
    """Root of every error massprops raises on purpose. Its message may refer to the caller's
    settings (`setting_ref`): ``settings`` names them, ``render`` says them in the caller's terms,
    ``str()`` as the library's keywords."""

    @property
    def template(self) -> str:
        return str(self.args[0]) if self.args else ""

    @property
    def settings(self) -> tuple[str, ...]:
        return settings_in(self.template)

    def render(self, say: Callable[[str], str] = str) -> str:
        return render_settings(self.template, say)

    def __str__(self) -> str:
        return self.render()


# --- exit 1: an input could not be processed -----------------------------------------------------
class InputError(MassPropsError):
    """An input (mesh file, scene file, option value read from a file) cannot be used."""


class MeshFileError(InputError, OSError):
    """The file cannot be opened or read: missing, a directory, no permission."""


class MeshFormatError(InputError, ValueError):
    """The bytes are not a valid mesh of the format: garbage, truncated, bad indices, NaN."""


class UnknownFormatError(InputError, ValueError):
    """No reader or writer for this file extension or ``--input-format``."""


class MeshTopologyError(InputError, ValueError):
    """The mesh is not a closed oriented surface (open, non-manifold, un-orientable)."""


class DegenerateMeshError(InputError, ValueError):
    """The mesh encloses no volume (flat, empty) or its inertia is unphysical."""


class NoVolumeError(DegenerateMeshError):
    """The mesh encloses no volume at all: a sheet, a few slivers, no triangles. Alone it has no
    mass properties; beside other geometry of a robot link it adds nothing (zero volume)."""


class UnphysicalInertiaError(InputError, ValueError):
    """An inertia tensor that no body can have: not symmetric, not positive definite, or a
    principal moment larger than the sum of the other two (triangle inequality)."""


class SceneError(InputError, ValueError):
    """The scene YAML is invalid; the message names the key path and, where known, the line."""


class OutputExistsError(InputError, FileExistsError):
    """The output file exists (use --force) or would overwrite an input."""


class RobotModelError(InputError, ValueError):
    """A robot description (URDF, SDF, MJCF) cannot be used: malformed XML, a joint loop, an
    unknown attribute value; the message names the file, the element and its line."""


# --- exit 2: usage -------------------------------------------------------------------------------
class UsageError(MassPropsError, ValueError):
    """Options that contradict each other or are out of range (exit 2)."""


# --- exit 3: the computation itself failed -------------------------------------------------------
class ComputationError(MassPropsError, ArithmeticError):
    """The computation failed although its inputs were valid (exit 3). ``partial``: what a run
    computed up to the failure (a SimulationResult or a SystemResult; None when nothing ran),
    so that the caller can still write it out."""

    def __init__(self, message: str, partial: object = None) -> None:
        super().__init__(message)
        self.partial = partial


class DivergenceError(ComputationError):
    """An integration produced NaN or grew without bound (``partial`` as for every
    ComputationError)."""


class RunBudgetError(ComputationError):
    """A run would need, or has taken, more steps or samples than the run bound allows
    (massprops.dynamics.budget): refused up front, or stopped with ``partial`` holding what was
    computed (None when nothing ran)."""


# --- exit 4: a check ran, and what was checked disagrees -----------------------------------------
class CheckFailedError(MassPropsError):
    """A requested check ran on valid inputs and failed (``model --check``: a stated inertial
    differs from the computed one by more than the tolerance). Not bad input: the input was read
    and understood; it is the description that is wrong (exit 4)."""


#: The contract's exit-code table; the four branches are disjoint, so order does not matter.
EXIT_CODES: dict[type[MassPropsError], int] = {
    InputError: 1,
    UsageError: 2,
    ComputationError: 3,
    CheckFailedError: 4,
}
EXIT_INTERRUPTED = 130


def exit_code(exc: BaseException) -> int:
    """Exit code of the contract for an exception reaching the command boundary."""
    if isinstance(exc, KeyboardInterrupt):
        return EXIT_INTERRUPTED
    for cls, code in EXIT_CODES.items():
        if isinstance(exc, cls):
            return code
    if isinstance(exc, OSError):  # the environment failed an input or output (disk full, ...)
        return 1
    return 3  # anything else is a failure of the computation itself (a bug)


def chain(exc: BaseException, *links: str) -> Iterator[BaseException]:
    """``exc`` and every exception behind it (``__cause__``, ``__context__`` and the attributes
    named in ``links``, such as a wrapper's ``exc``), each once."""
    seen: set[int] = set()
    stack: list[BaseException | None] = [exc]
    while stack:
        e = stack.pop()
        if not isinstance(e, BaseException) or id(e) in seen:
            continue
        seen.add(id(e))
        yield e
        stack += [*(getattr(e, link, None) for link in links), e.__cause__, e.__context__]


def format_traceback(exc: BaseException) -> str:
    """``exc``'s traceback as Python formats it (for ``--debug``), each massprops error's message
    in it as its template: the settings it names kept as `setting_ref` references, for whoever
    shows it to say in its own terms, as `error_message` does for the one line."""
    import traceback  # deferred: only a failure pays for it

    text = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    for e in chain(exc):
        if isinstance(e, MassPropsError) and e.settings:
            text = text.replace(str(e), e.template)
    return text


def error_message(exc: BaseException) -> str:
    """The one line that reports ``exc`` (the CLI prefixes it with ``massprops: error: ``), its
    `setting_ref` references kept for the caller to say in its terms (`render_settings`).

    Our own errors already name the file and the fix; an OSError names its file and reason; any
    other exception is a bug, said as such without a traceback."""
    if isinstance(exc, MassPropsError):
        return exc.template
    if isinstance(exc, OSError):
        return f"{exc.filename or ''}: {exc.strerror or exc}".lstrip(": ")
    return (f"internal error: {type(exc).__name__}: {exc} (run with {setting_ref('debug')} "
            f"for details)")
