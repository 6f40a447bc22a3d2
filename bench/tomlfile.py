"""Reading the bench's TOML files (scenes, the texture library, experiment files) safely: a regular file of bounded
size (a device or a pipe could block or never end), UTF-8 text without NUL bytes, TOML nested no deeper than a
limit (checked without recursion).  Every problem becomes the caller's error class, naming the file."""

from __future__ import annotations

import datetime
import os
import stat
import tomllib
from pathlib import Path

from bench.errors import shortened


def _position(data: bytes, offset: int) -> str:
    line = data.count(b"\n", 0, offset) + 1
    column = offset - data.rfind(b"\n", 0, offset)
    return f"line {line}, column {column}"


def too_deep(data, limit: int) -> str | None:
    """The first array or table nested inside more than ``limit`` others (the file itself not counted), or None: a
    value inside ``limit`` tables is fine (an iterative walk: no recursion)."""
    stack = [(data, "", 0)]
    while stack:
        v, where, depth = stack.pop()
        if depth > limit and isinstance(v, (dict, list)):
            return where or "the file"
        if isinstance(v, dict):
            stack += [(x, f"{where}.{k}" if where else str(k), depth + 1) for k, x in v.items()]
        elif isinstance(v, list):
            stack += [(x, f"{where}[{i}]", depth + 1) for i, x in enumerate(v)]
    return None


def unprintable(text: str, allowed: str = "") -> bool:
    """Whether ``text`` holds a control character (other than those in ``allowed``, e.g. line breaks), a NUL or a lone
    surrogate: text that is written into reports and terminals must not."""
    return (not text.translate({ord(ch): None for ch in allowed}).isprintable()
            or any(0xD800 <= ord(ch) <= 0xDFFF for ch in text))


def read_text(path: str | Path, error, max_bytes: int, empty_hint: str, folder_hint: str = "") -> str:
    """The text of a TOML file, or ``error(source, [problem])`` naming the file and what is wrong with it:
    unreadable, not a regular file, larger than ``max_bytes``, empty (``empty_hint`` says what it needs), not
    UTF-8 (a leading byte-order mark is allowed and dropped), a NUL byte."""
    return read_stored(path, error, max_bytes, empty_hint, folder_hint)[1]


