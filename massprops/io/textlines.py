"""Vectorised parsing of line-oriented text meshes: select lines, count tokens, convert numbers.

Text mesh files hold millions of short numeric lines. Looping over them in Python costs ~1 µs per
line per operation, so every step here works on the whole byte buffer with numpy and C-level
``bytes`` methods; only error reporting (after something is known to be wrong) loops.
"""

from __future__ import annotations

import contextlib
import io
import re
from dataclasses import dataclass

import numpy as np

from massprops.errors import MeshFormatError

# ASCII whitespace exactly as bytes.split() sees it: \t \n \v \f \r and space.
_IS_SPACE = np.zeros(256, dtype=bool)
_IS_SPACE[[9, 10, 11, 12, 13, 32]] = True
_NEWLINE = 10
_COMMENT = re.compile(rb"#[^\n]*")
_LEADING_BLANKS = re.compile(rb"^[ \t]+", re.MULTILINE)
_FEW_RUNS = 64  # gather: up to this many runs of consecutive lines are copied as byte ranges


def strip_comments(data: bytes) -> bytes:
    """``data`` with every ``#`` comment removed up to (not including) its newline."""
    return _COMMENT.sub(b"", data) if b"#" in data else data


@dataclass(frozen=True, eq=False)
class TextLines:
    """A text buffer cut into lines, leading blanks removed, line numbers kept.

    data : the text, ending with a newline.
    starts : (L,) int64, offset of each line's first byte.
    ends : (L,) int64, offset of each line's terminating ``\\n`` (CR, if any, is part of the line).
    Line i (0-based) is line i + 1 of the file.
    """

    data: bytes
    starts: np.ndarray
    ends: np.ndarray

    @classmethod
    def from_bytes(cls, data: bytes) -> TextLines:
        if not data.endswith(b"\n"):
            data += b"\n"
        buf = np.frombuffer(data, dtype=np.uint8)
        ends = np.flatnonzero(buf == _NEWLINE)
        starts = np.concatenate(([0], ends[:-1] + 1))
        first = buf[starts]
        if ((first == 32) | (first == 9)).any():
            # Rare (indented files): strip once so keywords sit at line starts; the line count,
            # hence every line number, is unchanged.
            return cls.from_bytes(_LEADING_BLANKS.sub(b"", data))
        return cls(data, starts, ends)

    def __len__(self) -> int:
        return int(self.starts.size)

    def select(self, keyword: bytes) -> np.ndarray:
        """Indices of the lines whose first word is ``keyword`` (e.g. ``b"v"``, not ``vt``)."""
        buf = np.frombuffer(self.data, dtype=np.uint8)
        hit = np.ones(self.starts.size, dtype=bool)
        for j, byte in enumerate(keyword):
            # Past-the-end reads are clipped to the final newline, which never equals a letter.
            hit &= buf[np.minimum(self.starts + j, buf.size - 1)] == byte
        after = buf[np.minimum(self.starts + len(keyword), buf.size - 1)]
        return np.flatnonzero(hit & _IS_SPACE[after])

    def gather(self, lines: np.ndarray, skip: int = 0) -> bytes:
        """Lines ``lines`` (indices, ascending) without their first ``skip`` bytes (or with
        them blanked, which no tokenizer tells apart), each ending with a newline: one block the
        number parsers read at C speed."""
        runs = np.flatnonzero(np.diff(lines) != 1) + 1
        if lines.size and runs.size < _FEW_RUNS:
            # The usual file keeps each kind of line together: copy the few byte ranges whole
            # and blank the keywords, instead of marking every byte (~3x faster).
            first = np.concatenate(([0], runs))
            last = np.concatenate((runs, [lines.size])) - 1
            lo, hi = self.starts[lines[first]], self.ends[lines[last]] + 1
            out = bytearray(b"".join(self.data[a:b] for a, b in zip(lo.tolist(), hi.tolist())))
            if skip:
                shift = np.repeat(np.cumsum(hi - lo) - (hi - lo) - lo, last - first + 1)
                at = self.starts[lines] + shift
                view = np.frombuffer(out, dtype=np.uint8)
                for j in range(skip):
                    view[at + j] = 32
            return bytes(out)
        buf = np.frombuffer(self.data, dtype=np.uint8)
        # Mark [start + skip, end] (the newline included) of every chosen line with a running sum
        # of +1/-1 steps: one pass over the buffer whatever the number of lines.
        step = np.zeros(buf.size + 1, dtype=np.int8)
        step[self.starts[lines] + skip] = 1
        step[self.ends[lines] + 1] -= 1
        keep = np.cumsum(step[:-1], dtype=np.int8).view(bool)
        return buf[keep].tobytes()

    def token_counts(self) -> np.ndarray:
        """(L,) int64: the number of whitespace-separated tokens on each line."""
        return token_counts(self.data)


