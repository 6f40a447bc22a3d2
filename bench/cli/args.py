"""Argument checks, help formatting, output and signal handling shared by every command group: argparse types that
name the flag in their one-line errors, the help formatter that shows defaults, strict JSON for --json output, and
SIGTERM/SIGINT helpers for long-running commands."""

from __future__ import annotations

import argparse
import ast
import functools
import json
import math
import numbers
import os
import re
import signal
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

from bench.atomic import open_regular
from bench.errors import escaped
from bench.scenes.limits import MAX_SEED
from bench.tomlfile import spelled


# --- help ------------------------------------------------------------


class HelpFormatter(argparse.RawDescriptionHelpFormatter, argparse.ArgumentDefaultsHelpFormatter):
    """Descriptions as written (their examples keep their lines), and each option's default after its help
    ("(default: 60.0)") unless the help already states it or there is none to state (None, an off flag)."""

    def _get_help_string(self, action):
        if action.help is None or "default" in action.help or action.default is None or action.default is False:
            return action.help
        return super()._get_help_string(action)


# --- argument checks -------------------------------------------------


class NotedWhenTyped(argparse.Action):
    """argparse action: store the value as "store" does, and note that the flag was typed (:func:`typed`), so a
    message can name a default the command chose as such rather than as a flag the user did not give."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        namespace.typed_flags = (*getattr(namespace, "typed_flags", ()), self.dest)


def typed(a, dest: str) -> bool:
    """Whether the flag storing ``dest`` (a :class:`NotedWhenTyped` one) was typed, not left at its default."""
    return dest in getattr(a, "typed_flags", ())


def number(lo: float | None = None, hi: float | None = None, lo_open: bool = False, what: str = "a number"):
    """argparse type: a finite float within [lo, hi] (``lo_open``: strictly above lo)."""

    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{spelled(text)} is not a number") from None
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
            raise argparse.ArgumentTypeError(f"{spelled(text)} is not a whole number") from None
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            rng = (f"{lo} to {hi}" if hi is not None else f"≥ {lo}") if lo is not None else f"≤ {hi}"
            raise argparse.ArgumentTypeError(f"{text}: must be {rng}")
        return v

    parse.__name__ = "a whole number"
    return parse


#: the most LocalCluster workers a command starts: 4 per core of this machine (more only thrash and exhaust its
#: memory, each worker a Python process of ~100 MB); a bigger cluster is an existing scheduler's (--scheduler)
MAX_LOCAL_WORKERS = 4 * (os.cpu_count() or 1)


def local_workers(text: str) -> int:
    """argparse type of ``--workers``: 1 to :data:`MAX_LOCAL_WORKERS` LocalCluster worker processes."""
    try:
        return whole(1, MAX_LOCAL_WORKERS)(text)
    except argparse.ArgumentTypeError as e:
        raise argparse.ArgumentTypeError(f"{e} (4 per core of this machine; for a bigger cluster, start one and give "
                                         f"--scheduler)") from None


local_workers.__name__ = "a number of workers"


def add_cluster_arguments(parser) -> None:
    """``--workers`` and ``--scheduler``, as every command that runs on Dask takes them."""
    parser.add_argument("--workers", type=local_workers,
                        help=f"LocalCluster worker processes, 1 to {MAX_LOCAL_WORKERS} (default: one per core)")
    parser.add_argument("--scheduler", type=scheduler_address,
                        help="address of an existing Dask scheduler, tcp://HOST:PORT (or DASK_SCHEDULER_ADDRESS)")


def scheduler_address(text: str) -> str:
    """argparse type of ``--scheduler``: a Dask scheduler's address (:func:`bench.campaigns.engine.check_address`)."""
    from bench.campaigns.engine import check_address

    try:
        return check_address(text, "--scheduler")
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e).removeprefix("--scheduler ")) from None


#: argparse type of every ``--seed``: 0 to 2**63 − 1 (:data:`bench.scenes.limits.MAX_SEED`, a scene's bound)
any_seed = whole(0, MAX_SEED)
any_seed.__name__ = "a seed"


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


