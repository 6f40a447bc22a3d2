"""The bench's error root: every error the bench raises on purpose is a :class:`BenchError`.

Each also inherits the builtin it is a kind of (``ValueError`` for bad input, ``RuntimeError`` for a part that
failed), so callers that catch builtins keep working; the CLI turns any of them into a one-line message and exit
status 2 (an error's own ``exit_status`` where it has one), never a traceback.
"""

from __future__ import annotations

import os
import shlex


def shortened(text: str, limit: int = 300) -> str:
    """``text`` for a message, at most ``limit`` characters: cut, with its length said, when longer (a hostile
    file can hold a 1 MB string or path).  The one rule for the scene's and the texture library's messages."""
    return text if len(text) <= limit else f"{text[:limit - 25]}… ({len(text)} characters)"


def escaped(text: str) -> str:
    """``text`` with each character that is not printable (a line break, a terminal's escape sequence — a path may
    hold them) written as Python writes it in a string (``\\n``, ``\\x1b``): one line, shown as it is."""
    return "".join(ch if ch.isprintable() else ch.encode("unicode_escape").decode("ascii") for ch in text)


def shell_word(text: str) -> str:
    """``text`` (a path a user gave) as one word of a command line to type into a POSIX shell: quoted when it
    needs it; one starting with '-' made a relative path ('./-x'), so argparse takes it as a value, not a flag; one
    holding a control or other unprintable character in bash's $'…' quoting, its bytes escaped (a message shows them,
    rather than acting on the terminal)."""
    if text.startswith("-"):
        text = "./" + text
    if text.isprintable():
        return shlex.quote(text)
    out = []
    for ch in text:
        if ch in "'\\":
            out.append("\\" + ch)
        elif ch.isprintable():
            out.append(ch)
        else:
            out.append("".join(f"\\x{b:02x}" for b in os.fsencode(ch)))
    return "$'" + "".join(out) + "'"


class BenchError(Exception):
    """Root of the bench's own errors."""


class FileProblems(BenchError, ValueError):
    """A file a user gave is invalid: ``source`` names it (as given), ``problems`` lists every problem found.  The
    message shows the file's name :func:`escaped` (a path may hold a line break or a terminal's escape sequence)."""

    def __init__(self, source: str, problems: list[str]):
        self.source, self.problems = source, problems
        super().__init__(f"{escaped(str(source))}: {len(problems)} problem(s):\n"
                         + "\n".join(f"  - {p}" for p in problems))


class SceneError(FileProblems):
    """A scene file is invalid; ``problems`` lists every problem found (field, value, what is allowed)."""


class TextureError(FileProblems):
    """A texture library file is invalid, or a texture asked for is not in it; ``problems`` lists every problem
    (texture, field, value, what is allowed)."""


class BuildError(BenchError, RuntimeError):
    """A native part (firmware, cheetah.so, a client) did not compile; the message carries the diagnostics."""


class FirmwareError(BenchError, RuntimeError):
    """The firmware misbehaved under co-simulation (a failing HAL call, a hang)."""


class ActionError(BenchError, RuntimeError):
    """An action a test scheduled on a bench (``at``/``now``: a fault, an unplug) raised: the message names the
    action (where it is defined), when it was due and its error; the bench stops, as for a firmware's error."""


class OutputNotWritten(BenchError, OSError):
    """A command's results could not be written where asked (a full disk, say), after the work was done: the message
    says what is missing and where anything saved went.  Exit status 1, as a failed run's."""

    exit_status = 1
