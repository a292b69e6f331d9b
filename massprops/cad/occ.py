"""The OpenCASCADE import, deferred to the first CAD file, with the one-line missing-extra error."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from typing import Any

from massprops.errors import InputError

__all__ = ["CadExtraMissingError", "curve_breaks", "face_edges", "quiet_stdout",
           "require_occ"]


class CadExtraMissingError(InputError):
    """Reading a CAD file needs the optional extra ``massprops[cad]`` (exit 1)."""


_READY = False


def require_occ(path: str | os.PathLike) -> None:
    """Import OpenCASCADE (``OCP``) once and silence its console printers; raise
    CadExtraMissingError naming ``path`` when the extra is not installed."""
    global _READY
    if _READY:
        return
    try:
        # optional extra, ~0.8 s: loaded only when a CAD file is actually read
        from OCP.Message import Message
    except ImportError as exc:
        raise CadExtraMissingError(
            f"{os.fspath(path)}: reading CAD files needs OpenCASCADE; install it with "
            f'pip install "massprops[cad]"') from exc
    messenger = Message.DefaultMessenger_s()
    # the STEP/IGES translators print progress on stdout, which belongs to our JSON
    for printer in list(messenger.Printers()):
        messenger.RemovePrinter(printer)
    _READY = True


@contextlib.contextmanager
def quiet_stdout() -> Iterator[None]:
    """Send file descriptor 1 to /dev/null while OpenCASCADE runs: some of its readers print
    on C++ std::cout (BRepTools on a foreign file), which would corrupt a JSON stdout."""
    with contextlib.suppress(AttributeError, ValueError, OSError):
        sys.stdout.flush()
    try:
        saved = os.dup(1)
    except OSError:   # no descriptor 1 (an embedding host): nothing to protect
        yield
        return
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, 1)
        finally:
            os.close(devnull)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def face_edges(face: Any, *, degenerate: bool = True) -> Iterator[Any]:
    """The edges of ``face`` (``TopoDS_Edge``, each with its orientation in the face), in the
    face's order; without the degenerate ones (a sphere's poles) where ``degenerate`` is False."""
    from OCP.BRep import BRep_Tool  # optional extra, loaded by `require_occ`
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    explorer = TopExp_Explorer(face, TopAbs_EDGE)
    while explorer.More():
        edge = TopoDS.Edge(explorer.Current())
        explorer.Next()
        if degenerate or not BRep_Tool.Degenerated_s(edge):
            yield edge


def curve_breaks(curve: Any) -> list[float]:
    """The parameters where the curve adaptor ``curve`` (3D or 2D) stops being infinitely smooth,
    its ends included, ascending: the spans an integration rule may treat as one polynomial."""
    from OCP.collections import Array1_double  # optional extra, loaded by `require_occ`
    from OCP.GeomAbs import GeomAbs_CN

    count = curve.NbIntervals(GeomAbs_CN)
    cuts = Array1_double(1, count + 1)
    curve.Intervals(cuts, GeomAbs_CN)
    return [cuts.Value(i) for i in range(1, count + 2)]
