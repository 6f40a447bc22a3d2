"""SIGINT and SIGTERM as requests to stop, never as exceptions in the middle of a write.

While a :class:`StopSignals` guard is active, the first SIGINT or SIGTERM (and any after it) only records the
signal: the runner stops at its next chunk boundary (``should_stop``), exports and plots stop at their next block
(``checkpoint`` raises :class:`StopRequested`), and the record is still written, with status ``"interrupted"``.
The exit status is 128 + the first signal's number (130 for SIGINT, 143 for SIGTERM).  Writes go through
temporary files renamed into place, so no signal leaves a half-written file behind.
"""

from __future__ import annotations

import os
import signal
import threading

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class StopRequested(Exception):
    """Raised by :meth:`StopSignals.checkpoint` once a stop signal has arrived."""


class StopSignals:
    """Context manager installing the handlers (main thread only; elsewhere it only offers the same API)."""

    def __init__(self, signals=STOP_SIGNALS, announce: bool = True):
        self.signals = tuple(signals)
        self.announce = announce
        self.signum: int | None = None
        self.count = 0
        self._previous: dict = {}

    def _handler(self, signum, frame):
        self.count += 1
        if self.signum is None:
            self.signum = signum
            if self.announce:
                msg = (f"\n{signal.Signals(signum).name}: stopping at the next chunk and writing what was "
                       f"recorded (status \"interrupted\")\n")
                try:
                    os.write(2, msg.encode())
                except OSError:
                    pass

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for s in self.signals:
                self._previous[s] = signal.signal(s, self._handler)
        return self

    def __exit__(self, *exc):
        for s, h in self._previous.items():
            signal.signal(s, h)
        self._previous.clear()

    # ---- what the runner and the writers ask
    def should_stop(self) -> bool:
        return self.signum is not None

    def checkpoint(self) -> None:
        if self.signum is not None:
            raise StopRequested(self.signal_name)

    @property
    def signal_name(self) -> str | None:
        return signal.Signals(self.signum).name if self.signum is not None else None

    @property
    def exit_code(self) -> int | None:
        return 128 + int(self.signum) if self.signum is not None else None