def firmware_file(text: str) -> str:
    """argparse type of --firmware (bridge, campaign): a readable C source (.c) or a built library (.so)."""
    existing_file(text)
    if Path(text).suffix not in (".c", ".so"):
        raise argparse.ArgumentTypeError(f"{text}: give C sources (.c) or one built library (.so)")
    return text


def firmware_choice(files, command: str) -> str | list | None:
    """FirmwareBench's ``firmware`` for --firmware's files: None (the reference firmware), one library, or the
    sources; a library among other files is a ValueError (one library is the whole firmware)."""
    if not files:
        return None
    libraries = [f for f in files if f.endswith(".so")]
    if libraries and len(files) > 1:
        raise ValueError(f"{command} --firmware: {libraries[0]} is a built library, the whole firmware: give it "
                         f"alone, or only C sources")
    return files[0] if libraries else list(files)


def output_file(text: str) -> str:
    """argparse type: a path a file can be written to (its folder exists or can be made, and a file can be created
    in it: tried with a file removed at once, so a path that only permissions would allow is refused before a long
    command runs, not after)."""
    if not text or "\0" in text:
        raise argparse.ArgumentTypeError("an empty path or one with a NUL byte")
    p = Path(text)
    if p.is_dir() or text.endswith(("/", os.sep)):
        raise argparse.ArgumentTypeError(f"{text}: is a folder, not a file")
    if p.exists() and not p.is_file():
        raise argparse.ArgumentTypeError(f"{text}: is not a regular file (a device, pipe or socket): never replaced")
    if p.exists() and not os.access(p, os.W_OK):
        raise argparse.ArgumentTypeError(f"{text}: not writable")
    parent = p.parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise argparse.ArgumentTypeError(f"{text}: {parent} is a file, not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"{text}: cannot write in {parent}")
    try:  # permissions do not tell everything (root, /proc, a read-only mount): create a file there and remove it
        fd, probe = tempfile.mkstemp(dir=parent, prefix=".biotac-bench-write-check-")
    except OSError as e:
        raise argparse.ArgumentTypeError(f"{text}: cannot write in {parent} ({e.strerror})") from None
    os.close(fd)
    os.unlink(probe)
    return text


def _checked(check, text: str) -> None:
    """Run an emulator check on a command-line value; its ValueError becomes argparse's error."""
    try:
        check(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def say_leftovers(folder):
    """``folder`` (an opened :class:`~bench.reporting.outdir.OutFolder`, or :class:`~bench.reporting.outdir.OutFile`),
    after saying on stderr which temporary files an interrupted run had left in it (or beside it) and that opening it
    removed them (nothing when there were none)."""
    note = folder.stale_note()
    if note:
        print(escaped(note), file=sys.stderr)
    return folder


def unit_serial(text: str) -> str:
    """A sensor unit's serial number ("BT...", emulator.units.seed_of_serial: also a seed it names in range)."""
    from emulator.units import seed_of_serial

    _checked(seed_of_serial, text)
    return text


def unit_choice(text: str):
    """A sensor unit: a unit seed (whole number), "nominal" or a serial number (emulator.units.unit)."""
    from emulator.units import unit

    which = int(text) if text.isascii() and text.isdigit() else text
    _checked(lambda _: unit(which), text)
    return which


def stimuli_count(n: int) -> str:
    """"1 stimulus", "3 stimuli": how the commands count a sensor's stimuli."""
    return f"{n} {'stimulus' if n == 1 else 'stimuli'}"


class OneLineErrorParser(argparse.ArgumentParser):
    """The parser of ``biotac-bench`` and of every subcommand (argparse makes a parser's subparsers of its own
    class): a usage error is one line on stderr, ``biotac-bench CMD: error: argument --flag: ... (see biotac-bench
    CMD --help)``, exit status 2, instead of argparse's usage block followed by the error.  The parsed arguments'
    ``command_prog`` is the innermost command's name (``biotac-bench cheetah serve``), for errors found later."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.set_defaults(command_prog=self.prog)

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {escaped(argparse_message(message))} (see {self.prog} --help)\n")


#: a Python string literal, as argparse's own messages quote a value with repr ('x', or "it's")
_PY_STR = r"'(?:[^'\\]|\\.)*'|\"(?:[^\"\\]|\\.)*\""
#: where argparse's own messages (Python 3.11 to 3.13) show the value typed in repr
_ARGPARSE_VALUE = re.compile(rf"(invalid choice: |invalid [^:]* value: |ignored explicit argument )({_PY_STR})")
#: the list of choices argparse's "invalid choice" ends with, each in repr
_ARGPARSE_CHOICES = re.compile(rf"\(choose from ((?:{_PY_STR})(?:, (?:{_PY_STR}))*)\)$")


def argparse_message(message: str) -> str:
    """argparse's own error ``message`` spoken as the bench's messages speak: the value typed in double quotes as
    :func:`bench.tomlfile.spelled` spells any value a user gave (``invalid choice: "x"``, never Python's ``'x'``),
    and the choices listed bare, comma-separated, as the bench's own messages list names (``choose from run,
    validate``).  Any other message (the bench's own, raised through argparse) is returned as it is."""
    message = _ARGPARSE_VALUE.sub(lambda m: m.group(1) + spelled(ast.literal_eval(m.group(2))), message)
    return _ARGPARSE_CHOICES.sub(
        lambda m: "(choose from " + ", ".join(ast.literal_eval(s.group()) for s in re.finditer(_PY_STR, m.group(1)))
                  + ")", message)


# --- output ----------------------------------------------------------


def strict_json(doc, **dumps_kw) -> str:
    """``doc`` as standard JSON: a non-finite number (inf, nan: an unbounded tolerance, say) becomes null, since
    JSON has none and jq, Go and JavaScript reject Python's ``Infinity``/``NaN``; numpy numbers become plain ones.
    ``allow_nan=False`` makes any other way of emitting them an error, never output."""
    return json.dumps(_finite_or_null(doc), allow_nan=False, default=float, **dumps_kw)


def _finite_or_null(value):
    if isinstance(value, dict):
        return {k: _finite_or_null(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite_or_null(v) for v in value]
    if isinstance(value, (str, bool)) or value is None:
        return value
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value) if math.isfinite(value) else None
    return value


# --- signals ---------------------------------------------------------


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


def sigterm_like_ctrl_c(command):
    """``command`` with SIGTERM handled as Ctrl-C is (the cluster closed, no output half-written) and reported as
    "terminated", exit status 143."""

    @functools.wraps(command)
    def run(a) -> int:
        try:
            with sigterm_raises():
                return command(a)
        except Terminated:
            print("terminated", file=sys.stderr)
            return 128 + signal.SIGTERM

    return run


def replaceable_report(marker: bytes, what: str):
    """argparse type: an :func:`output_file` that, if a file is already there, holds ``marker`` in its first 4 KB
    (a report this command wrote, which it replaces as CI tools expect); any other file is refused, never
    overwritten (a symbolic link there is replaced by the report, its target never touched)."""

    def parse(text: str) -> str:
        text = output_file(text)
        p = Path(text)
        if p.is_symlink():  # the report replaces the link itself (written aside, renamed): its target is untouched
            return text
        if p.exists():
            try:
                fh = open_regular(p)
            except OSError as e:
                raise argparse.ArgumentTypeError(f"{text}: cannot be read ({e.strerror})") from None
            head = b""
            if fh is not None:  # a link or a pipe put there since output_file() looked is not a report
                with fh:
                    head = fh.read(4096)
            if marker not in head:
                raise argparse.ArgumentTypeError(f"{text}: already there and not {what}: give another path, or "
                                                 f"move it away (only an earlier report is replaced)")
        return text

    parse.__name__ = what
    return parse


def library_option(value: str | None):
    """--library: the texture library file given (relative to the working folder, as
    :func:`bench.textures.library.named_library` names it), or the shipped library (None).  A bad file is a
    ValueError naming --library, the file, texture, field, value and allowed range: one line for one problem, else
    one problem a line, as an experiment file's ``[experiment] library`` lists them."""
    from bench.errors import TextureError
    from bench.textures.library import named_library, read_library

    if value is None:
        return read_library()  # a broken shipped library is reported as such
    try:
        return named_library(value, "--library")
    except TextureError as e:
        if len(e.problems) == 1:
            raise ValueError(e.problems[0]) from None
        raise ValueError(str(e)) from None

