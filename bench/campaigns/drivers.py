"""Your own host driver in the fault campaign (``campaign --driver MODULE:CALLABLE`` or ``--driver
PATH.py:CALLABLE``): every case then talks to the bridge firmware through it instead of the bench's
:class:`~bench.hosts.driver.BridgeDriver`.

The callable is called with the serial port's path (a str, the pty the firmware streams on) and returns the
driver object the case uses — the bench's own is ``bench.hosts.driver:BridgeDriver`` (:data:`BENCH_DRIVER`), the
class itself.  A case calls on it what it calls on the bench's (:data:`DRIVER_INTERFACE`): ``start()`` and
``request_status()`` send START and STATUS; ``wait_for(reply_type, timeout_s)`` returns the reply (START's
acknowledgement for ``CMD_START``, a :class:`~bench.hosts.driver.Status` for ``Status``) or None; ``frames(max_frames=,
timeout_s=)`` yields decoded :class:`~bench.hosts.driver.DataFrame` s; ``parser.stats`` counts ``crc_errors`` and
``dropped_frames``; ``close()``.  A wrapper around the bench's driver, or a subclass of it, is the simplest (see
``fixtures/drivers/``).

Checked before anything runs (:func:`load_driver`, :class:`DriverRefused` in one line naming the driver): the module
imports (a path: the file exists and runs), the name is in it, it is callable and takes the port as its one
argument.  A ``PATH.py`` driver is read where the campaign starts (a relative path: from its working directory) and
its text travels with every case (:class:`DriverFile`), run on the worker under the file's absolute path: a worker
in another directory or on another machine (``--scheduler``) runs the same driver, and its tracebacks name the
file; a ``MODULE:CALLABLE`` driver is imported by each worker, so it must be installed where they run.  In a case, a driver that raises, or whose object lacks part of the interface, makes that case an error
naming the driver (:class:`DriverFailed`); what it hands over is checked as the bench's driver's is, and more: a
frame missing from the sequence numbers it hands over that its ``parser.stats`` does not count as dropped fails the
case (a driver that silently loses frames).
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import linecache
import re
import sys
import types
from dataclasses import dataclass
from pathlib import Path

from bench.errors import BenchError, escaped

#: the bench's own host driver, as ``--driver`` spells a driver
BENCH_DRIVER = "bench.hosts.driver:BridgeDriver"

#: what a case calls on (or reads from) the object a driver's callable returns
DRIVER_INTERFACE = ("start", "request_status", "wait_for", "frames", "close", "parser")

#: How long (wall s) a case waits for the host driver's calls at most, plus :data:`HOST_LIMIT_PER_FRAME_S` per frame
#: it reads: far beyond what the bench's own driver takes on a loaded machine (its waits are bounded: START and
#: STATUS 3 × 5 s at most, frames 10 s without one), so only a driver that hangs reaches it.
HOST_LIMIT_S = 120.0
HOST_LIMIT_PER_FRAME_S = 0.1

_NAME = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*")


class DriverRefused(BenchError, ValueError):
    """A ``--driver`` the campaign cannot use: one line naming it and why."""


class DriverFailed(RuntimeError):
    """A driver that raised, or returned an object lacking part of :data:`DRIVER_INTERFACE`, in a case: the case
    is an error (no verdict on the firmware), its message naming the driver."""


def parse_driver(text: str) -> tuple[str, str]:
    """``text`` (``MODULE:CALLABLE`` or ``PATH.py:CALLABLE``) split into (module or path, callable's dotted name);
    ValueError saying how to spell it."""
    where, colon, name = text.rpartition(":")
    if not colon or not where or not _NAME.fullmatch(name) or not (where.endswith(".py") or _NAME.fullmatch(where)):
        raise ValueError(f"{escaped(text)}: give MODULE:CALLABLE (a module Python imports, e.g. my_team.driver:open) "
                         "or PATH.py:CALLABLE (a Python file, e.g. ci/driver.py:open)")
    return where, name


@dataclass(frozen=True)
class DriverFile:
    """A ``PATH.py`` driver as the campaign ships it to its workers: the file's absolute path where the campaign
    was started (resolved there: a relative path means the client's working directory, never a worker's) and its
    text, read there once.  A worker runs that text under that path, so a traceback names the team's file and shows
    its lines whether or not the worker's machine has the file — and a worker that has another file at that path
    still runs the client's."""

    path: str
    text: str


def driver_file(spec: str) -> DriverFile | None:
    """The file ``spec`` (``PATH.py:CALLABLE``) names, read here; None for ``MODULE:CALLABLE`` (a module each worker
    imports itself); :class:`DriverRefused` naming ``spec`` if it is no file or cannot be read as Python source."""
    try:
        where, _ = parse_driver(spec)
    except ValueError as e:
        raise DriverRefused(f"--driver {e}") from None
    if not where.endswith(".py"):
        return None
    path = Path(where)
    if not path.is_file():
        raise DriverRefused(f"--driver {escaped(spec)}: no file {escaped(where)}")
    try:  # (decoded as an import decodes it: UTF-8 unless the file declares its coding)
        text = importlib.util.decode_source(path.read_bytes())
    except (OSError, SyntaxError, UnicodeDecodeError) as e:
        raise DriverRefused(f"--driver {escaped(spec)}: cannot read {escaped(where)}: "
                            f"{one_line(f'{type(e).__name__}: {e}')}") from None
    return DriverFile(str(path.resolve()), text)


def _run_file(file: DriverFile):
    """``file``'s text run as a module of its own, under its path (its traceback lines from the text itself)."""
    name = f"_campaign_driver_{abs(hash(file))}"  # its path's and text's own name: (re)run afresh each time
    module = types.ModuleType(name)
    module.__file__ = file.path
    # the lines a traceback shows are the text that runs, even where the file is missing or differs (an entry with
    # no modification time is never checked against the disk)
    linecache.cache[file.path] = (len(file.text), None, file.text.splitlines(keepends=True), file.path)
    sys.modules[name] = module  # (as an import does: a dataclass in the file looks its module up there)
    try:
        exec(compile(file.text, file.path, "exec"), module.__dict__)
    except BaseException:
        if sys.modules.get(name) is module:  # (not another case's, run from the same file in another thread)
            del sys.modules[name]
        raise
    return module


def _import(where: str, spec: str, file: DriverFile | None):
    """The module ``where`` names: a Python file (``file``: its text as the client read it; None: read here) or an
    importable module."""
    try:
        if where.endswith(".py"):
            return _run_file(file or driver_file(spec))
        return importlib.import_module(where)
    except DriverRefused:
        raise
    except BaseException as e:  # (a file may raise anything, SystemExit too: the import failed, the campaign stops)
        if isinstance(e, KeyboardInterrupt):
            raise
        raise DriverRefused(f"--driver {escaped(spec)}: cannot import {escaped(where)}: "
                            f"{one_line(f'{type(e).__name__}: {e}')}") from None


def load_driver(spec: str, file: DriverFile | None = None):
    """The callable ``spec`` names (:func:`parse_driver`), imported and checked: callable, taking the port as its one
    argument; :class:`DriverRefused` naming ``spec`` otherwise.  ``file``: a ``PATH.py`` driver's text as the
    client read it (:func:`driver_file`; None: the file is read here)."""
    try:
        where, name = parse_driver(spec)
    except ValueError as e:
        raise DriverRefused(f"--driver {e}") from None
    obj = _import(where, spec, file)
    for part in name.split("."):
        if not hasattr(obj, part):
            raise DriverRefused(f"--driver {escaped(spec)}: {escaped(where)} has no {name}")
        obj = getattr(obj, part)
    if not callable(obj):
        raise DriverRefused(f"--driver {escaped(spec)}: {name} is a {type(obj).__name__}, not callable (give a "
                            "function or class taking the serial port's path)")
    try:
        signature = inspect.signature(obj)
    except (TypeError, ValueError):  # (some builtins have none: taken as they are)
        return obj
    try:
        signature.bind("/dev/pts/N")
    except TypeError as e:
        raise DriverRefused(f"--driver {escaped(spec)}: {name}{signature} cannot be called with the serial port's "
                            f"path alone ({e})") from None
    return obj


def open_driver(spec: str, port: str, file: DriverFile | None = None):
    """The driver object ``spec``'s callable returns for ``port``, with every part of :data:`DRIVER_INTERFACE`;
    :class:`DriverFailed` naming ``spec`` if the driver cannot be loaded here (a worker without its module, though
    the campaign's client could import it), the callable raises or the object lacks a part.  ``file``: as
    :func:`load_driver` takes it."""
    try:
        make = load_driver(spec, file)
    except DriverRefused as e:
        raise DriverFailed(f"{e} (where this case ran)") from None
    try:
        drv = make(port)
    except Exception as e:
        raise DriverFailed(f"driver {spec} raised {type(e).__name__} opening the port: {e}") from None
    missing = [part for part in DRIVER_INTERFACE if not hasattr(drv, part)]
    if missing:
        raise DriverFailed(f"driver {spec} returned a {type(drv).__name__} without {', '.join(missing)} (a case "
                           f"uses {', '.join(DRIVER_INTERFACE)}: see bench.campaigns.drivers)")
    return drv


def one_line(text: str) -> str:
    """``text`` on one line (a problem may hold several, e.g. a build's diagnostics): its lines joined by " / "."""
    return " / ".join(line.strip() for line in str(text).splitlines() if line.strip())


def uncounted_gaps(frames, dropped_frames: int) -> str | None:
    """Why the frames a driver handed over (in order) miss more frames, by their 16-bit sequence numbers, than its
    parser counted as dropped (``dropped_frames``), or None: a driver that loses frames must say so."""
    steps = [(k + 1, (b.seq - a.seq) % 65536) for k, (a, b) in enumerate(zip(frames, frames[1:]))]
    back = next(((k, frames[k].seq, frames[k - 1].seq) for k, step in steps if step == 0 or step >= 32768), None)
    if back is not None:  # (read as a gap, a repeat would be "missing 65535")
        k, seq, before = back
        return (f"the driver handed over frame {seq} right after frame {before} (its frames {k} and {k + 1}): a "
                f"frame repeated or out of order")
    missing = sum(step - 1 for _, step in steps)
    if missing > dropped_frames:
        return (f"the driver handed over {len(frames)} frames missing {missing} by their sequence numbers, but counted "
                f"{dropped_frames} dropped (frames lost without a word)")
    return None

