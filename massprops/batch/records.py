"""One mesh -> one small, picklable record: what every output format and the exit code need."""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from typing import Any

from massprops.errors import error_message, exit_code, format_traceback


@dataclass(frozen=True)
class ErrorInfo:
    """Why an input failed.

    message : the one line the CLI prints after ``massprops: error: `` (names the file).
    exit_code : the contract's code for it (1 bad input, 3 computation failed, ...).
    traceback : the formatted traceback where it was raised (for ``--debug``), or None.
    exception : the exception itself, kept only in the process that raised it (never pickled:
        a third-party exception need not survive the trip).
    """

    message: str
    exit_code: int
    traceback: str | None = None
    exception: BaseException | None = field(default=None, compare=False, repr=False)

    @classmethod
    def of(cls, exc: BaseException, *, keep: bool = False) -> ErrorInfo:
        return cls(error_message(exc), exit_code(exc), format_traceback(exc),
                   exc if keep else None)

    def __getstate__(self) -> dict:
        return {"message": self.message, "exit_code": self.exit_code,
                "traceback": self.traceback, "exception": None}

    def __setstate__(self, state: dict) -> None:
        for key, value in state.items():
            object.__setattr__(self, key, value)


@dataclass(frozen=True)
class MeshResult:
    """The outcome for one input.

    file : the input as named in messages and in the JSON's ``"file"`` (the path as given,
        ``<stdin>`` for ``-``).
    data : the contract's JSON object (`massprops.inspection.file.Inspection.as_dict`: python
        floats, lists, SI units, inertia about the COM in the mesh's axes), or None if it failed.
    warnings : one line each, as printed after ``massprops: warning: <file>: ``.
    error : why it failed, or None.
    repaired : the keys of ``data["repairs"]`` that repairs asked for produced (what the human
        table lists; a weld by the health check alone is reported in the JSON only).
    """

    file: str
    data: dict[str, Any] | None
    warnings: tuple[str, ...] = ()
    error: ErrorInfo | None = None
    repaired: tuple[str, ...] = ()

    @property
    def exit_code(self) -> int:
        return 0 if self.error is None else self.error.exit_code

    @classmethod
    def failed(cls, name: str, exc: BaseException, *, keep: bool = False) -> MeshResult:
        return cls(name, None, (), ErrorInfo.of(exc, keep=keep))


def inspect_one(path: str | os.PathLike, options: dict[str, Any], *, name: str | None = None,
                keep_exception: bool = False) -> MeshResult:
    """Inspect one file (``-``: standard input, named ``<stdin>``) with
    `massprops.inspection.file.inspect_file` keyword ``options``; any error becomes the record's
    `ErrorInfo` (KeyboardInterrupt propagates). ``name``: what messages call it (default: the
    path as given)."""
    # deferred: the parent of a pool never inspects; workers and jobs=1 load the mesh code
    from massprops.inspection.file import inspect_file

    stdin = os.fspath(path) == "-"
    label = "<stdin>" if stdin else (os.fsdecode(path) if name is None else name)
    try:
        result = inspect_file(sys.stdin.buffer if stdin else path, name=label, **options)
        return MeshResult(label, result.as_dict(), result.warnings,
                          repaired=tuple(result.repairs or ()))
    except Exception as exc:  # reported in the record: one bad file never stops a batch
        return MeshResult.failed(label, exc, keep=keep_exception)
