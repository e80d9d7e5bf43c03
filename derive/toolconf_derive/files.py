"""Reading a description's files: the bytes of a regular file, bounded; its TOML; and its tables,
checked key by key as serde's deny_unknown_fields would (descriptions and URDFs are data, read and
checked, never evaluated).
"""

from __future__ import annotations

import math
import os
import stat
import tomllib
import unicodedata
from pathlib import Path

from .errors import DescriptionError


# Characters no text field may hold besides the control characters (Unicode category Cc: C0, DEL,
# C1, the newline among them): the line and paragraph separators, the bidirectional controls
# (which rustc refuses in literals and comments) and the byte-order mark. The renderer's IR reader
# refuses the same (derive/render/src/escape.rs, `refused`).
REFUSED = frozenset("\u2028\u2029\u061c\u200e\u200f\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069\ufeff")


def refused_character(text: str, paragraph: bool = False) -> str | None:
    """The first character of `text` no text field may hold (a newline is allowed in a
    `paragraph`, a field of several lines), or None."""
    for c in text:
        if c == "\n" and paragraph:
            continue
        if c in REFUSED or unicodedata.category(c) == "Cc":
            return c
    return None


def text_problem(value: str, paragraph: bool = False) -> str | None:
    """Why `value` cannot be a text field (one line, or lines for a `paragraph`), or None."""
    c = refused_character(value, paragraph)
    if c is None:
        return None
    what = ("a line break" if c in "\n\r\u2028\u2029\x85" else
            "a control character" if unicodedata.category(c) == "Cc" else "an invisible formatting character")
    lines = "several lines (a newline is allowed)" if paragraph else "one line"
    return (f"holds U+{ord(c):04X} ({what}) at character {value.index(c) + 1}: a text field is {lines} of "
            "text with no control character")


def _is_matrix(v) -> bool:
    return isinstance(v, list) and all(isinstance(r, list) and all(isinstance(x, str) for x in r) for r in v)


_TYPES = {
    "string": ("a string", lambda v: isinstance(v, str)),
    # Free text (a title, a unit, a doc): one line; a paragraph may have several; texts, one each.
    "text": ("a string", lambda v: isinstance(v, str)),
    "paragraph": ("a string", lambda v: isinstance(v, str)),
    "texts": ("an array of strings", lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v)),
    "integer": ("an integer", lambda v: isinstance(v, int) and not isinstance(v, bool)),
    "number": ("a number", lambda v: isinstance(v, (int, float)) and not isinstance(v, bool)),
    "table": ("a table", lambda v: isinstance(v, dict)),
    "tables": ("an array of tables", lambda v: isinstance(v, list) and all(isinstance(x, dict) for x in v)),
    "strings": ("an array of strings", lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v)),
    "values": ("an array of numbers or expression strings",
               lambda v: isinstance(v, list) and all(isinstance(x, (str, int, float)) and not isinstance(x, bool)
                                                     for x in v)),
    "matrix": ("an array of rows of expression strings", _is_matrix),
    "numbers": ("an array of finite numbers",
                lambda v: isinstance(v, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                      and math.isfinite(x) for x in v)),
}


class Table:
    """One TOML table being read: unknown keys, missing keys and wrong types stop the derivation
    with the file and the key's full name (e.g. `coordinates.q[1].latex`)."""

    def __init__(self, path: Path, key: str, raw, spec: tuple):
        self.path, self.key = path, key
        if not isinstance(raw, dict):
            raise DescriptionError(path, key, "must be a table")
        known = [k for k, _, _ in spec]
        for k in raw:
            if k not in known:
                raise DescriptionError(path, self.sub(k), f"unknown key (known here: {', '.join(known)})")
        for k, kind, required in spec:
            if k not in raw:
                if required:
                    raise DescriptionError(path, self.sub(k), "missing (required)")
                continue
            name, ok = _TYPES[kind]
            if not ok(raw[k]):
                raise DescriptionError(path, self.sub(k), f"must be {name}, got {raw[k]!r}")
            if kind in ("text", "paragraph", "texts"):
                items = raw[k] if kind == "texts" else [raw[k]]
                for i, item in enumerate(items):
                    problem = text_problem(item, paragraph=kind == "paragraph")
                    if problem:
                        key = self.sub(k) + (f"[{i}]" if kind == "texts" else "")
                        raise DescriptionError(path, key, problem)
        self.raw = raw

    def sub(self, k: str) -> str:
        return f"{self.key}.{k}" if self.key else k

    def get(self, k: str, default=None):
        return self.raw.get(k, default)

    def table(self, k: str, spec: tuple) -> "Table":
        return Table(self.path, self.sub(k), self.raw.get(k, {}), spec)

    def tables(self, k: str, spec: tuple) -> list["Table"]:
        return [Table(self.path, f"{self.sub(k)}[{i}]", t, spec) for i, t in enumerate(self.raw.get(k, []))]

# The largest description file read (a model is a few kB): `/dev/zero` or a stray large file is
# one line and status 2, not an exhausted memory.
MAX_DESCRIPTION_BYTES = 1 << 20


def _not_a_file(mode: int) -> str | None:
    """What a file of this mode is when it is not a regular file (read, it would block or never end)."""
    for test, what in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device")):
        if test(mode):
            return what
    return None if stat.S_ISREG(mode) else "not a regular file"


def read_text(path: Path | str, limit: int, what: str) -> str:
    """The UTF-8 text of the regular file `path`, at most `limit` bytes. Opened without blocking
    (a FIFO's open would wait for a writer) and checked on the opened descriptor (what is read is
    what was checked); a folder, FIFO, socket or device, a larger file, an unreadable one or one
    that is not UTF-8 is a DescriptionError saying so, with `what` the file is meant to be."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as err:
        try:
            kind = _not_a_file(os.stat(path).st_mode)
        except OSError:
            kind = None
        problem = f"{kind}, not {what}" if kind else f"cannot read: {err.strerror}"
        raise DescriptionError(path, "", problem) from err
    try:
        kind = _not_a_file(os.fstat(fd).st_mode)
        if kind:
            raise DescriptionError(path, "", f"{kind}, not {what}")
        chunks, total = [], 0
        while total <= limit:
            chunk = os.read(fd, min(1 << 16, limit + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
    except OSError as err:
        raise DescriptionError(path, "", f"cannot read: {err.strerror}") from err
    finally:
        os.close(fd)
    if total > limit:
        raise DescriptionError(path, "", f"larger than {limit} bytes ({limit / (1 << 20):g} MiB), more than "
                                         f"{what} needs")
    data = b"".join(chunks)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise DescriptionError(path, "", f"not UTF-8 text: {err.reason} at byte {err.start}") from err


def read_toml(path: Path, what: str = "a description file") -> dict:
    """The parsed file (read_text's rules); a TOML syntax error is a DescriptionError."""
    text = read_text(path, MAX_DESCRIPTION_BYTES, what)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise DescriptionError(path, "", f"not valid TOML: {err}") from err
    except RecursionError as err:
        # tomllib recurses once per nested array or table: `q = [[[[…` thousands deep.
        raise DescriptionError(path, "", "nested too deeply to be a description") from err