def read_stored(path: str | Path, error, max_bytes: int, empty_hint: str, folder_hint: str = "") -> tuple[bytes, str]:
    """The file's bytes as stored (what ``sha256sum`` hashes: a byte-order mark included) and its text as
    :func:`read_text` gives it (the mark dropped), from one reading; the same errors."""
    where = str(path)
    if "\0" in where:
        raise error(repr(where)[1:-1], ["the path contains a NUL byte"])
    size_text = f"{max_bytes} bytes ({max_bytes / 1e6:g} MB)"
    try:
        st = os.stat(path)
        if stat.S_ISDIR(st.st_mode):
            raise error(where, ["cannot read the file: Is a directory" + (f" ({folder_hint})" if folder_hint else "")])
        if not stat.S_ISREG(st.st_mode):
            raise error(where, ["cannot read the file: not a regular file (a device, pipe or socket); save it "
                                "to a file"])
        if st.st_size > max_bytes:
            raise error(where, [f"the file is {st.st_size} bytes: it may hold at most {size_text}"])
        with open(path, "rb") as f:
            stored = data = f.read(max_bytes + 1)
    except OSError as e:
        raise error(where, [f"cannot read the file: {e.strerror or e}"]) from None
    if len(data) > max_bytes:
        raise error(where, [f"the file holds more than {max_bytes} bytes: it may hold at most {size_text}"])
    if data.startswith((b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff")):
        raise error(where, ["the file is UTF-32 text: save it as UTF-8 (TOML files are UTF-8)"])
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise error(where, ["the file is UTF-16 text: save it as UTF-8 (TOML files are UTF-8)"])
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]  # a byte-order mark some editors write: not part of the text
    if not data.strip():
        raise error(where, [f"the file is empty: {empty_hint}"])
    nul = data.find(b"\0")
    if nul >= 0:
        raise error(where, [f"the file holds a NUL byte at {_position(data, nul)}: not a text file"])
    try:
        return stored, data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise error(where, [f"not UTF-8 text: byte 0x{data[e.start]:02x} at {_position(data, e.start)} "
                            f"cannot be decoded (TOML files are UTF-8; save the file as UTF-8)"]) from None


def parse(text: str, source: str, error, max_nesting: int, needed: str) -> dict:
    """The TOML of ``text``, or ``error(source, [problem])``: syntax errors, values TOML cannot hold, nesting
    deeper than ``max_nesting`` (``needed`` says how deep the file's format goes)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise error(source, [f"TOML syntax error: {e}"]) from None
    except RecursionError:
        raise error(source, [f"arrays or inline tables nested too deeply to read ({needed}; at most {max_nesting} "
                             f"are allowed)"]) from None
    except ValueError as e:  # e.g. an integer of more than 4300 digits
        raise error(source, [f"TOML value error: {_cut(str(e))}"]) from None
    deep = too_deep(data, max_nesting)
    if deep is not None:
        raise error(source, [f"{_cut(deep, 120)}: nested more than {max_nesting} arrays or tables deep ({needed})"])
    return data


def _cut(text: str, limit: int = 300) -> str:
    return text if len(text) <= limit else text[:limit] + f"… ({len(text)} characters)"


_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}
_BARE_KEY = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-")


def _is_surrogate(ch: str) -> bool:
    return 0xD800 <= ord(ch) <= 0xDFFF


def _basic_string(text: str) -> str:
    """``text`` as a TOML basic string: quotes, backslashes and control or other unprintable characters escaped
    (so a message shows them rather than acting on the terminal); a lone surrogate, which no TOML string can hold
    (nor its ``\\uD800`` escape), as U+FFFD (:func:`spelled` says which surrogate it stands for)."""
    out = []
    for ch in text:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif _is_surrogate(ch):
            out.append(REPLACEMENT)
        elif ch.isprintable():
            out.append(ch)
        else:
            out.append(f"\\u{ord(ch):04X}" if ord(ch) <= 0xFFFF else f"\\U{ord(ch):08X}")
    return '"' + "".join(out) + '"'


#: what a message shows in place of a lone surrogate (only a JSON file holds one, as "\\ud800"; TOML text cannot)
REPLACEMENT = "\ufffd"


def _surrogates(v, found: dict) -> None:
    """Collect the lone surrogates in the text of ``v`` (strings, keys, nested lists and tables) into ``found``,
    in order (an iterative walk: no recursion)."""
    stack = [v]
    while stack:
        x = stack.pop()
        if isinstance(x, str):
            found.update((ch, None) for ch in x if _is_surrogate(ch))
        elif isinstance(x, dict):
            stack += [x[k] for k in reversed(list(x))] + [k for k in reversed(list(x))]
        elif isinstance(x, (list, tuple)):
            stack += reversed(x)


def _spell(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)  # Python's float spelling is TOML's too: 0.5, 1e+300, inf, -inf, nan
    if isinstance(v, str):
        return _basic_string(v)
    if isinstance(v, (datetime.datetime, datetime.date, datetime.time)):
        return v.isoformat()
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(map(_spell, v)) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k if isinstance(k, str) and k and set(k) <= _BARE_KEY else _spell(str(k))} = "
                               f"{_spell(x)}" for k, x in v.items()) + "}"
    return repr(v)  # not from a TOML file (None, an object a Python caller passed): Python's spelling


def spelled(v, limit: int = 80, note: bool = True) -> str:
    """``v`` for a message as a TOML file spells it (``"x"``, ``true``, ``[1, "a"]``, ``{a = 1}``, ``inf``, a date
    as written), so a message about a TOML file speaks TOML back; a value TOML cannot hold (None, an object)
    keeps its ``repr``.  Text holding a lone surrogate (a JSON library's ``"\\ud800"``) is shown with U+FFFD in its
    place, and a note after it names the surrogates as JSON escapes them.  Shortened past ``limit`` characters
    (:func:`bench.errors.shortened`; the note after it, at most three surrogates named).  ``note=False`` leaves the
    note out: for a label repeated before problems, one of which shows the value with its note."""
    try:
        text = _spell(v)
        found: dict = {}
        if note:
            _surrogates(v, found)
    except (RecursionError, ValueError):
        text, found = f"<{type(v).__name__}>", {}
    text = shortened(text, limit)
    if not found:
        return text
    named = ", ".join(f"\\u{ord(ch):04x}" for ch in list(found)[:3]) + (", …" if len(found) > 3 else "")
    return (f"{text} ({REPLACEMENT} stands for the lone surrogate{'s' if len(found) > 1 else ''} {named}, which TOML "
            f"text cannot hold)")
