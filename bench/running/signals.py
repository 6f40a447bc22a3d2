"""SIGINT and SIGTERM as requests to stop, never as exceptions in the middle of a write.

While a :class:`StopSignals` guard is active, a SIGINT or SIGTERM only records the signal.  During the
simulation, the first one stops the runner at its next chunk boundary (``should_stop``); everything recorded so
far is then written in full — exports and plots included — with status ``"interrupted"``.  A second signal —
whenever it arrives, even before the chunk has ended — or any signal arriving after
:meth:`StopSignals.begin_writing` stops exports and plots at their next block (``checkpoint`` raises
:class:`StopRequested`); the record is still written.  The exit status is 128 + the first signal's number (130 for SIGINT, 143 for SIGTERM).  Writes go through
temporary files renamed into place, so no signal leaves a half-written file behind.
"""

from __future__ import annotations

import os
import signal
from contextlib import contextmanager
import threading

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def heeded(signals) -> tuple:
    """Those of ``signals`` this process is not told to ignore: a command started in the background of a script
    inherits SIGINT ignored (as Python itself then leaves it), and no guard here may turn it into a stop."""
    return tuple(s for s in signals if signal.getsignal(s) is not signal.SIG_IGN)


class StopRequested(Exception):
    """Raised by :meth:`StopSignals.checkpoint` once a stop signal has arrived while the outputs are written;
    its argument is that signal's name."""


class StopSignals:
    """Context manager installing the handlers (main thread only; elsewhere it only offers the same API)."""

    def __init__(self, signals=STOP_SIGNALS, announce: bool = True):
        self.signals = tuple(signals)
        self.announce = announce
        self.signum: int | None = None  # the first signal: the run's status and exit code
        self.count = 0
        self._writing_signum: int | None = None  # the signal that stops the writing: a second one, or one after
        #                                            begin_writing()
        self._writing = False
        self._previous: dict = {}

    def _handler(self, signum, frame):
        self.count += 1
        name = signal.Signals(signum).name
        msg = None
        if self._writing_signum is None and (self._writing or self.signum is not None):
            self._writing_signum = signum
            msg = (f"\n{name}: stopping the exports and plots; writing the record (status \"interrupted\")\n"
                   if self._writing else
                   f"\n{name}: the exports and plots will be skipped; the record is still written (status "
                   f"\"interrupted\")\n")
        if self.signum is None:
            self.signum = signum
            msg = msg or (f"\n{name}: stopping at the next chunk and writing what was recorded "
                          f"(status \"interrupted\"); another signal stops the exports and plots\n")
        if msg and self.announce:
            try:
                os.write(2, msg.encode())
            except OSError:
                pass

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for s in heeded(self.signals):
                self._previous[s] = signal.signal(s, self._handler)
        return self

    def __exit__(self, *exc):
        for s, h in self._previous.items():
            signal.signal(s, h)
        self._previous.clear()

    # ---- what the runner and the writers ask
    def should_stop(self) -> bool:
        return self.signum is not None

    def begin_writing(self) -> None:
        """The simulation is over and the outputs are being written: from now on :meth:`checkpoint` raises if a
        signal arrived after this call, or a second signal arrived at any time (one signal before this call only
        stopped the simulation)."""
        self._writing = True

    def checkpoint(self) -> None:
        """Raise :class:`StopRequested` if the writing is to stop (:meth:`begin_writing`; before that call: if
        any signal arrived since the guard was entered)."""
        signum = self._writing_signum if self._writing else self.signum
        if signum is not None:
            raise StopRequested(signal.Signals(signum).name)

    @property
    def signal_name(self) -> str | None:
        return signal.Signals(self.signum).name if self.signum is not None else None

    @property
    def exit_code(self) -> int | None:
        return 128 + int(self.signum) if self.signum is not None else None


@contextmanager
def signals_deferred():
    """Within the block SIGINT and SIGTERM are noted, not raised (a second Ctrl-C cannot cut a file short)."""
    seen = []

    def note(signum, frame):
        seen.append(signum)

    try:
        old = {s: signal.signal(s, note) for s in heeded((signal.SIGINT, signal.SIGTERM))}
    except ValueError:
        yield seen
        return
    try:
        yield seen
    finally:
        for s, h in old.items():
            signal.signal(s, h)
