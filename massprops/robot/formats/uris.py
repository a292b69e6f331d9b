"""Where a mesh reference points: ``package://``, ``model://``, ``file://`` and plain paths.

The resolution rule:
- ``package://PKG/rest`` is looked up, in order, in: a folder named PKG among the description
  file's folder and its parents (the usual PKG/urdf/robot.urdf layout), then PKG inside each
  ``--package-path`` folder and each ``ROS_PACKAGE_PATH`` entry (a listed folder that is itself
  named PKG counts too). ``package:///PKG/rest`` (three slashes, an empty host, as some
  exporters write it) is the same reference: the first path segment is the package.
- ``model://NAME/rest`` likewise, with ``GZ_SIM_RESOURCE_PATH``, ``IGN_GAZEBO_RESOURCE_PATH``,
  ``SDF_PATH`` and ``GAZEBO_MODEL_PATH`` added to the search path (after ``--package-path``).
- ``file:///abs/path`` (or ``file://localhost/abs/path``) is that absolute path;
  ``file://rel/path`` (a host that is not localhost, as some tools write a relative path) and a
  plain relative path are relative to ``base`` (the folder of the file holding the reference, or
  MJCF's meshdir); an absolute path is itself. Percent escapes (``%20``) are decoded in URIs.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from urllib.parse import unquote, urlparse

from massprops.errors import setting_ref

__all__ = ["resolve_uri"]

_ENV = {"package": ("ROS_PACKAGE_PATH",),
        "model": ("ROS_PACKAGE_PATH", "GZ_SIM_RESOURCE_PATH", "IGN_GAZEBO_RESOURCE_PATH",
                  "SDF_PATH", "GAZEBO_MODEL_PATH")}


def resolve_uri(uri: str, base: Path, description: Path,
                package_paths: Sequence[Path] = ()) -> tuple[Path | None, str | None]:
    """(path, None) for the file ``uri`` names, or (None, why not) saying where it looked.

    The path is returned even if it does not exist for plain and ``file://`` references (the
    reader then says "no such file"); for ``package://``/``model://`` a missing package is the
    problem reported.
    """
    scheme, sep, rest = uri.partition("://")
    if not sep:
        p = Path(uri)
        return (p if p.is_absolute() else base / p), None
    scheme = scheme.lower()
    if scheme == "file":
        parsed = urlparse(uri)
        host = parsed.netloc
        if host in ("", "localhost"):
            return Path(unquote(parsed.path)), None
        return base / unquote(host + parsed.path), None
    if scheme not in _ENV:
        return None, (f"cannot resolve {uri!r}: unknown scheme {scheme}://; use a path, "
                      "package:// or model://")
    package, _, inner = unquote(rest).lstrip("/").partition("/")
    roots = _roots(scheme, description, package_paths)
    for folder in roots:
        if folder.name == package and folder.is_dir():
            return folder / inner, None
        if (folder / package).is_dir():
            return folder / package / inner, None
    looked = ", ".join(str(r) for r in roots) or "(nowhere)"
    env = " or ".join(_ENV[scheme])
    return None, (f"cannot find {scheme} {package!r} for {uri!r} (looked in: {looked}); "
                  f"give {setting_ref('package_path')} DIR (the folder holding {package}/) or "
                  f"set {env}")


def _roots(scheme: str, description: Path, package_paths: Sequence[Path]) -> list[Path]:
    folder = description.resolve().parent
    roots = [folder, *folder.parents]
    roots += [Path(p) for p in package_paths]
    for var in _ENV[scheme]:
        roots += [Path(p) for p in os.environ.get(var, "").split(os.pathsep) if p]
    seen, out = set(), []
    for r in roots:
        if r not in seen:
            seen.add(r)
            out.append(r)
    return out