def token_starts(block: bytes) -> np.ndarray:
    """(T,) int64: the offset of each whitespace-separated token of ``block``."""
    space = _IS_SPACE[np.frombuffer(block, dtype=np.uint8)]
    first = ~space
    first[1:] &= space[:-1]  # a token starts where a non-space follows a space
    return np.flatnonzero(first)


def token_counts(block: bytes) -> np.ndarray:
    """(L,) int64: tokens on each ``\\n``-terminated line of ``block``."""
    buf = np.frombuffer(block, dtype=np.uint8)
    bounds = np.concatenate(([0], np.flatnonzero(buf == _NEWLINE) + 1))
    return np.diff(np.searchsorted(token_starts(block), bounds)).astype(np.int64)


def parse_numbers(
    block: bytes,
    counts: np.ndarray,
    dtype: type[np.floating] | type[np.integer],
    *,
    name: str,
    line_numbers: np.ndarray,
    what: str,
) -> np.ndarray:
    """All tokens of ``block`` as one flat array of ``dtype``, in order.

    counts : (L,) tokens per line of ``block`` (from ``token_counts``).
    line_numbers : (L,) 1-based file line of each line of ``block``, for error messages.
    what : what the lines should hold, for the message (e.g. ``"vertex 'x y z'"``).
    """
    if counts.size and (counts == counts[0]).all() and counts[0] > 0:
        # numpy's C reader is 2-3x faster than converting a list of tokens, but needs a fixed
        # number of columns; anything it rejects goes the general way below.
        with contextlib.suppress(ValueError):
            table = np.loadtxt(io.BytesIO(block), dtype=dtype, comments=None, ndmin=2)
            return table.reshape(-1)
    tokens = block.split()
    try:
        return np.array(tokens, dtype=dtype)
    except (ValueError, OverflowError) as exc:
        raise _bad_token(tokens, counts, dtype, name, line_numbers, what) from exc


def first_columns(flat: np.ndarray, counts: np.ndarray, width: int) -> np.ndarray:
    """(L, width): the first ``width`` values of each line of a flat token array.

    counts : (L,) tokens per line, each >= width (checked by the caller).
    """
    if (counts == width).all():
        return flat.reshape(-1, width)
    first = np.cumsum(counts) - counts
    return flat[first[:, None] + np.arange(width)]


def line_of_token(counts: np.ndarray, token: int) -> int:
    """0-based line (of a block) holding flat token number ``token``."""
    return int(np.searchsorted(np.cumsum(counts), token, side="right"))


def _bad_token(tokens, counts, dtype, name, line_numbers, what) -> MeshFormatError:
    """The error naming the first token that does not convert (slow: runs only on bad files)."""
    kind = "an integer" if np.issubdtype(dtype, np.integer) else "a number"
    for k, token in enumerate(tokens):
        try:
            np.array([token], dtype=dtype)
        except (ValueError, OverflowError):
            line = line_numbers[line_of_token(counts, k)]
            text = token.decode("utf-8", "replace")
            return MeshFormatError(
                f"{name}: line {line}: {text!r} is not {kind}; expected {what}"
            )
    return MeshFormatError(f"{name}: unreadable numbers; expected {what}")
