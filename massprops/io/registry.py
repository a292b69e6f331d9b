"""The format registry (one line per format) and the unit table; CLI choices derive from both."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from massprops.errors import UnknownFormatError
from massprops.io import obj, off, ply_off, stl, vf
from massprops.io.fallback import FallbackReader
from massprops.io.source import Source
from massprops.mesh import Mesh

Reader = Callable[[Source], Mesh]
"""Reads a whole mesh, coordinates in the file's units, name = source.name."""

Writer = Callable[[Mesh, BinaryIO], None]
"""Writes one file's bytes to a binary stream."""

UNITS: dict[str, float] = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "um": 1e-6,
    "in": 0.0254,  # exact by the 1959 international yard and pound agreement
    "ft": 0.3048,  # exact, likewise
}
"""Length units of mesh coordinates -> metres per unit."""


@dataclass(frozen=True)
class Format:
    """A mesh file format.

    extensions : lower-case suffixes with the dot, e.g. ``(".obj",)``.
    reader : reads a Source, or None if massprops cannot read the format.
    writer : writes the file, or None.
    parts : for a format stored in several files side by side (NAME.vtx + NAME.fac): each part's
        suffix and writer, in writing order; ``writer`` is then None.
    """

    extensions: tuple[str, ...]
    reader: Reader | None = None
    writer: Writer | None = None
    parts: tuple[tuple[str, Writer], ...] = ()

    @property
    def can_write(self) -> bool:
        return self.writer is not None or bool(self.parts)

    def files(self, path: Path) -> list[tuple[Path, Writer | None]]:
        """The files that make up this format at ``path``, each with its writer."""
        if not self.parts:
            return [(path, self.writer)]
        upper = path.suffix.isupper()
        return [(path.with_suffix(s.upper() if upper else s), w) for s, w in self.parts]


def _read_dae(source: Source) -> Mesh:
    from massprops.io.collada import read_dae  # lazy: `inspect` of other formats loads no XML

    return read_dae(source)


FORMATS: dict[str, Format] = {
    "obj": Format((".obj",), obj.read_obj, obj.write_obj),
    "stl": Format((".stl",), stl.read_stl, stl.write_stl),
    "vf": Format((".vf",), vf.read_vf, vf.write_vf),
    "vtx": Format((".vtx", ".fac"), vf.read_vtx_fac,
                  parts=((".vtx", vf.write_vtx), (".fac", vf.write_fac))),
    "ply": Format((".ply",), FallbackReader("ply", "ply", ".ply", check=ply_off.check_ply_body),
                  ply_off.write_ply),
    "off": Format((".off",), off.read_off, ply_off.write_off),
    "vtk": Format((".vtk",), FallbackReader("vtk", None, ".vtk")),
    "vtu": Format((".vtu",), FallbackReader("vtu", None, ".vtu")),
    "msh": Format((".msh",), FallbackReader("gmsh", None, ".msh")),
    "dae": Format((".dae",), _read_dae),
    "gltf": Format((".gltf",), FallbackReader(None, "gltf", ".gltf", float32_only=True)),
    "glb": Format((".glb",), FallbackReader(None, "glb", ".glb", float32_only=True)),
}


def input_formats() -> list[str]:
    """Sorted names of the formats massprops reads."""
    return sorted(name for name, fmt in FORMATS.items() if fmt.reader is not None)


def output_formats() -> list[str]:
    """Sorted names of the formats massprops writes."""
    return sorted(name for name, fmt in FORMATS.items() if fmt.can_write)


def format_key(name: str) -> str:
    """The key of ``FORMATS`` that ``name`` means: case-insensitive, a leading dot allowed."""
    return name.lower().lstrip(".")


def format_named(name: str) -> Format:
    """The format called ``name`` (`format_key`)."""
    key = format_key(name)
    if key not in FORMATS:
        raise UnknownFormatError(
            f"unknown format {name!r}; expected one of: {', '.join(sorted(FORMATS))}"
        )
    return FORMATS[key]


def format_of_path(path: Path, *, for_writing: bool = False, name: str | None = None) -> Format:
    """The format of ``path`` from its extension (case-insensitive); for writing, one with a
    writer. Raises UnknownFormatError listing the known extensions, naming the file ``name``
    (default: the path; a batch worker reads an absolute path the user gave as relative)."""
    suffix = path.suffix.lower()
    for fmt in FORMATS.values():
        if suffix in fmt.extensions and (fmt.can_write or not for_writing):
            return fmt
    usable = [f for f in FORMATS.values() if f.can_write] if for_writing else list(FORMATS.values())
    known = ", ".join(sorted(ext for f in usable for ext in f.extensions))
    action = "write" if for_writing else "read"
    raise UnknownFormatError(
        f"{path if name is None else name}: cannot {action} files with extension "
        f"{path.suffix or '(none)'!r}; known: {known}"
    )
