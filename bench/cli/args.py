"""Argument checks, help formatting and signal handling shared by every command group: argparse types that name the
flag in their one-line errors, the help formatter that shows defaults, and SIGTERM/SIGINT helpers for long-running
commands."""

from __future__ import annotations

import argparse
import math
import os
import signal
from contextlib import contextmanager
from pathlib import Path


# --- help ------------------------------------------------------------


class HelpFormatter(argparse.RawDescriptionHelpFormatter, argparse.ArgumentDefaultsHelpFormatter):
    """Descriptions as written (their examples keep their lines), and each option's default after its help
    ("(default: 60.0)") unless the help already states it or there is none to state (None, an off flag)."""

    def _get_help_string(self, action):
        if action.help is None or "default" in action.help or action.default is None or action.default is False:
            return action.help
        return super()._get_help_string(action)


def describe_on_demand(parser: argparse.ArgumentParser, describe) -> argparse.ArgumentParser:
    """``parser``'s description is ``describe()``, built only when its --help is printed (for descriptions that
    list a registry whose import would slow every other command down)."""
    format_help = parser.format_help

    def with_description() -> str:
        parser.description = describe()
        return format_help()

    parser.format_help = with_description
    return parser


# --- argument checks -------------------------------------------------


def number(lo: float | None = None, hi: float | None = None, lo_open: bool = False, what: str = "a number"):
    """argparse type: a finite float within [lo, hi] (``lo_open``: strictly above lo)."""

    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"{text}: must be a finite number")
        if lo is not None and (v <= lo if lo_open else v < lo):
            raise argparse.ArgumentTypeError(f"{text}: must be {'>' if lo_open else '≥'} {lo:g}" +
                                             (f" and ≤ {hi:g}" if hi is not None else ""))
        if hi is not None and v > hi:
            raise argparse.ArgumentTypeError(f"{text}: must be ≤ {hi:g}")
        return v

    parse.__name__ = what
    return parse


def whole(lo: int | None = None, hi: int | None = None):
    """argparse type: an integer within [lo, hi]."""

    def parse(text: str) -> int:
        try:
            v = int(text, 10)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            rng = (f"{lo} to {hi}" if hi is not None else f"≥ {lo}") if lo is not None else f"≤ {hi}"
            raise argparse.ArgumentTypeError(f"{text}: must be {rng}")
        return v

    parse.__name__ = "a whole number"
    return parse


def existing_file(text: str) -> str:
    """argparse type: a readable regular file."""
    if "\0" in text:
        raise argparse.ArgumentTypeError("the path contains a NUL byte")
    p = Path(text)
    if not p.exists():
        raise argparse.ArgumentTypeError(f"{text}: no such file")
    if not p.is_file():
        raise argparse.ArgumentTypeError(f"{text}: not a regular file")
    if not os.access(p, os.R_OK):
        raise argparse.ArgumentTypeError(f"{text}: not readable")
    return text


def output_file(text: str) -> str:
    """argparse type: a path a file can be written to (its folder exists or can be made, and is writable)."""
    if not text or "\0" in text:
        raise argparse.ArgumentTypeError("an empty path or one with a NUL byte")
    p = Path(text)
    if p.is_dir():
        raise argparse.ArgumentTypeError(f"{text}: is a folder, not a file")
    if p.exists() and not os.access(p, os.W_OK):
        raise argparse.ArgumentTypeError(f"{text}: not writable")
    parent = p.parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise argparse.ArgumentTypeError(f"{text}: {parent} is a file, not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"{text}: cannot write in {parent}")
    return text


def _checked(check, text: str) -> None:
    """Run an emulator check on a command-line value; its ValueError becomes argparse's error."""
    try:
        check(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def unit_serial(text: str) -> str:
    """A sensor unit's serial number ("BT...", emulator.units.check_serial)."""
    from emulator.units import check_serial

    _checked(check_serial, text)
    return text


def unit_choice(text: str):
    """A sensor unit: a unit seed (whole number), "nominal" or a serial number (emulator.units.unit)."""
    from emulator.units import unit

    which = int(text) if text.isdigit() else text
    _checked(lambda _: unit(which), text)
    return which


def one_line_errors(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Usage errors of this subcommand as one line (``biotac-bench CMD: error: argument --flag: ...``), status 2."""

    def error(message: str):
        parser.exit(2, f"{parser.prog}: error: {message} (see {parser.prog} --help)\n")

    parser.error = error
    return parser


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that the same clean-up runs."""


@contextmanager
def sigterm_raises():
    """Within the block SIGTERM raises :class:`Terminated` (Ctrl-C raises KeyboardInterrupt as always)."""

    def handler(signum, frame):
        raise Terminated()

    try:
        old = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)
