"""Messages fitted to the command that prints them: never name an option it does not have.

The library words its fixes for the command line (``--fill-holes``, ``(or --step)``), but its
modules serve several commands: ``model`` has no ``--unit``, ``simulate`` reads repairs from the
scene's body keys, ``precision`` has no ``--step``. `fit_message` rewrites a message for the
running command's options: a parenthesis that names a missing option is dropped (the library
always puts such hints in parentheses beside the spelled-out fix), and a bare mention becomes
what that command reads instead (a scene key), or the parenthesis-free phrase around it stays.
"""

from __future__ import annotations

import re
from collections.abc import Collection

__all__ = ["fit_message", "SCENE_KEYS"]

_OPTION = re.compile(r"(?<![\w-])--([a-z][a-z0-9-]*)")
_PAREN = re.compile(r"\s*\(([^()]*)\)")

SCENE_KEYS = {
    "allow-open": "the body key allow_open: true",
    "fill-holes": "the body key fill_holes: true",
    "max-hole": "the body key max_hole",
    "union": "the body key union: true",
    "shell": "the body key shell: THICKNESS",
    "unit": "the body key unit",
    "step": "time.step",
    "rtol": "time.rtol",
    "every": "output.every",
    "max-steps": "time.max_steps",
}
"""What a scene-reading command (simulate, precision) takes instead of inspect's options."""


def fit_message(message: str, options: Collection[str], scene: bool = False) -> str:
    """``message`` with no ``--name`` outside ``options`` (names without the dashes).

    scene : the command reads a scene file, so a bare option becomes its scene key."""
    def missing(text: str) -> bool:
        return any(name not in options for name in _OPTION.findall(text))

    if not missing(message):
        return message

    def paren(m: re.Match) -> str:
        return "" if missing(m.group(1)) else m.group(0)

    out = _PAREN.sub(paren, message)

    def bare(m: re.Match) -> str:
        name = m.group(1)
        if name in options:
            return m.group(0)
        if scene and name in SCENE_KEYS:
            return SCENE_KEYS[name]
        return f"the {name.replace('-', ' ')} setting"

    return _OPTION.sub(bare, out)
